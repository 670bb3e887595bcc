/* A z-buffer rasteriser of leaf quads for orthographic views, on the CPU: what the image error
 * and the viewpoint-driven collapse measure leaves with.
 *
 * Coverage is exact and watertight: each quad (a parallelogram, so its projection is convex)
 * is drawn as one convex polygon whose vertices are snapped to 1/256 pixel; a pixel belongs to
 * it when its centre is inside every edge, evaluated in 64-bit integers, or on an edge that is
 * a top or a left one (the top-left convention). Two quads that share an edge therefore never
 * both cover, nor both miss, a pixel centre on it. Setup is in double, relative to the view's
 * centre, so leaves far from the origin lose nothing to the float of their coordinates.
 * Triangles (another simplifier's output, measured the same way) take the same path. */
#include <string.h>

#include "foliage_internal.h"

#define SUBPIXEL 256.0      /* 8 bits of sub-pixel precision */
#define HALF_SUB 128        /* a pixel centre, in sub-pixel units */
/* Polygons are clipped to this many pixels around the image: snapped coordinates then stay
 * under 2^29, differences under 2^30, and each edge function's two products under 2^60. */
#define GUARD 1048576.0
#define MAX_VERTS 8

xyl_result xyl__raster_init(xyl__raster *r, uint32_t width, uint32_t height, const xyl_allocator *a)
{
    memset(r, 0, sizeof *r);
    if (width == 0 || height == 0 || width > XYL__RASTER_MAX || height > XYL__RASTER_MAX)
        return XYL_ERR_INVALID_ARGUMENT;
    size_t px = (size_t)width * height;
    r->width = width, r->height = height;
    r->depth = xyl__alloc_array(a, px, sizeof *r->depth);
    r->id = xyl__alloc_array(a, px, sizeof *r->id);
    r->shade = xyl__alloc_array(a, px, sizeof *r->shade);
    if (!r->depth || !r->id || !r->shade) {
        xyl__raster_free(r, a);
        return XYL_ERR_OUT_OF_MEMORY;
    }
    xyl__raster_clear(r);
    return XYL_OK;
}

void xyl__raster_free(xyl__raster *r, const xyl_allocator *a)
{
    xyl__free(a, r->depth);
    xyl__free(a, r->id);
    xyl__free(a, r->shade);
    memset(r, 0, sizeof *r);
}

void xyl__raster_clear(xyl__raster *r)
{
    size_t px = (size_t)r->width * r->height;
    for (size_t k = 0; k < px; ++k) {
        r->depth[k] = -INFINITY;
        r->id[k] = XYL__RASTER_NONE;
        r->shade[k] = 0.0f;
    }
}

/* A vertex in pixel coordinates (x right, y down, the image [0, w) x [0, h)) with its depth
 * (larger is nearer the eye). */
typedef struct pvert {
    double x, y, z;
} pvert;

/* Keeps the part of poly on the side k * (coordinate axis) <= limit (Sutherland-Hodgman). */
static int clip_side(const pvert *in, int n, pvert *out, int axis, double sign, double limit)
{
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const pvert *p = &in[i], *q = &in[(i + 1) % n];
        double dp = sign * (axis ? p->y : p->x) - limit, dq = sign * (axis ? q->y : q->x) - limit;
        if (dp <= 0.0) out[m++] = *p;
        if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0)) {
            double t = dp / (dp - dq);
            out[m++] = (pvert){p->x + t * (q->x - p->x), p->y + t * (q->y - p->y),
                               p->z + t * (q->z - p->z)};
        }
    }
    return m;
}

/* The polygon clipped to the guard band around a w x h image; its vertex count (0 if none). */
static int clip_guard(pvert *poly, int n, uint32_t w, uint32_t h)
{
    bool inside = true;
    for (int i = 0; i < n; ++i)
        inside = inside && poly[i].x >= -GUARD && poly[i].x <= w + GUARD && poly[i].y >= -GUARD &&
                 poly[i].y <= h + GUARD;
    if (inside) return n;
    pvert tmp[MAX_VERTS];
    n = clip_side(poly, n, tmp, 0, -1.0, GUARD);
    n = clip_side(tmp, n, poly, 0, 1.0, w + GUARD);
    n = clip_side(poly, n, tmp, 1, -1.0, GUARD);
    n = clip_side(tmp, n, poly, 1, 1.0, h + GUARD);
    return n;
}

static int64_t floor_div(int64_t a, int64_t b)
{
    int64_t q = a / b;
    return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

typedef struct edge {
    int64_t dx, dy, e; /* e: the edge function at the current pixel centre */
    bool inclusive;    /* a top or left edge: centres exactly on it are in */
} edge;

/* Writes the covered pixels whose depth is nearer than what is there. z of a pixel centre is
 * z0 + za X + zb Y (pixel coordinates), clamped to [zlo, zhi]. */
static void fill(xyl__raster *r, const int64_t (*v)[2], int n, const double plane[3], double zlo,
                 double zhi, uint32_t id, float shade)
{
    int64_t lo[2] = {INT64_MAX, INT64_MAX}, hi[2] = {INT64_MIN, INT64_MIN};
    for (int i = 0; i < n; ++i)
        for (int d = 0; d < 2; ++d) {
            if (v[i][d] < lo[d]) lo[d] = v[i][d];
            if (v[i][d] > hi[d]) hi[d] = v[i][d];
        }
    /* pixels whose centre (i * 256 + 128) lies in [lo, hi] */
    int64_t x0 = floor_div(lo[0] - HALF_SUB + 255, 256), x1 = floor_div(hi[0] - HALF_SUB, 256);
    int64_t y0 = floor_div(lo[1] - HALF_SUB + 255, 256), y1 = floor_div(hi[1] - HALF_SUB, 256);
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > (int64_t)r->width - 1) x1 = (int64_t)r->width - 1;
    if (y1 > (int64_t)r->height - 1) y1 = (int64_t)r->height - 1;
    if (x0 > x1 || y0 > y1) return;
    edge e[MAX_VERTS];
    int64_t px = x0 * 256 + HALF_SUB, py = y0 * 256 + HALF_SUB;
    for (int i = 0; i < n; ++i) {
        const int64_t *a = v[i], *b = v[(i + 1) % n];
        e[i].dx = b[0] - a[0], e[i].dy = b[1] - a[1];
        e[i].e = e[i].dx * (py - a[1]) - e[i].dy * (px - a[0]);
        /* interior on the positive side, y down: left edges run up, top edges run right */
        e[i].inclusive = e[i].dy < 0 || (e[i].dy == 0 && e[i].dx > 0);
    }
    for (int64_t y = y0; y <= y1; ++y) {
        /* the covered pixels of a row are a span: along the row each edge function falls by
           dy * 256 a pixel, so each edge bounds it on one side, in exact integers */
        int64_t first = 0, last = x1 - x0;
        for (int i = 0; i < n && first <= last; ++i) {
            int64_t t = e[i].inclusive ? 0 : 1, d = e[i].dy * 256, f = e[i].e;
            if (d == 0) {
                if (f < t) last = -1;
            } else if (d > 0) { /* f - d k >= t  <=>  k <= (f - t) / d */
                if (f - t < 0) last = -1;
                else if ((f - t) / d < last) last = (f - t) / d;
            } else { /* k >= (t - f) / -d */
                int64_t k = t - f <= 0 ? 0 : (t - f + (-d) - 1) / (-d);
                if (k > first) first = k;
            }
        }
        for (int i = 0; i < n; ++i) e[i].e += e[i].dx * 256;
        if (first > last) continue;
        double zy = plane[0] + plane[2] * ((double)y + 0.5);
        size_t base = (size_t)y * r->width;
        for (int64_t x = x0 + first; x <= x0 + last; ++x) {
            double z = zy + plane[1] * ((double)x + 0.5);
            z = z < zlo ? zlo : z > zhi ? zhi : z;
            size_t k = base + (size_t)x;
            if ((float)z > r->depth[k]) {
                r->depth[k] = (float)z;
                r->id[k] = id;
                r->shade[k] = shade;
            }
        }
    }
}

/* Depth as an affine function of pixel coordinates, from the polygon's plane (normal n through
 * the projected point on): z0 + za X + zb Y. false when the plane is seen (almost) edge-on. */
static bool depth_plane(const xyl__ortho_view *v, const xyl__raster *r, xyl__dvec3 n,
                        const pvert *on, double plane[3])
{
    double nr = xyl__d3_dot(n, v->right), nu = xyl__d3_dot(n, v->up), nt = xyl__d3_dot(n, v->toward);
    if (!(fabs(nt) > 1e-9)) return false;
    double pix = 2.0 * v->half / r->width;
    /* world offsets a = (X - X0) pix, b = -(Y - Y0) pix; z = z0 - (nr a + nu b) / nt */
    double za = -nr * pix / nt, zb = nu * pix / nt;
    plane[1] = za, plane[2] = zb;
    plane[0] = on->z - za * on->x - zb * on->y;
    return true;
}

static pvert project(const xyl__ortho_view *v, const xyl__raster *r, xyl__dvec3 p)
{
    double inv = r->width / (2.0 * v->half);
    xyl__dvec3 q = xyl__d3_sub(p, v->center);
    return (pvert){0.5 * r->width + xyl__d3_dot(q, v->right) * inv,
                   0.5 * r->height - xyl__d3_dot(q, v->up) * inv, xyl__d3_dot(q, v->toward)};
}

/* Draws the convex planar polygon p[0 .. count) (3 or 4 corners in order round it) whose
 * plane has the normal n and passes through on. */
static void raster_polygon(xyl__raster *r, const xyl__ortho_view *v, const xyl__dvec3 *p, int count,
                           xyl__dvec3 n, xyl__dvec3 on, uint32_t id, float shade)
{
    pvert poly[MAX_VERTS];
    double zlo = INFINITY, zhi = -INFINITY;
    for (int i = 0; i < count; ++i) {
        poly[i] = project(v, r, p[i]);
        zlo = fmin(zlo, poly[i].z), zhi = fmax(zhi, poly[i].z);
    }
    pvert centre = project(v, r, on);
    double plane[3];
    if (!depth_plane(v, r, n, &centre, plane)) plane[0] = 0.5 * (zlo + zhi), plane[1] = plane[2] = 0.0;
    int m = clip_guard(poly, count, r->width, r->height);
    if (m < 3) return;
    int64_t s[MAX_VERTS][2];
    for (int i = 0; i < m; ++i) {
        s[i][0] = (int64_t)llround(poly[i].x * SUBPIXEL);
        s[i][1] = (int64_t)llround(poly[i].y * SUBPIXEL);
    }
    int64_t area2 = 0;
    for (int i = 0; i < m; ++i) {
        const int64_t *a = s[i], *b = s[(i + 1) % m];
        area2 += a[0] * b[1] - a[1] * b[0];
    }
    if (area2 == 0) return; /* edge-on after snapping: covers no pixel centre */
    if (area2 < 0)          /* make the interior the positive side of every edge */
        for (int i = 0, j = m - 1; i < j; ++i, --j) {
            int64_t t0 = s[i][0], t1 = s[i][1];
            s[i][0] = s[j][0], s[i][1] = s[j][1], s[j][0] = t0, s[j][1] = t1;
        }
    fill(r, (const int64_t(*)[2])s, m, plane, zlo, zhi, id, shade);
}

void xyl__raster_leaf(xyl__raster *r, const xyl__ortho_view *v, const xyl_leaf *leaf, uint32_t id,
                      float shade)
{
    xyl__dvec3 c[4];
    xyl__leaf_corners(leaf, c);
    const xyl__dvec3 round[4] = {c[0], c[1], c[3], c[2]};
    raster_polygon(r, v, round, 4, xyl__from_f3(leaf->normal), xyl__from_f3(leaf->center), id, shade);
}

void xyl__raster_triangle(xyl__raster *r, const xyl__ortho_view *v, const xyl__dvec3 p[3], uint32_t id,
                          float shade)
{
    xyl__dvec3 n = xyl__d3_cross(xyl__d3_sub(p[1], p[0]), xyl__d3_sub(p[2], p[0]));
    n = xyl__d3_normalize_or(n, v->right); /* degenerate: seen edge-on, it covers nothing */
    raster_polygon(r, v, p, 3, n, p[0], id, shade);
}

void xyl__raster_leaves(xyl__raster *r, const xyl__ortho_view *v, const xyl_leaf *leaves, size_t n,
                        xyl__dvec3 light)
{
    for (size_t i = 0; i < n; ++i) {
        double shade = fabs(xyl__d3_dot(xyl__d3_normalize_or(xyl__from_f3(leaves[i].normal), light), light));
        xyl__raster_leaf(r, v, &leaves[i], (uint32_t)i, (float)fmin(shade, 1.0));
    }
}

xyl__dvec3 xyl__raster_light(void)
{
    return xyl__d3_scale(xyl__d3(1, 2, 3), 1.0 / sqrt(14.0));
}

void xyl__dodecahedron_views(xyl__dvec3 center, double radius, xyl__ortho_view out[XYL__VIEWS])
{
    const double phi = 0.5 * (1.0 + sqrt(5.0)), iphi = 1.0 / phi;
    double d[XYL__VIEWS][3];
    int k = 0;
    for (int i = 0; i < 8; ++i) /* the cube's vertices */
        d[k][0] = i & 1 ? 1 : -1, d[k][1] = i & 2 ? 1 : -1, d[k][2] = i & 4 ? 1 : -1, ++k;
    for (int i = 0; i < 4; ++i) { /* the three golden rectangles' */
        double a = i & 1 ? iphi : -iphi, b = i & 2 ? phi : -phi;
        d[k][0] = 0, d[k][1] = a, d[k][2] = b, ++k;
        d[k][0] = a, d[k][1] = b, d[k][2] = 0, ++k;
        d[k][0] = b, d[k][1] = 0, d[k][2] = a, ++k;
    }
    for (k = 0; k < XYL__VIEWS; ++k) {
        xyl__ortho_view *v = &out[k];
        v->center = center;
        v->toward = xyl__d3_scale(xyl__d3(d[k][0], d[k][1], d[k][2]), 1.0 / sqrt(3.0));
        /* up: world +Y made orthogonal to the view direction (no vertex lies on the Y axis) */
        xyl__dvec3 y = xyl__d3(0, 1, 0);
        v->up = xyl__d3_normalize_or(xyl__d3_sub(y, xyl__d3_scale(v->toward, xyl__d3_dot(y, v->toward))),
                                     xyl__d3_any_orthogonal(v->toward));
        v->right = xyl__d3_cross(v->up, v->toward);
        v->half = radius;
    }
}

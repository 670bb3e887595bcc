/* The error of a leaf set against a reference: images from the 20 dodecahedron views (RMSE of
 * the shade, coverage) and the Hausdorff distance between the sets as surfaces; the leaves of
 * a LOD; the resolution at which a LOD is drawn. */
#include <string.h>

#include "foliage_internal.h"

#define DEFAULT_RESOLUTION 256
#define DEFAULT_MAX_SAMPLES ((uint64_t)1 << 26)
#define GRID_MAX_DIM 64 /* cells along each axis of the Hausdorff grid, at most */

/* ---- the leaves of a LOD ------------------------------------------------------------------- */

xyl_result xyl_foliage_gather(const xyl_foliage *f, const uint32_t *lods, size_t lod_count,
                              xyl_leaf *out, size_t capacity, size_t *count, xyl_diag *diag)
{
    if (!f || !lods || !count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "foliage, lods and count must not be NULL");
    if (lod_count != f->sector_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "%zu LODs given for %u sectors: one per sector", lod_count, f->sector_count);
    size_t total = 0;
    for (uint32_t s = 0; s < f->sector_count; ++s) {
        if (lods[s] > f->sectors[s].merged_count)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)s,
                             "LOD %u of sector %u does not exist (it has %u merges)", lods[s], s,
                             f->sectors[s].merged_count);
        total += (size_t)f->sectors[s].lods[lods[s]].a + f->sectors[s].lods[lods[s]].c;
    }
    if (out && capacity < total)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "capacity %zu is less than the LOD's %zu leaves", capacity, total);
    if (out) {
        size_t at = 0;
        for (uint32_t s = 0; s < f->sector_count; ++s) {
            const xyl_foliage_sector *sec = &f->sectors[s];
            const xyl_foliage_lod *l = &sec->lods[lods[s]];
            memcpy(out + at, f->leaves + sec->base, l->a * sizeof *out);
            at += l->a;
            memcpy(out + at, f->leaves + sec->base + l->b, l->c * sizeof *out);
            at += l->c;
        }
    }
    *count = total;
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_result xyl_foliage_lod_resolution(const xyl_foliage *f, uint32_t sector, uint32_t lod,
                                      float error_px, uint32_t *resolution, xyl_diag *diag)
{
    if (!f || !resolution)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "foliage and resolution must not be NULL");
    if (!isfinite(error_px)) return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "error_px is NaN or infinite");
    if (error_px < 0.0f) return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "error_px must be >= 0 (0: 0.5)");
    if (sector >= f->sector_count || lod > f->sectors[sector].merged_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)sector,
                         "sector %u, LOD %u does not exist", sector, lod);
    double budget = error_px > 0.0f ? error_px : 0.5;
    double e = f->sectors[sector].lods[lod].error;
    double res = e > 0.0 ? floor(2.0 * f->radius * budget / e) : INFINITY;
    *resolution = res >= XYL_FOLIAGE_IMAGE_MAX_RESOLUTION ? XYL_FOLIAGE_IMAGE_MAX_RESOLUTION
                  : res < 1.0                             ? 1u
                                                          : (uint32_t)res;
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- the two sets -------------------------------------------------------------------------- */

/* The surfaces compared: leaf quads (tidy copies), or triangles of a mesh. */
typedef struct facets {
    const xyl_leaf *leaves; /* quads; NULL for triangles */
    const float *pos;       /* triangles: xyz per vertex */
    const uint32_t *idx;    /* three per triangle */
    size_t n;               /* quads or triangles */
} facets;

static void triangle_of(const facets *f, size_t i, xyl__dvec3 p[3])
{
    for (int k = 0; k < 3; ++k) {
        const float *v = f->pos + 3 * (size_t)f->idx[3 * i + k];
        p[k] = xyl__d3(v[0], v[1], v[2]);
    }
}

/* The shade of a facet: |normal . light|, double-sided. */
static float facet_shade(const facets *f, size_t i, xyl__dvec3 light)
{
    xyl__dvec3 n;
    if (f->leaves) {
        n = xyl__from_f3(f->leaves[i].normal);
    } else {
        xyl__dvec3 p[3];
        triangle_of(f, i, p);
        n = xyl__d3_cross(xyl__d3_sub(p[1], p[0]), xyl__d3_sub(p[2], p[0]));
    }
    return (float)fmin(fabs(xyl__d3_dot(xyl__d3_normalize_or(n, light), light)), 1.0);
}

static void raster_facets(xyl__raster *r, const xyl__ortho_view *v, const facets *f, xyl__dvec3 light)
{
    for (size_t i = 0; i < f->n; ++i) {
        float shade = facet_shade(f, i, light);
        if (f->leaves) {
            xyl__raster_leaf(r, v, &f->leaves[i], (uint32_t)i, shade);
        } else {
            xyl__dvec3 p[3];
            triangle_of(f, i, p);
            xyl__raster_triangle(r, v, p, (uint32_t)i, shade);
        }
    }
}

/* ---- options and input --------------------------------------------------------------------- */

typedef struct options {
    uint32_t resolution;
    double step;        /* 0 until the sphere is known */
    uint64_t max_samples;
} options;

static xyl_result check_set(const xyl_leaf *leaves, size_t count, const xyl_foliage_limits *limits,
                            const char *which, xyl_diag *diag)
{
    xyl_diag d = {0};
    xyl_result r = xyl_foliage_check_leaves(leaves, count, limits, &d);
    if (r != XYL_OK) return xyl__fail(diag, r, 0, 0, d.index, "%s: %s", which, d.message);
    return XYL_OK;
}

static xyl_result check_input(const xyl_leaf *ref, size_t nref, const xyl_leaf *approx, size_t napprox,
                              const xyl_foliage_image_desc *d, xyl_foliage_image_error *out,
                              options *o, xyl_diag *diag)
{
    if (!ref || !out || (napprox && !approx))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "reference and out must not be NULL, nor approx with a count");
    if (nref == 0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "an empty reference frames no view");
    if (!isfinite(d->hausdorff_step))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "hausdorff_step is NaN or infinite");
    if (d->hausdorff_step < 0.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "hausdorff_step must be >= 0 (0: a pixel)");
    if (d->resolution > XYL_FOLIAGE_IMAGE_MAX_RESOLUTION)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "resolution %u; at most %u",
                         d->resolution, XYL_FOLIAGE_IMAGE_MAX_RESOLUTION);
    xyl_result r = check_set(ref, nref, &d->limits, "reference", diag);
    if (r == XYL_OK) r = check_set(approx, napprox, &d->limits, "approx", diag);
    if (r != XYL_OK) return r;
    o->resolution = d->resolution ? d->resolution : DEFAULT_RESOLUTION;
    o->step = d->hausdorff_step;
    o->max_samples = d->max_samples ? d->max_samples : DEFAULT_MAX_SAMPLES;
    return XYL_OK;
}

/* The sphere of the views: the centre of the box of the corners, the farthest corner. */
static void bounding_sphere(const xyl_leaf *l, size_t n, xyl__dvec3 *center, double *radius)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    xyl__dvec3 c[4];
    for (size_t i = 0; i < n; ++i) {
        xyl__leaf_corners(&l[i], c);
        for (int k = 0; k < 4; ++k) {
            const double v[3] = {c[k].x, c[k].y, c[k].z};
            for (int d = 0; d < 3; ++d) lo[d] = fmin(lo[d], v[d]), hi[d] = fmax(hi[d], v[d]);
        }
    }
    *center = xyl__d3(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    double r = 0.0;
    for (size_t i = 0; i < n; ++i) {
        xyl__leaf_corners(&l[i], c);
        for (int k = 0; k < 4; ++k) r = fmax(r, xyl__d3_len(xyl__d3_sub(c[k], *center)));
    }
    *radius = r;
}

/* ---- images -------------------------------------------------------------------------------- */

static void compare_views(xyl__raster *ra, xyl__raster *rb, const facets *ref, const facets *approx,
                          xyl__dvec3 center, double radius, xyl_foliage_image_error *e)
{
    xyl__ortho_view views[XYL__VIEWS];
    xyl__dodecahedron_views(center, radius, views);
    xyl__dvec3 light = xyl__raster_light();
    size_t px = (size_t)ra->width * ra->height;
    e->rmse_mean = e->rmse_worst = e->coverage_mean = e->coverage_worst = 0.0;
    for (int v = 0; v < XYL__VIEWS; ++v) {
        xyl__raster_clear(ra);
        xyl__raster_clear(rb);
        raster_facets(ra, &views[v], ref, light);
        raster_facets(rb, &views[v], approx, light);
        double sq = 0.0;
        size_t one = 0, either = 0;
        for (size_t k = 0; k < px; ++k) {
            double d = (double)ra->shade[k] - rb->shade[k];
            sq += d * d;
            bool a = ra->id[k] != XYL__RASTER_NONE, b = rb->id[k] != XYL__RASTER_NONE;
            one += a != b;
            either += a || b;
        }
        e->rmse[v] = sqrt(sq / (double)px);
        e->coverage[v] = either ? (double)one / (double)either : 0.0;
        e->rmse_mean += e->rmse[v] / XYL__VIEWS;
        e->coverage_mean += e->coverage[v] / XYL__VIEWS;
        e->rmse_worst = fmax(e->rmse_worst, e->rmse[v]);
        e->coverage_worst = fmax(e->coverage_worst, e->coverage[v]);
    }
}

/* ---- Hausdorff ----------------------------------------------------------------------------- */

/* The samples of a quad along one half-axis of length half: at least 2 (its two edges), spaced
 * at most step apart. */
static double samples_along(double half, double step)
{
    return fmax(2.0, ceil(2.0 * half / step) + 1.0);
}

/* A triangle is sampled on the barycentric grid p0 + (i e1 + j e2) / k, i + j <= k, with k the
 * fewest parts that make every edge of the small triangles at most step long; any point of it
 * then lies within step / sqrt(3) of a sample (the circumradius of an acute small triangle, half
 * the longest edge of an obtuse one). */
static double triangle_parts(const xyl__dvec3 p[3], double step)
{
    double l = fmax(xyl__d3_len(xyl__d3_sub(p[1], p[0])),
                    fmax(xyl__d3_len(xyl__d3_sub(p[2], p[1])), xyl__d3_len(xyl__d3_sub(p[0], p[2]))));
    return fmax(1.0, ceil(l / step));
}

static double count_samples(const facets *f, double step)
{
    double total = 0.0;
    for (size_t i = 0; i < f->n; ++i) {
        if (f->leaves) {
            const xyl_leaf *l = &f->leaves[i];
            total += samples_along(xyl__d3_len(xyl__from_f3(l->side)), step) *
                     samples_along(xyl__d3_len(xyl__from_f3(l->axis)), step);
        } else {
            xyl__dvec3 p[3];
            triangle_of(f, i, p);
            double k = triangle_parts(p, step);
            total += 0.5 * (k + 1.0) * (k + 2.0);
        }
    }
    return total;
}

static double segment_distance(xyl__dvec3 x, xyl__dvec3 a, xyl__dvec3 b)
{
    xyl__dvec3 ab = xyl__d3_sub(b, a);
    double l2 = xyl__d3_dot(ab, ab);
    double t = l2 > 0.0 ? xyl__d3_dot(xyl__d3_sub(x, a), ab) / l2 : 0.0;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    return xyl__d3_len(xyl__d3_sub(x, xyl__d3_add(a, xyl__d3_scale(ab, t))));
}

/* The distance from x to the triangle: to its plane where x projects inside it, else to the
 * nearest edge (which also covers a degenerate triangle). */
static double triangle_distance(xyl__dvec3 x, const xyl__dvec3 p[3])
{
    xyl__dvec3 n = xyl__d3_cross(xyl__d3_sub(p[1], p[0]), xyl__d3_sub(p[2], p[0]));
    double n2 = xyl__d3_dot(n, n);
    if (n2 > 0.0) {
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
            xyl__dvec3 e = xyl__d3_sub(p[(k + 1) % 3], p[k]);
            inside = xyl__d3_dot(xyl__d3_cross(e, xyl__d3_sub(x, p[k])), n) >= 0.0;
        }
        if (inside) return fabs(xyl__d3_dot(xyl__d3_sub(x, p[0]), n)) / sqrt(n2);
    }
    return fmin(segment_distance(x, p[0], p[1]),
                fmin(segment_distance(x, p[1], p[2]), segment_distance(x, p[2], p[0])));
}

static double facet_distance(const facets *f, size_t i, xyl__dvec3 x)
{
    if (f->leaves) return xyl__leaf_quad_distance(x, &f->leaves[i]);
    xyl__dvec3 p[3];
    triangle_of(f, i, p);
    return triangle_distance(x, p);
}

/* A uniform grid over the facets of a set: each facet listed in every cell its bounding box
 * meets. */
typedef struct qgrid {
    double min[3], h;
    int32_t dim[3];
    uint32_t *start; /* cells + 1 */
    uint32_t *items;
    uint32_t *stamp; /* per facet: the last query that measured it */
    uint32_t query;
    size_t n;
} qgrid;

static void facet_box(const facets *f, size_t i, double lo[3], double hi[3])
{
    xyl__dvec3 c[4];
    int count = 3;
    if (f->leaves) xyl__leaf_corners(&f->leaves[i], c), count = 4;
    else triangle_of(f, i, c);
    for (int d = 0; d < 3; ++d) lo[d] = INFINITY, hi[d] = -INFINITY;
    for (int k = 0; k < count; ++k) {
        const double v[3] = {c[k].x, c[k].y, c[k].z};
        for (int d = 0; d < 3; ++d) lo[d] = fmin(lo[d], v[d]), hi[d] = fmax(hi[d], v[d]);
    }
}

static int32_t cell_of(const qgrid *g, int d, double x)
{
    double c = floor((x - g->min[d]) / g->h);
    return c < 0.0 ? 0 : c >= g->dim[d] ? g->dim[d] - 1 : (int32_t)c;
}

static void cell_span(const qgrid *g, const facets *f, size_t i, int32_t c0[3], int32_t c1[3])
{
    double lo[3], hi[3];
    facet_box(f, i, lo, hi);
    for (int d = 0; d < 3; ++d) c0[d] = cell_of(g, d, lo[d]), c1[d] = cell_of(g, d, hi[d]);
}

static size_t cell_index(const qgrid *g, int32_t x, int32_t y, int32_t z)
{
    return ((size_t)z * (size_t)g->dim[1] + (size_t)y) * (size_t)g->dim[0] + (size_t)x;
}

static void grid_free(qgrid *g, const xyl_allocator *a)
{
    xyl__free(a, g->start);
    xyl__free(a, g->items);
    xyl__free(a, g->stamp);
    memset(g, 0, sizeof *g);
}

/* Cells of about one facet each, at most GRID_MAX_DIM along an axis. */
static xyl_result grid_build(qgrid *g, const facets *f, const xyl_allocator *a)
{
    memset(g, 0, sizeof *g);
    size_t n = f->n;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n; ++i) {
        double a0[3], a1[3];
        facet_box(f, i, a0, a1);
        for (int d = 0; d < 3; ++d) lo[d] = fmin(lo[d], a0[d]), hi[d] = fmax(hi[d], a1[d]);
    }
    double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    double vol = fmax(hi[0] - lo[0], ext * 1e-3) * fmax(hi[1] - lo[1], ext * 1e-3) *
                 fmax(hi[2] - lo[2], ext * 1e-3);
    g->h = fmax(fmax(cbrt(vol / (double)n), ext / GRID_MAX_DIM), fmax(ext, 1e-30) * 1e-6);
    size_t cells = 1;
    for (int d = 0; d < 3; ++d) {
        g->min[d] = lo[d];
        double k = ceil((hi[d] - lo[d]) / g->h);
        g->dim[d] = k < 1.0 ? 1 : k > GRID_MAX_DIM ? GRID_MAX_DIM : (int32_t)k;
        cells *= (size_t)g->dim[d];
    }
    g->start = xyl__calloc(a, cells + 1, sizeof *g->start);
    g->stamp = xyl__calloc(a, n, sizeof *g->stamp);
    g->n = n;
    if (!g->start || !g->stamp) return XYL_ERR_OUT_OF_MEMORY;
    uint64_t entries = 0;
    for (size_t i = 0; i < n; ++i) {
        int32_t c0[3], c1[3];
        cell_span(g, f, i, c0, c1);
        for (int32_t z = c0[2]; z <= c1[2]; ++z)
            for (int32_t y = c0[1]; y <= c1[1]; ++y)
                for (int32_t x = c0[0]; x <= c1[0]; ++x) g->start[cell_index(g, x, y, z) + 1]++;
        entries += (uint64_t)(c1[0] - c0[0] + 1) * (uint64_t)(c1[1] - c0[1] + 1) * (uint64_t)(c1[2] - c0[2] + 1);
    }
    if (entries > UINT32_MAX) return XYL_ERR_OUT_OF_MEMORY;
    for (size_t c = 0; c < cells; ++c) g->start[c + 1] += g->start[c];
    g->items = xyl__alloc_array(a, (size_t)entries, sizeof *g->items);
    if (!g->items) return XYL_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < n; ++i) { /* fill each cell from its end back: start ends as the start */
        int32_t c0[3], c1[3];
        cell_span(g, f, i, c0, c1);
        for (int32_t z = c0[2]; z <= c1[2]; ++z)
            for (int32_t y = c0[1]; y <= c1[1]; ++y)
                for (int32_t x = c0[0]; x <= c1[0]; ++x) g->items[g->start[cell_index(g, x, y, z)]++] = (uint32_t)i;
    }
    for (size_t c = cells; c > 0; --c) g->start[c] = g->start[c - 1];
    g->start[0] = 0;
    return XYL_OK;
}

static void scan_cell(qgrid *g, const facets *f, size_t cell, xyl__dvec3 p, double *best)
{
    for (uint32_t k = g->start[cell]; k < g->start[cell + 1]; ++k) {
        uint32_t q = g->items[k];
        if (g->stamp[q] == g->query) continue;
        g->stamp[q] = g->query;
        double d = facet_distance(f, q, p);
        if (d < *best) *best = d;
    }
}

/* The distance from p to the nearest facet, or any value <= enough once one is found that
 * near (the caller wants only a maximum over points of these minima). Rings of cells around
 * p's (clamped) cell: a cell k rings out lies at least (k - 1) h from p. */
static double nearest(qgrid *g, const facets *f, xyl__dvec3 p, double enough)
{
    if (++g->query == 0) { /* wrapped: forget every stamp */
        memset(g->stamp, 0, g->n * sizeof *g->stamp);
        g->query = 1;
    }
    const double v[3] = {p.x, p.y, p.z};
    int32_t c[3];
    for (int d = 0; d < 3; ++d) c[d] = cell_of(g, d, v[d]);
    int32_t kmax = g->dim[0];
    if (g->dim[1] > kmax) kmax = g->dim[1];
    if (g->dim[2] > kmax) kmax = g->dim[2];
    double best = INFINITY;
    for (int32_t k = 0; k < kmax; ++k) {
        if (best <= enough || (k > 0 && (double)(k - 1) * g->h >= best)) break;
        for (int32_t z = c[2] - k; z <= c[2] + k; ++z) {
            if (z < 0 || z >= g->dim[2]) continue;
            for (int32_t y = c[1] - k; y <= c[1] + k; ++y) {
                if (y < 0 || y >= g->dim[1]) continue;
                bool face = z == c[2] - k || z == c[2] + k || y == c[1] - k || y == c[1] + k;
                for (int32_t x = c[0] - k; x <= c[0] + k; x += face || k == 0 ? 1 : 2 * k) {
                    if (x < 0 || x >= g->dim[0]) continue;
                    scan_cell(g, f, cell_index(g, x, y, z), p, &best);
                }
            }
        }
    }
    return best;
}

/* max over the samples of a of the distance to b's facets, given that it is at least floor. */
static double directed(const facets *a, qgrid *g, const facets *b, double step, double floor_d)
{
    double h = floor_d;
    for (size_t i = 0; i < a->n; ++i) {
        if (a->leaves) {
            const xyl_leaf *l = &a->leaves[i];
            xyl__dvec3 c = xyl__from_f3(l->center), s = xyl__from_f3(l->side), t = xyl__from_f3(l->axis);
            double ks = samples_along(xyl__d3_len(s), step), kt = samples_along(xyl__d3_len(t), step);
            for (double u = 0; u < ks; ++u)
                for (double w = 0; w < kt; ++w) {
                    double su = -1.0 + 2.0 * u / (ks - 1.0), tw = -1.0 + 2.0 * w / (kt - 1.0);
                    xyl__dvec3 p = xyl__d3_add(c, xyl__d3_add(xyl__d3_scale(s, su), xyl__d3_scale(t, tw)));
                    h = fmax(h, nearest(g, b, p, h));
                }
        } else {
            xyl__dvec3 p[3];
            triangle_of(a, i, p);
            double k = triangle_parts(p, step);
            xyl__dvec3 e1 = xyl__d3_scale(xyl__d3_sub(p[1], p[0]), 1.0 / k);
            xyl__dvec3 e2 = xyl__d3_scale(xyl__d3_sub(p[2], p[0]), 1.0 / k);
            for (double u = 0; u <= k; ++u)
                for (double w = 0; u + w <= k; ++w) {
                    xyl__dvec3 x = xyl__d3_add(p[0], xyl__d3_add(xyl__d3_scale(e1, u), xyl__d3_scale(e2, w)));
                    h = fmax(h, nearest(g, b, x, h));
                }
        }
    }
    return h;
}

/* ---- the calls ----------------------------------------------------------------------------- */

static xyl_leaf *tidy_copy(const xyl_leaf *l, size_t n, const xyl_allocator *a)
{
    xyl_leaf *t = xyl__alloc_array(a, n, sizeof *t);
    if (t)
        for (size_t i = 0; i < n; ++i) t[i] = xyl__leaf_tidy(&l[i]);
    return t;
}

/* Both measures of approx against the reference quads ref (tidy), into *out; the inputs are
 * checked. Allocates and frees its images and grids. */
static xyl_result measure(const facets *ref, const facets *approx, const options *o,
                          const xyl_allocator *a, xyl_foliage_image_error *out, xyl_diag *diag)
{
    xyl_foliage_image_error e;
    memset(&e, 0, sizeof e);
    xyl__dvec3 center;
    double radius;
    bounding_sphere(ref->leaves, ref->n, &center, &radius);
    double step = o->step > 0.0 ? o->step : 2.0 * radius / o->resolution;
    double samples = count_samples(ref, step) + count_samples(approx, step);
    if (samples > (double)o->max_samples)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%.0f Hausdorff samples at step %g exceed max_samples (%llu)", samples, step,
                         (unsigned long long)o->max_samples);
    xyl__raster ra, rb;
    qgrid ga, gb;
    memset(&ga, 0, sizeof ga), memset(&gb, 0, sizeof gb);
    memset(&rb, 0, sizeof rb);
    xyl_result r = xyl__raster_init(&ra, o->resolution, o->resolution, a);
    if (r == XYL_OK) r = xyl__raster_init(&rb, o->resolution, o->resolution, a);
    if (r == XYL_OK) r = grid_build(&ga, ref, a);
    if (r == XYL_OK && approx->n) r = grid_build(&gb, approx, a);
    if (r == XYL_OK) {
        compare_views(&ra, &rb, ref, approx, center, radius, &e);
        if (approx->n) {
            double h = directed(ref, &gb, approx, step, 0.0);
            e.hausdorff = directed(approx, &ga, ref, step, h);
        } else {
            e.hausdorff = INFINITY;
        }
        e.center = xyl__to_f3(center);
        e.radius = xyl__round_up(radius);
        e.resolution = o->resolution;
    }
    xyl__raster_free(&ra, a);
    xyl__raster_free(&rb, a);
    grid_free(&ga, a);
    grid_free(&gb, a);
    if (r != XYL_OK)
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1,
                         "out of memory for %u x %u images of %zu and %zu facets", o->resolution,
                         o->resolution, ref->n, approx->n);
    *out = e;
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_result xyl_foliage_image_error_of(const xyl_leaf *reference, size_t reference_count,
                                      const xyl_leaf *approx, size_t approx_count,
                                      const xyl_foliage_image_desc *desc,
                                      xyl_foliage_image_error *out, xyl_diag *diag)
{
    static const xyl_foliage_image_desc zero;
    const xyl_foliage_image_desc *d = desc ? desc : &zero;
    options o;
    xyl_result r = check_input(reference, reference_count, approx, approx_count, d, out, &o, diag);
    if (r != XYL_OK) return r;
    const xyl_allocator *a = &d->alloc;
    xyl_leaf *ta = tidy_copy(reference, reference_count, a);
    xyl_leaf *tb = approx_count ? tidy_copy(approx, approx_count, a) : NULL;
    if (ta && (tb || !approx_count)) {
        facets fa = {ta, NULL, NULL, reference_count}, fb = {tb, NULL, NULL, approx_count};
        r = measure(&fa, &fb, &o, a, out, diag);
    } else {
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for copies of %zu and %zu leaves",
                      reference_count, approx_count);
    }
    xyl__free(a, ta);
    xyl__free(a, tb);
    return r;
}

static xyl_result check_triangles(const float *positions, size_t vertex_count, const uint32_t *indices,
                                  size_t triangle_count, const xyl_foliage_limits *limits, xyl_diag *diag)
{
    if ((vertex_count && !positions) || (triangle_count && !indices))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "positions and indices must not be NULL with a count");
    xyl__foliage_limits lim;
    xyl_result r = xyl__foliage_limits_resolve(limits, &lim, diag);
    if (r != XYL_OK) return r;
    if (vertex_count > UINT32_MAX)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1, "%zu vertices; 32-bit indices reach %u",
                         vertex_count, UINT32_MAX);
    if (triangle_count > lim.max_leaves)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1, "%zu triangles exceed limits.max_leaves (%llu)",
                         triangle_count, (unsigned long long)lim.max_leaves);
    for (size_t v = 0; v < vertex_count; ++v)
        for (int k = 0; k < 3; ++k) {
            float x = positions[3 * v + (size_t)k];
            if (!isfinite(x))
                return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)v, "approx: vertex %zu is NaN or infinite", v);
            if (fabs((double)x) > lim.max_coordinate)
                return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, (int64_t)v,
                                 "approx: vertex %zu has a coordinate beyond limits.max_coordinate (%g)", v,
                                 lim.max_coordinate);
        }
    for (size_t t = 0; t < triangle_count; ++t)
        for (int k = 0; k < 3; ++k)
            if (indices[3 * t + (size_t)k] >= vertex_count)
                return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)t,
                                 "approx: triangle %zu names vertex %u of %zu", t, indices[3 * t + (size_t)k],
                                 vertex_count);
    return XYL_OK;
}

xyl_result xyl_foliage_image_error_triangles(const xyl_leaf *reference, size_t reference_count,
                                             const float *positions, size_t vertex_count,
                                             const uint32_t *indices, size_t triangle_count,
                                             const xyl_foliage_image_desc *desc,
                                             xyl_foliage_image_error *out, xyl_diag *diag)
{
    static const xyl_foliage_image_desc zero;
    const xyl_foliage_image_desc *d = desc ? desc : &zero;
    options o;
    xyl_result r = check_input(reference, reference_count, NULL, 0, d, out, &o, diag);
    if (r == XYL_OK) r = check_triangles(positions, vertex_count, indices, triangle_count, &d->limits, diag);
    if (r != XYL_OK) return r;
    const xyl_allocator *a = &d->alloc;
    xyl_leaf *ta = tidy_copy(reference, reference_count, a);
    if (!ta)
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for a copy of %zu leaves",
                         reference_count);
    facets fa = {ta, NULL, NULL, reference_count}, fb = {NULL, positions, indices, triangle_count};
    r = measure(&fa, &fb, &o, a, out, diag);
    xyl__free(a, ta);
    return r;
}

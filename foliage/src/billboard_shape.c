/* The billboards' CPU side, shared by the GL and Vulkan bakes and draws (billboard_shape.h). */
#include <math.h>
#include <string.h>

#include "billboard_shape.h"
#include "foliage_draw.h"
#include "foliage_internal.h"

xyl_result xyl__billboard_check(const xyl__billboard_params *d, xyl_diag *diag)
{
    if (d->kind != XYL_BILLBOARD_SPHERICAL && d->kind != XYL_BILLBOARD_CYLINDRICAL &&
        d->kind != XYL_BILLBOARD_CROSS && d->kind != XYL_BILLBOARD_OCTAHEDRAL)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "unknown billboard kind %d (spherical 0, cylindrical 1, cross 2, "
                         "octahedral 3)", (int)d->kind);
    if (d->kind == XYL_BILLBOARD_CROSS &&
        (d->planes < 2 || d->planes > XYL_BILLBOARD_MAX_PLANES))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a cross billboard has 2 to %d planes, not %u", XYL_BILLBOARD_MAX_PLANES,
                         d->planes);
    if (d->kind != XYL_BILLBOARD_CROSS && d->planes > 1)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "%u planes: only a cross billboard has more than one", d->planes);
    if (d->resolution < XYL_BILLBOARD_MIN_RESOLUTION ||
        d->resolution > XYL_BILLBOARD_MAX_RESOLUTION)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a billboard resolution of %u: from %d to %d texels", d->resolution,
                         XYL_BILLBOARD_MIN_RESOLUTION, XYL_BILLBOARD_MAX_RESOLUTION);
    if (d->kind != XYL_BILLBOARD_OCTAHEDRAL && d->grid != 0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a grid of %u: only an octahedral billboard has a grid", d->grid);
    if (d->kind == XYL_BILLBOARD_OCTAHEDRAL) {
        uint32_t g = d->grid ? d->grid : XYL_BILLBOARD_DEFAULT_GRID;
        if (g < XYL_BILLBOARD_MIN_GRID || g > XYL_BILLBOARD_MAX_GRID)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                             "an octahedral grid of %u views per side: from %d to %d", g,
                             XYL_BILLBOARD_MIN_GRID, XYL_BILLBOARD_MAX_GRID);
        if ((uint64_t)g * d->resolution > XYL_BILLBOARD_MAX_ATLAS)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                             "an octahedral atlas of %u x %u views of %u texels is %llu texels "
                             "wide, over %d", g, g, d->resolution,
                             (unsigned long long)g * d->resolution, XYL_BILLBOARD_MAX_ATLAS);
    }
    for (int k = 0; k < 3; ++k)
        if (!isfinite(d->light_dir[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, k, "the bake's light is not finite");
    for (int k = 0; k < 3; ++k) {
        if (!isfinite(d->lo[k]) || !isfinite(d->hi[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, k, "the tree's box is not finite");
        if (!(d->lo[k] < d->hi[k]))
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, k,
                             "the tree's box is empty or inverted on axis %d (%g .. %g)", k,
                             (double)d->lo[k], (double)d->hi[k]);
    }
    return XYL_OK;
}

/* ---- views ------------------------------------------------------------------------------- */

/* Grid view v's direction on the octahedron (the header's formula). */
static void octahedral_dir(uint32_t grid, uint32_t v, double d[3])
{
    double ox = 2.0 * (v % grid) / (grid - 1) - 1.0, oz = 2.0 * (v / grid) / (grid - 1) - 1.0;
    double y = 1.0 - fabs(ox) - fabs(oz);
    if (y < 0.0) {
        double fx = (1.0 - fabs(oz)) * (ox >= 0.0 ? 1.0 : -1.0);
        double fz = (1.0 - fabs(ox)) * (oz >= 0.0 ? 1.0 : -1.0);
        ox = fx, oz = fz;
    }
    double len = sqrt(ox * ox + y * y + oz * oz);
    d[0] = ox / len, d[1] = y / len, d[2] = oz / len;
}

/* View v's frame: d from the centre towards its camera, right and up across its picture. */
void xyl__billboard_view_frame(const xyl__billboard_shape *bb, uint32_t v, float right[3],
                               float up[3], float d[3])
{
    double w[3] = {0.0, 0.0, 1.0};
    if (bb->kind == XYL_BILLBOARD_OCTAHEDRAL) {
        octahedral_dir(bb->grid, v, w);
    } else if (bb->kind == XYL_BILLBOARD_CROSS) {
        double a = 3.14159265358979323846 * v / bb->views;
        w[0] = sin(a), w[2] = cos(a);
    }
    double h = sqrt(w[0] * w[0] + w[2] * w[2]); /* right = normalize(Y x d) */
    double r[3] = {h > 1e-4 ? w[2] / h : 1.0, 0.0, h > 1e-4 ? -w[0] / h : 0.0};
    double u[3] = {w[1] * r[2] - w[2] * r[1], w[2] * r[0] - w[0] * r[2], w[0] * r[1] - w[1] * r[0]};
    for (int k = 0; k < 3; ++k) right[k] = (float)r[k], up[k] = (float)u[k], d[k] = (float)w[k];
}

/* Orthographic world-to-clip matrix (column-major, GL clip) looking along -d at the centre,
 * the quad's rectangle (2 * half[0] by 2 * half[1]) filling the view and depth [-radius, radius]
 * around the centre. */
static void bake_matrix(const xyl__billboard_shape *bb, const float right[3], const float up[3],
                        const float d[3], float radius, float m[16])
{
    const float *rows[3] = {right, up, d};
    const float scale[3] = {1.0f / bb->half[0], 1.0f / bb->half[1], -1.0f / radius};
    memset(m, 0, 16 * sizeof *m);
    for (int r = 0; r < 3; ++r) {
        float c = 0.0f;
        for (int k = 0; k < 3; ++k) {
            m[k * 4 + r] = rows[r][k] * scale[r];
            c += rows[r][k] * bb->center[k];
        }
        m[12 + r] = -c * scale[r];
    }
    m[15] = 1.0f;
}

/* Normals from the depth buffer (rows bottom to top, depth in [0, 1], 1 = nothing): the height
 * towards the camera h = (1 - 2 depth) * radius, n ~ (-dh/dx, -dh/dy, 1), texels step[0] wide
 * and step[1] high in world units; h / radius * 0.5 + 0.5 goes to alpha (0.5 where empty), for
 * the impostor's parallax correction. A neighbour that is empty or lies across a jump of more
 * than four texels' size is not used. */
static void depth_to_normals(const float *depth, uint32_t n, float radius, const float step[2],
                             uint8_t *out)
{
    const float jump = 4.0f * fmaxf(step[0], step[1]);
    for (uint32_t y = 0; y < n; ++y)
        for (uint32_t x = 0; x < n; ++x) {
            size_t i = (size_t)y * n + x;
            uint8_t *o = out + 4 * i;
            if (depth[i] >= 1.0f) {
                o[0] = 128, o[1] = 128, o[2] = 255, o[3] = 128;
                continue;
            }
            float h = (1.0f - 2.0f * depth[i]) * radius, g[2] = {0.0f, 0.0f};
            for (int axis = 0; axis < 2; ++axis) {
                float sum = 0.0f;
                int used = 0;
                for (int s = -1; s <= 1; s += 2) {
                    int64_t xx = (int64_t)x + (axis == 0 ? s : 0);
                    int64_t yy = (int64_t)y + (axis == 1 ? s : 0);
                    if (xx < 0 || yy < 0 || xx >= (int64_t)n || yy >= (int64_t)n) continue;
                    float dn = depth[(size_t)yy * n + (size_t)xx];
                    if (dn >= 1.0f) continue;
                    float dh = ((1.0f - 2.0f * dn) * radius - h) * (float)s;
                    if (fabsf(dh) > jump) continue;
                    sum += dh;
                    ++used;
                }
                g[axis] = used ? sum / (float)used / step[axis] : 0.0f;
            }
            float v[3] = {-g[0], -g[1], 1.0f};
            float len = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            for (int k = 0; k < 3; ++k)
                o[k] = (uint8_t)lrintf((v[k] / len * 0.5f + 0.5f) * 255.0f);
            o[3] = (uint8_t)lrintf(fminf(fmaxf(h / radius * 0.5f + 0.5f, 0.0f), 1.0f) * 255.0f);
        }
}

/* Coverage from depth into the colour's alpha, the colour premultiplied by it (empty texels
 * 0): filtering and mipmaps then average colour over covered texels only, once the draw
 * divides by alpha, and an edge texel is not darkened by the empty ones around it. */
static void colour_coverage(const float *depth, uint32_t n, uint8_t *rgba)
{
    for (size_t i = 0; i < (size_t)n * n; ++i)
        if (depth[i] < 1.0f)
            rgba[4 * i + 3] = 255;
        else
            memset(rgba + 4 * i, 0, 4);
}


void xyl__billboard_shape_of(const xyl__billboard_params *p, xyl__billboard_shape *s)
{
    memset(s, 0, sizeof *s);
    uint32_t grid = p->kind != XYL_BILLBOARD_OCTAHEDRAL ? 0
                    : p->grid                           ? p->grid
                                                        : XYL_BILLBOARD_DEFAULT_GRID;
    s->kind = p->kind;
    s->views = p->kind == XYL_BILLBOARD_CROSS ? p->planes : grid ? grid * grid : 1;
    s->resolution = p->resolution;
    s->grid = grid;
    float ll = sqrtf(p->light_dir[0] * p->light_dir[0] + p->light_dir[1] * p->light_dir[1] +
                     p->light_dir[2] * p->light_dir[2]);
    if (ll > 0.0f && isfinite(ll))
        for (int k = 0; k < 3; ++k) s->bake_light[k] = p->light_dir[k] / ll;
    float ext[3];
    for (int k = 0; k < 3; ++k) {
        s->center[k] = 0.5f * (p->lo[k] + p->hi[k]);
        ext[k] = 0.5f * (p->hi[k] - p->lo[k]);
    }
    s->half[0] = sqrtf(ext[0] * ext[0] + ext[2] * ext[2]); /* any turn about the axis fits */
    s->half[1] = ext[1];
    s->radius = sqrtf(ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]) * 1.01f;
    if (grid) s->half[0] = s->half[1] = s->radius; /* the sphere fits from every direction */
}

void xyl__billboard_bake_camera(const xyl__billboard_shape *s, uint32_t v, float m[16],
                                float light[3])
{
    float right[3], up[3], d[3];
    xyl__billboard_view_frame(s, v, right, up, d);
    bake_matrix(s, right, up, d, s->radius, m);
    bool fixed = s->bake_light[0] != 0.0f || s->bake_light[1] != 0.0f || s->bake_light[2] != 0.0f;
    memcpy(light, fixed ? s->bake_light : d, 3 * sizeof *light);
}

void xyl__billboard_maps(const xyl__billboard_shape *s, const float *depth, uint8_t *rgba,
                         uint8_t *normal)
{
    uint32_t n = s->resolution;
    const float step[2] = {2.0f * s->half[0] / (float)n, 2.0f * s->half[1] / (float)n};
    colour_coverage(depth, n, rgba);
    depth_to_normals(depth, n, s->radius, step, normal);
}

xyl_result xyl__billboard_frame_check(const float view_proj[16], const float eye[3],
                                      const float light_dir[3], float alpha_cutoff,
                                      const float dither[2], float light[3], float *cutoff,
                                      xyl_diag *diag)
{
    bool any = false;
    for (int i = 0; i < 16; ++i) {
        if (!isfinite(view_proj[i]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, i, "view_proj[%d] is not finite", i);
        any = any || view_proj[i] != 0.0f;
    }
    if (!any)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "view_proj is all zero");
    for (int k = 0; k < 3; ++k)
        if (!isfinite(eye[k]) || !isfinite(light_dir[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, k, "eye or light_dir is not finite");
    if (!(alpha_cutoff >= 0.0f && alpha_cutoff <= 1.0f))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "alpha_cutoff %g is outside [0, 1]", (double)alpha_cutoff);
    xyl_result checked = xyl__foliage_dither_check(dither, diag);
    if (checked != XYL_OK) return checked;
    float l[3] = {light_dir[0], light_dir[1], light_dir[2]};
    float len = sqrtf(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
    if (!(len > 0.0f) || !isfinite(len)) l[0] = 0.0f, l[1] = 1.0f, l[2] = 0.0f, len = 1.0f;
    for (int k = 0; k < 3; ++k) light[k] = l[k] / len;
    *cutoff = alpha_cutoff > 0.0f ? alpha_cutoff : 0.5f;
    return XYL_OK;
}

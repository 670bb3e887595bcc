/* The input rules both GPU leaf renderers share (foliage_draw.h): the species' LOD tables and a
 * draw's values. They run before any GL or Vulkan call: the shaders read the leaf buffer
 * unchecked, so a bad LOD or range must never reach a driver. */
#include <math.h>
#include <string.h>

#include "foliage_draw.h"
#include "foliage_internal.h"

/* A table from xyl_foliage_build is always well formed; one a program assembled by hand must
 * still keep every range inside the array. */
static xyl_result check_tables(const xyl_foliage *f, size_t *lod_total, xyl_diag *diag)
{
    if (f->leaf_count == 0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the foliage has no leaves: there is nothing to draw");
    if (!f->leaves || !f->sectors || f->sector_count == 0 ||
        f->sector_count > XYL_FOLIAGE_MAX_SECTORS)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the foliage's leaves or sectors are missing");
    size_t total = 0;
    for (uint32_t s = 0; s < f->sector_count; ++s) {
        const xyl_foliage_sector *sec = &f->sectors[s];
        uint64_t n = sec->original_count, end = (uint64_t)sec->base + n + sec->merged_count;
        bool ok = sec->lods && end <= f->leaf_count && sec->merged_count < UINT32_MAX;
        for (uint32_t i = 0; ok && i <= sec->merged_count; ++i) {
            const xyl_foliage_lod *l = &sec->lods[i];
            ok = l->a <= n && (uint64_t)l->b + l->c <= n + sec->merged_count &&
                 (l->c == 0 || l->b >= n);
        }
        if (!ok)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)s,
                             "sector %u's LOD table reaches outside the leaf array", s);
        total += (size_t)sec->merged_count + 1;
    }
    *lod_total = total;
    return XYL_OK;
}

xyl_result xyl__foliage_tables_make(const xyl_foliage *f, const xyl_allocator *alloc,
                                    xyl__foliage_tables *out, xyl_diag *diag)
{
    size_t lod_total = 0;
    xyl_result r = check_tables(f, &lod_total, diag);
    if (r != XYL_OK) return r;
    xyl__foliage_sector_ref *sectors = xyl__alloc_array(alloc, f->sector_count, sizeof *sectors);
    xyl__foliage_range *ranges = xyl__alloc_array(alloc, lod_total, sizeof *ranges);
    if (!sectors || !ranges) {
        xyl__free(alloc, sectors);
        xyl__free(alloc, ranges);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    }
    uint32_t at = 0;
    for (uint32_t s = 0; s < f->sector_count; ++s) {
        const xyl_foliage_sector *sec = &f->sectors[s];
        sectors[s] = (xyl__foliage_sector_ref){sec->base, at, sec->merged_count + 1};
        for (uint32_t i = 0; i <= sec->merged_count; ++i, ++at)
            ranges[at] = (xyl__foliage_range){sec->lods[i].a, sec->lods[i].b, sec->lods[i].c};
    }
    out->sectors = sectors;
    out->ranges = ranges;
    out->sector_count = f->sector_count;
    out->leaf_count = f->leaf_count;
    return XYL_OK;
}

void xyl__foliage_tables_free(xyl__foliage_tables *t, const xyl_allocator *alloc)
{
    xyl__free(alloc, t->sectors);
    xyl__free(alloc, t->ranges);
    memset(t, 0, sizeof *t);
}

uint64_t xyl__foliage_tables_leaves(const xyl__foliage_tables *t, const uint32_t *lods)
{
    uint64_t n = 0;
    for (uint32_t s = 0; s < t->sector_count; ++s) {
        const xyl__foliage_range *r = &t->ranges[t->sectors[s].first_lod + lods[s]];
        n += (uint64_t)r->a + r->c;
    }
    return n;
}

xyl_result xyl__foliage_dither_check(const float dither[2], xyl_diag *diag)
{
    if (!isfinite(dither[0]) || !isfinite(dither[1]))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "a dither bound is not finite");
    if ((dither[0] != 0.0f || dither[1] != 0.0f) &&
        !(dither[0] >= 0.0f && dither[0] < dither[1] && dither[1] <= 1.0f))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the dither keeps [%g, %g): give (0, 0) for every fragment, or "
                         "0 <= lo < hi <= 1 (skip a draw whose share is empty)",
                         (double)dither[0], (double)dither[1]);
    return XYL_OK;
}

xyl_result xyl__foliage_frame_resolve(const xyl__foliage_frame_in *in, xyl__foliage_frame *out,
                                      xyl_diag *diag)
{
    const float *view_proj = in->view_proj, *light_dir = in->light_dir, *color = in->color;
    float alpha_cutoff = in->alpha_cutoff, translucency = in->translucency;
    bool any = false;
    for (int k = 0; k < 16; ++k) {
        if (!isfinite(view_proj[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, k,
                             "view_proj[%d] is not finite", k);
        any = any || view_proj[k] != 0.0f;
    }
    if (!any)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "view_proj is all zero (no camera given)");
    const float scalars[9] = {light_dir[0], light_dir[1], light_dir[2], color[0],    color[1],
                              color[2],     color[3],     alpha_cutoff, translucency};
    for (int k = 0; k < 9; ++k)
        if (!isfinite(scalars[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1,
                             "a light, colour, cutoff or translucency value is not finite");
    if (alpha_cutoff < 0.0f || alpha_cutoff > 1.0f || translucency > 1.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "alpha_cutoff %g must lie in [0, 1] and translucency %g be at most 1",
                         (double)alpha_cutoff, (double)translucency);
    xyl_result r = xyl__foliage_dither_check(in->dither, diag);
    if (r != XYL_OK) return r;
    memcpy(out->view_proj, view_proj, sizeof out->view_proj);
    double l2 = (double)light_dir[0] * light_dir[0] + (double)light_dir[1] * light_dir[1] +
                (double)light_dir[2] * light_dir[2];
    double il = l2 > 0.0 && isfinite(l2) ? 1.0 / sqrt(l2) : 0.0;
    for (int k = 0; k < 3; ++k) out->light[k] = il > 0.0 ? (float)(light_dir[k] * il) : 0.0f;
    if (il == 0.0) out->light[1] = 1.0f;
    bool no_color = color[0] == 0.0f && color[1] == 0.0f && color[2] == 0.0f && color[3] == 0.0f;
    const float green[4] = {0.42f, 0.62f, 0.25f, 1.0f};
    memcpy(out->color, no_color ? green : color, sizeof out->color);
    out->cutoff = alpha_cutoff > 0.0f ? alpha_cutoff : 0.5f;
    out->translucency = translucency > 0.0f ? translucency : translucency < 0.0f ? 0.0f : 0.5f;
    memcpy(out->dither, in->dither, sizeof out->dither);
    return XYL_OK;
}

xyl_result xyl__foliage_frame_check(const xyl__foliage_tables *t,
                                    const xyl__foliage_frame_in *in, xyl__foliage_frame *out,
                                    xyl_diag *diag)
{
    if (t->leaf_count == 0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "no foliage uploaded (set_foliage first)");
    return xyl__foliage_frame_resolve(in, out, diag);
}

xyl_result xyl__foliage_draw_check(const xyl__foliage_tables *t, const uint32_t *lods,
                                   size_t lod_count, const xyl__foliage_frame_in *in,
                                   xyl__foliage_frame *out, xyl_diag *diag)
{
    if (t->leaf_count == 0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "no foliage uploaded (set_foliage first)");
    if (lod_count != t->sector_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "%zu LODs given for %u sectors: one per sector", lod_count,
                         t->sector_count);
    for (uint32_t s = 0; s < t->sector_count; ++s)
        if (lods[s] >= t->sectors[s].lod_count)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)s,
                             "sector %u has LODs 0 to %u, not %u", s,
                             t->sectors[s].lod_count - 1, lods[s]);
    return xyl__foliage_frame_resolve(in, out, diag);
}

_Static_assert(sizeof(xyl__foliage_cut_node) == 32, "std430 stride of xyl_cut_node");

xyl_result xyl__foliage_cut_nodes(const xyl_foliage *f, xyl__foliage_cut_node *nodes,
                                  xyl_diag *diag)
{
    if (!f->links)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "the foliage has no links");
    for (size_t k = 0; k < f->leaf_count; ++k) {
        const xyl_leaf *l = &f->leaves[k];
        const xyl_leaf_link *ln = &f->links[k];
        if (ln->parent < -1 || (int64_t)ln->parent >= (int64_t)f->leaf_count ||
            !(ln->error >= 0.0f) || !isfinite(ln->error))
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)k,
                             "leaf %zu's link has a parent outside the array or a bad error", k);
        nodes[k] = (xyl__foliage_cut_node){{l->center.x, l->center.y, l->center.z,
                                            (float)xyl__foliage_node_radius(l, ln)},
                                           ln->error, ln->parent, {0, 0}};
    }
    return XYL_OK;
}

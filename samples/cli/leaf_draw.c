/* The leaves beside the stems in the samples' GL windows (leaf_draw.h). */
#include "leaf_draw.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef XYL_HAVE_GL
#include <xylem/xyl_foliage_gl.h>
#endif

#include "leaf_texture.h"

#ifdef XYL_HAVE_GL
xyl_result leaf_draw_create(xyl_foliage_gl **out, xyl_diag *d)
{
    *out = NULL;
    uint32_t w = XYL_LEAF_TEXTURE_WIDTH, h = XYL_LEAF_TEXTURE_HEIGHT;
    uint8_t *tex = malloc((size_t)w * h * 4);
    if (!tex) {
        snprintf(d->message, sizeof d->message, "out of memory for the %ux%u leaf texture", w, h);
        return XYL_ERR_OUT_OF_MEMORY;
    }
    xyl_leaf_texture(tex, w, h);
    xyl_foliage_gl *gl = NULL;
    xyl_result r = xyl_foliage_gl_create(NULL, &gl, d);
    if (r == XYL_OK) r = xyl_foliage_gl_set_texture(gl, tex, w, h, d);
    free(tex);
    if (r != XYL_OK) {
        xyl_foliage_gl_destroy(gl);
        return r;
    }
    *out = gl;
    return XYL_OK;
}
#endif

void leaf_draw_bounds(const xyl_foliage *f, float lo[3], float hi[3])
{
    for (uint32_t s = 0; f && s < f->sector_count; ++s) {
        const xyl_foliage_sector *sec = &f->sectors[s];
        for (uint32_t i = 0; i < sec->original_count; ++i) {
            const xyl_leaf *l = &f->leaves[sec->base + i];
            const float c[3] = {l->center.x, l->center.y, l->center.z};
            const float e[3] = {fabsf(l->side.x) + fabsf(l->axis.x),
                                fabsf(l->side.y) + fabsf(l->axis.y),
                                fabsf(l->side.z) + fabsf(l->axis.z)};
            for (int k = 0; k < 3; ++k) {
                lo[k] = fminf(lo[k], c[k] - e[k]);
                hi[k] = fmaxf(hi[k], c[k] + e[k]);
            }
        }
    }
}

xyl_result leaf_draw_pick(const xyl_foliage *f, bool full, const xyl_tess_camera *cam,
                          uint32_t viewport_height, float error_px, uint32_t *lods,
                          size_t lod_cap, leaf_draw_pick_info *info, xyl_diag *d)
{
    if (!f || f->original_count == 0) {
        snprintf(d->message, sizeof d->message, "no leaves to draw");
        return XYL_ERR_INVALID_ARGUMENT;
    }
    if (f->sector_count > lod_cap) {
        snprintf(d->message, sizeof d->message, "%u sectors, room for %zu LODs", f->sector_count,
                 lod_cap);
        return XYL_ERR_INVALID_ARGUMENT;
    }
    xyl_result r = XYL_OK;
    if (full) {
        memset(lods, 0, f->sector_count * sizeof *lods);
    } else {
        xyl_foliage_view v = {0};
        memcpy(v.eye, cam->eye, sizeof v.eye);
        v.fovy = cam->fovy;
        v.viewport_height = viewport_height;
        v.error_px = error_px;
        r = xyl_foliage_pick(f, &v, lods, lod_cap, d);
    }
    size_t drawn = 0;
    if (r == XYL_OK) r = xyl_foliage_gather(f, lods, f->sector_count, NULL, 0, &drawn, d);
    if (r != XYL_OK) return r;
    memset(info, 0, sizeof *info);
    info->drawn = drawn;
    info->original = f->original_count;
    info->lod_lo = UINT32_MAX;
    for (uint32_t s = 0; s < f->sector_count; ++s) {
        const xyl_foliage_sector *sec = &f->sectors[s];
        info->lod_lo = lods[s] < info->lod_lo ? lods[s] : info->lod_lo;
        info->lod_hi = lods[s] > info->lod_hi ? lods[s] : info->lod_hi;
        info->lod_top = sec->merged_count > info->lod_top ? sec->merged_count : info->lod_top;
        info->error = fmaxf(info->error, sec->lods[lods[s]].error);
    }
    return XYL_OK;
}

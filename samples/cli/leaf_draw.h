/* The leaves of a tree on screen: the pieces `xylem view` and any other GL window of the samples
 * share to draw an xyl_foliage beside its stems with the same camera (docs/foliage.md, "Drawing
 * on the GPU"). The renderer is xyl_foliage_gl; what is here is the glue: the procedural leaf
 * texture, the framing box that takes the leaves in, and the per-frame LOD pick with its counts.
 * Main thread (the GL context's) for leaf_draw_create only; the rest is plain CPU work. */
#ifndef XYL_SAMPLES_LEAF_DRAW_H
#define XYL_SAMPLES_LEAF_DRAW_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <xylem/xyl_foliage.h>
#include <xylem/xyl_tessellate.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The most sectors a pick fills (the viewer's leaf_sectors limit). */
#define LEAF_DRAW_MAX_SECTORS 256

/* What one pick chose: the counts a panel or a log line shows. */
typedef struct leaf_draw_pick_info {
    uint64_t drawn;          /* leaves of the chosen LODs (xyl_foliage_gather's count) */
    uint64_t original;       /* the foliage's leaves before any merge */
    uint32_t lod_lo, lod_hi; /* the chosen LODs, over the sectors */
    uint32_t lod_top;        /* the largest merged_count: the coarsest LOD of any sector */
    float error;             /* the worst sector's error bound, world units */
} leaf_draw_pick_info;

#ifdef XYL_HAVE_GL
typedef struct xyl_foliage_gl xyl_foliage_gl;
/* A leaf renderer with the procedural leaf texture (leaf_texture.h); no foliage uploaded yet.
 * Needs a current GL 4.5 core context. Errors: those of xyl_foliage_gl_create and _set_texture,
 * XYL_ERR_OUT_OF_MEMORY for the texture's pixels. On failure *out is NULL. */
xyl_result leaf_draw_create(xyl_foliage_gl **out, xyl_diag *d);
#endif

#ifdef XYL_HAVE_GL
/* An offscreen colour + depth target (multisampled when samples > 1) and its resolve target,
 * for a picture of stems and leaves that is not the window's: both renderers draw into
 * whatever framebuffer is bound. */
typedef struct leaf_draw_target {
    unsigned int fbo, rb[2], resolve_fbo, resolve_rb; /* GL names */
    uint32_t width, height;
} leaf_draw_target;

/* Makes the target and binds it (GL_FRAMEBUFFER) with a full viewport. Errors:
 * XYL_ERR_UNSUPPORTED (more samples than the driver has, an incomplete framebuffer); on failure
 * what was made is deleted. */
xyl_result leaf_draw_target_make(leaf_draw_target *t, uint32_t width, uint32_t height,
                                 uint32_t samples, xyl_diag *d);
/* Resolves and reads the picture into rgba (width * height * 4 bytes), top row first. */
void leaf_draw_target_read(const leaf_draw_target *t, uint8_t *rgba);
/* Deletes the target and binds the default framebuffer. */
void leaf_draw_target_free(leaf_draw_target *t);
#endif

/* The LOD of each sector (lods: f->sector_count entries, at most LEAF_DRAW_MAX_SECTORS) for a
 * camera and a viewport height in pixels: full, LOD 0 everywhere; else the coarsest within
 * error_px pixels (xyl_foliage_pick), as `xylem render --foliage lod` picks. Fills *info.
 * Errors: XYL_ERR_INVALID_ARGUMENT (a foliage without leaves, more sectors than lod_cap), those
 * of xyl_foliage_pick. */
xyl_result leaf_draw_pick(const xyl_foliage *f, bool full, const xyl_tess_camera *cam,
                          uint32_t viewport_height, float error_px, uint32_t *lods,
                          size_t lod_cap, leaf_draw_pick_info *info, xyl_diag *d);

#ifdef __cplusplus
}
#endif

#endif

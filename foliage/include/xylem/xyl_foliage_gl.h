/* xyl_foliage_gl.h: leaves drawn with OpenGL 4.5 core, the whole species' leaf array uploaded
 * once and any LOD drawn as its two ranges (docs/foliage.md, "Drawing on the GPU").
 *
 * How to use
 *     // a current GL 4.5 core context: the application's own, or tessellate's headless one
 *     // (xyl_gl_context_create_headless in xylem/xyl_tess_gl.h)
 *     xyl_diag diag = {0};
 *     xyl_foliage_gl *leaves = NULL;
 *     if (xyl_foliage_gl_create(NULL, &leaves, &diag)) puts(diag.message);
 *     xyl_foliage_gl_set_foliage(leaves, foliage, &diag);   // once per species; foliage may
 *                                                            // be destroyed afterwards
 *     xyl_foliage_gl_set_texture(leaves, rgba, 128, 256, &diag); // optional, RGBA8
 *
 *     // each frame, into the bound framebuffer (depth-tested, after or before the stems)
 *     xyl_foliage_gl_frame fr = {0};         // zero = leaf green, cutoff 0.5, light from +Y
 *     memcpy(fr.view_proj, view_proj, sizeof fr.view_proj);
 *     uint32_t lod[1];                       // one per sector, from xyl_foliage_pick
 *     xyl_foliage_pick(foliage, &view, lod, 1, &diag);
 *     xyl_foliage_gl_draw(leaves, &fr, lod, 1, &diag);
 *     // or per leaf, chosen on the GPU (xyl_foliage_cut's test): one compute pass, one draw
 *     xyl_foliage_gl_draw_adaptive(leaves, &fr, &view, &diag);
 *     xyl_foliage_gl_destroy(leaves);
 *
 * A draw is, per sector, two instanced draws of a 4-vertex triangle strip over the LOD's two
 * ranges of the one storage buffer of 32-byte records (xyl_foliage_shared.h); the vertex shader
 * expands record u_base + gl_InstanceID to its quad. No index buffer, nothing per leaf on the
 * CPU. Every call checks its input before it makes any GL call, and must come from the thread
 * where the context is current. The renderer keeps a copy of the LOD tables (a few bytes per
 * LOD) from its desc's allocator.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_FOLIAGE_GL_H
#define XYL_FOLIAGE_GL_H

#include "xylem/xyl_foliage.h"

#ifdef __cplusplus
extern "C" {
#endif

#define XYL_FOLIAGE_GL_MAX_TEXTURE_SIDE 8192 /* and the driver's GL_MAX_TEXTURE_SIZE */

typedef struct xyl_foliage_gl xyl_foliage_gl;

typedef struct xyl_foliage_gl_desc {
    xyl_allocator alloc; /* every host allocation of the renderer, as long as it lives */
} xyl_foliage_gl_desc;

/* The uniforms of a draw. */
typedef struct xyl_foliage_gl_frame {
    float view_proj[16];  /* column-major world-to-clip matrix, GL clip convention (as
                             xyl_tess_camera_matrix's XYL_TESS_CLIP_GL); all 0 is refused */
    float light_dir[3];   /* towards the light, normalised by the call; default (all 0): +Y */
    float color[4];       /* multiplies the texture's colour; default (all 0): 0.42, 0.62,
                             0.25, 1 (a leaf green; white texture: the leaf's own colour) */
    float alpha_cutoff;   /* texels with alpha below it are discarded, (0, 1]; default (0): 0.5 */
    float translucency;   /* how much light from behind a blade shines through it, [0, 1];
                             default (0): 0.5; negative: none */
    float dither[2];      /* keep range [lo, hi) of the screen-door dither that cross-fades two
                             levels of detail (docs/foliage.md, "Transitions"; xyl_fade_update
                             gives it); default (0, 0): every fragment. Otherwise
                             0 <= lo < hi <= 1 */
} xyl_foliage_gl_frame;

/* Compiles the leaf program and makes the buffers, with a 1 x 1 opaque white texture until
 * xyl_foliage_gl_set_texture. desc may be NULL (defaults). Errors: XYL_ERR_INVALID_ARGUMENT
 * (NULL out), XYL_ERR_UNSUPPORTED (no current GL 4.5 core context, a shader that does not
 * compile or link: the driver's log in diag.message), XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_foliage_gl_create(const xyl_foliage_gl_desc *desc, xyl_foliage_gl **out,
                                         xyl_diag *diag);
/* NULL is fine. Deletes its GL objects when a context is current (else they died with it). */
XYL_API void xyl_foliage_gl_destroy(xyl_foliage_gl *gl);

/* Packs foliage->leaves (xyl_foliage_pack_gpu) into the storage buffer and keeps a copy of the
 * sectors' LOD tables, replacing what was uploaded before. Errors: XYL_ERR_INVALID_ARGUMENT
 * (NULL gl or foliage, a foliage without leaves, a malformed table), XYL_ERR_LIMIT_EXCEEDED
 * (more leaves than the driver's storage block holds), those of xyl_foliage_pack_gpu,
 * XYL_ERR_OUT_OF_MEMORY (host or GL). On failure the previous upload stays. Allocates the
 * packed records for the upload (freed before it returns) and the tables. */
XYL_API xyl_result xyl_foliage_gl_set_foliage(xyl_foliage_gl *gl, const xyl_foliage *foliage,
                                              xyl_diag *diag);

/* The leaf texture: width * height RGBA8 texels, rows top to bottom as image files store them,
 * the top row the leaves' tip end (v = 1), alpha the blade's shape (texels under the frame's
 * alpha_cutoff are discarded). Mipmapped, linear filtering, clamped at the edges. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL gl or rgba, a side of 0 or over
 * XYL_FOLIAGE_GL_MAX_TEXTURE_SIDE or the driver's limit), XYL_ERR_OUT_OF_MEMORY (GL). */
XYL_API xyl_result xyl_foliage_gl_set_texture(xyl_foliage_gl *gl, const uint8_t *rgba,
                                              uint32_t width, uint32_t height, xyl_diag *diag);

/* Draws the LOD lods[s] of each sector s (lod_count = the uploaded foliage's sector count, as
 * xyl_foliage_pick gives them) into the bound framebuffer with the current viewport: depth test
 * (GL_LESS) and depth writes on, no face culling (the leaves are double-sided; the cull-face
 * state is restored), no blending. Errors: XYL_ERR_INVALID_ARGUMENT (NULL gl, frame or lods, no
 * foliage uploaded, lod_count != sector count, a LOD beyond its sector's merged_count:
 * diag.index = the sector, an all-zero matrix, an alpha_cutoff outside [0, 1], a
 * translucency over 1, a dither range other than (0, 0) outside 0 <= lo < hi <= 1),
 * XYL_ERR_NON_FINITE (a matrix, light, colour or dither entry),
 * XYL_ERR_OUT_OF_MEMORY (GL_OUT_OF_MEMORY). */
XYL_API xyl_result xyl_foliage_gl_draw(xyl_foliage_gl *gl, const xyl_foliage_gl_frame *frame,
                                       const uint32_t *lods, size_t lod_count, xyl_diag *diag);

/* Per-leaf LOD (docs/foliage.md, "Per-leaf LOD"): a compute pass over the uploaded collapse
 * forest keeps, per cluster, the coarsest leaf within the view's budget (the cut of
 * xyl_foliage_cut, in float), writes the chosen records' indices to a buffer and their count
 * into an indirect draw command, and one glDrawArraysIndirect draws them as instanced 4-vertex
 * strips. No LOD table, nothing per leaf on the CPU, no read-back. view gives the eye in the
 * foliage's coordinates, fovy, viewport height and pixel budget as xyl_foliage_pick takes them
 * (zero fields: its defaults). The same GL state as xyl_foliage_gl_draw. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL gl, frame or view, no foliage uploaded, the frame's and the
 * view's bad values as xyl_foliage_gl_draw and xyl_foliage_pick refuse them), XYL_ERR_NON_FINITE,
 * XYL_ERR_OUT_OF_MEMORY (GL). Uses GL_SHADER_STORAGE_BUFFER bindings 0 to 3; restores the
 * draw-indirect buffer binding. */
XYL_API xyl_result xyl_foliage_gl_draw_adaptive(xyl_foliage_gl *gl,
                                                const xyl_foliage_gl_frame *frame,
                                                const xyl_foliage_view *view, xyl_diag *diag);

/* The record indices the last xyl_foliage_gl_draw_adaptive drew, in the GPU's order (not
 * sorted: invocations append as they finish), read back (this waits for the GPU). For
 * statistics and tests, not for every frame. Count-then-fill: out NULL sets *count only; with
 * capacity < *count, XYL_ERR_INVALID_ARGUMENT. Errors: XYL_ERR_INVALID_ARGUMENT (NULL gl or
 * count, no adaptive draw since the last upload), XYL_ERR_UNSUPPORTED (a GL error). */
XYL_API xyl_result xyl_foliage_gl_last_cut(xyl_foliage_gl *gl, uint32_t *out, size_t capacity,
                                           size_t *count, xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif /* XYL_FOLIAGE_GL_H */

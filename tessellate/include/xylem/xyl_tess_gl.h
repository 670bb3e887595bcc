/* xyl_tess_gl.h: the OpenGL 4.5 core backend of tessellate/.
 *
 * How to use
 *   - With your own context: make a GL 4.5 core context current (GLFW, SDL, your engine), then
 *     xyl_tess_gl_create(NULL, patterns, &gl). Headless: xyl_gl_context_create_headless() first (EGL,
 *     Mesa's surfaceless platform; llvmpipe on machines without a GPU).
 *   - xyl_tess_gl_set_patches() uploads a patch set (storage buffer); each frame, after
 *     xyl_tess_select(), xyl_tess_gl_draw() draws into the bound framebuffer: the instanced path
 *     (one indirect draw per (kind, level), instance records as a per-instance attribute) or the
 *     hardware path (TCS/TES with the same evaluation code).
 *   - xyl_tess_gl_render_rgba() renders into an offscreen image and reads it back.
 * All calls must come from the thread where the GL context is current.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_TESS_GL_H
#define XYL_TESS_GL_H

#include "xylem/xyl_tessellate.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- optional headless context ---------------------------------------------------------- */

typedef struct xyl_gl_context xyl_gl_context;

/* EGL surfaceless display, OpenGL 4.5 core context, made current on this thread. alloc (NULL:
 * the default) holds the context's own record; EGL and the driver allocate as they do. Errors:
 * XYL_ERR_UNSUPPORTED (no EGL display, no GL 4.5 core: the message says which),
 * XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_gl_context_create_headless(const xyl_allocator *alloc,
                                                  xyl_gl_context **out, xyl_diag *diag);
XYL_API void xyl_gl_context_destroy(xyl_gl_context *context);
/* GL_RENDERER of the context ("llvmpipe (LLVM 15.0.6, 256 bits)"). */
XYL_API const char *xyl_gl_context_renderer(const xyl_gl_context *context);

/* ---- renderer --------------------------------------------------------------------------- */

typedef struct xyl_tess_gl xyl_tess_gl;

typedef struct xyl_tess_gl_desc {
    xyl_allocator alloc; /* every host allocation of the renderer, as long as it lives */
} xyl_tess_gl_desc;

/* Compiles the programs and uploads the patterns. desc may be NULL (defaults). Errors:
 * XYL_ERR_UNSUPPORTED (no current GL 4.5 core context, a shader that does not compile or link:
 * the driver's log in diag.message), XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_tess_gl_create(const xyl_tess_gl_desc *desc,
                                      const xyl_tess_patterns *patterns, xyl_tess_gl **out,
                                      xyl_diag *diag);
XYL_API void xyl_tess_gl_destroy(xyl_tess_gl *gl);

/* Uploads the patch records (replacing earlier ones). */
XYL_API xyl_result xyl_tess_gl_set_patches(xyl_tess_gl *gl, const xyl_tess_patches *patches,
                                           xyl_diag *diag);

/* Draws the batches into the bound framebuffer with the frame's uniforms (depth test on, back
 * faces culled); with XYL_TESS_FLAG_WIREFRAME in frame->flags, the shaded surface and then its
 * triangle edges in frame->line_color on top. Errors: XYL_ERR_INVALID_ARGUMENT (batches from another patch set, a level the
 * patterns lack), XYL_ERR_OUT_OF_MEMORY (GL_OUT_OF_MEMORY). */
XYL_API xyl_result xyl_tess_gl_draw(xyl_tess_gl *gl, const xyl_tess_batches *batches,
                                    const xyl_tess_frame *frame, xyl_tess_path path,
                                    xyl_diag *diag);

/* Renders into an offscreen colour + depth target and writes width * height RGBA8 pixels, top
 * row first, into rgba (4 * width * height bytes). */
XYL_API xyl_result xyl_tess_gl_render_rgba(xyl_tess_gl *gl, const xyl_tess_batches *batches,
                                           const xyl_tess_frame *frame, xyl_tess_path path,
                                           const xyl_tess_image_desc *image, uint8_t *rgba,
                                           xyl_diag *diag);

/* Milliseconds of GPU time of the last draw (GL_TIME_ELAPSED query), or a negative value when
 * the query is not available yet. */
XYL_API double xyl_tess_gl_last_gpu_ms(const xyl_tess_gl *gl);

#ifdef __cplusplus
}
#endif

#endif /* XYL_TESS_GL_H */

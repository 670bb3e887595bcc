/* GL helpers shared by foliage/'s GL renderers (foliage_gl.c, billboard_gl.c, forest_gl.c);
 * built only with the GL backend. */
#ifndef XYL_FOLIAGE_GL_UTIL_H
#define XYL_FOLIAGE_GL_UTIL_H

#include <epoxy/gl.h>

#include "foliage_draw.h"
#include "xylem/xyl_core.h"

/* Clears errors left by the caller's own GL code, which would otherwise be reported as ours. */
void xyl__fgl_drain_errors(void);

/* XYL_OK, or the pending GL error as XYL_ERR_OUT_OF_MEMORY / XYL_ERR_UNSUPPORTED naming what. */
xyl_result xyl__fgl_check(xyl_diag *diag, const char *what);

/* XYL_OK when a desktop OpenGL 4.5 context is current. */
xyl_result xyl__fgl_need_context(xyl_diag *diag);

/* A compiled shader of the stage, or 0 with the compiler's log in log. */
GLuint xyl__fgl_compile(GLenum stage, const unsigned char *text, char *log, GLsizei log_size);

/* The leaf fragment and vertex uniforms of a resolved frame (foliage_leaf.vert / .frag's
 * locations) on program p, which the leaf and forest renderers both draw with. */
void xyl__fgl_leaf_uniforms(GLuint p, const xyl__foliage_frame *rf);

/* The leaf texture of w x h RGBA8 texels (top row first), mipmapped, linear, clamped; the
 * caller checks for GL errors. */
GLuint xyl__fgl_leaf_texture(const uint8_t *rgba, uint32_t w, uint32_t h);

/* Checks a leaf texture's size against XYL_FOLIAGE_GL_MAX_TEXTURE_SIDE and the driver's
 * max_side, uploads it and swaps it in for *texture (deleted), as the leaf and forest
 * renderers' set_texture do: XYL_ERR_INVALID_ARGUMENT, or GL's error with *texture kept. */
xyl_result xyl__fgl_replace_leaf_texture(GLuint *texture, GLint max_side, const uint8_t *rgba,
                                         uint32_t width, uint32_t height, xyl_diag *diag);

#endif

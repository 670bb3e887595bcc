/* GL helpers shared by foliage/'s GL renderers (foliage_gl.c, billboard_gl.c); built only with
 * the GL backend. */
#ifndef XYL_FOLIAGE_GL_UTIL_H
#define XYL_FOLIAGE_GL_UTIL_H

#include <epoxy/gl.h>

#include "xylem/xyl_core.h"

/* Clears errors left by the caller's own GL code, which would otherwise be reported as ours. */
void xyl__fgl_drain_errors(void);

/* XYL_OK, or the pending GL error as XYL_ERR_OUT_OF_MEMORY / XYL_ERR_UNSUPPORTED naming what. */
xyl_result xyl__fgl_check(xyl_diag *diag, const char *what);

/* XYL_OK when a desktop OpenGL 4.5 context is current. */
xyl_result xyl__fgl_need_context(xyl_diag *diag);

/* A compiled shader of the stage, or 0 with the compiler's log in log. */
GLuint xyl__fgl_compile(GLenum stage, const unsigned char *text, char *log, GLsizei log_size);

#endif

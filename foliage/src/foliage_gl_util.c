/* GL helpers shared by foliage/'s GL renderers (foliage_gl_util.h). */
#include "foliage_gl_util.h"

#include "foliage_internal.h"

void xyl__fgl_drain_errors(void)
{
    for (int i = 0; i < 32 && glGetError() != GL_NO_ERROR; ++i) {}
}

xyl_result xyl__fgl_check(xyl_diag *diag, const char *what)
{
    GLenum e = glGetError();
    if (e == GL_NO_ERROR) return XYL_OK;
    xyl__fgl_drain_errors();
    if (e == GL_OUT_OF_MEMORY)
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "GL out of memory while %s", what);
    return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "GL error 0x%04x while %s", (unsigned)e,
                     what);
}

xyl_result xyl__fgl_need_context(xyl_diag *diag)
{
    int v = epoxy_gl_version(); /* 0 without a current context */
    if (v == 0)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "no current OpenGL context");
    if (!epoxy_is_desktop_gl() || v < 45)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "OpenGL 4.5 is needed, the current context is %s %d.%d",
                         epoxy_is_desktop_gl() ? "OpenGL" : "OpenGL ES", v / 10, v % 10);
    return XYL_OK;
}

GLuint xyl__fgl_compile(GLenum stage, const unsigned char *text, char *log, GLsizei log_size)
{
    GLuint sh = glCreateShader(stage);
    const GLchar *src = (const GLchar *)text;
    glShaderSource(sh, 1, &src, NULL);
    glCompileShader(sh);
    GLint ok = GL_FALSE;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (ok) return sh;
    glGetShaderInfoLog(sh, log_size, NULL, log);
    glDeleteShader(sh);
    return 0;
}

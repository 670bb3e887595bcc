/* GL helpers shared by foliage/'s GL renderers (foliage_gl_util.h). */
#include "foliage_gl_util.h"

#include "foliage_internal.h"
#include "xylem/xyl_foliage_gl.h"

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

GLuint xyl__fgl_leaf_texture(const uint8_t *rgba, uint32_t w, uint32_t h)
{
    GLsizei levels = 1;
    for (uint32_t side = w > h ? w : h; side > 1; side >>= 1) ++levels;
    GLuint t = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &t);
    glTextureStorage2D(t, levels, GL_RGBA8, (GLsizei)w, (GLsizei)h);
    GLint align = 4, row = 0;
    glGetIntegerv(GL_UNPACK_ALIGNMENT, &align);
    glGetIntegerv(GL_UNPACK_ROW_LENGTH, &row);
    GLint unpack_buf = 0;
    glGetIntegerv(GL_PIXEL_UNPACK_BUFFER_BINDING, &unpack_buf);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
    glTextureSubImage2D(t, 0, 0, 0, (GLsizei)w, (GLsizei)h, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    glPixelStorei(GL_UNPACK_ALIGNMENT, align);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, row);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, (GLuint)unpack_buf);
    glGenerateTextureMipmap(t);
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return t;
}

xyl_result xyl__fgl_replace_leaf_texture(GLuint *texture, GLint max_side, const uint8_t *rgba,
                                         uint32_t width, uint32_t height, xyl_diag *diag)
{
    uint32_t cap = XYL_FOLIAGE_GL_MAX_TEXTURE_SIDE;
    if (max_side > 0 && (uint32_t)max_side < cap) cap = (uint32_t)max_side;
    if (width == 0 || height == 0 || width > cap || height > cap)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a leaf texture of %u x %u: each side from 1 to %u", width, height, cap);
    xyl__fgl_drain_errors();
    GLuint t = xyl__fgl_leaf_texture(rgba, width, height);
    xyl_result r = xyl__fgl_check(diag, "uploading the leaf texture");
    if (r != XYL_OK) {
        glDeleteTextures(1, &t);
        return r;
    }
    glDeleteTextures(1, texture);
    *texture = t;
    xyl__diag_ok(diag);
    return XYL_OK;
}

void xyl__fgl_leaf_uniforms(GLuint p, const xyl__foliage_frame *rf)
{
    glProgramUniformMatrix4fv(p, XYL_FOLIAGE_GL_UNIFORM_VIEW_PROJ, 1, GL_FALSE, rf->view_proj);
    glProgramUniform3fv(p, XYL_FOLIAGE_GL_UNIFORM_LIGHT, 1, rf->light);
    glProgramUniform4fv(p, XYL_FOLIAGE_GL_UNIFORM_COLOR, 1, rf->color);
    glProgramUniform1f(p, XYL_FOLIAGE_GL_UNIFORM_CUTOFF, rf->cutoff);
    glProgramUniform1f(p, XYL_FOLIAGE_GL_UNIFORM_TRANSLUCENCY, rf->translucency);
    glProgramUniform2fv(p, XYL_FOLIAGE_GL_UNIFORM_DITHER, 1, rf->dither);
}

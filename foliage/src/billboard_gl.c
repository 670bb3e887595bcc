/* A tree as a billboard (xyl_billboard_gl.h): orthographic bakes of the caller's own tree draw
 * into 2D array textures (colour with coverage alpha, and normals reconstructed from depth),
 * drawn as vertex-shader expanded quads. The bake takes a draw callback because foliage/ does
 * not see tessellate/, whose renderer draws the stems. */
#include <epoxy/gl.h>
#include <math.h>
#include <string.h>

#include "billboard_gl_internal.h"
#include "billboard_shape.h"
#include "foliage_draw.h"
#include "foliage_gl_util.h"
#include "foliage_internal.h"
#include "xylem/xyl_billboard_gl.h"

extern const unsigned char xyl__shader_gl_billboard_vert[];
extern const unsigned char xyl__shader_gl_billboard_frag[];
extern const unsigned char xyl__shader_gl_impostor_vert[];
extern const unsigned char xyl__shader_gl_impostor_frag[];

enum { U_VIEW_PROJ = 0, U_EYE, U_CENTER, U_HALF, U_KIND, U_PLANES, U_LIGHT, U_CUTOFF,
       U_BAKE_LIGHT, U_TO_COVERAGE, U_DITHER };
/* impostor.vert/.frag: U_VIEW_PROJ, U_EYE, U_CENTER, U_LIGHT, U_CUTOFF, U_BAKE_LIGHT,
 * U_TO_COVERAGE and U_DITHER as above, and these */
enum { U_RADIUS = 3, U_GRID = 4 };

struct xyl_billboard_gl {
    GLuint program, vao, color_tex, normal_tex;
    xyl_billboard_kind kind;
    uint32_t views, resolution, grid; /* grid: the octahedral kind's, else 0 */
    float center[3], half[2]; /* the quads' centre, half width and half height */
    float bake_light[3];      /* the bake's light; all 0: each view's own direction */
    xyl__billboard_shape shape; /* all of the above, as the bake computed them */
    xyl_allocator alloc;
};

/* ---- program ------------------------------------------------------------------------------ */

static xyl_result build_program(xyl_billboard_gl *bb, xyl_diag *diag)
{
    char log[192] = "";
    const GLenum stages[2] = {GL_VERTEX_SHADER, GL_FRAGMENT_SHADER};
    bool octa = bb->kind == XYL_BILLBOARD_OCTAHEDRAL;
    const unsigned char *texts[2] = {
        octa ? xyl__shader_gl_impostor_vert : xyl__shader_gl_billboard_vert,
        octa ? xyl__shader_gl_impostor_frag : xyl__shader_gl_billboard_frag};
    const char *names[2] = {octa ? "impostor.vert" : "billboard.vert",
                            octa ? "impostor.frag" : "billboard.frag"};
    GLuint p = glCreateProgram();
    for (int i = 0; i < 2; ++i) {
        GLuint sh = xyl__fgl_compile(stages[i], texts[i], log, (GLsizei)sizeof log);
        if (!sh) {
            glDeleteProgram(p);
            return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "shader %s: %s", names[i], log);
        }
        glAttachShader(p, sh);
        glDeleteShader(sh);
    }
    glLinkProgram(p);
    GLint ok = GL_FALSE;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        glGetProgramInfoLog(p, (GLsizei)sizeof log, NULL, log);
        glDeleteProgram(p);
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "program billboard: %s", log);
    }
    bb->program = p;
    return XYL_OK;
}

/* ---- bake --------------------------------------------------------------------------------- */

typedef struct bake_target {
    GLuint fbo, rb[2];
} bake_target;

static void target_free(bake_target *t)
{
    glDeleteFramebuffers(1, &t->fbo);
    glDeleteRenderbuffers(2, t->rb);
}

static xyl_result target_make(bake_target *t, uint32_t side, xyl_diag *diag)
{
    glCreateRenderbuffers(2, t->rb);
    glNamedRenderbufferStorage(t->rb[0], GL_RGBA8, (GLsizei)side, (GLsizei)side);
    glNamedRenderbufferStorage(t->rb[1], GL_DEPTH_COMPONENT32F, (GLsizei)side, (GLsizei)side);
    glCreateFramebuffers(1, &t->fbo);
    glNamedFramebufferRenderbuffer(t->fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, t->rb[0]);
    glNamedFramebufferRenderbuffer(t->fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t->rb[1]);
    xyl_result r = xyl__fgl_check(diag, "making the bake target");
    if (r == XYL_OK &&
        glCheckNamedFramebufferStatus(t->fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        r = xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                      "a %u x %u bake framebuffer is incomplete", side, side);
    return r;
}

static GLuint make_array(uint32_t side, uint32_t layers)
{
    GLsizei levels = 1;
    for (uint32_t s = side; s > 1; s >>= 1) ++levels;
    GLuint t = 0;
    glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &t);
    glTextureStorage3D(t, levels, GL_RGBA8, (GLsizei)side, (GLsizei)side, (GLsizei)layers);
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return t;
}

/* The octahedral kind's atlas: one 2D texture of side cells x cell, mipmapped down to cells
 * of 4 texels while the cell halves exactly, so that no level mixes two cells' texels. */
static GLuint make_atlas(uint32_t cell, uint32_t cells)
{
    GLsizei levels = 1;
    for (uint32_t s = cell; s % 2 == 0 && s > 4; s /= 2) ++levels;
    GLuint t = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &t);
    glTextureStorage2D(t, levels, GL_RGBA8, (GLsizei)(cell * cells), (GLsizei)(cell * cells));
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, levels > 1 ? GL_LINEAR_MIPMAP_LINEAR : GL_LINEAR);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return t;
}

/* Where view v lies in the textures: layer v of the arrays, or the atlas's cell. */
static void view_place(const xyl_billboard_gl *bb, uint32_t v, GLint xyz[3])
{
    bool octa = bb->kind == XYL_BILLBOARD_OCTAHEDRAL;
    xyz[0] = octa ? (GLint)(v % bb->grid * bb->resolution) : 0;
    xyz[1] = octa ? (GLint)(v / bb->grid * bb->resolution) : 0;
    xyz[2] = octa ? 0 : (GLint)v;
}

typedef struct saved_state {
    GLint draw_fbo, read_fbo, viewport[4], pack_align, unpack_align, unpack_row, pack_buf,
        unpack_buf;
    GLfloat clear[4];
} saved_state;

static void save_state(saved_state *s)
{
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &s->draw_fbo);
    glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &s->read_fbo);
    glGetIntegerv(GL_VIEWPORT, s->viewport);
    glGetIntegerv(GL_PACK_ALIGNMENT, &s->pack_align);
    glGetIntegerv(GL_UNPACK_ALIGNMENT, &s->unpack_align);
    glGetIntegerv(GL_UNPACK_ROW_LENGTH, &s->unpack_row);
    glGetIntegerv(GL_PIXEL_PACK_BUFFER_BINDING, &s->pack_buf);
    glGetIntegerv(GL_PIXEL_UNPACK_BUFFER_BINDING, &s->unpack_buf);
    glGetFloatv(GL_COLOR_CLEAR_VALUE, s->clear);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
}

static void restore_state(const saved_state *s)
{
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, (GLuint)s->draw_fbo);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, (GLuint)s->read_fbo);
    glViewport(s->viewport[0], s->viewport[1], s->viewport[2], s->viewport[3]);
    glPixelStorei(GL_PACK_ALIGNMENT, s->pack_align);
    glPixelStorei(GL_UNPACK_ALIGNMENT, s->unpack_align);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, s->unpack_row);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, (GLuint)s->pack_buf);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, (GLuint)s->unpack_buf);
    glClearColor(s->clear[0], s->clear[1], s->clear[2], s->clear[3]);
}

/* Every view: clear, the caller's draw, read colour and depth back, fill the layers. */
static xyl_result bake_views(xyl_billboard_gl *bb, xyl_billboard_draw_fn draw,
                             void *user, uint8_t *rgba, uint8_t *nrm, float *depth,
                             xyl_diag *diag)
{
    uint32_t n = bb->resolution;
    bake_target t = {0};
    xyl_result r = target_make(&t, n, diag);
    for (uint32_t v = 0; r == XYL_OK && v < bb->views; ++v) {
        float m[16], light[3];
        xyl__billboard_bake_camera(&bb->shape, v, m, light);
        glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
        glViewport(0, 0, (GLsizei)n, (GLsizei)n);
        glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
        glClearDepth(1.0);
        glDepthMask(GL_TRUE);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        r = draw(user, m, light, diag);
        if (r != XYL_OK) break;
        xyl__fgl_drain_errors(); /* the caller's draw reports its own */
        glBindFramebuffer(GL_READ_FRAMEBUFFER, t.fbo);
        glReadPixels(0, 0, (GLsizei)n, (GLsizei)n, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
        glReadPixels(0, 0, (GLsizei)n, (GLsizei)n, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
        xyl__billboard_maps(&bb->shape, depth, rgba, nrm);
        GLint at[3];
        view_place(bb, v, at);
        if (bb->kind == XYL_BILLBOARD_OCTAHEDRAL) {
            glTextureSubImage2D(bb->color_tex, 0, at[0], at[1], (GLsizei)n, (GLsizei)n, GL_RGBA,
                                GL_UNSIGNED_BYTE, rgba);
            glTextureSubImage2D(bb->normal_tex, 0, at[0], at[1], (GLsizei)n, (GLsizei)n, GL_RGBA,
                                GL_UNSIGNED_BYTE, nrm);
        } else {
            glTextureSubImage3D(bb->color_tex, 0, 0, 0, at[2], (GLsizei)n, (GLsizei)n, 1,
                                GL_RGBA, GL_UNSIGNED_BYTE, rgba);
            glTextureSubImage3D(bb->normal_tex, 0, 0, 0, at[2], (GLsizei)n, (GLsizei)n, 1,
                                GL_RGBA, GL_UNSIGNED_BYTE, nrm);
        }
        r = xyl__fgl_check(diag, "baking a billboard view");
    }
    if (r == XYL_OK) {
        glGenerateTextureMipmap(bb->color_tex);
        glGenerateTextureMipmap(bb->normal_tex);
        r = xyl__fgl_check(diag, "making the billboard's mipmaps");
    }
    target_free(&t);
    return r;
}

xyl_result xyl_billboard_gl_bake(const xyl_billboard_gl_desc *desc, xyl_billboard_draw_fn draw,
                                 void *user, xyl_billboard_gl **out, xyl_diag *diag)
{
    if (!desc || !draw || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "desc, draw and out are required");
    const xyl__billboard_params params = {desc->kind, desc->planes, desc->resolution,
                                          desc->grid, desc->lo, desc->hi, desc->light_dir};
    xyl_result r = xyl__billboard_check(&params, diag);
    if (r == XYL_OK) r = xyl__fgl_need_context(diag);
    if (r != XYL_OK) return r;
    GLint max_side = 0, max_layers = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_side);
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
    if (max_side > 0 && desc->resolution > (uint32_t)max_side)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a billboard resolution of %u exceeds the driver's %d",
                         desc->resolution, max_side);
    uint32_t grid = desc->kind != XYL_BILLBOARD_OCTAHEDRAL ? 0
                    : desc->grid                           ? desc->grid
                                                           : XYL_BILLBOARD_DEFAULT_GRID;
    if (max_side > 0 && grid * desc->resolution > (uint32_t)max_side)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "an octahedral atlas of %u x %u views of %u texels is %u texels wide, "
                         "over the driver's %d", grid, grid, desc->resolution,
                         grid * desc->resolution, max_side);
    xyl_allocator a = desc->alloc;
    xyl_billboard_gl *bb = xyl__calloc(&a, 1, sizeof *bb);
    if (!bb) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    bb->alloc = a;
    xyl__billboard_shape_of(&params, &bb->shape);
    bb->kind = bb->shape.kind;
    bb->views = bb->shape.views;
    bb->resolution = bb->shape.resolution;
    bb->grid = bb->shape.grid;
    memcpy(bb->bake_light, bb->shape.bake_light, sizeof bb->bake_light);
    memcpy(bb->center, bb->shape.center, sizeof bb->center);
    memcpy(bb->half, bb->shape.half, sizeof bb->half);
    size_t texels = (size_t)bb->resolution * bb->resolution;
    uint8_t *rgba = xyl__alloc_array(&a, texels, 8);
    float *depth = xyl__alloc_array(&a, texels, sizeof *depth);
    if (!rgba || !depth) r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    saved_state saved;
    if (r == XYL_OK) {
        xyl__fgl_drain_errors();
        save_state(&saved);
        r = build_program(bb, diag);
        if (r == XYL_OK) {
            glCreateVertexArrays(1, &bb->vao);
            bb->color_tex = grid ? make_atlas(bb->resolution, grid)
                                 : make_array(bb->resolution, bb->views);
            bb->normal_tex = grid ? make_atlas(bb->resolution, grid)
                                  : make_array(bb->resolution, bb->views);
            r = xyl__fgl_check(diag, "making the billboard's textures");
        }
        if (r == XYL_OK)
            r = bake_views(bb, draw, user, rgba, rgba + 4 * texels, depth, diag);
        restore_state(&saved);
    }
    xyl__free(&a, rgba);
    xyl__free(&a, depth);
    if (r != XYL_OK) {
        xyl_billboard_gl_destroy(bb);
        return r;
    }
    *out = bb;
    xyl__diag_ok(diag);
    return XYL_OK;
}

void xyl_billboard_gl_destroy(xyl_billboard_gl *bb)
{
    if (!bb) return;
    if (epoxy_gl_version() != 0) {
        glDeleteProgram(bb->program);
        glDeleteVertexArrays(1, &bb->vao);
        GLuint t[2] = {bb->color_tex, bb->normal_tex};
        glDeleteTextures(2, t);
    }
    xyl_allocator a = bb->alloc;
    xyl__free(&a, bb);
}

uint32_t xyl_billboard_gl_view_count(const xyl_billboard_gl *bb)
{
    return bb ? bb->views : 0;
}

xyl_result xyl_billboard_gl_read_view(const xyl_billboard_gl *bb, uint32_t view, bool normal,
                                      uint8_t *rgba, xyl_diag *diag)
{
    if (!bb || !rgba)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "bb and rgba are required");
    if (view >= bb->views)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "view %u of a billboard with %u", view, bb->views);
    xyl__fgl_drain_errors();
    GLint align = 4, pack_buf = 0;
    glGetIntegerv(GL_PACK_ALIGNMENT, &align);
    glGetIntegerv(GL_PIXEL_PACK_BUFFER_BINDING, &pack_buf);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    GLsizei n = (GLsizei)bb->resolution;
    size_t bytes = 4u * (size_t)n * (size_t)n;
    GLint at[3];
    view_place(bb, view, at);
    glGetTextureSubImage(normal ? bb->normal_tex : bb->color_tex, 0, at[0], at[1], at[2], n, n, 1,
                         GL_RGBA, GL_UNSIGNED_BYTE, (GLsizei)bytes, rgba);
    glPixelStorei(GL_PACK_ALIGNMENT, align);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, (GLuint)pack_buf);
    xyl_result r = xyl__fgl_check(diag, "reading a billboard view");
    if (r != XYL_OK) return r;
    size_t row = 4u * (size_t)n; /* stored bottom row first */
    for (GLsizei y = 0; y < n / 2; ++y) {
        uint8_t *p = rgba + (size_t)y * row, *q = rgba + (size_t)(n - 1 - y) * row;
        for (size_t i = 0; i < row; ++i) {
            uint8_t c = p[i];
            p[i] = q[i];
            q[i] = c;
        }
    }
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_result xyl_billboard_gl_draw(xyl_billboard_gl *bb, const xyl_billboard_gl_frame *frame,
                                 xyl_diag *diag)
{
    if (!bb || !frame)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "bb and frame are required");
    float l[3], cutoff;
    xyl_result checked =
        xyl__billboard_frame_check(frame->view_proj, frame->eye, frame->light_dir,
                                   frame->alpha_cutoff, frame->dither, l, &cutoff, diag);
    if (checked != XYL_OK) return checked;
    xyl__fgl_drain_errors();
    GLboolean cull = glIsEnabled(GL_CULL_FACE);
    GLboolean a2c = glIsEnabled(GL_SAMPLE_ALPHA_TO_COVERAGE), a21 = glIsEnabled(GL_SAMPLE_ALPHA_TO_ONE);
    GLint sample_buffers = 0;
    glGetIntegerv(GL_SAMPLE_BUFFERS, &sample_buffers);
    /* multisampled: a texel's filtered coverage becomes the share of samples covered, as the
     * tree's own sub-pixel leaves do, instead of all or nothing at the cutoff */
    bool to_coverage = sample_buffers > 0;
    if (to_coverage) glEnable(GL_SAMPLE_ALPHA_TO_COVERAGE), glEnable(GL_SAMPLE_ALPHA_TO_ONE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    GLuint p = bb->program;
    glUseProgram(p);
    glProgramUniformMatrix4fv(p, U_VIEW_PROJ, 1, GL_FALSE, frame->view_proj);
    glProgramUniform3fv(p, U_EYE, 1, frame->eye);
    glProgramUniform3fv(p, U_CENTER, 1, bb->center);
    if (bb->kind == XYL_BILLBOARD_OCTAHEDRAL) {
        glProgramUniform1f(p, U_RADIUS, bb->half[0]);
        glProgramUniform1i(p, U_GRID, (GLint)bb->grid);
    } else {
        glProgramUniform2fv(p, U_HALF, 1, bb->half);
        glProgramUniform1i(p, U_KIND, (GLint)bb->kind);
        glProgramUniform1i(p, U_PLANES, (GLint)bb->views);
    }
    glProgramUniform3fv(p, U_LIGHT, 1, l);
    glProgramUniform1f(p, U_CUTOFF, cutoff);
    glProgramUniform3fv(p, U_BAKE_LIGHT, 1, bb->bake_light);
    glProgramUniform1i(p, U_TO_COVERAGE, to_coverage ? 1 : 0);
    glProgramUniform2fv(p, U_DITHER, 1, frame->dither);
    glBindVertexArray(bb->vao);
    glBindTextureUnit(0, bb->color_tex);
    glBindTextureUnit(1, bb->normal_tex);
    glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4,
                          bb->kind == XYL_BILLBOARD_OCTAHEDRAL ? 1 : (GLsizei)bb->views);
    if (cull) glEnable(GL_CULL_FACE);
    if (to_coverage && !a2c) glDisable(GL_SAMPLE_ALPHA_TO_COVERAGE);
    if (to_coverage && !a21) glDisable(GL_SAMPLE_ALPHA_TO_ONE);
    xyl_result r = xyl__fgl_check(diag, "drawing the billboard");
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

void xyl__billboard_gl_parts(const xyl_billboard_gl *bb, xyl__billboard_parts *out)
{
    out->color_tex = bb->color_tex;
    out->normal_tex = bb->normal_tex;
    out->kind = (int)bb->kind;
    out->views = bb->views;
    out->grid = bb->grid;
    memcpy(out->center, bb->center, sizeof out->center);
    memcpy(out->half, bb->half, sizeof out->half);
    memcpy(out->bake_light, bb->bake_light, sizeof out->bake_light);
}

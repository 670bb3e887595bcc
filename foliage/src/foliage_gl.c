/* The GL 4.5 leaf renderer: the species' packed leaves in one storage buffer, each LOD drawn as
 * its two ranges (per sector) of instanced 4-vertex strips, and the transform feedback capture
 * of those draws for the tests. Every entry point validates all of its input before its first
 * GL call: a bad LOD or matrix must not reach the driver, which reads the buffer unchecked. */
#include <epoxy/gl.h>
#include <math.h>
#include <string.h>

#include "foliage_draw.h"
#include "foliage_gl_debug.h"
#include "foliage_gl_util.h"
#include "foliage_internal.h"

extern const unsigned char xyl__shader_gl_foliage_leaf_vert[];
extern const unsigned char xyl__shader_gl_foliage_leaf_frag[];
extern const unsigned char xyl__shader_gl_foliage_cut_comp[];


#define XFB_VERTEX_BYTES 28u /* gl_Position, v_st, v_leaf */
#define VERTICES_PER_LEAF_CAPTURED 6u /* a strip of 4 is two triangles */
#define MAX_READBACK_BYTES ((size_t)1 << 31)

_Static_assert(sizeof(xyl__foliage_captured) == XFB_VERTEX_BYTES, "captured = xfb record");
_Static_assert(offsetof(xyl__foliage_captured, leaf) == 24, "v_leaf follows vec4 and vec2");

struct xyl_foliage_gl {
    GLuint program, vao, leaf_buf, texture, capture_fbo, xfb_buf;
    GLuint cut_program, node_buf, list_buf, command_buf; /* the per-leaf cut */
    bool has_cut; /* an adaptive draw ran since the last upload */
    GLuint generated_query, written_query;
    GLint64 max_ssbo_bytes;
    GLint max_texture_side;
    xyl__foliage_tables tables; /* leaf_count 0: nothing uploaded */
    xyl_allocator alloc;
};

/* ---- program ------------------------------------------------------------------------------ */

/* One program draws and captures: the feedback varyings only matter while feedback is on. */
static xyl_result build_program(xyl_foliage_gl *gl, xyl_diag *diag)
{
    char log[192] = "";
    const GLenum stages[2] = {GL_VERTEX_SHADER, GL_FRAGMENT_SHADER};
    const unsigned char *texts[2] = {xyl__shader_gl_foliage_leaf_vert,
                                     xyl__shader_gl_foliage_leaf_frag};
    const char *names[2] = {"foliage_leaf.vert", "foliage_leaf.frag"};
    GLuint p = glCreateProgram();
    for (int i = 0; i < 2; ++i) {
        GLuint sh = xyl__fgl_compile(stages[i], texts[i], log, (GLsizei)sizeof log);
        if (!sh) {
            glDeleteProgram(p);
            return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "shader %s: %s", names[i], log);
        }
        glAttachShader(p, sh);
        glDeleteShader(sh); /* freed with the program */
    }
    const char *const xfb[] = {"gl_Position", "v_st", "v_leaf"};
    glTransformFeedbackVaryings(p, 3, xfb, GL_INTERLEAVED_ATTRIBS);
    glLinkProgram(p);
    GLint ok = GL_FALSE;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        glGetProgramInfoLog(p, (GLsizei)sizeof log, NULL, log);
        glDeleteProgram(p);
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "program foliage_leaf: %s", log);
    }
    gl->program = p;
    return XYL_OK;
}

static xyl_result build_cut_program(xyl_foliage_gl *gl, xyl_diag *diag)
{
    char log[192] = "";
    GLuint sh = xyl__fgl_compile(GL_COMPUTE_SHADER, xyl__shader_gl_foliage_cut_comp, log,
                        (GLsizei)sizeof log);
    if (!sh) return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "shader foliage_cut.comp: %s", log);
    GLuint p = glCreateProgram();
    glAttachShader(p, sh);
    glDeleteShader(sh);
    glLinkProgram(p);
    GLint ok = GL_FALSE;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        glGetProgramInfoLog(p, (GLsizei)sizeof log, NULL, log);
        glDeleteProgram(p);
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "program foliage_cut: %s", log);
    }
    gl->cut_program = p;
    return XYL_OK;
}

static xyl_result build_objects(xyl_foliage_gl *gl, xyl_diag *diag)
{
    glCreateVertexArrays(1, &gl->vao); /* core profile draws need one, even without attributes */
    glCreateBuffers(1, &gl->leaf_buf);
    glCreateBuffers(1, &gl->xfb_buf);
    GLuint *cut_bufs[3] = {&gl->node_buf, &gl->list_buf, &gl->command_buf};
    for (int k = 0; k < 3; ++k) {
        glCreateBuffers(1, cut_bufs[k]);
        glNamedBufferData(*cut_bufs[k], 16, NULL, GL_DYNAMIC_DRAW);
    }
    glCreateFramebuffers(1, &gl->capture_fbo);
    /* no attachments: captures draw with the rasterizer off, but a draw still needs a complete
     * framebuffer, which a surfaceless context's default one is not */
    glNamedFramebufferParameteri(gl->capture_fbo, GL_FRAMEBUFFER_DEFAULT_WIDTH, 1);
    glNamedFramebufferParameteri(gl->capture_fbo, GL_FRAMEBUFFER_DEFAULT_HEIGHT, 1);
    glCreateQueries(GL_PRIMITIVES_GENERATED, 1, &gl->generated_query);
    glCreateQueries(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN, 1, &gl->written_query);
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &gl->max_ssbo_bytes);
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &gl->max_texture_side);
    const uint8_t white[4] = {255, 255, 255, 255};
    gl->texture = xyl__fgl_leaf_texture(white, 1, 1);
    return xyl__fgl_check(diag, "creating the leaf renderer's objects");
}

xyl_result xyl_foliage_gl_create(const xyl_foliage_gl_desc *desc, xyl_foliage_gl **out,
                                 xyl_diag *diag)
{
    if (!out) return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "out is required");
    xyl_result r = xyl__fgl_need_context(diag);
    if (r != XYL_OK) return r;
    xyl_allocator a = {0};
    if (desc) a = desc->alloc;
    xyl_foliage_gl *gl = xyl__calloc(&a, 1, sizeof *gl);
    if (!gl) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    gl->alloc = a;
    xyl__fgl_drain_errors();
    r = build_program(gl, diag);
    if (r == XYL_OK) r = build_cut_program(gl, diag);
    if (r == XYL_OK) r = build_objects(gl, diag);
    if (r != XYL_OK) {
        xyl_foliage_gl_destroy(gl);
        return r;
    }
    *out = gl;
    xyl__diag_ok(diag);
    return XYL_OK;
}

void xyl_foliage_gl_destroy(xyl_foliage_gl *gl)
{
    if (!gl) return;
    if (epoxy_gl_version() != 0) { /* GL objects died with the context otherwise */
        glDeleteProgram(gl->program);
        glDeleteProgram(gl->cut_program);
        glDeleteVertexArrays(1, &gl->vao);
        GLuint bufs[5] = {gl->leaf_buf, gl->xfb_buf, gl->node_buf, gl->list_buf, gl->command_buf};
        glDeleteBuffers(5, bufs);
        glDeleteTextures(1, &gl->texture);
        glDeleteFramebuffers(1, &gl->capture_fbo);
        GLuint qs[2] = {gl->generated_query, gl->written_query};
        glDeleteQueries(2, qs);
    }
    xyl_allocator a = gl->alloc;
    xyl__foliage_tables_free(&gl->tables, &a);
    xyl__free(&a, gl);
}

/* ---- the species' leaves ------------------------------------------------------------------ */

/* New buffers, swapped in only when the whole upload worked. */
static xyl_result upload_records(xyl_foliage_gl *gl, const xyl_foliage_gpu_leaf *records,
                                 const xyl__foliage_cut_node *nodes, size_t count, xyl_diag *diag)
{
    xyl__fgl_drain_errors();
    GLuint buf[3] = {0, 0, 0};
    glCreateBuffers(3, buf);
    glNamedBufferStorage(buf[0], (GLsizeiptr)(count * sizeof *records), records, 0);
    glNamedBufferData(buf[1], (GLsizeiptr)(count * sizeof *nodes), nodes, GL_STATIC_DRAW);
    glNamedBufferData(buf[2], (GLsizeiptr)(count * sizeof(uint32_t)), NULL, GL_DYNAMIC_DRAW);
    xyl_result r = xyl__fgl_check(diag, "uploading the leaves");
    if (r != XYL_OK) {
        glDeleteBuffers(3, buf);
        return r;
    }
    GLuint old[3] = {gl->leaf_buf, gl->node_buf, gl->list_buf};
    glDeleteBuffers(3, old);
    gl->leaf_buf = buf[0];
    gl->node_buf = buf[1];
    gl->list_buf = buf[2];
    gl->has_cut = false;
    return XYL_OK;
}

xyl_result xyl_foliage_gl_set_foliage(xyl_foliage_gl *gl, const xyl_foliage *foliage,
                                      xyl_diag *diag)
{
    if (!gl || !foliage)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "gl and foliage are required");
    size_t n = foliage->leaf_count;
    if (n > UINT32_MAX || (GLint64)(n * sizeof(xyl_foliage_gpu_leaf)) > gl->max_ssbo_bytes)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu leaves exceed the driver's storage block size (%lld bytes)", n,
                         (long long)gl->max_ssbo_bytes);
    xyl__foliage_tables tables;
    xyl_result r = xyl__foliage_tables_make(foliage, &gl->alloc, &tables, diag);
    if (r != XYL_OK) return r;
    xyl_foliage_gpu_leaf *records = xyl__alloc_array(&gl->alloc, n, sizeof *records);
    xyl__foliage_cut_node *nodes = xyl__alloc_array(&gl->alloc, n, sizeof *nodes);
    if (!records || !nodes) r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    if (r == XYL_OK) r = xyl_foliage_pack_gpu(foliage->leaves, n, records, diag);
    if (r == XYL_OK) r = xyl__foliage_cut_nodes(foliage, nodes, diag);
    if (r == XYL_OK) r = upload_records(gl, records, nodes, n, diag);
    xyl__free(&gl->alloc, records);
    xyl__free(&gl->alloc, nodes);
    if (r != XYL_OK) {
        xyl__foliage_tables_free(&tables, &gl->alloc);
        return r;
    }
    xyl__foliage_tables_free(&gl->tables, &gl->alloc);
    gl->tables = tables;
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_result xyl_foliage_gl_set_texture(xyl_foliage_gl *gl, const uint8_t *rgba, uint32_t width,
                                      uint32_t height, xyl_diag *diag)
{
    if (!gl || !rgba)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "gl and rgba are required");
    return xyl__fgl_replace_leaf_texture(&gl->texture, gl->max_texture_side, rgba, width, height,
                                         diag);
}

/* ---- draws -------------------------------------------------------------------------------- */

static xyl_result check_draw(const xyl_foliage_gl *gl, const xyl_foliage_gl_frame *frame,
                             const uint32_t *lods, size_t lod_count, xyl__foliage_frame *rf,
                             xyl_diag *diag)
{
    if (!gl || !frame || !lods)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "gl, frame and lods are required");
    const xyl__foliage_frame_in in = XYL__FOLIAGE_FRAME_IN(frame);
    return xyl__foliage_draw_check(&gl->tables, lods, lod_count, &in, rf, diag);
}

static void bind_program(const xyl_foliage_gl *gl, const xyl__foliage_frame *rf)
{
    GLuint p = gl->program;
    glUseProgram(p);
    xyl__fgl_leaf_uniforms(p, rf);
    glProgramUniform1ui(p, XYL_FOLIAGE_GL_UNIFORM_LIST, 0);
    glBindVertexArray(gl->vao);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_FOLIAGE_GL_BINDING_LEAVES, gl->leaf_buf);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_FOLIAGE_GL_BINDING_LIST, gl->list_buf);
    glBindTextureUnit(XYL_FOLIAGE_GL_BINDING_TEXTURE, gl->texture);
}

/* Per sector the LOD's two ranges, [base, base + a) and [base + b, base + b + c). */
static void draw_ranges(const xyl_foliage_gl *gl, const uint32_t *lods)
{
    for (uint32_t s = 0; s < gl->tables.sector_count; ++s) {
        const xyl__foliage_sector_ref *sec = &gl->tables.sectors[s];
        const xyl__foliage_range *r = &gl->tables.ranges[sec->first_lod + lods[s]];
        const uint32_t first[2] = {sec->base, sec->base + r->b}, count[2] = {r->a, r->c};
        for (int k = 0; k < 2; ++k) {
            if (!count[k]) continue;
            glProgramUniform1ui(gl->program, XYL_FOLIAGE_GL_UNIFORM_BASE, first[k]);
            glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, (GLsizei)count[k]);
        }
    }
}

xyl_result xyl_foliage_gl_draw(xyl_foliage_gl *gl, const xyl_foliage_gl_frame *frame,
                               const uint32_t *lods, size_t lod_count, xyl_diag *diag)
{
    xyl__foliage_frame rf;
    xyl_result r = check_draw(gl, frame, lods, lod_count, &rf, diag);
    if (r != XYL_OK) return r;
    xyl__fgl_drain_errors();
    GLboolean cull = glIsEnabled(GL_CULL_FACE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    bind_program(gl, &rf);
    draw_ranges(gl, lods);
    if (cull) glEnable(GL_CULL_FACE);
    r = xyl__fgl_check(diag, "drawing the leaves");
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

/* ---- the per-leaf cut --------------------------------------------------------------------- */

/* The cut into the list and the command's instance count, then one indirect draw of it. */
static void draw_cut(xyl_foliage_gl *gl, const xyl__foliage_frame *rf, const double eye[3],
                     double per_distance)
{
    const uint32_t command[4] = {4, 0, 0, 0};
    glNamedBufferSubData(gl->command_buf, 0, sizeof command, command);
    uint32_t n = (uint32_t)gl->tables.leaf_count;
    GLuint c = gl->cut_program;
    glProgramUniform3f(c, XYL_FOLIAGE_GL_UNIFORM_CUT_EYE, (float)eye[0], (float)eye[1],
                       (float)eye[2]);
    glProgramUniform1f(c, XYL_FOLIAGE_GL_UNIFORM_CUT_PER_DISTANCE, (float)per_distance);
    glProgramUniform1ui(c, XYL_FOLIAGE_GL_UNIFORM_CUT_COUNT, n);
    glUseProgram(c);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_FOLIAGE_GL_BINDING_NODES, gl->node_buf);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_FOLIAGE_GL_BINDING_LIST, gl->list_buf);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_FOLIAGE_GL_BINDING_COMMAND, gl->command_buf);
    glDispatchCompute((n + XYL_FOLIAGE_GL_CUT_GROUP - 1) / XYL_FOLIAGE_GL_CUT_GROUP, 1, 1);
    glMemoryBarrier(GL_COMMAND_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    bind_program(gl, rf);
    glProgramUniform1ui(gl->program, XYL_FOLIAGE_GL_UNIFORM_LIST, 1);
    GLint indirect = 0;
    glGetIntegerv(GL_DRAW_INDIRECT_BUFFER_BINDING, &indirect);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, gl->command_buf);
    glDrawArraysIndirect(GL_TRIANGLE_STRIP, NULL);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, (GLuint)indirect);
}

xyl_result xyl_foliage_gl_draw_adaptive(xyl_foliage_gl *gl, const xyl_foliage_gl_frame *frame,
                                        const xyl_foliage_view *view, xyl_diag *diag)
{
    if (!gl || !frame || !view)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "gl, frame and view are required");
    xyl__foliage_frame rf;
    const xyl__foliage_frame_in in = XYL__FOLIAGE_FRAME_IN(frame);
    xyl_result r = xyl__foliage_frame_check(&gl->tables, &in, &rf, diag);
    double eye[3], per_distance = 0.0;
    if (r == XYL_OK) r = xyl__foliage_view_resolve(view, eye, &per_distance, diag);
    if (r != XYL_OK) return r;
    xyl__fgl_drain_errors();
    GLboolean cull = glIsEnabled(GL_CULL_FACE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    draw_cut(gl, &rf, eye, per_distance);
    if (cull) glEnable(GL_CULL_FACE);
    r = xyl__fgl_check(diag, "drawing the leaves' cut");
    gl->has_cut = r == XYL_OK;
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

xyl_result xyl_foliage_gl_last_cut(xyl_foliage_gl *gl, uint32_t *out, size_t capacity,
                                   size_t *count, xyl_diag *diag)
{
    if (!gl || !count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "gl and count are required");
    if (!gl->has_cut)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "no adaptive draw since the foliage was uploaded");
    xyl__fgl_drain_errors();
    uint32_t command[4] = {0, 0, 0, 0};
    glGetNamedBufferSubData(gl->command_buf, 0, sizeof command, command);
    xyl_result r = xyl__fgl_check(diag, "reading the cut's draw command back");
    if (r != XYL_OK) return r;
    size_t n = command[1];
    if (n > gl->tables.leaf_count)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "the GPU's cut counts %zu of %zu leaves", n, gl->tables.leaf_count);
    if (out) {
        if (capacity < n)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                             "the cut has %zu leaves, out holds %zu", n, capacity);
        if (n) glGetNamedBufferSubData(gl->list_buf, 0, (GLsizeiptr)(n * sizeof *out), out);
        r = xyl__fgl_check(diag, "reading the cut back");
        if (r != XYL_OK) return r;
    }
    *count = n;
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- capture ------------------------------------------------------------------------------ */

static xyl_result run_feedback(xyl_foliage_gl *gl, const xyl__foliage_frame *rf, const uint32_t *lods,
                               size_t bytes, GLuint64 *written, GLuint64 *generated,
                               xyl_diag *diag)
{
    xyl__fgl_drain_errors();
    glNamedBufferData(gl->xfb_buf, (GLsizeiptr)bytes, NULL, GL_STREAM_READ);
    xyl_result r = xyl__fgl_check(diag, "allocating the transform feedback buffer");
    if (r != XYL_OK) return r;
    GLint draw_fbo = 0;
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &draw_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, gl->capture_fbo);
    bind_program(gl, rf);
    glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, gl->xfb_buf);
    glEnable(GL_RASTERIZER_DISCARD);
    glBeginQuery(GL_PRIMITIVES_GENERATED, gl->generated_query);
    glBeginQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN, gl->written_query);
    glBeginTransformFeedback(GL_TRIANGLES);
    draw_ranges(gl, lods);
    glEndTransformFeedback();
    glEndQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN);
    glEndQuery(GL_PRIMITIVES_GENERATED);
    glDisable(GL_RASTERIZER_DISCARD);
    glGetQueryObjectui64v(gl->written_query, GL_QUERY_RESULT, written);
    glGetQueryObjectui64v(gl->generated_query, GL_QUERY_RESULT, generated);
    glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, 0);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, (GLuint)draw_fbo);
    return xyl__fgl_check(diag, "capturing the leaves with transform feedback");
}

xyl_result xyl__foliage_gl_capture(xyl_foliage_gl *gl, const xyl_foliage_gl_frame *frame,
                                   const uint32_t *lods, size_t lod_count,
                                   xyl__foliage_captured *out, size_t capacity, size_t *count,
                                   uint64_t *generated, xyl_diag *diag)
{
    if (!count || !generated || (capacity && !out))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "count, generated, and out when capacity > 0, are required");
    xyl__foliage_frame rf;
    xyl_result r = check_draw(gl, frame, lods, lod_count, &rf, diag);
    if (r != XYL_OK) return r;
    uint64_t vertices = xyl__foliage_tables_leaves(&gl->tables, lods) * VERTICES_PER_LEAF_CAPTURED;
    if (vertices * XFB_VERTEX_BYTES > MAX_READBACK_BYTES)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%llu captured vertices exceed 2 GiB", (unsigned long long)vertices);
    size_t bytes = (size_t)(vertices ? vertices : 1) * XFB_VERTEX_BYTES;
    GLuint64 written = 0, gen = 0;
    r = run_feedback(gl, &rf, lods, bytes, &written, &gen, diag);
    if (r == XYL_OK && written < gen)
        r = xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                      "transform feedback wrote %llu of %llu triangles",
                      (unsigned long long)written, (unsigned long long)gen);
    if (r != XYL_OK) return r;
    size_t total = (size_t)written * 3;
    size_t n = capacity < total ? capacity : total;
    if (n) glGetNamedBufferSubData(gl->xfb_buf, 0, (GLsizeiptr)(n * XFB_VERTEX_BYTES), out);
    r = xyl__fgl_check(diag, "reading the transform feedback back");
    if (r != XYL_OK) return r;
    *count = total;
    *generated = gen;
    xyl__diag_ok(diag);
    return XYL_OK;
}

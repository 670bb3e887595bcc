/* The OpenGL 4.5 core backend: programs, buffers, the instanced and hardware draws, offscreen
 * rendering and the capture of evaluated vertices. Every draw goes through check_batches first:
 * storage buffers are read without robust access, so an instance naming a patch that was never
 * uploaded must be stopped on the CPU. */
#include <epoxy/gl.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "shader_sources.h"
#include "tess_debug.h"
#include "xyl_internal.h"
#include "xylem/xyl_tess_gl.h"

#define MAX_IMAGE_SIDE 8192u
#define DEFAULT_IMAGE_SIDE 512u
#define MAX_CMDS (2 * XYL_TESS_MAX_LEVEL)
#define CAPTURE_SLOT_BYTES 32u /* (position, 1), (normal, 0) */
#define XFB_VERTEX_BYTES 40u   /* v_position, v_normal, v_tess_coord, v_patch */
#define MAX_READBACK_BYTES ((size_t)1 << 31)

/* A transform feedback record is exactly a xyl__tess_captured, so it is read back in place. */
_Static_assert(sizeof(xyl__tess_captured) == XFB_VERTEX_BYTES, "captured = xfb record");
_Static_assert(offsetof(xyl__tess_captured, patch) == 36, "v_patch follows three vec3");

typedef struct target {
    GLuint fbo, color, depth;       /* what is drawn into (multisampled when samples > 1) */
    GLuint resolve_fbo, resolve_rb; /* single-sampled copy that is read back */
    uint32_t width, height, samples;
} target;

struct xyl_tess_gl {
    GLuint prog_inst, prog_capture, prog_hw[2]; /* hardware: [0] quads, [1] triangles */
    GLuint prog_hw_edges[2];                    /* their wireframe overlay (edges from a GS) */
    GLuint vao_inst, vao_hw;
    GLuint capture_fbo; /* no attachments: captures draw with the rasterizer off, but a draw
                           still needs a complete framebuffer, which a surfaceless context's
                           default one is not */
    GLuint pattern_vbo, pattern_ibo, patch_buf, instance_buf, cmd_buf, frame_buf;
    GLuint capture_buf, offset_buf, xfb_buf;
    GLuint time_query, written_query, generated_query;
    bool timed;
    GLint ubo_align;
    GLint64 max_ssbo_bytes;
    target target;
    size_t patch_count;
    uint8_t *patch_kinds;       /* CPU copy: instances are checked against it */
    uint32_t *pattern_vertices; /* CPU copy: captures decode (i, j) of each slot from it */
    size_t pattern_vertex_count;
    uint32_t max_level;
    xyl_tess_pattern_range ranges[2][XYL_TESS_MAX_LEVEL + 1];
    xyl_allocator alloc;
};

/* ---- errors ------------------------------------------------------------------------------- */

/* Errors left by the caller's own GL code would otherwise be reported as ours. */
static void drain_errors(void)
{
    for (int i = 0; i < 32 && glGetError() != GL_NO_ERROR; ++i) {}
}

static xyl_result gl_check(xyl_diag *diag, const char *what)
{
    GLenum e = glGetError();
    if (e == GL_NO_ERROR) return XYL_OK;
    drain_errors();
    if (e == GL_OUT_OF_MEMORY)
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "GL out of memory while %s", what);
    return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "GL error 0x%04x while %s", (unsigned)e,
                     what);
}

static xyl_result need_context(xyl_diag *diag)
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

/* ---- programs ----------------------------------------------------------------------------- */

typedef struct stage_src {
    GLenum stage;
    const unsigned char *text;
    const char *name;
} stage_src;

static GLuint compile(const stage_src *s, char *log, GLsizei log_size)
{
    GLuint sh = glCreateShader(s->stage);
    const GLchar *text = (const GLchar *)s->text;
    glShaderSource(sh, 1, &text, NULL);
    glCompileShader(sh);
    GLint ok = GL_FALSE;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (ok) return sh;
    glGetShaderInfoLog(sh, log_size, NULL, log);
    glDeleteShader(sh);
    return 0;
}

/* Links the stages; xfb names the transform feedback varyings (NULL: none). */
static xyl_result link_program(const stage_src *stages, int n, const char *const *xfb, int nxfb,
                               GLuint *out, xyl_diag *diag)
{
    char log[192] = "";
    GLuint p = glCreateProgram();
    for (int i = 0; i < n; ++i) {
        GLuint sh = compile(&stages[i], log, (GLsizei)sizeof log);
        if (!sh) {
            glDeleteProgram(p);
            return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "shader %s: %s", stages[i].name,
                             log);
        }
        glAttachShader(p, sh);
        glDeleteShader(sh); /* freed with the program */
    }
    if (nxfb) glTransformFeedbackVaryings(p, nxfb, xfb, GL_INTERLEAVED_ATTRIBS);
    glLinkProgram(p);
    GLint ok = GL_FALSE;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        glGetProgramInfoLog(p, (GLsizei)sizeof log, NULL, log);
        glDeleteProgram(p);
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "program %s: %s", stages[0].name, log);
    }
    *out = p;
    return XYL_OK;
}

static xyl_result build_programs(xyl_tess_gl *gl, xyl_diag *diag)
{
    const stage_src inst[] = {{GL_VERTEX_SHADER, xyl__shader_gl_instanced_vert, "instanced.vert"},
                              {GL_FRAGMENT_SHADER, xyl__shader_gl_shade_frag, "shade.frag"}};
    const stage_src cap[] = {
        {GL_VERTEX_SHADER, xyl__shader_gl_instanced_capture_vert, "instanced_capture.vert"}};
    const stage_src quad[] = {{GL_VERTEX_SHADER, xyl__shader_gl_hw_vert, "hw.vert"},
                              {GL_TESS_CONTROL_SHADER, xyl__shader_gl_hw_quad_tesc, "hw_quad.tesc"},
                              {GL_TESS_EVALUATION_SHADER, xyl__shader_gl_hw_quad_tese, "hw_quad.tese"},
                              {GL_FRAGMENT_SHADER, xyl__shader_gl_shade_frag, "shade.frag"}};
    const stage_src tri[] = {{GL_VERTEX_SHADER, xyl__shader_gl_hw_vert, "hw.vert"},
                             {GL_TESS_CONTROL_SHADER, xyl__shader_gl_hw_tri_tesc, "hw_tri.tesc"},
                             {GL_TESS_EVALUATION_SHADER, xyl__shader_gl_hw_tri_tese, "hw_tri.tese"},
                             {GL_FRAGMENT_SHADER, xyl__shader_gl_shade_frag, "shade.frag"}};
    /* The hardware programs double as capture programs: the varyings only matter while
     * transform feedback is active. */
    const char *const xfb[] = {"v_position", "v_normal", "v_tess_coord", "v_patch"};
    xyl_result r = link_program(inst, 2, NULL, 0, &gl->prog_inst, diag);
    if (r == XYL_OK) r = link_program(cap, 1, NULL, 0, &gl->prog_capture, diag);
    if (r == XYL_OK) r = link_program(quad, 4, xfb, 4, &gl->prog_hw[0], diag);
    if (r == XYL_OK) r = link_program(tri, 4, xfb, 4, &gl->prog_hw[1], diag);
    /* the same stages with the edge geometry shader before the fragment stage */
    const stage_src geom = {GL_GEOMETRY_SHADER, xyl__shader_gl_hw_edges_geom, "hw_edges.geom"};
    const stage_src quad_edges[] = {quad[0], quad[1], quad[2], geom, quad[3]};
    const stage_src tri_edges[] = {tri[0], tri[1], tri[2], geom, tri[3]};
    if (r == XYL_OK) r = link_program(quad_edges, 5, NULL, 0, &gl->prog_hw_edges[0], diag);
    if (r == XYL_OK) r = link_program(tri_edges, 5, NULL, 0, &gl->prog_hw_edges[1], diag);
    return r;
}

/* ---- buffers and vertex arrays ------------------------------------------------------------ */

static void build_vertex_arrays(xyl_tess_gl *gl)
{
    GLuint v = gl->vao_inst;
    glVertexArrayVertexBuffer(v, 0, gl->pattern_vbo, 0, sizeof(uint32_t));
    glVertexArrayAttribIFormat(v, 0, 1, GL_UNSIGNED_INT, 0);
    glVertexArrayAttribBinding(v, 0, 0);
    glEnableVertexArrayAttrib(v, 0);
    /* divisor 1: the indirect commands' base_instance then selects each batch's records */
    glVertexArrayVertexBuffer(v, 1, gl->instance_buf, 0, sizeof(xyl_tess_instance));
    glVertexArrayAttribIFormat(v, 1, 4, GL_UNSIGNED_INT, 0);
    glVertexArrayAttribBinding(v, 1, 1);
    glVertexArrayBindingDivisor(v, 1, 1);
    glEnableVertexArrayAttrib(v, 1);
    glVertexArrayElementBuffer(v, gl->pattern_ibo);
}

static xyl_result build_buffers(xyl_tess_gl *gl, const xyl_tess_patterns *pat, xyl_diag *diag)
{
    GLuint *bufs[] = {&gl->pattern_vbo, &gl->pattern_ibo, &gl->patch_buf, &gl->instance_buf,
                      &gl->cmd_buf, &gl->frame_buf, &gl->capture_buf, &gl->offset_buf,
                      &gl->xfb_buf};
    for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; ++i) glCreateBuffers(1, bufs[i]);
    glNamedBufferStorage(gl->pattern_vbo, (GLsizeiptr)(pat->vertex_count * sizeof(uint32_t)),
                         pat->vertices, 0);
    glNamedBufferStorage(gl->pattern_ibo, (GLsizeiptr)(pat->index_count * sizeof(uint32_t)),
                         pat->indices, 0);
    glCreateFramebuffers(1, &gl->capture_fbo);
    glNamedFramebufferParameteri(gl->capture_fbo, GL_FRAMEBUFFER_DEFAULT_WIDTH, 1);
    glNamedFramebufferParameteri(gl->capture_fbo, GL_FRAMEBUFFER_DEFAULT_HEIGHT, 1);
    glCreateVertexArrays(1, &gl->vao_inst);
    glCreateVertexArrays(1, &gl->vao_hw); /* core profile draws need one, even without attributes */
    build_vertex_arrays(gl);
    glCreateQueries(GL_TIME_ELAPSED, 1, &gl->time_query);
    glCreateQueries(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN, 1, &gl->written_query);
    glCreateQueries(GL_PRIMITIVES_GENERATED, 1, &gl->generated_query);
    glGetIntegerv(GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT, &gl->ubo_align);
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &gl->max_ssbo_bytes);
    if (gl->ubo_align < 1) gl->ubo_align = 256;
    return gl_check(diag, "creating buffers");
}

/* Patterns come from xyl_tess_patterns_create; a hand-made one must still stay inside its
 * arrays, since the indirect commands are checked against these ranges. */
static bool patterns_ok(const xyl_tess_patterns *p)
{
    if (!p->vertices || !p->indices || p->max_level < 1 || p->max_level > XYL_TESS_MAX_LEVEL ||
        p->vertex_count > UINT32_MAX || p->index_count > UINT32_MAX)
        return false;
    for (int k = 0; k < 2; ++k)
        for (uint32_t l = 1; l <= p->max_level; ++l) {
            const xyl_tess_pattern_range *r = &p->ranges[k][l];
            if ((uint64_t)r->first_vertex + r->vertex_count > p->vertex_count ||
                (uint64_t)r->first_index + r->index_count > p->index_count ||
                r->vertex_count == 0 || r->index_count == 0 || r->vertex_count > 65536)
                return false;
            for (uint32_t i = 0; i < r->index_count; ++i)
                if (p->indices[r->first_index + i] >= r->vertex_count) return false;
        }
    return true;
}

static xyl_result copy_patterns(xyl_tess_gl *gl, const xyl_tess_patterns *p)
{
    gl->pattern_vertices = xyl__alloc_array(&gl->alloc, p->vertex_count, sizeof(uint32_t));
    if (!gl->pattern_vertices) return XYL_ERR_OUT_OF_MEMORY;
    memcpy(gl->pattern_vertices, p->vertices, p->vertex_count * sizeof(uint32_t));
    gl->pattern_vertex_count = p->vertex_count;
    gl->max_level = p->max_level;
    memcpy(gl->ranges, p->ranges, sizeof gl->ranges);
    return XYL_OK;
}

xyl_result xyl_tess_gl_create(const xyl_tess_gl_desc *desc, const xyl_tess_patterns *patterns,
                              xyl_tess_gl **out, xyl_diag *diag)
{
    if (!patterns || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "patterns and out are required");
    if (!patterns_ok(patterns))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "patterns are inconsistent (ranges outside their arrays)");
    xyl_result r = need_context(diag);
    if (r != XYL_OK) return r;
    xyl_allocator a = {0};
    if (desc) a = desc->alloc;
    xyl_tess_gl *gl = xyl__calloc(&a, 1, sizeof *gl);
    if (gl) gl->alloc = a;
    if (!gl || copy_patterns(gl, patterns) != XYL_OK) {
        xyl_tess_gl_destroy(gl);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    }
    drain_errors();
    r = build_programs(gl, diag);
    if (r == XYL_OK) r = build_buffers(gl, patterns, diag);
    if (r != XYL_OK) {
        xyl_tess_gl_destroy(gl);
        return r;
    }
    *out = gl;
    xyl__diag_ok(diag);
    return XYL_OK;
}

static void destroy_target(target *t)
{
    GLuint fbos[2] = {t->fbo, t->resolve_fbo}, rbs[3] = {t->color, t->depth, t->resolve_rb};
    glDeleteFramebuffers(2, fbos);
    glDeleteRenderbuffers(3, rbs);
    memset(t, 0, sizeof *t);
}

void xyl_tess_gl_destroy(xyl_tess_gl *gl)
{
    if (!gl) return;
    if (epoxy_gl_version() != 0) { /* GL objects died with the context otherwise */
        GLuint progs[6] = {gl->prog_inst,     gl->prog_capture,      gl->prog_hw[0],
                           gl->prog_hw[1],    gl->prog_hw_edges[0],  gl->prog_hw_edges[1]};
        for (int i = 0; i < 6; ++i) glDeleteProgram(progs[i]);
        GLuint vaos[2] = {gl->vao_inst, gl->vao_hw};
        glDeleteVertexArrays(2, vaos);
        GLuint bufs[9] = {gl->pattern_vbo, gl->pattern_ibo, gl->patch_buf,
                          gl->instance_buf, gl->cmd_buf, gl->frame_buf,
                          gl->capture_buf, gl->offset_buf, gl->xfb_buf};
        glDeleteBuffers(9, bufs);
        GLuint qs[3] = {gl->time_query, gl->written_query, gl->generated_query};
        glDeleteQueries(3, qs);
        destroy_target(&gl->target);
        glDeleteFramebuffers(1, &gl->capture_fbo);
    }
    xyl_allocator a = gl->alloc;
    xyl__free(&a, gl->patch_kinds);
    xyl__free(&a, gl->pattern_vertices);
    xyl__free(&a, gl);
}

/* ---- patches ------------------------------------------------------------------------------ */

xyl_result xyl_tess_gl_set_patches(xyl_tess_gl *gl, const xyl_tess_patches *patches,
                                   xyl_diag *diag)
{
    if (!gl || !patches || (patches->count && !patches->records))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "gl and patches are required");
    if (patches->count > UINT32_MAX ||
        (GLint64)(patches->count * sizeof(xyl_tess_patch)) > gl->max_ssbo_bytes)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu patches exceed the driver's storage block size", patches->count);
    uint8_t *kinds = xyl__alloc_array(&gl->alloc, patches->count, 1);
    if (!kinds) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    for (size_t i = 0; i < patches->count; ++i)
        kinds[i] = (uint8_t)xyl_tess_patch_kind(&patches->records[i]);
    drain_errors();
    /* at least one record: a zero-sized storage buffer cannot be bound */
    xyl_tess_patch none;
    memset(&none, 0, sizeof none);
    glNamedBufferData(gl->patch_buf,
                      (GLsizeiptr)((patches->count ? patches->count : 1) * sizeof(xyl_tess_patch)),
                      patches->count ? (const void *)patches->records : (const void *)&none,
                      GL_STATIC_DRAW);
    xyl_result r = gl_check(diag, "uploading patches");
    if (r != XYL_OK) {
        xyl__free(&gl->alloc, kinds);
        gl->patch_count = 0;
        return r;
    }
    xyl__free(&gl->alloc, gl->patch_kinds);
    gl->patch_kinds = kinds;
    gl->patch_count = patches->count;
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- batches ------------------------------------------------------------------------------ */

static const xyl_tess_pattern_range *range_of(const xyl_tess_gl *gl, uint32_t kind, uint32_t level)
{
    return &gl->ranges[kind == XYL_TESS_KIND_QUAD ? 0 : 1][level];
}

static bool instance_ok(const xyl_tess_gl *gl, const xyl_tess_instance *in,
                        const xyl_tess_batch *b)
{
    if (in->patch >= gl->patch_count || in->kind != b->kind || in->level != b->level ||
        gl->patch_kinds[in->patch] != in->kind)
        return false;
    for (uint32_t e = 0; e < in->kind; ++e) {
        uint32_t le = (in->edge_levels >> (XYL_TESS_EDGE_LEVEL_BITS * e)) & 0xffu;
        if (le < 1 || le > in->level) return false;
    }
    return true;
}

/* A command must draw its batch's pattern exactly, and the commands must cover the instances
 * in order, quads first (as xyl_tess_select builds them): captures rely on that order and the
 * hardware path draws each kind's instances at once. */
static bool cmd_ok(const xyl_tess_gl *gl, const xyl_tess_draw_cmd *c, const xyl_tess_batch *b,
                   size_t first)
{
    if ((b->kind != XYL_TESS_KIND_QUAD && b->kind != XYL_TESS_KIND_TRIANGLE) || b->level < 1 ||
        b->level > gl->max_level)
        return false;
    const xyl_tess_pattern_range *r = range_of(gl, b->kind, b->level);
    return c->index_count == r->index_count && c->first_index == r->first_index &&
           c->base_vertex == (int32_t)r->first_vertex && c->base_instance == first &&
           c->instance_count > 0;
}

static xyl_result check_batches(const xyl_tess_gl *gl, const xyl_tess_batches *b, xyl_diag *diag)
{
    if ((b->instance_count && !b->instances) || (b->cmd_count && (!b->cmds || !b->batches)) ||
        b->cmd_count > MAX_CMDS || b->instance_count > UINT32_MAX)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "batches are malformed");
    size_t at = 0;
    for (size_t c = 0; c < b->cmd_count; ++c) {
        const xyl_tess_batch *bt = &b->batches[c];
        bool quad_after_triangle = c && bt->kind == XYL_TESS_KIND_QUAD &&
                                   b->batches[c - 1].kind == XYL_TESS_KIND_TRIANGLE;
        if (quad_after_triangle || !cmd_ok(gl, &b->cmds[c], bt, at) ||
            b->cmds[c].instance_count > b->instance_count - at)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)c,
                             "command %zu does not match the patterns (kind %u, level %u of %u)",
                             c, bt->kind, bt->level, gl->max_level);
        for (uint32_t i = 0; i < b->cmds[c].instance_count; ++i, ++at)
            if (!instance_ok(gl, &b->instances[at], bt))
                return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)at,
                                 "instance %zu does not match the uploaded patches (%zu) or its "
                                 "command", at, gl->patch_count);
    }
    if (at != b->instance_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "commands cover %zu of %zu instances", at, b->instance_count);
    return XYL_OK;
}

static xyl_result check_common(const xyl_tess_gl *gl, const xyl_tess_batches *batches,
                               uint32_t variant, xyl_tess_path path, xyl_diag *diag)
{
    if (!gl || !batches)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "gl and batches are required");
    if (variant >= XYL_TESS_VARIANT_COUNT ||
        (path != XYL_TESS_PATH_INSTANCED && path != XYL_TESS_PATH_HARDWARE))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "unknown variant %u or path %d",
                         variant, (int)path);
    return check_batches(gl, batches, diag);
}

/* ---- uploads ------------------------------------------------------------------------------ */

static size_t frame_stride(const xyl_tess_gl *gl)
{
    size_t a = (size_t)gl->ubo_align;
    return (sizeof(xyl_tess_frame) + a - 1) / a * a;
}

/* Instances of one kind, [first, first + count): one hardware draw each (check_batches has
 * made sure the quad commands come first and each kind's instances are contiguous). */
static void kind_span(const xyl_tess_batches *b, uint32_t kind, uint32_t *first, uint32_t *count)
{
    *first = 0;
    *count = 0;
    for (size_t c = 0; c < b->cmd_count; ++c) {
        if (b->batches[c].kind != kind) continue;
        if (!*count) *first = b->cmds[c].base_instance;
        *count += b->cmds[c].instance_count;
    }
}

/* Three frame slots per pass: the instanced draw, the hardware quads and triangles (each with
 * its first instance record as base_instance). */
#define SLOTS_PER_PASS 3

static size_t slot_index(int pass, uint32_t kind)
{
    size_t k = kind == XYL_TESS_KIND_QUAD ? 1 : kind == XYL_TESS_KIND_TRIANGLE ? 2 : 0;
    return (size_t)pass * SLOTS_PER_PASS + k;
}

static xyl_result upload_frames(xyl_tess_gl *gl, const xyl_tess_batches *b,
                                const xyl_tess_frame *frames, int passes, xyl_diag *diag)
{
    size_t stride = frame_stride(gl), slots = (size_t)passes * SLOTS_PER_PASS;
    uint8_t *data = xyl__calloc(&gl->alloc, slots, stride);
    if (!data) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    const uint32_t kinds[SLOTS_PER_PASS] = {0, XYL_TESS_KIND_QUAD, XYL_TESS_KIND_TRIANGLE};
    for (int p = 0; p < passes; ++p)
        for (int k = 0; k < SLOTS_PER_PASS; ++k) {
            xyl_tess_frame f = frames[p];
            uint32_t count;
            kind_span(b, kinds[k], &f.base_instance, &count);
            memcpy(data + slot_index(p, kinds[k]) * stride, &f, sizeof f);
        }
    glNamedBufferData(gl->frame_buf, (GLsizeiptr)(slots * stride), data, GL_STREAM_DRAW);
    xyl__free(&gl->alloc, data);
    return gl_check(diag, "uploading frame uniforms");
}

static xyl_result upload_batches(xyl_tess_gl *gl, const xyl_tess_batches *b,
                                 const xyl_tess_frame *frames, int passes, xyl_diag *diag)
{
    drain_errors();
    if (b->instance_count) {
        glNamedBufferData(gl->instance_buf, (GLsizeiptr)(b->instance_count * sizeof *b->instances),
                          b->instances, GL_STREAM_DRAW);
        glNamedBufferData(gl->cmd_buf, (GLsizeiptr)(b->cmd_count * sizeof *b->cmds), b->cmds,
                          GL_STREAM_DRAW);
    }
    xyl_result r = gl_check(diag, "uploading instances");
    return r == XYL_OK ? upload_frames(gl, b, frames, passes, diag) : r;
}

static void bind_frame(const xyl_tess_gl *gl, int pass, uint32_t kind)
{
    glBindBufferRange(GL_UNIFORM_BUFFER, XYL_TESS_BINDING_FRAME, gl->frame_buf,
                      (GLintptr)(slot_index(pass, kind) * frame_stride(gl)),
                      sizeof(xyl_tess_frame));
}

/* ---- draws -------------------------------------------------------------------------------- */

static void draw_instanced(const xyl_tess_gl *gl, const xyl_tess_batches *b, GLuint program,
                           int pass)
{
    glUseProgram(program);
    bind_frame(gl, pass, 0);
    glBindVertexArray(gl->vao_inst);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, gl->cmd_buf);
    glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT, NULL, (GLsizei)b->cmd_count, 0);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
}

/* Patches per hardware draw: llvmpipe (Mesa 22.3) garbles a draw's output (stray triangles when
 * rendering, misplaced records when capturing) once it emits a few hundred thousand vertices,
 * so each kind goes in draws of at most about 32768 emitted vertices. */
static uint32_t patches_per_draw(const xyl_tess_batches *b, uint32_t kind)
{
    uint32_t level = 1;
    for (size_t c = 0; c < b->cmd_count; ++c)
        if (b->batches[c].kind == kind && b->batches[c].level > level) level = b->batches[c].level;
    uint32_t per_patch = 6u * level * level; /* 3 vertices x the 2 L^2 triangle bound */
    return per_patch >= 32768u ? 1u : 32768u / per_patch;
}

/* The patches of one kind: the vertex index (draw start included) over the patch size counts
 * them, the frame slot's base_instance says where their records start. A program cannot change
 * while transform feedback records, so a capture records each kind in a session of its own. */
static void draw_hardware_kind(const xyl_tess_gl *gl, const xyl_tess_batches *b, uint32_t kind,
                               int pass, bool capture)
{
    uint32_t first, count;
    kind_span(b, kind, &first, &count);
    if (!count) return;
    int which = kind == XYL_TESS_KIND_QUAD ? 0 : 1;
    glUseProgram(pass == 1 && !capture ? gl->prog_hw_edges[which] : gl->prog_hw[which]);
    glBindVertexArray(gl->vao_hw);
    glPatchParameteri(GL_PATCH_VERTICES, (GLint)kind);
    bind_frame(gl, pass, kind);
    uint32_t chunk = patches_per_draw(b, kind);
    if (capture) glBeginTransformFeedback(GL_TRIANGLES);
    for (uint32_t at = 0; at < count; at += chunk) {
        uint32_t n = count - at < chunk ? count - at : chunk;
        glDrawArrays(GL_PATCHES, (GLint)(at * kind), (GLsizei)(n * kind));
    }
    if (capture) glEndTransformFeedback();
}

static void bind_storage(const xyl_tess_gl *gl)
{
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_TESS_BINDING_PATCHES, gl->patch_buf);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_TESS_BINDING_INSTANCES, gl->instance_buf);
}

static void draw_geometry(const xyl_tess_gl *gl, const xyl_tess_batches *b, xyl_tess_path path,
                          int pass)
{
    bind_storage(gl);
    if (path == XYL_TESS_PATH_INSTANCED) {
        draw_instanced(gl, b, gl->prog_inst, pass);
    } else {
        draw_hardware_kind(gl, b, XYL_TESS_KIND_QUAD, pass, false);
        draw_hardware_kind(gl, b, XYL_TESS_KIND_TRIANGLE, pass, false);
    }
}

/* Depth-tested, back faces culled. With XYL__TESS_FLAG_BACKFACES the back faces follow in a
 * second pass, pushed back by a slope-scaled offset: at a silhouette a front and a back face
 * meet at equal depth and interpolation noise would let the back face win a few pixels, red
 * where there is no hole. Seen through a hole, a back face lies a branch's width behind. */
static void draw_pass(const xyl_tess_gl *gl, const xyl_tess_batches *b, xyl_tess_path path,
                      uint32_t flags, int pass)
{
    if (!b->cmd_count) return;
    glEnable(GL_DEPTH_TEST);
    glFrontFace(GL_CCW);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    draw_geometry(gl, b, path, pass);
    if (!(flags & XYL__TESS_FLAG_BACKFACES)) return;
    glCullFace(GL_FRONT);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(2.0f, 8.0f);
    draw_geometry(gl, b, path, pass);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glCullFace(GL_BACK);
}

/* The shaded pass, then optionally the edges on top (lines pulled towards the viewer). */
static void render_passes(xyl_tess_gl *gl, const xyl_tess_batches *b, xyl_tess_path path,
                          const xyl_tess_frame *frames, bool wireframe)
{
    glDepthFunc(GL_LESS);
    draw_pass(gl, b, path, frames[0].flags, 0);
    if (!wireframe) return;
    glDepthFunc(GL_LEQUAL);
    if (path == XYL_TESS_PATH_HARDWARE) { /* pass 1 draws edges as lines (tess_hw_edges.geom) */
        draw_pass(gl, b, path, frames[1].flags, 1);
        glDepthFunc(GL_LESS);
        return;
    }
    glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    glEnable(GL_POLYGON_OFFSET_LINE);
    glPolygonOffset(-1.0f, -1.0f);
    draw_pass(gl, b, path, frames[1].flags, 1);
    glDisable(GL_POLYGON_OFFSET_LINE);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    glDepthFunc(GL_LESS);
}

xyl_result xyl_tess_gl_draw(xyl_tess_gl *gl, const xyl_tess_batches *batches,
                            const xyl_tess_frame *frame, xyl_tess_path path, xyl_diag *diag)
{
    if (!frame) return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "frame is required");
    xyl_result r = check_common(gl, batches, frame->variant, path, diag);
    bool wireframe = (frame->flags & XYL_TESS_FLAG_WIREFRAME) != 0;
    xyl_tess_frame frames[2] = {*frame, *frame};
    frames[0].flags &= ~XYL_TESS_FLAG_WIREFRAME;
    if (r == XYL_OK) r = upload_batches(gl, batches, frames, wireframe ? 2 : 1, diag);
    if (r != XYL_OK) return r;
    glBeginQuery(GL_TIME_ELAPSED, gl->time_query);
    render_passes(gl, batches, path, frames, wireframe);
    glEndQuery(GL_TIME_ELAPSED);
    gl->timed = true;
    r = gl_check(diag, "drawing");
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

double xyl_tess_gl_last_gpu_ms(const xyl_tess_gl *gl)
{
    if (!gl || !gl->timed) return -1.0;
    GLuint available = 0;
    glGetQueryObjectuiv(gl->time_query, GL_QUERY_RESULT_AVAILABLE, &available);
    if (!available) return -1.0;
    GLuint64 ns = 0;
    glGetQueryObjectui64v(gl->time_query, GL_QUERY_RESULT, &ns);
    return (double)ns * 1e-6;
}

/* ---- offscreen rendering ------------------------------------------------------------------ */

static GLuint make_renderbuffer(GLenum format, uint32_t samples, uint32_t w, uint32_t h)
{
    GLuint rb = 0;
    glCreateRenderbuffers(1, &rb);
    glNamedRenderbufferStorageMultisample(rb, samples > 1 ? (GLsizei)samples : 0, format,
                                          (GLsizei)w, (GLsizei)h);
    return rb;
}

/* Kept from call to call: a renderer usually draws the same size again. */
static xyl_result ensure_target(xyl_tess_gl *gl, uint32_t w, uint32_t h, uint32_t samples,
                                xyl_diag *diag)
{
    target *t = &gl->target;
    if (t->fbo && t->width == w && t->height == h && t->samples == samples) return XYL_OK;
    destroy_target(t);
    t->color = make_renderbuffer(GL_RGBA8, samples, w, h);
    t->depth = make_renderbuffer(GL_DEPTH_COMPONENT24, samples, w, h);
    glCreateFramebuffers(1, &t->fbo);
    glNamedFramebufferRenderbuffer(t->fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, t->color);
    glNamedFramebufferRenderbuffer(t->fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t->depth);
    bool ok = glCheckNamedFramebufferStatus(t->fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
    if (ok && samples > 1) {
        t->resolve_rb = make_renderbuffer(GL_RGBA8, 1, w, h);
        glCreateFramebuffers(1, &t->resolve_fbo);
        glNamedFramebufferRenderbuffer(t->resolve_fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                       t->resolve_rb);
        ok = glCheckNamedFramebufferStatus(t->resolve_fbo, GL_FRAMEBUFFER) ==
             GL_FRAMEBUFFER_COMPLETE;
    }
    xyl_result r = gl_check(diag, "creating the offscreen target");
    if (r == XYL_OK && !ok)
        r = xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                      "offscreen target %ux%u with %u samples is incomplete", w, h, samples);
    if (r != XYL_OK) {
        destroy_target(t);
        return r;
    }
    t->width = w;
    t->height = h;
    t->samples = samples;
    return XYL_OK;
}

typedef struct image_params {
    uint32_t width, height, samples;
    float background[4];
    bool wireframe;
} image_params;

static xyl_result check_image(const xyl_tess_image_desc *image, image_params *ip, xyl_diag *diag)
{
    xyl_tess_image_desc zero = {0};
    const xyl_tess_image_desc *d = image ? image : &zero;
    ip->width = d->width ? d->width : DEFAULT_IMAGE_SIDE;
    ip->height = d->height ? d->height : DEFAULT_IMAGE_SIDE;
    ip->samples = d->samples ? d->samples : 1;
    ip->wireframe = d->wireframe;
    if (ip->width > MAX_IMAGE_SIDE || ip->height > MAX_IMAGE_SIDE)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "image %ux%u: at most %u pixels a side", ip->width, ip->height,
                         MAX_IMAGE_SIDE);
    for (int k = 0; k < 4; ++k) {
        if (!isfinite(d->background[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "background is not finite");
        ip->background[k] = d->background[k];
    }
    GLint max_samples = 1;
    glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    if (ip->samples > (uint32_t)max_samples)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "%u samples asked, the driver has %d",
                         ip->samples, max_samples);
    return XYL_OK;
}


/* GL's rows start at the bottom; the API's at the top. */
static void flip_rows(uint8_t *rgba, uint32_t w, uint32_t h)
{
    size_t row = 4u * (size_t)w;
    for (uint32_t y = 0; y < h / 2; ++y) {
        uint8_t *a = rgba + y * row, *b = rgba + (h - 1 - y) * row;
        for (size_t i = 0; i < row; ++i) {
            uint8_t t = a[i];
            a[i] = b[i];
            b[i] = t;
        }
    }
}

static void read_back(const xyl_tess_gl *gl, const image_params *ip, uint8_t *rgba)
{
    const target *t = &gl->target;
    GLuint src = t->fbo;
    if (t->samples > 1) {
        glBlitNamedFramebuffer(t->fbo, t->resolve_fbo, 0, 0, (GLint)t->width, (GLint)t->height, 0,
                               0, (GLint)t->width, (GLint)t->height, GL_COLOR_BUFFER_BIT,
                               GL_NEAREST);
        src = t->resolve_fbo;
    }
    glBindFramebuffer(GL_READ_FRAMEBUFFER, src);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glPixelStorei(GL_PACK_ROW_LENGTH, 0);
    glPixelStorei(GL_PACK_SKIP_ROWS, 0);
    glPixelStorei(GL_PACK_SKIP_PIXELS, 0);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glReadPixels(0, 0, (GLsizei)ip->width, (GLsizei)ip->height, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
}

static void clear_target(const xyl_tess_gl *gl, const image_params *ip)
{
    glBindFramebuffer(GL_FRAMEBUFFER, gl->target.fbo);
    glViewport(0, 0, (GLsizei)ip->width, (GLsizei)ip->height);
    glDisable(GL_SCISSOR_TEST);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthMask(GL_TRUE);
    glClearColor(ip->background[0], ip->background[1], ip->background[2], ip->background[3]);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

xyl_result xyl_tess_gl_render_rgba(xyl_tess_gl *gl, const xyl_tess_batches *batches,
                                   const xyl_tess_frame *frame, xyl_tess_path path,
                                   const xyl_tess_image_desc *image, uint8_t *rgba, xyl_diag *diag)
{
    if (!frame || !rgba)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "frame and rgba are required");
    image_params ip;
    xyl_result r = check_common(gl, batches, frame->variant, path, diag);
    if (r == XYL_OK) r = check_image(image, &ip, diag);
    xyl_tess_frame frames[2] = {*frame, *frame};
    frames[1].flags |= XYL_TESS_FLAG_WIREFRAME;
    if (r == XYL_OK) r = upload_batches(gl, batches, frames, ip.wireframe ? 2 : 1, diag);
    if (r == XYL_OK) r = ensure_target(gl, ip.width, ip.height, ip.samples, diag);
    if (r != XYL_OK) return r;
    GLint draw_fbo = 0, read_fbo = 0, viewport[4];
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &draw_fbo);
    glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &read_fbo);
    glGetIntegerv(GL_VIEWPORT, viewport);
    clear_target(gl, &ip);
    glBeginQuery(GL_TIME_ELAPSED, gl->time_query);
    render_passes(gl, batches, path, frames, ip.wireframe);
    glEndQuery(GL_TIME_ELAPSED);
    gl->timed = true;
    read_back(gl, &ip, rgba);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, (GLuint)draw_fbo);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, (GLuint)read_fbo);
    glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
    r = gl_check(diag, "rendering");
    if (r != XYL_OK) return r;
    flip_rows(rgba, ip.width, ip.height);
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- capture: instanced path -------------------------------------------------------------- */

/* First capture slot of each patch: a running sum over the instances, so slots follow the
 * instance order. The shader indexes offsets by patch, so a patch may appear only once. */
static xyl_result capture_offsets(xyl_tess_gl *gl, const xyl_tess_batches *b, uint32_t **out,
                                  size_t *total, xyl_diag *diag)
{
    uint32_t *off = xyl__alloc_array(&gl->alloc, gl->patch_count, sizeof *off);
    if (!off) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    for (size_t p = 0; p < gl->patch_count; ++p) off[p] = UINT32_MAX;
    size_t at = 0;
    for (size_t i = 0; i < b->instance_count; ++i) {
        const xyl_tess_instance *in = &b->instances[i];
        if (off[in->patch] != UINT32_MAX || at > UINT32_MAX / 2) {
            xyl__free(&gl->alloc, off);
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)i,
                             "instance %zu: patch %u drawn twice or too many vertices", i,
                             in->patch);
        }
        off[in->patch] = (uint32_t)at;
        at += range_of(gl, in->kind, in->level)->vertex_count;
    }
    for (size_t p = 0; p < gl->patch_count; ++p)
        if (off[p] == UINT32_MAX) off[p] = 0; /* not drawn: never read */
    *out = off;
    *total = at;
    return XYL_OK;
}

static xyl_result run_capture_draw(xyl_tess_gl *gl, const xyl_tess_batches *b,
                                   const uint32_t *offsets, size_t total, xyl_diag *diag)
{
    drain_errors();
    glNamedBufferData(gl->offset_buf, (GLsizeiptr)((gl->patch_count ? gl->patch_count : 1) * 4),
                      offsets, GL_STREAM_DRAW);
    glNamedBufferData(gl->capture_buf, (GLsizeiptr)(total * CAPTURE_SLOT_BYTES), NULL,
                      GL_STREAM_READ);
    xyl_result r = gl_check(diag, "allocating the capture buffer");
    if (r != XYL_OK) return r;
    bind_storage(gl);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_TESS_BINDING_CAPTURE, gl->capture_buf);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_TESS_BINDING_OFFSETS, gl->offset_buf);
    glEnable(GL_RASTERIZER_DISCARD);
    draw_instanced(gl, b, gl->prog_capture, 0);
    glDisable(GL_RASTERIZER_DISCARD);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT); /* shader writes, then a buffer read */
    return gl_check(diag, "capturing");
}

/* Slots hold what the GPU computed; (i, j, level) and the patch come from the instances. */
static void fill_instanced(const xyl_tess_gl *gl, const xyl_tess_batches *b, const float *slots,
                           size_t n, xyl__tess_captured *out)
{
    size_t base = 0;
    for (size_t i = 0; i < b->instance_count && base < n; ++i) {
        const xyl_tess_instance *in = &b->instances[i];
        const xyl_tess_pattern_range *r = range_of(gl, in->kind, in->level);
        for (uint32_t v = 0; v < r->vertex_count; ++v) {
            uint32_t pk = gl->pattern_vertices[r->first_vertex + v];
            size_t s = base + (pk >> XYL_TESS_PATTERN_SHIFT_LOCAL);
            if (s >= n) continue;
            memcpy(out[s].position, slots + 8 * s, 3 * sizeof(float));
            memcpy(out[s].normal, slots + 8 * s + 4, 3 * sizeof(float));
            out[s].coord[0] = (float)(pk & 0xffu);
            out[s].coord[1] = (float)((pk >> XYL_TESS_PATTERN_SHIFT_J) & 0xffu);
            out[s].coord[2] = (float)in->level;
            out[s].patch = in->patch;
        }
        base += r->vertex_count;
    }
}

static xyl_result capture_instanced(xyl_tess_gl *gl, const xyl_tess_batches *b,
                                    xyl__tess_captured *out, size_t capacity, size_t *count,
                                    xyl_diag *diag)
{
    uint32_t *offsets = NULL;
    size_t total = 0;
    xyl_result r = capture_offsets(gl, b, &offsets, &total, diag);
    if (r != XYL_OK) return r;
    size_t n = capacity < total ? capacity : total;
    float *slots = NULL;
    if ((GLint64)(total * CAPTURE_SLOT_BYTES) > gl->max_ssbo_bytes)
        r = xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                      "%zu captured vertices exceed the driver's storage block size", total);
    else if (n && !(slots = xyl__alloc_array(&gl->alloc, n, CAPTURE_SLOT_BYTES)))
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    if (r == XYL_OK && total) r = run_capture_draw(gl, b, offsets, total, diag);
    if (r == XYL_OK && n) {
        glGetNamedBufferSubData(gl->capture_buf, 0, (GLsizeiptr)(n * CAPTURE_SLOT_BYTES), slots);
        r = gl_check(diag, "reading the capture back");
    }
    if (r == XYL_OK) {
        fill_instanced(gl, b, slots, n, out);
        *count = total;
    }
    xyl__free(&gl->alloc, slots);
    xyl__free(&gl->alloc, offsets);
    return r;
}

/* ---- capture: hardware path --------------------------------------------------------------- */

/* The tessellator's triangle count is not the pattern's (an inner level 2 triangle gives 6, not
 * 4), but 2 L^2 bounds both domains; the generated-primitives query catches any excess. */
static size_t hardware_bound(const xyl_tess_batches *b)
{
    size_t tris = 0;
    for (size_t i = 0; i < b->instance_count; ++i)
        tris += 2u * (size_t)b->instances[i].level * b->instances[i].level;
    return 3 * tris;
}

/* One transform feedback session per kind, the second appending after the first. */
static xyl_result run_feedback(xyl_tess_gl *gl, const xyl_tess_batches *b, size_t bound,
                               GLuint64 written[2], GLuint64 generated[2], xyl_diag *diag)
{
    size_t bytes = (bound + 3) * XFB_VERTEX_BYTES, offset = 0;
    if (bytes / XFB_VERTEX_BYTES != bound + 3 || bytes > MAX_READBACK_BYTES)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1, "%zu captured vertices", bound);
    drain_errors();
    glNamedBufferData(gl->xfb_buf, (GLsizeiptr)bytes, NULL, GL_STREAM_READ);
    xyl_result r = gl_check(diag, "allocating the transform feedback buffer");
    if (r != XYL_OK) return r;
    bind_storage(gl);
    glEnable(GL_RASTERIZER_DISCARD);
    for (int k = 0; k < 2; ++k) {
        glBindBufferRange(GL_TRANSFORM_FEEDBACK_BUFFER, 0, gl->xfb_buf, (GLintptr)offset,
                          (GLsizeiptr)(bytes - offset));
        glBeginQuery(GL_PRIMITIVES_GENERATED, gl->generated_query);
        glBeginQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN, gl->written_query);
        draw_hardware_kind(gl, b, k ? XYL_TESS_KIND_TRIANGLE : XYL_TESS_KIND_QUAD, 0, true);
        glEndQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN);
        glEndQuery(GL_PRIMITIVES_GENERATED);
        glGetQueryObjectui64v(gl->written_query, GL_QUERY_RESULT, &written[k]);
        glGetQueryObjectui64v(gl->generated_query, GL_QUERY_RESULT, &generated[k]);
        offset += (size_t)written[k] * 3 * XFB_VERTEX_BYTES;
    }
    glDisable(GL_RASTERIZER_DISCARD);
    glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, 0);
    return gl_check(diag, "capturing with transform feedback");
}

static xyl_result capture_hardware(xyl_tess_gl *gl, const xyl_tess_batches *b,
                                   xyl__tess_captured *out, size_t capacity, size_t *count,
                                   xyl_diag *diag)
{
    GLuint64 written[2] = {0}, generated[2] = {0};
    xyl_result r = run_feedback(gl, b, hardware_bound(b), written, generated, diag);
    if (r == XYL_OK && (generated[0] > written[0] || generated[1] > written[1]))
        r = run_feedback(gl, b, (size_t)(3 * (generated[0] + generated[1])), written, generated,
                         diag); /* the bound was short: once more with the real size */
    if (r == XYL_OK && (generated[0] > written[0] || generated[1] > written[1]))
        r = xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                      "transform feedback wrote %llu of %llu triangles",
                      (unsigned long long)(written[0] + written[1]),
                      (unsigned long long)(generated[0] + generated[1]));
    if (r != XYL_OK) return r;
    size_t total = (size_t)(3 * (written[0] + written[1]));
    size_t n = capacity < total ? capacity : total;
    if (n) glGetNamedBufferSubData(gl->xfb_buf, 0, (GLsizeiptr)(n * XFB_VERTEX_BYTES), out);
    r = gl_check(diag, "reading the transform feedback back");
    if (r == XYL_OK) *count = total;
    return r;
}

xyl_result xyl__tess_gl_capture(xyl_tess_gl *gl, const xyl_tess_batches *batches,
                                xyl_tess_variant variant, xyl_tess_path path,
                                xyl__tess_captured *out, size_t capacity, size_t *count,
                                xyl_diag *diag)
{
    if (!count || (capacity && !out))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "count, and out when capacity > 0, are required");
    xyl_result r = check_common(gl, batches, (uint32_t)variant, path, diag);
    xyl_tess_frame frame = {0};
    frame.variant = (uint32_t)variant;
    if (r == XYL_OK) r = upload_batches(gl, batches, &frame, 1, diag);
    if (r != XYL_OK) return r;
    GLint draw_fbo = 0;
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &draw_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, gl->capture_fbo);
    r = path == XYL_TESS_PATH_INSTANCED ? capture_instanced(gl, batches, out, capacity, count, diag)
                                        : capture_hardware(gl, batches, out, capacity, count, diag);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, (GLuint)draw_fbo);
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

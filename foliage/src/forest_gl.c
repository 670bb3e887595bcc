/* The GL 4.5 forest renderer (xyl_forest_gl.h): per species the packed leaves, the leaf levels,
 * the stems' base mesh and a borrowed billboard; per frame the flat CPU choice of forest.c,
 * the visible instances sorted by species and level into one storage buffer, and a few
 * instanced draws per species. */
#include <epoxy/gl.h>
#include <math.h>
#include <string.h>
#include <time.h>

#include "billboard_gl_internal.h"
#include "foliage_draw.h"
#include "foliage_gl_util.h"
#include "foliage_internal.h"
#include "forest_internal.h"
#include "xylem/xyl_foliage_gl.h"
#include "xylem/xyl_forest_gl.h"

extern const unsigned char xyl__shader_gl_forest_leaf_vert[];
extern const unsigned char xyl__shader_gl_forest_leaf_list_vert[];
extern const unsigned char xyl__shader_gl_foliage_cut_comp[];
extern const unsigned char xyl__shader_gl_forest_leaf_frag[];
extern const unsigned char xyl__shader_gl_forest_stem_vert[];
extern const unsigned char xyl__shader_gl_forest_stem_frag[];
extern const unsigned char xyl__shader_gl_forest_billboard_vert[];
extern const unsigned char xyl__shader_gl_forest_billboard_frag[];
extern const unsigned char xyl__shader_gl_forest_impostor_vert[];
extern const unsigned char xyl__shader_gl_forest_impostor_frag[];

#define BB_UNIFORM_LIGHT 6  /* billboard.frag's */
#define BB_UNIFORM_CUTOFF 7
#define BB_UNIFORM_BAKE_LIGHT 8
#define BB_UNIFORM_TO_COVERAGE 9
#define BB_UNIFORM_DITHER 10
#define IMP_UNIFORM_CENTER 2 /* impostor.vert's and .frag's */
#define IMP_UNIFORM_RADIUS 3
#define IMP_UNIFORM_GRID 4

typedef struct species {
    GLuint leaf_buf, stem_vao, stem_vbo, stem_ibo;
    GLuint node_buf; /* the collapse forest's nodes for the per-leaf cut */
    uint32_t leaf_count;
    xyl__forest_plan plan;
    uint32_t stem_index_count, stem_levels;
    xyl_billboard_gl *billboard;
    float billboard_error, center_y, radius;
} species;

struct xyl_forest_gl {
    GLuint leaf_program, stem_program, bb_program, imp_program, vao, instance_buf, texture;
    GLuint list_program, cut_program, list_buf, command_buf; /* the per-leaf instances */
    GLsizeiptr list_capacity;                                /* bytes */
    GLint ssbo_align;
    uint32_t near[XYL_FOREST_MAX_PER_LEAF]; /* this frame's per-leaf instances, by species */
    uint32_t near_count;
    GLsizeiptr instance_capacity; /* bytes */
    species species[XYL_FOREST_MAX_SPECIES];
    uint32_t species_count;
    xyl_forest_instance *instances, *sorted; /* sorted: room for every instance twice */
    uint16_t *bucket, *fine_bucket;         /* per instance, per frame */
    uint8_t *share;                         /* per instance, per frame: its fade */
    size_t count;
    uint64_t max_instances;
    uint32_t max_levels;
    float hysteresis;
    GLint64 max_ssbo_bytes;
    GLint max_texture_side;
    xyl_allocator alloc;
};

_Static_assert(sizeof(xyl_forest_instance) == 16, "std430 stride of xyl_forest_instance");

static double now_ms(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* ---- programs ----------------------------------------------------------------------------- */

static xyl_result link(const unsigned char *vs, const unsigned char *fs, const char *name,
                       GLuint *out, xyl_diag *diag)
{
    char log[192] = "";
    const GLenum stages[2] = {GL_VERTEX_SHADER, GL_FRAGMENT_SHADER};
    const unsigned char *texts[2] = {vs, fs};
    GLuint p = glCreateProgram();
    for (int i = 0; i < 2; ++i) {
        GLuint sh = xyl__fgl_compile(stages[i], texts[i], log, (GLsizei)sizeof log);
        if (!sh) {
            glDeleteProgram(p);
            return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "shader of %s: %s", name, log);
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
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "program %s: %s", name, log);
    }
    *out = p;
    return XYL_OK;
}

static xyl_result link_compute(const unsigned char *cs, GLuint *out, xyl_diag *diag)
{
    char log[192] = "";
    GLuint sh = xyl__fgl_compile(GL_COMPUTE_SHADER, cs, log, (GLsizei)sizeof log);
    if (!sh) return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "shader of the cut: %s", log);
    GLuint p = glCreateProgram();
    glAttachShader(p, sh);
    glDeleteShader(sh);
    glLinkProgram(p);
    GLint ok = GL_FALSE;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        glGetProgramInfoLog(p, (GLsizei)sizeof log, NULL, log);
        glDeleteProgram(p);
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "program of the cut: %s", log);
    }
    *out = p;
    return XYL_OK;
}

static xyl_result check_desc(const xyl_forest_gl_desc *d, xyl_diag *diag)
{
    if (!isfinite(d->hysteresis))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "hysteresis is not finite");
    if (d->hysteresis > 1.0f || d->max_levels > XYL_FOREST_MAX_LEVELS)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "hysteresis %g (at most 1) or max_levels %u (at most %d)",
                         (double)d->hysteresis, d->max_levels, XYL_FOREST_MAX_LEVELS);
    if (d->max_instances > XYL_FOREST_LIMIT_MAX_INSTANCES)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "max_instances %llu is over the limit of %llu",
                         (unsigned long long)d->max_instances,
                         (unsigned long long)XYL_FOREST_LIMIT_MAX_INSTANCES);
    return XYL_OK;
}

xyl_result xyl_forest_gl_create(const xyl_forest_gl_desc *desc, xyl_forest_gl **out,
                                xyl_diag *diag)
{
    if (!out) return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "out is required");
    xyl_forest_gl_desc d = {0};
    if (desc) d = *desc;
    xyl_result r = check_desc(&d, diag);
    if (r == XYL_OK) r = xyl__fgl_need_context(diag);
    if (r != XYL_OK) return r;
    xyl_forest_gl *f = xyl__calloc(&d.alloc, 1, sizeof *f);
    if (!f) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    f->alloc = d.alloc;
    f->max_instances = d.max_instances ? d.max_instances : XYL_FOREST_DEFAULT_MAX_INSTANCES;
    f->max_levels = d.max_levels ? d.max_levels : XYL_FOREST_MAX_LEVELS;
    f->hysteresis = d.hysteresis > 0.0f ? d.hysteresis : d.hysteresis < 0.0f ? 0.0f : 0.1f;
    xyl__fgl_drain_errors();
    r = link(xyl__shader_gl_forest_leaf_vert, xyl__shader_gl_forest_leaf_frag, "forest_leaf",
             &f->leaf_program, diag);
    if (r == XYL_OK)
        r = link(xyl__shader_gl_forest_stem_vert, xyl__shader_gl_forest_stem_frag, "forest_stem",
                 &f->stem_program, diag);
    if (r == XYL_OK)
        r = link(xyl__shader_gl_forest_billboard_vert, xyl__shader_gl_forest_billboard_frag,
                 "forest_billboard", &f->bb_program, diag);
    if (r == XYL_OK)
        r = link(xyl__shader_gl_forest_impostor_vert, xyl__shader_gl_forest_impostor_frag,
                 "forest_impostor", &f->imp_program, diag);
    if (r == XYL_OK)
        r = link(xyl__shader_gl_forest_leaf_list_vert, xyl__shader_gl_forest_leaf_frag,
                 "forest_leaf_list", &f->list_program, diag);
    if (r == XYL_OK) r = link_compute(xyl__shader_gl_foliage_cut_comp, &f->cut_program, diag);
    if (r == XYL_OK) {
        glCreateVertexArrays(1, &f->vao);
        glCreateBuffers(1, &f->list_buf);
        glCreateBuffers(1, &f->command_buf);
        glGetIntegerv(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT, &f->ssbo_align);
        if (f->ssbo_align < 16) f->ssbo_align = 16;
        glCreateBuffers(1, &f->instance_buf);
        glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &f->max_ssbo_bytes);
        glGetIntegerv(GL_MAX_TEXTURE_SIZE, &f->max_texture_side);
        const uint8_t white[4] = {255, 255, 255, 255};
        f->texture = xyl__fgl_leaf_texture(white, 1, 1);
        r = xyl__fgl_check(diag, "creating the forest renderer's objects");
    }
    if (r != XYL_OK) {
        xyl_forest_gl_destroy(f);
        return r;
    }
    *out = f;
    xyl__diag_ok(diag);
    return XYL_OK;
}

static void species_free(xyl_forest_gl *f, species *s, bool gl)
{
    if (gl) {
        GLuint bufs[4] = {s->leaf_buf, s->stem_vbo, s->stem_ibo, s->node_buf};
        glDeleteBuffers(4, bufs);
        glDeleteVertexArrays(1, &s->stem_vao);
    }
    xyl__forest_plan_free(&s->plan, &f->alloc);
}

void xyl_forest_gl_destroy(xyl_forest_gl *f)
{
    if (!f) return;
    bool gl = epoxy_gl_version() != 0;
    if (gl) {
        glDeleteProgram(f->leaf_program);
        glDeleteProgram(f->stem_program);
        glDeleteProgram(f->bb_program);
        glDeleteProgram(f->imp_program);
        glDeleteProgram(f->list_program);
        glDeleteProgram(f->cut_program);
        GLuint bufs[2] = {f->list_buf, f->command_buf};
        glDeleteBuffers(2, bufs);
        glDeleteVertexArrays(1, &f->vao);
        glDeleteBuffers(1, &f->instance_buf);
        glDeleteTextures(1, &f->texture);
    }
    for (uint32_t s = 0; s < f->species_count; ++s) species_free(f, &f->species[s], gl);
    xyl_allocator a = f->alloc;
    xyl__free(&a, f->instances);
    xyl__free(&a, f->sorted);
    xyl__free(&a, f->bucket);
    xyl__free(&a, f->fine_bucket);
    xyl__free(&a, f->share);
    xyl__free(&a, f);
}

/* ---- species ------------------------------------------------------------------------------ */

static xyl_result check_species(const xyl_forest_gl *f, const xyl_forest_gl_species_desc *d,
                                xyl_diag *diag)
{
    if (f->species_count >= XYL_FOREST_MAX_SPECIES)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the forest has %d species already, the most an instance can name",
                         XYL_FOREST_MAX_SPECIES);
    if (!isfinite(d->billboard_error) || !isfinite(d->stem_width))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1,
                         "billboard_error or stem_width is not finite");
    if (d->billboard_error < 0.0f || d->stem_width < 0.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "billboard_error %g and stem_width %g must not be negative",
                         (double)d->billboard_error, (double)d->stem_width);
    const xyl_mesh *m = d->stems;
    if (m && (m->tri_view_count == 0 || !m->tri_view || !m->positions || !m->normals ||
              m->vertex_count > UINT32_MAX || m->tri_view_count > UINT32_MAX / 3))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the stem mesh has no triangles, positions or normals");
    size_t n = d->foliage->leaf_count;
    if ((GLint64)(n * sizeof(xyl_foliage_gpu_leaf)) > f->max_ssbo_bytes)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu leaves exceed the driver's storage block size", n);
    for (size_t k = 0; m && k < m->tri_view_count * 3; ++k)
        if (m->tri_view[k] >= m->vertex_count)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)(k / 3),
                             "stem triangle %zu names a vertex beyond the mesh", k / 3);
    return XYL_OK;
}

/* The sphere on the +Y axis that holds the box lo..hi however the instance turns. */
static void axis_sphere(const float lo[3], const float hi[3], float *cy, float *radius)
{
    double rx = fmax(fabs(lo[0]), fabs(hi[0])), rz = fmax(fabs(lo[2]), fabs(hi[2]));
    double hh = 0.5 * ((double)hi[1] - lo[1]);
    *cy = 0.5f * (lo[1] + hi[1]);
    *radius = (float)sqrt(rx * rx + rz * rz + hh * hh);
}

static xyl_result upload_stems(species *s, const xyl_mesh *m, const xyl_allocator *a,
                               xyl_diag *diag)
{
    float *v = xyl__alloc_array(a, m->vertex_count, 6 * sizeof *v);
    if (!v) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    for (size_t i = 0; i < m->vertex_count; ++i) {
        const xyl_vec3 p = m->positions[i], nn = m->normals[i];
        const float e[6] = {p.x, p.y, p.z, nn.x, nn.y, nn.z};
        memcpy(v + 6 * i, e, sizeof e);
    }
    glCreateBuffers(1, &s->stem_vbo);
    glCreateBuffers(1, &s->stem_ibo);
    glNamedBufferStorage(s->stem_vbo, (GLsizeiptr)(m->vertex_count * 6 * sizeof *v), v, 0);
    glNamedBufferStorage(s->stem_ibo, (GLsizeiptr)(m->tri_view_count * 3 * sizeof(uint32_t)),
                         m->tri_view, 0);
    xyl__free(a, v);
    glCreateVertexArrays(1, &s->stem_vao);
    glVertexArrayVertexBuffer(s->stem_vao, 0, s->stem_vbo, 0, 6 * sizeof(float));
    glVertexArrayElementBuffer(s->stem_vao, s->stem_ibo);
    for (GLuint k = 0; k < 2; ++k) {
        glEnableVertexArrayAttrib(s->stem_vao, k);
        glVertexArrayAttribFormat(s->stem_vao, k, 3, GL_FLOAT, GL_FALSE, k * 3 * sizeof(float));
        glVertexArrayAttribBinding(s->stem_vao, k, 0);
    }
    s->stem_index_count = (uint32_t)(m->tri_view_count * 3);
    return XYL_OK;
}

static void resolve_species(species *s, const xyl_forest_gl_species_desc *d)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    xyl_foliage_bounds(d->foliage, lo, hi);
    if (d->stems) xyl_mesh_bounds(d->stems, lo, hi);
    axis_sphere(lo, hi, &s->center_y, &s->radius);
    const xyl__forest_plan *p = &s->plan;
    float coarsest = p->levels[p->level_count - 1].error;
    double rx = fmax(fabs(lo[0]), fabs(hi[0])), rz = fmax(fabs(lo[2]), fabs(hi[2]));
    float flat = (float)sqrt(rx * rx + rz * rz);
    s->billboard = d->billboard;
    s->billboard_error = fmaxf(d->billboard_error > 0.0f ? d->billboard_error : flat, coarsest);
    s->stem_levels = p->level_count;
    if (d->stem_width > 0.0f) {
        s->stem_levels = 1;
        while (s->stem_levels < p->level_count && p->levels[s->stem_levels].error < d->stem_width)
            ++s->stem_levels;
    }
}

xyl_result xyl_forest_gl_add_species(xyl_forest_gl *f, const xyl_forest_gl_species_desc *d,
                                     uint32_t *index, xyl_diag *diag)
{
    if (!f || !d || !d->foliage || !index)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "forest, desc, desc->foliage and index are required");
    xyl__foliage_tables tables; /* the tables' checks: no leaves, ranges outside the array */
    xyl_result r = xyl__foliage_tables_make(d->foliage, &f->alloc, &tables, diag);
    if (r != XYL_OK) return r;
    xyl__foliage_tables_free(&tables, &f->alloc);
    r = check_species(f, d, diag);
    if (r != XYL_OK) return r;
    species s;
    memset(&s, 0, sizeof s);
    size_t n = d->foliage->leaf_count;
    xyl_foliage_gpu_leaf *records = xyl__alloc_array(&f->alloc, n, sizeof *records);
    xyl__foliage_cut_node *nodes = xyl__alloc_array(&f->alloc, n, sizeof *nodes);
    if (!records || !nodes) {
        xyl__free(&f->alloc, records);
        xyl__free(&f->alloc, nodes);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    }
    r = xyl_foliage_pack_gpu(d->foliage->leaves, n, records, diag);
    if (r == XYL_OK) r = xyl__foliage_cut_nodes(d->foliage, nodes, diag);
    if (r == XYL_OK) r = xyl__forest_plan_make(d->foliage, f->max_levels, &f->alloc, &s.plan, diag);
    if (r == XYL_OK) {
        xyl__fgl_drain_errors();
        glCreateBuffers(1, &s.leaf_buf);
        glNamedBufferStorage(s.leaf_buf, (GLsizeiptr)(n * sizeof *records), records, 0);
        glCreateBuffers(1, &s.node_buf);
        glNamedBufferStorage(s.node_buf, (GLsizeiptr)(n * sizeof *nodes), nodes, 0);
        s.leaf_count = (uint32_t)n;
        if (d->stems) r = upload_stems(&s, d->stems, &f->alloc, diag);
        if (r == XYL_OK) r = xyl__fgl_check(diag, "uploading a species");
    }
    xyl__free(&f->alloc, records);
    xyl__free(&f->alloc, nodes);
    if (r != XYL_OK) {
        species_free(f, &s, true);
        return r;
    }
    resolve_species(&s, d);
    *index = f->species_count;
    f->species[f->species_count++] = s;
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_result xyl_forest_gl_set_texture(xyl_forest_gl *f, const uint8_t *rgba, uint32_t width,
                                     uint32_t height, xyl_diag *diag)
{
    if (!f || !rgba)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "forest and rgba are required");
    return xyl__fgl_replace_leaf_texture(&f->texture, f->max_texture_side, rgba, width, height,
                                         diag);
}

xyl_result xyl_forest_gl_species(const xyl_forest_gl *f, uint32_t sp,
                                 xyl_forest_gl_species_info *info, xyl_diag *diag)
{
    if (!f || !info || sp >= f->species_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "forest and info are required, and species %u must have been added", sp);
    const species *s = &f->species[sp];
    memset(info, 0, sizeof *info);
    info->level_count = s->plan.level_count;
    for (uint32_t k = 0; k < s->plan.level_count; ++k) {
        info->level_error[k] = s->plan.levels[k].error;
        info->level_leaves[k] = s->plan.levels[k].leaves;
    }
    info->stem_levels = s->stem_levels;
    info->has_billboard = s->billboard != NULL;
    info->billboard_error = s->billboard_error;
    info->center_y = s->center_y;
    info->radius = s->radius;
    info->stem_triangles = s->stem_index_count / 3;
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- instances ---------------------------------------------------------------------------- */

static xyl_result check_instances(const xyl_forest_gl *f, const xyl_forest_instance *in,
                                  size_t n, xyl_diag *diag)
{
    if (n == 0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a forest of 0 instances: give at least one");
    if (n > f->max_instances)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu instances exceed max_instances (%llu)", n,
                         (unsigned long long)f->max_instances);
    for (size_t i = 0; i < n; ++i) {
        uint32_t p = in[i].bits, sp = (p >> 8) & 63u, lod = p & 255u;
        if (!isfinite(in[i].position[0]) || !isfinite(in[i].position[1]) ||
            !isfinite(in[i].position[2]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)i,
                             "instance %zu's position is not finite", i);
        if (sp >= f->species_count)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)i,
                             "instance %zu names species %u of %u", i, sp, f->species_count);
        const species *s = &f->species[sp];
        bool ok = lod == XYL_FOREST_LOD_BILLBOARD ? s->billboard != NULL
                                                  : lod < s->plan.level_count;
        if (!ok)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)i,
                             "instance %zu has LOD %u; species %u has levels 0 to %u%s", i, lod,
                             sp, s->plan.level_count - 1,
                             s->billboard ? " and a billboard" : " and no billboard");
    }
    return XYL_OK;
}

xyl_result xyl_forest_gl_set_instances(xyl_forest_gl *f, const xyl_forest_instance *in,
                                       size_t n, xyl_diag *diag)
{
    if (!f || (!in && n))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "forest, and instances with a count, are required");
    xyl_result r = check_instances(f, in, n, diag);
    if (r != XYL_OK) return r;
    xyl_forest_instance *copy = xyl__alloc_array(&f->alloc, n, sizeof *copy);
    xyl_forest_instance *sorted = xyl__alloc_array(&f->alloc, 2 * n, sizeof *sorted);
    uint16_t *bucket = xyl__alloc_array(&f->alloc, n, sizeof *bucket);
    uint16_t *fine_bucket = xyl__alloc_array(&f->alloc, n, sizeof *fine_bucket);
    uint8_t *share = xyl__alloc_array(&f->alloc, n, sizeof *share);
    if (!copy || !sorted || !bucket || !fine_bucket || !share) {
        xyl__free(&f->alloc, copy);
        xyl__free(&f->alloc, sorted);
        xyl__free(&f->alloc, bucket);
        xyl__free(&f->alloc, fine_bucket);
        xyl__free(&f->alloc, share);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    }
    memcpy(copy, in, n * sizeof *copy);
    xyl__free(&f->alloc, f->instances);
    xyl__free(&f->alloc, f->sorted);
    xyl__free(&f->alloc, f->bucket);
    xyl__free(&f->alloc, f->fine_bucket);
    xyl__free(&f->alloc, f->share);
    f->instances = copy, f->sorted = sorted, f->bucket = bucket, f->count = n;
    f->fine_bucket = fine_bucket, f->share = share;
    xyl__diag_ok(diag);
    return XYL_OK;
}

const xyl_forest_instance *xyl_forest_gl_instances(const xyl_forest_gl *f, size_t *count)
{
    if (count) *count = f ? f->count : 0;
    return f ? f->instances : NULL;
}

/* ---- a frame ------------------------------------------------------------------------------ */

typedef struct resolved {
    xyl__foliage_frame leaf;  /* view_proj, light, leaf colour, cutoff, translucency */
    float stem_color[4];
    float eye[3];
    double per_distance;
} resolved;

static xyl_result check_frame(const xyl_forest_gl *f, const xyl_forest_gl_frame *fr,
                              resolved *out, xyl_diag *diag)
{
    if (!f || !fr)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "forest and frame are required");
    if (f->count == 0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "no instances (set_instances first)");
    /* the eye, fovy, viewport and budget as xyl_foliage_pick takes them, but a budget of 0 is
     * refused rather than defaulted */
    const xyl_foliage_view view = {{fr->eye[0], fr->eye[1], fr->eye[2]}, fr->fovy,
                                   fr->viewport_height, fr->error_px};
    double eye[3];
    xyl_result r = xyl__foliage_view_resolve(&view, eye, &out->per_distance, diag);
    if (r != XYL_OK) return r;
    for (int k = 0; k < 4; ++k)
        if (!isfinite(fr->stem_color[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "stem_color is not finite");
    if (!(fr->error_px > 0.0f))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a pixel budget of %g: error_px must be > 0", (double)fr->error_px);
    if (!isfinite(fr->fade))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "fade is not finite");
    if (fr->fade < 0.0f || fr->fade > XYL_FOREST_MAX_FADE)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a fade band of %g: from 0 (none) to %g times the switch distance",
                         (double)fr->fade, (double)XYL_FOREST_MAX_FADE);
    if (fr->per_leaf > XYL_FOREST_MAX_PER_LEAF)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "per_leaf %u: at most %d instances get a cut of their own",
                         fr->per_leaf, XYL_FOREST_MAX_PER_LEAF);
    if (fr->mode != XYL_FOREST_LOD && fr->mode != XYL_FOREST_LEAF_LEVELS &&
        fr->mode != XYL_FOREST_FULL)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "unknown forest mode %d (lod 0, leaf levels 1, full 2)", (int)fr->mode);
    const float no_dither[2] = {0.0f, 0.0f}; /* every fragment */
    const xyl__foliage_frame_in in = {fr->view_proj, fr->light_dir, fr->leaf_color, no_dither,
                                      fr->alpha_cutoff, 0.0f};
    r = xyl__foliage_frame_resolve(&in, &out->leaf, diag);
    if (r != XYL_OK) return r;
    const float bark[4] = {0.47f, 0.35f, 0.24f, 1.0f};
    bool none = fr->stem_color[0] == 0.0f && fr->stem_color[1] == 0.0f &&
                fr->stem_color[2] == 0.0f && fr->stem_color[3] == 0.0f;
    memcpy(out->stem_color, none ? bark : fr->stem_color, sizeof out->stem_color);
    memcpy(out->eye, fr->eye, sizeof out->eye);
    return XYL_OK;
}

/* Level k's band: from its threshold t_k to t_k (1 + fade), cut at the next larger threshold
 * so that bands never overlap and the share reaches 1 where the next band starts. */
static void fade_bands(xyl__forest_choice_species *c, double r, float fade)
{
    double t[XYL__FOREST_BUCKETS_PER_SPECIES + 1];
    for (uint32_t k = 0; k <= c->top; ++k) t[k] = k ? sqrt((double)c->refine2[k]) - r : 0.0;
    for (uint32_t k = 1; k <= c->top; ++k) {
        uint32_t fine = k - 1;
        while (fine > 0 && !(t[fine] < t[k])) --fine;
        double end = t[k] * (1.0 + fade);
        for (uint32_t j = k + 1; j <= c->top; ++j)
            if (t[j] > t[k]) {
                end = fmin(end, t[j]);
                break;
            }
        c->fine[k] = (uint8_t)fine;
        if (!(end > t[k]) || !isfinite(end)) continue;
        c->band_lo[k] = (float)(t[k] + r);
        c->band_inv[k] = (float)(1.0 / (end - t[k]));
        c->band_end2[k] = (float)((end + r) * (end + r));
    }
}

static void choice_species(const xyl_forest_gl *f, const xyl_forest_gl_frame *fr,
                           double per_distance, xyl__forest_choice_species *cs)
{
    for (uint32_t s = 0; s < f->species_count; ++s) {
        const species *sp = &f->species[s];
        xyl__forest_choice_species *c = &cs[s];
        memset(c, 0, sizeof *c);
        c->center_y = sp->center_y;
        c->radius = sp->radius;
        c->level_count = sp->plan.level_count;
        bool bb = sp->billboard && fr->mode == XYL_FOREST_LOD;
        double r = sp->radius, grow = 1.0 + f->hysteresis;
        for (uint32_t k = 1; k <= c->level_count; ++k) {
            double t = k < c->level_count ? sp->plan.levels[k].error / per_distance
                       : bb ? sp->billboard_error / per_distance : INFINITY;
            c->refine2[k] = (float)((t + r) * (t + r));
            c->coarsen2[k] = (float)((t * grow + r) * (t * grow + r));
        }
        c->top = bb ? c->level_count : c->level_count - 1;
        if (fr->fade > 0.0f) fade_bands(c, r, fr->fade);
    }
}

/* Quads an instance's billboard draws: one per plane, one for an impostor. */
static uint32_t quads_of(xyl_billboard_gl *bb)
{
    xyl__billboard_parts bp;
    xyl__billboard_gl_parts(bb, &bp);
    return bp.kind == XYL_BILLBOARD_OCTAHEDRAL ? 1 : bp.views;
}

static void count_stats(const xyl_forest_gl *f, const uint32_t *counts, size_t twice,
                        xyl_forest_gl_stats *st)
{
    for (uint32_t s = 0; s < f->species_count; ++s) {
        const species *sp = &f->species[s];
        const uint32_t *c = counts + s * XYL__FOREST_BUCKETS_PER_SPECIES;
        for (uint32_t k = 0; k < sp->plan.level_count; ++k) {
            st->per_level[k] += c[k];
            st->visible += c[k];
            st->leaves += (uint64_t)c[k] * sp->plan.levels[k].leaves;
            if (k < sp->stem_levels && sp->stem_index_count) {
                st->with_stems += c[k];
                st->triangles += (uint64_t)c[k] * (sp->stem_index_count / 3);
            }
        }
        uint32_t nb = c[sp->plan.level_count];
        st->per_level[XYL_FOREST_MAX_LEVELS] += nb;
        st->visible += nb;
        if (nb && sp->billboard) st->triangles += 2ull * nb * quads_of(sp->billboard);
    }
    st->triangles += 2 * st->leaves;
    st->faded = twice;
    st->visible -= twice;
}

_Static_assert(XYL__FOREST_NEAR_MAX == XYL_FOREST_MAX_PER_LEAF, "the choice's heap holds per_leaf");

/* The nearest instances the choice gathered (h) leave their buckets (both, when fading) for
 * f->near, ordered by species. Returns the instances taken out of the fade's doubled ones. */
static size_t take_near(xyl_forest_gl *f, const xyl__forest_near *h, bool fade, uint32_t *counts)
{
    uint32_t heap[XYL_FOREST_MAX_PER_LEAF], n = h->count;
    memcpy(heap, h->index, n * sizeof *heap);
    size_t twice = 0;
    for (uint32_t k = 0; k < n; ++k) {
        uint32_t i = heap[k];
        --counts[f->bucket[i]];
        if (fade && f->share[i]) --counts[f->fine_bucket[i]], ++twice;
        f->bucket[i] = UINT16_MAX;
    }
    /* by species (insertion sort of at most 64), so that their stems are one draw a species */
    for (uint32_t k = 1; k < n; ++k) {
        uint32_t x = heap[k], j = k, sx = (f->instances[x].bits >> 8) & 63u;
        while (j > 0 && ((f->instances[heap[j - 1]].bits >> 8) & 63u) > sx) heap[j] = heap[j - 1], --j;
        heap[j] = x;
    }
    memcpy(f->near, heap, n * sizeof *heap);
    f->near_count = n;
    return twice;
}

/* The choice and the sort; counts and offsets per bucket. */
static void choose_sort(xyl_forest_gl *f, const xyl_forest_gl_frame *fr, const resolved *rs,
                        uint32_t *counts, uint32_t *offsets, xyl_forest_gl_stats *st)
{
    double t0 = now_ms();
    xyl__forest_choice_species cs[XYL_FOREST_MAX_SPECIES];
    choice_species(f, fr, rs->per_distance, cs);
    xyl__forest_choice c;
    memset(&c, 0, sizeof c);
    c.species = cs;
    c.species_count = f->species_count;
    memcpy(c.eye, fr->eye, sizeof c.eye);
    c.cull = !fr->no_cull && xyl__forest_cone(rs->leaf.view_proj, c.axis, &c.inv_sin, &c.cos2);
    c.full = fr->mode == XYL_FOREST_FULL;
    c.fade = !c.full && fr->fade > 0.0f;
    xyl__forest_near near;
    near.max = fr->per_leaf && !c.full ? fr->per_leaf : 0;
    size_t twice = xyl__forest_choose(&c, f->instances, f->count, f->bucket, f->fine_bucket,
                                      f->share, counts, &near);
    f->near_count = 0;
    if (near.count) twice -= take_near(f, &near, c.fade, counts);
    uint32_t total = f->species_count * XYL__FOREST_BUCKETS_PER_SPECIES;
    xyl__forest_sort(f->instances, f->count, f->bucket, f->fine_bucket, c.fade ? f->share : NULL,
                     counts, total, offsets, f->sorted);
    for (uint32_t k = 0; k < f->near_count; ++k) { /* after the buckets, drawn every pixel */
        xyl_forest_instance x = f->instances[f->near[k]];
        x.bits &= ~255u;
        f->sorted[offsets[total] + k] = x;
    }
    memset(st, 0, sizeof *st);
    st->choose_ms = now_ms() - t0;
    st->instances = f->count;
    st->bytes_per_instance = XYL_FOREST_INSTANCE_SIZE;
    count_stats(f, counts, twice, st);
    st->per_leaf = f->near_count;
    st->visible += f->near_count;
}

xyl_result xyl_forest_gl_choose(xyl_forest_gl *f, const xyl_forest_gl_frame *fr,
                                xyl_forest_gl_stats *stats, xyl_diag *diag)
{
    resolved rs;
    xyl_result r = check_frame(f, fr, &rs, diag);
    if (r != XYL_OK) return r;
    uint32_t counts[XYL_FOREST_MAX_SPECIES * XYL__FOREST_BUCKETS_PER_SPECIES];
    uint32_t offsets[XYL_FOREST_MAX_SPECIES * XYL__FOREST_BUCKETS_PER_SPECIES + 1];
    xyl_forest_gl_stats st;
    choose_sort(f, fr, &rs, counts, offsets, &st);
    if (stats) *stats = st;
    xyl__diag_ok(diag);
    return XYL_OK;
}

static xyl_result upload_sorted(xyl_forest_gl *f, uint32_t visible, xyl_diag *diag)
{
    GLsizeiptr bytes = (GLsizeiptr)((visible ? visible : 1) * sizeof(xyl_forest_instance));
    if (bytes > f->max_ssbo_bytes)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%u visible instances exceed the driver's storage block size", visible);
    if (bytes > f->instance_capacity) {
        glNamedBufferData(f->instance_buf, bytes, NULL, GL_STREAM_DRAW);
        f->instance_capacity = bytes;
    } else {
        glInvalidateBufferData(f->instance_buf);
    }
    if (visible)
        glNamedBufferSubData(f->instance_buf, 0, (GLsizeiptr)(visible * sizeof *f->sorted),
                             f->sorted);
    return xyl__fgl_check(diag, "uploading the forest's instances");
}

/* A bucket's leaves: per range of its level, draws of as many instances as GLsizei holds. */
static uint64_t draw_leaf_bucket(const xyl_forest_gl *f, const species *sp, uint32_t level,
                                 uint32_t first, uint32_t count)
{
    const xyl__forest_level *lv = &sp->plan.levels[level];
    GLuint p = f->leaf_program;
    uint64_t draws = 0;
    for (uint32_t r = 0; r < lv->range_count; ++r) {
        const xyl__forest_range *rg = &sp->plan.ranges[lv->first_range + r];
        uint32_t chunk = (uint32_t)(INT32_MAX / rg->count);
        glProgramUniform1ui(p, XYL_FOREST_GL_UNIFORM_FIRST, rg->first);
        glProgramUniform1ui(p, XYL_FOREST_GL_UNIFORM_LENGTH, rg->count);
        for (uint32_t at = 0; at < count; at += chunk) {
            uint32_t n = count - at < chunk ? count - at : chunk;
            glProgramUniform1ui(p, XYL_FOREST_GL_UNIFORM_INSTANCE, first + at);
            glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, (GLsizei)(n * rg->count));
            ++draws;
        }
    }
    return draws;
}

static uint64_t draw_leaves(const xyl_forest_gl *f, const resolved *rs, const uint32_t *counts,
                            const uint32_t *offsets)
{
    GLuint p = f->leaf_program;
    glUseProgram(p);
    xyl__fgl_leaf_uniforms(p, &rs->leaf);
    glBindVertexArray(f->vao);
    glBindTextureUnit(XYL_FOLIAGE_GL_BINDING_TEXTURE, f->texture);
    uint64_t draws = 0;
    for (uint32_t s = 0; s < f->species_count; ++s) {
        const species *sp = &f->species[s];
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_FOLIAGE_GL_BINDING_LEAVES, sp->leaf_buf);
        for (uint32_t k = 0; k < sp->plan.level_count; ++k) {
            uint32_t b = s * XYL__FOREST_BUCKETS_PER_SPECIES + k;
            if (counts[b]) draws += draw_leaf_bucket(f, sp, k, offsets[b], counts[b]);
        }
    }
    return draws;
}

/* Stems for the levels under stem_levels: their buckets are consecutive in the sort. */
static uint64_t draw_stems(const xyl_forest_gl *f, const resolved *rs, const uint32_t *counts,
                           const uint32_t *offsets)
{
    GLuint p = f->stem_program;
    glUseProgram(p);
    glProgramUniformMatrix4fv(p, XYL_FOLIAGE_GL_UNIFORM_VIEW_PROJ, 1, GL_FALSE, rs->leaf.view_proj);
    glProgramUniform3fv(p, XYL_FOLIAGE_GL_UNIFORM_LIGHT, 1, rs->leaf.light);
    glProgramUniform4fv(p, XYL_FOREST_GL_UNIFORM_STEM_COLOR, 1, rs->stem_color);
    uint64_t draws = 0;
    for (uint32_t s = 0; s < f->species_count; ++s) {
        const species *sp = &f->species[s];
        uint32_t b = s * XYL__FOREST_BUCKETS_PER_SPECIES, n = 0;
        for (uint32_t k = 0; k < sp->stem_levels; ++k) n += counts[b + k];
        if (!sp->stem_index_count || !n) continue;
        glBindVertexArray(sp->stem_vao);
        glProgramUniform1ui(p, XYL_FOREST_GL_UNIFORM_INSTANCE, offsets[b]);
        glDrawElementsInstanced(GL_TRIANGLES, (GLsizei)sp->stem_index_count, GL_UNSIGNED_INT,
                                NULL, (GLsizei)n);
        ++draws;
    }
    return draws;
}

static uint64_t draw_billboards(const xyl_forest_gl *f, const xyl_forest_gl_frame *fr,
                                const resolved *rs, const uint32_t *counts,
                                const uint32_t *offsets)
{
    GLuint p = f->bb_program;
    glUseProgram(p);
    glProgramUniformMatrix4fv(p, 0, 1, GL_FALSE, rs->leaf.view_proj);
    glProgramUniform3fv(p, XYL_FOREST_GL_UNIFORM_EYE, 1, fr->eye);
    glProgramUniform3fv(p, BB_UNIFORM_LIGHT, 1, rs->leaf.light);
    glProgramUniform1f(p, BB_UNIFORM_CUTOFF, rs->leaf.cutoff);
    glProgramUniform2fv(p, BB_UNIFORM_DITHER, 1, rs->leaf.dither);
    glBindVertexArray(f->vao);
    uint64_t draws = 0;
    for (uint32_t s = 0; s < f->species_count; ++s) {
        const species *sp = &f->species[s];
        uint32_t b = s * XYL__FOREST_BUCKETS_PER_SPECIES + sp->plan.level_count;
        if (!sp->billboard || !counts[b]) continue;
        xyl__billboard_parts bp;
        xyl__billboard_gl_parts(sp->billboard, &bp);
        if (bp.kind == XYL_BILLBOARD_OCTAHEDRAL) continue; /* draw_impostors' */
        glProgramUniform1ui(p, XYL_FOREST_GL_UNIFORM_INSTANCE, offsets[b]);
        glProgramUniform3fv(p, XYL_FOREST_GL_UNIFORM_BB_CENTER, 1, bp.center);
        glProgramUniform2fv(p, XYL_FOREST_GL_UNIFORM_BB_HALF, 1, bp.half);
        glProgramUniform1i(p, XYL_FOREST_GL_UNIFORM_BB_KIND, bp.kind);
        glProgramUniform1i(p, XYL_FOREST_GL_UNIFORM_BB_PLANES, (GLint)bp.views);
        glProgramUniform3fv(p, BB_UNIFORM_BAKE_LIGHT, 1, bp.bake_light);
        glProgramUniform1i(p, BB_UNIFORM_TO_COVERAGE, 0); /* alpha-tested at the cutoff */
        glBindTextureUnit(0, bp.color_tex);
        glBindTextureUnit(1, bp.normal_tex);
        glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, (GLsizei)(counts[b] * bp.views));
        ++draws;
    }
    return draws;
}

/* Octahedral impostors: impostor.vert/.frag's uniforms, the eye and light per instance. */
static uint64_t draw_impostors(const xyl_forest_gl *f, const xyl_forest_gl_frame *fr,
                               const resolved *rs, const uint32_t *counts,
                               const uint32_t *offsets)
{
    GLuint p = f->imp_program;
    glUseProgram(p);
    glProgramUniformMatrix4fv(p, 0, 1, GL_FALSE, rs->leaf.view_proj);
    glProgramUniform3fv(p, XYL_FOREST_GL_UNIFORM_EYE, 1, fr->eye);
    glProgramUniform3fv(p, XYL_FOREST_GL_UNIFORM_LIGHT, 1, rs->leaf.light);
    glProgramUniform1f(p, BB_UNIFORM_CUTOFF, rs->leaf.cutoff);
    glProgramUniform2fv(p, BB_UNIFORM_DITHER, 1, rs->leaf.dither);
    glProgramUniform1i(p, BB_UNIFORM_TO_COVERAGE, 0); /* alpha-tested at the cutoff */
    glBindVertexArray(f->vao);
    uint64_t draws = 0;
    for (uint32_t s = 0; s < f->species_count; ++s) {
        const species *sp = &f->species[s];
        uint32_t b = s * XYL__FOREST_BUCKETS_PER_SPECIES + sp->plan.level_count;
        if (!sp->billboard || !counts[b]) continue;
        xyl__billboard_parts bp;
        xyl__billboard_gl_parts(sp->billboard, &bp);
        if (bp.kind != XYL_BILLBOARD_OCTAHEDRAL) continue;
        glProgramUniform1ui(p, XYL_FOREST_GL_UNIFORM_INSTANCE, offsets[b]);
        glProgramUniform3fv(p, IMP_UNIFORM_CENTER, 1, bp.center);
        glProgramUniform1f(p, IMP_UNIFORM_RADIUS, bp.half[0]);
        glProgramUniform1i(p, IMP_UNIFORM_GRID, (GLint)bp.grid);
        glProgramUniform3fv(p, BB_UNIFORM_BAKE_LIGHT, 1, bp.bake_light);
        glBindTextureUnit(0, bp.color_tex);
        glBindTextureUnit(1, bp.normal_tex);
        glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, (GLsizei)counts[b]);
        ++draws;
    }
    return draws;
}

/* The list and command buffers for this frame's per-leaf instances: each a range of its own,
 * at offsets the storage buffer alignment allows. */
static GLsizeiptr align_up(GLsizeiptr x, GLint a)
{
    return (x + a - 1) / a * a;
}

static xyl_result near_buffers(xyl_forest_gl *f, GLsizeiptr *list_at, GLsizeiptr *cmd_stride,
                               xyl_diag *diag)
{
    GLsizeiptr at = 0;
    for (uint32_t k = 0; k < f->near_count; ++k) {
        const species *sp = &f->species[(f->instances[f->near[k]].bits >> 8) & 63u];
        list_at[k] = at;
        at = align_up(at + (GLsizeiptr)sp->leaf_count * 4, f->ssbo_align);
    }
    if (at > f->max_ssbo_bytes)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "the per-leaf instances' lists exceed the driver's storage block size");
    if (at > f->list_capacity) {
        glNamedBufferData(f->list_buf, at, NULL, GL_DYNAMIC_COPY);
        f->list_capacity = at;
    }
    *cmd_stride = align_up(16, f->ssbo_align);
    uint32_t cmds[XYL_FOREST_MAX_PER_LEAF * 64];
    GLsizeiptr words = *cmd_stride / 4;
    if (words > 64) return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                                     "a storage buffer alignment of %d bytes", f->ssbo_align);
    memset(cmds, 0, sizeof cmds);
    for (uint32_t k = 0; k < f->near_count; ++k) cmds[k * words] = 4; /* vertices a leaf */
    glNamedBufferData(f->command_buf, (GLsizeiptr)f->near_count * *cmd_stride, cmds,
                      GL_DYNAMIC_COPY);
    return XYL_OK;
}

/* Per-leaf instances: per instance one cut (foliage_cut.comp, the eye in the instance's own
 * frame, the same per-distance budget since both the errors and the distances are then in
 * species units), then per instance one indirect draw of its list, and its stems. With st,
 * the cuts' sizes are read back (a wait for the GPU) and counted. */
static xyl_result draw_near(xyl_forest_gl *f, const resolved *rs, uint32_t first,
                            xyl_forest_gl_stats *st, xyl_diag *diag)
{
    GLsizeiptr list_at[XYL_FOREST_MAX_PER_LEAF], stride = 0;
    xyl_result r = near_buffers(f, list_at, &stride, diag);
    if (r != XYL_OK) return r;
    GLuint c = f->cut_program;
    glUseProgram(c);
    glProgramUniform1f(c, XYL_FOLIAGE_GL_UNIFORM_CUT_PER_DISTANCE, (float)rs->per_distance);
    for (uint32_t k = 0; k < f->near_count; ++k) {
        xyl_forest_instance_values v;
        xyl_forest_instance_unpack(&f->instances[f->near[k]], &v);
        const species *sp = &f->species[v.species];
        float cs = cosf(v.rotation), sn = sinf(v.rotation), e[3];
        for (int i = 0; i < 3; ++i) e[i] = (rs->eye[i] - v.position[i]) / v.scale;
        glProgramUniform3f(c, XYL_FOLIAGE_GL_UNIFORM_CUT_EYE, cs * e[0] - sn * e[2], e[1],
                           sn * e[0] + cs * e[2]);
        glProgramUniform1ui(c, XYL_FOLIAGE_GL_UNIFORM_CUT_COUNT, sp->leaf_count);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_FOLIAGE_GL_BINDING_NODES, sp->node_buf);
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, XYL_FOLIAGE_GL_BINDING_LIST, f->list_buf,
                          list_at[k], (GLsizeiptr)sp->leaf_count * 4);
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, XYL_FOLIAGE_GL_BINDING_COMMAND,
                          f->command_buf, (GLintptr)k * stride, 16);
        glDispatchCompute((sp->leaf_count + XYL_FOLIAGE_GL_CUT_GROUP - 1) / XYL_FOLIAGE_GL_CUT_GROUP,
                          1, 1);
    }
    glMemoryBarrier(GL_COMMAND_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    GLuint p = f->list_program;
    glUseProgram(p);
    xyl__fgl_leaf_uniforms(p, &rs->leaf);
    glBindVertexArray(f->vao);
    glBindTextureUnit(XYL_FOLIAGE_GL_BINDING_TEXTURE, f->texture);
    GLint indirect = 0;
    glGetIntegerv(GL_DRAW_INDIRECT_BUFFER_BINDING, &indirect);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, f->command_buf);
    for (uint32_t k = 0; k < f->near_count; ++k) {
        const species *sp = &f->species[(f->instances[f->near[k]].bits >> 8) & 63u];
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_FOLIAGE_GL_BINDING_LEAVES, sp->leaf_buf);
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, XYL_FOLIAGE_GL_BINDING_LIST, f->list_buf,
                          list_at[k], (GLsizeiptr)sp->leaf_count * 4);
        glProgramUniform1ui(p, XYL_FOREST_GL_UNIFORM_INSTANCE, first + k);
        glDrawArraysIndirect(GL_TRIANGLE_STRIP, (const void *)(uintptr_t)((GLsizeiptr)k * stride));
    }
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, (GLuint)indirect);
    uint64_t draws = f->near_count, tris = 0, stems = 0;
    /* stems: one draw per species' run (near is ordered by species) */
    GLuint sp_prog = f->stem_program;
    glUseProgram(sp_prog);
    glProgramUniformMatrix4fv(sp_prog, XYL_FOLIAGE_GL_UNIFORM_VIEW_PROJ, 1, GL_FALSE,
                              rs->leaf.view_proj);
    glProgramUniform3fv(sp_prog, XYL_FOLIAGE_GL_UNIFORM_LIGHT, 1, rs->leaf.light);
    glProgramUniform4fv(sp_prog, XYL_FOREST_GL_UNIFORM_STEM_COLOR, 1, rs->stem_color);
    for (uint32_t k = 0; k < f->near_count;) {
        uint32_t s = (f->instances[f->near[k]].bits >> 8) & 63u, n = 1;
        while (k + n < f->near_count && ((f->instances[f->near[k + n]].bits >> 8) & 63u) == s) ++n;
        const species *sp = &f->species[s];
        if (sp->stem_index_count) {
            glBindVertexArray(sp->stem_vao);
            glProgramUniform1ui(sp_prog, XYL_FOREST_GL_UNIFORM_INSTANCE, first + k);
            glDrawElementsInstanced(GL_TRIANGLES, (GLsizei)sp->stem_index_count, GL_UNSIGNED_INT,
                                    NULL, (GLsizei)n);
            ++draws;
            tris += (uint64_t)n * (sp->stem_index_count / 3);
            stems += n;
        }
        k += n;
    }
    if (st) {
        st->draws += draws;
        st->triangles += tris;
        st->with_stems += stems;
        uint32_t cmds[XYL_FOREST_MAX_PER_LEAF * 64];
        glGetNamedBufferSubData(f->command_buf, 0, (GLsizeiptr)f->near_count * stride, cmds);
        for (uint32_t k = 0; k < f->near_count; ++k) {
            uint64_t leaves = cmds[k * (stride / 4) + 1];
            st->leaves += leaves;
            st->triangles += 2 * leaves;
        }
    }
    return xyl__fgl_check(diag, "drawing the per-leaf instances");
}

xyl_result xyl_forest_gl_draw(xyl_forest_gl *f, const xyl_forest_gl_frame *fr,
                              xyl_forest_gl_stats *stats, xyl_diag *diag)
{
    resolved rs;
    xyl_result r = check_frame(f, fr, &rs, diag);
    if (r != XYL_OK) return r;
    uint32_t counts[XYL_FOREST_MAX_SPECIES * XYL__FOREST_BUCKETS_PER_SPECIES];
    uint32_t offsets[XYL_FOREST_MAX_SPECIES * XYL__FOREST_BUCKETS_PER_SPECIES + 1];
    xyl_forest_gl_stats st;
    choose_sort(f, fr, &rs, counts, offsets, &st);
    xyl__fgl_drain_errors();
    double t0 = now_ms();
    r = upload_sorted(f, offsets[f->species_count * XYL__FOREST_BUCKETS_PER_SPECIES] + f->near_count,
                      diag);
    st.upload_ms = now_ms() - t0;
    if (r != XYL_OK) return r;
    GLboolean cull = glIsEnabled(GL_CULL_FACE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, XYL_FOREST_GL_BINDING_INSTANCES, f->instance_buf);
    st.draws = draw_stems(f, &rs, counts, offsets);
    st.draws += draw_leaves(f, &rs, counts, offsets);
    st.draws += draw_billboards(f, fr, &rs, counts, offsets);
    st.draws += draw_impostors(f, fr, &rs, counts, offsets);
    if (f->near_count)
        r = draw_near(f, &rs, offsets[f->species_count * XYL__FOREST_BUCKETS_PER_SPECIES],
                      stats ? &st : NULL, diag);
    glBindVertexArray(0);
    if (cull) glEnable(GL_CULL_FACE);
    if (r == XYL_OK) r = xyl__fgl_check(diag, "drawing the forest");
    if (r != XYL_OK) return r;
    if (stats) *stats = st;
    xyl__diag_ok(diag);
    return XYL_OK;
}

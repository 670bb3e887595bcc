/* Mesh export: Wavefront OBJ text and glTF 2.0 binary (.glb), both rendered here by hand
 * (docs/mesh-export.md describes the layouts).
 *
 * In memory both writers count, then fill, so a too-small buffer is refused before a byte of it
 * is touched: OBJ text is counted by rendering it, a GLB is sized from its document
 * (glb_write.h, shared with foliage/'s writer, which puts a mesh's part next to its leaves).
 * xyl_mesh_write_file renders OBJ text once, into a growing buffer. Nothing depends on the C
 * locale or the host's byte order (glb_write.h). */
#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "glb_write.h"
#include "mesh_internal.h"

/* Branch ids travel as float: glTF allows UNSIGNED_INT only for indices, and a float holds every
 * integer up to 2^24 exactly. */
#define MAX_FLOAT_EXACT_ID (UINT32_C(1) << 24)
typedef xyl__sink sink;

/* ==== checking a view ======================================================================== */

/* What the writers read: everything of a mesh (the seams are split where it has wraps). */
#define WRITER_READS (XYL__SPLIT_SEAMS_READS | XYL__MESH_TRI_VIEW)

/* A GLB's own limit on a valid view: its branch ids travel as floats. */
static xyl_result check_float_ids(const xyl_mesh *m, xyl_diag *diag)
{
    for (size_t v = 0; v < m->vertex_count; ++v)
        if (m->branch_ids[v] > MAX_FLOAT_EXACT_ID)
            return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, (int64_t)v,
                             "vertex %zu has branch id %u; a GLB stores ids up to %u exactly", v,
                             m->branch_ids[v], (unsigned)MAX_FLOAT_EXACT_ID);
    return XYL_OK;
}

/* ==== OBJ ==================================================================================== */

static void obj_vec(sink *s, const char *tag, const float *c, int n)
{
    xyl__put_str(s, tag);
    for (int k = 0; k < n; ++k) {
        xyl__put_str(s, " ");
        xyl__put_float(s, c[k]);
    }
    xyl__put_str(s, "\n");
}

/* A position in world coordinates: origin + p summed in double, as the shortest text that
 * reads back as that double. */
static void obj_world(sink *s, const double origin[3], const float p[3])
{
    xyl__put_str(s, "v");
    for (int k = 0; k < 3; ++k) {
        xyl__put_str(s, " ");
        xyl__put_double(s, origin[k] + (double)p[k]);
    }
    xyl__put_str(s, "\n");
}

/* Positions (in world coordinates) and normals of m; UVs of uvm, m with its seams split (or m
 * itself), whose first vertices are m's. With origin 0 a position is its floats, as before
 * meshes had origins. */
static void obj_vertices(const xyl_mesh *m, const xyl_mesh *uvm, sink *s)
{
    const bool world = m->origin[0] != 0.0 || m->origin[1] != 0.0 || m->origin[2] != 0.0;
    for (size_t v = 0; v < m->vertex_count && !s->overflow; ++v) {
        const float p[3] = {m->positions[v].x, m->positions[v].y, m->positions[v].z};
        if (world) obj_world(s, m->origin, p);
        else obj_vec(s, "v", p, 3);
    }
    for (size_t v = 0; v < uvm->vertex_count && !s->overflow; ++v)
        obj_vec(s, "vt", uvm->uvs + 2 * v, 2);
    for (size_t v = 0; v < m->vertex_count && !s->overflow; ++v) {
        const float n[3] = {m->normals[v].x, m->normals[v].y, m->normals[v].z};
        obj_vec(s, "vn", n, 3);
    }
}

/* Position and normal share the vertex index, the UV is the split mesh's corner: "f a/a'/a",
 * 1-based, where a' = a except at a seam. */
static void obj_face(sink *s, const uint32_t *f, const uint32_t *ft, int n)
{
    xyl__put_str(s, "f");
    for (int k = 0; k < n; ++k) {
        uint64_t i = (uint64_t)f[k] + 1;
        xyl__put_str(s, " ");
        xyl__put_uint(s, i);
        xyl__put_str(s, "/");
        xyl__put_uint(s, (uint64_t)ft[k] + 1);
        xyl__put_str(s, "/");
        xyl__put_uint(s, i);
    }
    xyl__put_str(s, "\n");
}

/* A "g branch_<id>" line wherever the face branch changes, so each branch can be picked in a
 * modeller; a branch whose faces are not contiguous gets the same name again, which readers
 * merge into one group. uvm: as obj_vertices (same faces in the same order). */
static void obj_faces(const xyl_mesh *m, const xyl_mesh *uvm, sink *s)
{
    size_t faces = m->quad_count + m->triangle_count;
    for (size_t f = 0; f < faces && !s->overflow; ++f) {
        if (f == 0 || m->face_branches[f] != m->face_branches[f - 1]) {
            xyl__put_str(s, "g branch_");
            xyl__put_uint(s, m->face_branches[f]);
            xyl__put_str(s, "\n");
        }
        if (f < m->quad_count) {
            obj_face(s, m->quads + 4 * f, uvm->quads + 4 * f, 4);
        } else {
            size_t t = 3 * (f - m->quad_count);
            obj_face(s, m->triangles + t, uvm->triangles + t, 3);
        }
    }
}

static void render_obj(const xyl_mesh *m, const xyl_mesh *uvm, sink *s)
{
    xyl__put_str(s, "# xylem mesh: ");
    xyl__put_uint(s, m->vertex_count);
    xyl__put_str(s, " vertices, ");
    xyl__put_uint(s, m->quad_count);
    xyl__put_str(s, " quads, ");
    xyl__put_uint(s, m->triangle_count);
    xyl__put_str(s, " triangles\n");
    obj_vertices(m, uvm, s);
    obj_faces(m, uvm, s);
}

/* ==== GLB ==================================================================================== */

/* Unit normals pass bit for bit; others are renormalised (a zero one becomes +Y), since glTF
 * requires NORMAL to be unit. */
static void emit_positions(const void *ctx, sink *s)
{
    const xyl_mesh *m = ctx;
    for (size_t v = 0; v < m->vertex_count; ++v) {
        xyl__put_f32le(s, m->positions[v].x);
        xyl__put_f32le(s, m->positions[v].y);
        xyl__put_f32le(s, m->positions[v].z);
    }
}

static void emit_normals(const void *ctx, sink *s)
{
    const xyl_mesh *m = ctx;
    for (size_t v = 0; v < m->vertex_count; ++v) {
        xyl_vec3 n = xyl__glb_unit_normal(m->normals[v]);
        xyl__put_f32le(s, n.x);
        xyl__put_f32le(s, n.y);
        xyl__put_f32le(s, n.z);
    }
}

static void emit_uvs(const void *ctx, sink *s)
{
    const xyl_mesh *m = ctx;
    for (size_t i = 0; i < 2 * m->vertex_count; ++i) xyl__put_f32le(s, m->uvs[i]);
}

static void emit_branch_ids(const void *ctx, sink *s)
{
    const xyl_mesh *m = ctx;
    for (size_t v = 0; v < m->vertex_count; ++v) xyl__put_f32le(s, (float)m->branch_ids[v]);
}

static void emit_indices(const void *ctx, sink *s)
{
    const xyl_mesh *m = ctx;
    for (size_t i = 0; i < 3 * m->tri_view_count; ++i) xyl__put_u32le(s, m->tri_view[i]);
}

/* One view per attribute, then the indices, each tightly packed, accessor i on view i of the
 * part; from the counts alone. */
static void add_views(const xyl_mesh *m, xyl__glb *g)
{
    uint64_t nv = m->vertex_count, ni = 3 * (uint64_t)m->tri_view_count;
    static const struct {
        xyl__glb_emit_fn emit;
        const char *type;
        int component;
        unsigned bytes;
        int target;
    } kinds[] = {
        {emit_positions, "VEC3", XYL__GL_FLOAT, 12, XYL__GL_ARRAY_BUFFER},
        {emit_normals, "VEC3", XYL__GL_FLOAT, 12, XYL__GL_ARRAY_BUFFER},
        {emit_uvs, "VEC2", XYL__GL_FLOAT, 8, XYL__GL_ARRAY_BUFFER},
        {emit_branch_ids, "SCALAR", XYL__GL_FLOAT, 4, XYL__GL_ARRAY_BUFFER},
        {emit_indices, "SCALAR", XYL__GL_UNSIGNED_INT, 4, XYL__GL_ELEMENT_ARRAY_BUFFER},
    };
    for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; ++k) {
        uint64_t count = k == 4 ? ni : nv; /* < 2^34: no overflow */
        uint32_t v = xyl__glb_add_view(g, count * kinds[k].bytes, kinds[k].target, kinds[k].emit, m);
        xyl__glb_add_accessor(g, v, kinds[k].component, kinds[k].type, count);
    }
}

/* The part's views from the counts, refused when the file could not hold them; g is restored
 * to *mark first (the views and accessors before the part). */
static xyl_result size_part(const xyl_mesh *m, xyl__glb *g, const xyl__glb *mark, xyl_diag *diag)
{
    g->view_count = mark->view_count;
    g->accessor_count = mark->accessor_count;
    if (m->vertex_count && !m->tri_view_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a GLB mesh needs at least one face (%zu vertices, no faces)",
                         m->vertex_count);
    if (m->vertex_count > UINT32_MAX || m->tri_view_count > UINT32_MAX)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu vertices and %zu triangles do not fit in a GLB's 4 GiB",
                         m->vertex_count, m->tri_view_count);
    add_views(m, g);
    uint64_t total = xyl__glb_layout(g);
    return total > UINT32_MAX ? xyl__glb_too_large(total, diag) : XYL_OK;
}

static void position_bounds(const xyl_mesh *m, xyl__glb_accessor *a)
{
    a->bounds = true;
    a->min = a->max = m->positions[0];
    for (size_t v = 1; v < m->vertex_count; ++v) {
        xyl_vec3 p = m->positions[v];
        a->min.x = fminf(a->min.x, p.x);
        a->min.y = fminf(a->min.y, p.y);
        a->min.z = fminf(a->min.z, p.z);
        a->max.x = fmaxf(a->max.x, p.x);
        a->max.y = fmaxf(a->max.y, p.y);
        a->max.z = fmaxf(a->max.z, p.z);
    }
}

static bool has_wraps(const xyl_mesh *m)
{
    for (size_t f = 0; m->uv_wraps && f < m->quad_count + m->triangle_count; ++f)
        if (m->uv_wraps[f]) return true;
    return false;
}

xyl_result xyl__glb_mesh_add(const xyl_mesh *m, const xyl_allocator *alloc, xyl__glb *g,
                             xyl__glb_mesh *out, xyl_diag *diag)
{
    const xyl__glb mark = {.view_count = g->view_count, .accessor_count = g->accessor_count};
    xyl__glb_mesh p = {m, NULL, g->accessor_count, false};
    /* a view's size is checked before its arrays are read */
    xyl_result r = size_part(m, g, &mark, diag);
    if (r == XYL_OK) r = xyl__mesh_validate(m, WRITER_READS, diag);
    if (r == XYL_OK) r = check_float_ids(m, diag);
    if (r == XYL_OK && has_wraps(m)) r = xyl__mesh_split_seams(m, alloc, &p.split, diag);
    /* the split only adds vertices: its part is sized again */
    if (r == XYL_OK && p.split) r = size_part(p.mesh = p.split, g, &mark, diag);
    if (r != XYL_OK) {
        xyl_mesh_destroy(p.split);
        g->view_count = mark.view_count;
        g->accessor_count = mark.accessor_count;
        return r;
    }
    /* glTF has no empty accessor or buffer: an empty mesh is no glTF mesh at all */
    p.empty = p.mesh->vertex_count == 0;
    if (p.empty) {
        g->view_count = mark.view_count;
        g->accessor_count = mark.accessor_count;
    } else {
        position_bounds(p.mesh, &g->accessors[p.first_accessor]);
    }
    *out = p;
    return XYL_OK;
}

void xyl__glb_mesh_json(const xyl__glb_mesh *p, sink *s)
{
    xyl__glb_mesh_json_open(p, s);
    xyl__put_str(s, "}");
}

void xyl__glb_mesh_json_open(const xyl__glb_mesh *p, sink *s)
{
    static const char *const keys[] = {("{\"name\":\"stems\",\"primitives\":[{\"attributes\":{"
                                        "\"POSITION\":"),
                                       ",\"NORMAL\":", ",\"TEXCOORD_0\":", ",\"_BRANCH_ID\":",
                                       "},\"indices\":"};
    for (uint32_t k = 0; k < 5; ++k) {
        xyl__put_str(s, keys[k]);
        xyl__put_uint(s, p->first_accessor + k);
    }
    xyl__put_str(s, ",\"mode\":");
    xyl__put_uint(s, XYL__GL_TRIANGLES);
    xyl__put_str(s, "}]");
}

void xyl__glb_mesh_free(xyl__glb_mesh *p)
{
    xyl_mesh_destroy(p->split);
    p->split = NULL;
}

/* A mesh alone: one node, "xylem", with the mesh, or without one when it is empty. */
static void mesh_body(const void *ctx, sink *s)
{
    const xyl__glb_mesh *p = ctx;
    xyl__put_str(s, "\"scenes\":[{\"nodes\":[0]}],");
    if (p->empty) {
        xyl__put_str(s, "\"nodes\":[{\"name\":\"xylem\"}]");
        return;
    }
    xyl__put_str(s, "\"nodes\":[{\"name\":\"xylem\",\"mesh\":0");
    xyl__put_json_translation(s, p->mesh->origin);
    xyl__put_str(s, "}],\"meshes\":[");
    xyl__glb_mesh_json(p, s);
    xyl__put_str(s, "]");
}

/* The document of a mesh alone; on success p holds the part (xyl__glb_mesh_free). */
static xyl_result mesh_glb(const xyl_mesh *m, const xyl_allocator *alloc, xyl__glb *g,
                           xyl__glb_mesh *p, xyl_diag *diag)
{
    memset(g, 0, sizeof *g);
    xyl_result r = xyl__glb_mesh_add(m, alloc, g, p, diag);
    if (r != XYL_OK) return r;
    g->body = mesh_body;
    g->body_ctx = p;
    r = xyl__glb_finish(g, diag);
    if (r != XYL_OK) xyl__glb_mesh_free(p);
    return r;
}

/* ==== public entry points ==================================================================== */

/* What prepare() learnt of an OBJ: the size (size_output) and the split mesh. */
typedef struct plan {
    size_t size; /* bytes, without the NUL the text gets in memory */
    xyl_mesh *split; /* the mesh with its UV seams split, where it has any (plan_free) */
} plan;

static void plan_free(plan *p)
{
    xyl_mesh_destroy(p->split);
    p->split = NULL;
}

/* The mesh whose vertices carry the UVs the file writes: the split one, else m. */
static const xyl_mesh *uv_mesh(const xyl_mesh *m, const plan *p)
{
    return p->split ? p->split : m;
}

static bool format_ok(xyl_mesh_format format)
{
    return format == XYL_MESH_FORMAT_OBJ || format == XYL_MESH_FORMAT_GLB;
}

/* On success the plan may hold the split mesh (plan_free); on failure it holds nothing. */
static xyl_result prepare_obj(const xyl_mesh *m, const xyl_allocator *alloc, plan *p,
                              xyl_diag *diag)
{
    p->split = NULL;
    p->size = 0;
    xyl_result r = xyl__mesh_validate(m, WRITER_READS, diag);
    if (r == XYL_OK && has_wraps(m)) r = xyl__mesh_split_seams(m, alloc, &p->split, diag);
    return r;
}

/* The exact size of the OBJ text into p->size, counted by rendering it. On failure the plan is
 * freed. */
static xyl_result size_obj(const xyl_mesh *m, plan *p)
{
    sink count = {NULL, 0, false, 0, NULL};
    render_obj(m, uv_mesh(m, p), &count);
    p->size = count.len;
    if (!count.overflow) return XYL_OK;
    plan_free(p);
    return XYL_ERR_OUT_OF_MEMORY; /* the OBJ text would not fit in memory */
}

static xyl_result write_memory_glb(const xyl_mesh *mesh, const xyl_allocator *alloc,
                                   void *buffer, size_t capacity, size_t *needed)
{
    xyl__glb g;
    xyl__glb_mesh part;
    xyl_result r = mesh_glb(mesh, alloc, &g, &part, NULL);
    if (r != XYL_OK) return r;
    r = xyl__glb_write_memory(&g, buffer, capacity, needed, NULL);
    xyl__glb_mesh_free(&part);
    return r;
}

xyl_result xyl_mesh_write_memory(const xyl_mesh *mesh, xyl_mesh_format format,
                                 const xyl_allocator *alloc, void *buffer, size_t capacity,
                                 size_t *needed)
{
    if (!mesh || !format_ok(format) || (!buffer && !needed)) return XYL_ERR_INVALID_ARGUMENT;
    if (format == XYL_MESH_FORMAT_GLB) return write_memory_glb(mesh, alloc, buffer, capacity, needed);
    plan p;
    xyl_result r = prepare_obj(mesh, alloc, &p, NULL);
    if (r == XYL_OK) r = size_obj(mesh, &p);
    if (r != XYL_OK) return r;
    if (needed) *needed = p.size;
    /* OBJ is text and gets a terminating NUL, as xyl_skeleton_write_text; GLB is bytes. */
    if (buffer && capacity < p.size + 1) {
        r = XYL_ERR_INVALID_ARGUMENT;
    } else if (buffer) {
        sink fill = {buffer, 0, false, 0, NULL};
        render_obj(mesh, uv_mesh(mesh, &p), &fill);
        assert(!fill.overflow && fill.len == p.size);
        fill.buf[fill.len] = '\0';
    }
    plan_free(&p);
    return r;
}

static xyl_result write_file_glb(const xyl_mesh *mesh, const char *path,
                                 const xyl_allocator *alloc, xyl_diag *diag)
{
    xyl__glb g;
    xyl__glb_mesh part;
    xyl_result r = mesh_glb(mesh, alloc, &g, &part, diag);
    if (r != XYL_OK) return r;
    r = xyl__glb_write_file(&g, path, alloc, diag);
    xyl__glb_mesh_free(&part);
    return r;
}

xyl_result xyl_mesh_write_file(const xyl_mesh *mesh, const char *path, xyl_mesh_format format,
                               const xyl_allocator *alloc, xyl_diag *diag)
{
    if (!mesh || !path || !*path || !format_ok(format))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "mesh and path must be given and the format must be OBJ or GLB");
    xyl_result r;
    if (format == XYL_MESH_FORMAT_GLB) {
        r = write_file_glb(mesh, path, alloc, diag);
        if (r == XYL_OK) xyl__diag_ok(diag);
        return r;
    }
    /* OBJ text is rendered once, into a buffer that grows, not counted first: formatting the
     * floats is most of its cost */
    plan p;
    r = prepare_obj(mesh, alloc, &p, diag);
    if (r != XYL_OK) return r;
    sink out = {NULL, 0, false, (size_t)1 << 16, alloc};
    out.buf = xyl__alloc(alloc, out.cap);
    if (out.buf) render_obj(mesh, uv_mesh(mesh, &p), &out);
    plan_free(&p);
    if (!out.buf || out.overflow) {
        xyl__free(alloc, out.buf);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the OBJ text");
    }
    r = xyl__write_file_atomic(path, out.buf, out.len, alloc, diag);
    xyl__free(alloc, out.buf);
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

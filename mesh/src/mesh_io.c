/* Mesh export: Wavefront OBJ text and glTF 2.0 binary (.glb), both rendered here by hand
 * (docs/mesh-export.md describes the layouts).
 *
 * In memory both writers count, then fill: prepare() checks the view, size_output() sizes the
 * output exactly and emit() writes exactly that many bytes, so a too-small buffer is refused
 * before a byte of it is touched; xyl_mesh_write_file renders OBJ text once, into a growing
 * buffer. Nothing depends on the C locale or the host's byte order: integers are printed by
 * hand, floats through float_text.h, and GLB numbers are stored byte by byte, little-endian, as
 * glTF requires. */
#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "float_text.h"
#include "mesh_internal.h"

/* GLB container (glTF 2.0 spec, "Binary glTF Layout"). */
#define GLB_MAGIC UINT32_C(0x46546C67)      /* "glTF" */
#define GLB_VERSION UINT32_C(2)
#define GLB_CHUNK_JSON UINT32_C(0x4E4F534A) /* "JSON" */
#define GLB_CHUNK_BIN UINT32_C(0x004E4942)  /* "BIN\0" */
#define GLB_HEADER_BYTES 12u
#define GLB_CHUNK_HEADER_BYTES 8u
#define GLB_ALIGN 4u

/* OpenGL enums that glTF uses for component types, buffer targets and primitive modes. */
#define GL_UNSIGNED_INT 5125
#define GL_FLOAT 5126
#define GL_ARRAY_BUFFER 34962
#define GL_ELEMENT_ARRAY_BUFFER 34963
#define GL_TRIANGLES 4

/* Branch ids travel as float: glTF allows UNSIGNED_INT only for indices, and a float holds every
 * integer up to 2^24 exactly. */
#define MAX_FLOAT_EXACT_ID (UINT32_C(1) << 24)
/* A normal whose squared length is this close to 1 is written bit for bit; others are
 * renormalised, because the glTF-Validator rejects NORMAL elements that are not unit (it allows
 * about 5e-4 in the length; this keeps far inside that). */
#define NORMAL_UNIT_TOLERANCE_SQ 1e-5

/* ==== byte sink ============================================================================== */

/* Counts bytes, and also stores them when buf is set: sized by an earlier counting pass, or,
 * with cap set, grown as it goes (from alloc; overflow on failure). */
typedef struct sink {
    unsigned char *buf;
    size_t len;
    bool overflow; /* the output would not fit in a size_t (with room for a NUL), or memory
                      ran out */
    size_t cap;    /* 0: buf has room for everything */
    const xyl_allocator *alloc;
} sink;

static bool sink_room(sink *s, size_t n)
{
    size_t cap = s->cap;
    while (cap - s->len < n) cap = cap > SIZE_MAX / 2 ? SIZE_MAX : 2 * cap;
    unsigned char *b = xyl__alloc(s->alloc, cap);
    if (!b) return false;
    memcpy(b, s->buf, s->len);
    xyl__free(s->alloc, s->buf);
    s->buf = b;
    s->cap = cap;
    return true;
}

static void put(sink *s, const void *bytes, size_t n)
{
    if (s->overflow || n > SIZE_MAX - 1 - s->len ||
        (s->cap && s->cap - s->len < n + 1 && !sink_room(s, n + 1))) {
        s->overflow = true;
        return;
    }
    if (s->buf) memcpy(s->buf + s->len, bytes, n);
    s->len += n;
}

static void put_str(sink *s, const char *text)
{
    put(s, text, strlen(text));
}

static void put_uint(sink *s, uint64_t v)
{
    char b[24];
    size_t k = sizeof b;
    do {
        b[--k] = (char)('0' + v % 10);
        v /= 10;
    } while (v != 0);
    put(s, b + k, sizeof b - k);
}

/* The shortest text that reads back as the same float (float_text.h): valid JSON for finite
 * values, '.' whatever the locale. */
static void put_float(sink *s, float v)
{
    char out[XYL__FLOAT_TEXT_MAX];
    put(s, out, xyl__float_text(v, out));
}

static void put_u32le(sink *s, uint32_t v)
{
    const unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8),
                                (unsigned char)(v >> 16), (unsigned char)(v >> 24)};
    put(s, b, sizeof b);
}

static void put_f32le(sink *s, float v)
{
    uint32_t bits;
    memcpy(&bits, &v, sizeof bits);
    put_u32le(s, bits);
}

static void put_padding(sink *s, size_t n, char byte)
{
    for (size_t i = 0; i < n; ++i) put(s, &byte, 1);
}

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
    put_str(s, tag);
    for (int k = 0; k < n; ++k) {
        put_str(s, " ");
        put_float(s, c[k]);
    }
    put_str(s, "\n");
}

/* Positions and normals of m; UVs of uvm, m with its seams split (or m itself), whose first
 * vertices are m's. */
static void obj_vertices(const xyl_mesh *m, const xyl_mesh *uvm, sink *s)
{
    for (size_t v = 0; v < m->vertex_count && !s->overflow; ++v) {
        const float p[3] = {m->positions[v].x, m->positions[v].y, m->positions[v].z};
        obj_vec(s, "v", p, 3);
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
    put_str(s, "f");
    for (int k = 0; k < n; ++k) {
        uint64_t i = (uint64_t)f[k] + 1;
        put_str(s, " ");
        put_uint(s, i);
        put_str(s, "/");
        put_uint(s, (uint64_t)ft[k] + 1);
        put_str(s, "/");
        put_uint(s, i);
    }
    put_str(s, "\n");
}

/* A "g branch_<id>" line wherever the face branch changes, so each branch can be picked in a
 * modeller; a branch whose faces are not contiguous gets the same name again, which readers
 * merge into one group. uvm: as obj_vertices (same faces in the same order). */
static void obj_faces(const xyl_mesh *m, const xyl_mesh *uvm, sink *s)
{
    size_t faces = m->quad_count + m->triangle_count;
    for (size_t f = 0; f < faces && !s->overflow; ++f) {
        if (f == 0 || m->face_branches[f] != m->face_branches[f - 1]) {
            put_str(s, "g branch_");
            put_uint(s, m->face_branches[f]);
            put_str(s, "\n");
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
    put_str(s, "# xylem mesh: ");
    put_uint(s, m->vertex_count);
    put_str(s, " vertices, ");
    put_uint(s, m->quad_count);
    put_str(s, " quads, ");
    put_uint(s, m->triangle_count);
    put_str(s, " triangles\n");
    obj_vertices(m, uvm, s);
    obj_faces(m, uvm, s);
}

/* ==== GLB ==================================================================================== */

/* One bufferView per attribute, then the indices, each tightly packed in the BIN chunk. */
enum { VIEW_POSITION, VIEW_NORMAL, VIEW_UV, VIEW_BRANCH, VIEW_INDEX, VIEW_COUNT };

typedef struct view_kind {
    const char *type;    /* accessor type */
    int component;       /* accessor componentType */
    unsigned bytes;      /* per element */
    int target;          /* bufferView target */
} view_kind;

static const view_kind VIEW_KINDS[VIEW_COUNT] = {
    [VIEW_POSITION] = {"VEC3", GL_FLOAT, 12, GL_ARRAY_BUFFER},
    [VIEW_NORMAL] = {"VEC3", GL_FLOAT, 12, GL_ARRAY_BUFFER},
    [VIEW_UV] = {"VEC2", GL_FLOAT, 8, GL_ARRAY_BUFFER},
    [VIEW_BRANCH] = {"SCALAR", GL_FLOAT, 4, GL_ARRAY_BUFFER},
    [VIEW_INDEX] = {"SCALAR", GL_UNSIGNED_INT, 4, GL_ELEMENT_ARRAY_BUFFER},
};

typedef struct glb_layout {
    uint64_t count[VIEW_COUNT];  /* accessor counts */
    uint64_t offset[VIEW_COUNT]; /* in the BIN chunk; all multiples of 4 */
    uint64_t bin_len;            /* 0: no BIN chunk (the empty mesh) */
    uint64_t json_len;           /* before padding */
    uint64_t total;
    xyl_vec3 min, max;           /* POSITION bounds, required by glTF */
} glb_layout;

static uint64_t pad4(uint64_t n)
{
    return (GLB_ALIGN - n % GLB_ALIGN) % GLB_ALIGN;
}

static void plan_views(const xyl_mesh *m, glb_layout *l)
{
    uint64_t at = 0;
    for (int i = 0; i < VIEW_COUNT; ++i) {
        l->count[i] = i == VIEW_INDEX ? 3 * (uint64_t)m->tri_view_count : m->vertex_count;
        l->offset[i] = at;
        at += l->count[i] * VIEW_KINDS[i].bytes; /* no overflow: the counts are < 2^34 */
    }
    l->bin_len = at;
}

static void position_bounds(const xyl_mesh *m, glb_layout *l)
{
    l->min = l->max = m->positions[0];
    for (size_t v = 1; v < m->vertex_count; ++v) {
        xyl_vec3 p = m->positions[v];
        l->min.x = fminf(l->min.x, p.x);
        l->min.y = fminf(l->min.y, p.y);
        l->min.z = fminf(l->min.z, p.z);
        l->max.x = fmaxf(l->max.x, p.x);
        l->max.y = fmaxf(l->max.y, p.y);
        l->max.z = fmaxf(l->max.z, p.z);
    }
}

static void json_vec3(sink *s, const char *key, xyl_vec3 v)
{
    put_str(s, key);
    put_str(s, "[");
    put_float(s, v.x);
    put_str(s, ",");
    put_float(s, v.y);
    put_str(s, ",");
    put_float(s, v.z);
    put_str(s, "]");
}

static void json_accessors(const glb_layout *l, sink *s)
{
    put_str(s, "\"accessors\":[");
    for (int i = 0; i < VIEW_COUNT; ++i) {
        put_str(s, i ? ",{\"bufferView\":" : "{\"bufferView\":");
        put_uint(s, (uint64_t)i);
        put_str(s, ",\"componentType\":");
        put_uint(s, (uint64_t)VIEW_KINDS[i].component);
        put_str(s, ",\"count\":");
        put_uint(s, l->count[i]);
        put_str(s, ",\"type\":\"");
        put_str(s, VIEW_KINDS[i].type);
        put_str(s, "\"");
        if (i == VIEW_POSITION) {
            json_vec3(s, ",\"min\":", l->min);
            json_vec3(s, ",\"max\":", l->max);
        }
        put_str(s, "}");
    }
    put_str(s, "]");
}

static void json_buffers(const glb_layout *l, sink *s)
{
    put_str(s, ",\"bufferViews\":[");
    for (int i = 0; i < VIEW_COUNT; ++i) {
        put_str(s, i ? ",{\"buffer\":0,\"byteOffset\":" : "{\"buffer\":0,\"byteOffset\":");
        put_uint(s, l->offset[i]);
        put_str(s, ",\"byteLength\":");
        put_uint(s, l->count[i] * VIEW_KINDS[i].bytes);
        put_str(s, ",\"target\":");
        put_uint(s, (uint64_t)VIEW_KINDS[i].target);
        put_str(s, "}");
    }
    put_str(s, "],\"buffers\":[{\"byteLength\":");
    put_uint(s, l->bin_len);
    put_str(s, "}]");
}

/* The empty mesh is a scene with one node and no mesh: glTF has no empty accessor or buffer. */
static void render_json(const glb_layout *l, sink *s)
{
    put_str(s, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"xylem\"},"
               "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],");
    if (l->bin_len == 0) {
        put_str(s, "\"nodes\":[{\"name\":\"xylem\"}]}");
        return;
    }
    put_str(s, "\"nodes\":[{\"name\":\"xylem\",\"mesh\":0}],"
               "\"meshes\":[{\"name\":\"stems\",\"primitives\":[{\"attributes\":{"
               "\"POSITION\":0,\"NORMAL\":1,\"TEXCOORD_0\":2,\"_BRANCH_ID\":3},"
               "\"indices\":4,\"mode\":");
    put_uint(s, GL_TRIANGLES);
    put_str(s, "}]}],");
    json_accessors(l, s);
    json_buffers(l, s);
    put_str(s, "}");
}

/* Unit normals pass bit for bit; others are renormalised (a zero one becomes +Y), since glTF
 * requires NORMAL to be unit. */
static xyl_vec3 unit_normal(xyl_vec3 n)
{
    xyl__dvec3 d = xyl__from_f3(n);
    if (fabs(xyl__d3_dot(d, d) - 1.0) <= NORMAL_UNIT_TOLERANCE_SQ) return n;
    return xyl__to_f3(xyl__d3_normalize_or(d, xyl__d3(0, 1, 0)));
}

static void emit_bin(const xyl_mesh *m, sink *s)
{
    for (size_t v = 0; v < m->vertex_count; ++v) {
        put_f32le(s, m->positions[v].x);
        put_f32le(s, m->positions[v].y);
        put_f32le(s, m->positions[v].z);
    }
    for (size_t v = 0; v < m->vertex_count; ++v) {
        xyl_vec3 n = unit_normal(m->normals[v]);
        put_f32le(s, n.x);
        put_f32le(s, n.y);
        put_f32le(s, n.z);
    }
    for (size_t i = 0; i < 2 * m->vertex_count; ++i) put_f32le(s, m->uvs[i]);
    for (size_t v = 0; v < m->vertex_count; ++v) put_f32le(s, (float)m->branch_ids[v]);
    for (size_t i = 0; i < 3 * m->tri_view_count; ++i) put_u32le(s, m->tri_view[i]);
}

static void emit_glb(const xyl_mesh *m, const glb_layout *l, sink *s)
{
    uint64_t json_chunk = l->json_len + pad4(l->json_len);
    put_u32le(s, GLB_MAGIC);
    put_u32le(s, GLB_VERSION);
    put_u32le(s, (uint32_t)l->total);
    put_u32le(s, (uint32_t)json_chunk);
    put_u32le(s, GLB_CHUNK_JSON);
    render_json(l, s);
    put_padding(s, (size_t)pad4(l->json_len), ' ');
    if (l->bin_len == 0) return;
    put_u32le(s, (uint32_t)(l->bin_len + pad4(l->bin_len)));
    put_u32le(s, GLB_CHUNK_BIN);
    emit_bin(m, s);
    put_padding(s, (size_t)pad4(l->bin_len), '\0');
}

/* Every length field of a GLB is a uint32, which bounds the whole file. */
static uint64_t glb_total(const glb_layout *l)
{
    uint64_t t = GLB_HEADER_BYTES + GLB_CHUNK_HEADER_BYTES + l->json_len + pad4(l->json_len);
    if (l->bin_len) t += GLB_CHUNK_HEADER_BYTES + l->bin_len + pad4(l->bin_len);
    return t;
}

static xyl_result fail_too_large(uint64_t bytes, xyl_diag *diag)
{
    return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                     "the GLB would take %llu bytes; its length fields hold at most %lu",
                     (unsigned long long)bytes, (unsigned long)UINT32_MAX);
}

/* The GLB's size from the counts alone, before any array is read, so an oversized view is
 * refused cheaply. */
static xyl_result size_glb(const xyl_mesh *m, glb_layout *l, xyl_diag *diag)
{
    memset(l, 0, sizeof *l);
    if (m->vertex_count && !m->tri_view_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a GLB mesh needs at least one face (%zu vertices, no faces)",
                         m->vertex_count);
    if (m->vertex_count > UINT32_MAX || m->tri_view_count > UINT32_MAX)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu vertices and %zu triangles do not fit in a GLB's 4 GiB",
                         m->vertex_count, m->tri_view_count);
    plan_views(m, l);
    return glb_total(l) > UINT32_MAX ? fail_too_large(glb_total(l), diag) : XYL_OK;
}

/* The rest of the layout of a valid view sized by size_glb: bounds and the JSON chunk. */
static xyl_result plan_glb(const xyl_mesh *m, glb_layout *l, xyl_diag *diag)
{
    if (m->vertex_count) position_bounds(m, l);
    sink count = {NULL, 0, false, 0, NULL};
    render_json(l, &count);
    l->json_len = count.len;
    l->total = glb_total(l);
    return l->total > UINT32_MAX ? fail_too_large(l->total, diag) : XYL_OK;
}

/* ==== public entry points ==================================================================== */

/* What prepare() learnt: for GLB the layout and size, for OBJ (size_output) the size. */
typedef struct plan {
    xyl_mesh_format format;
    size_t size; /* bytes, without the NUL an OBJ text gets in memory (size_output) */
    glb_layout glb;
    xyl_mesh *split; /* the mesh with its UV seams split, where it has any (plan_free) */
} plan;

static void plan_free(plan *p)
{
    xyl_mesh_destroy(p->split);
    p->split = NULL;
}

static bool has_wraps(const xyl_mesh *m)
{
    for (size_t f = 0; m->uv_wraps && f < m->quad_count + m->triangle_count; ++f)
        if (m->uv_wraps[f]) return true;
    return false;
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
static xyl_result prepare(const xyl_mesh *m, xyl_mesh_format format, const xyl_allocator *alloc,
                          plan *p, xyl_diag *diag)
{
    p->format = format;
    p->split = NULL;
    p->size = 0;
    bool glb = format == XYL_MESH_FORMAT_GLB;
    xyl_result r = glb ? size_glb(m, &p->glb, diag) : XYL_OK;
    if (r == XYL_OK) r = xyl__mesh_validate(m, WRITER_READS, diag);
    if (r == XYL_OK && glb) r = check_float_ids(m, diag);
    if (r == XYL_OK && has_wraps(m)) r = xyl__mesh_split_seams(m, alloc, &p->split, diag);
    /* the split only adds vertices: its GLB is sized again */
    if (r == XYL_OK && glb && p->split) r = size_glb(p->split, &p->glb, diag);
    if (r == XYL_OK && glb) r = plan_glb(uv_mesh(m, p), &p->glb, diag);
    if (r == XYL_OK && glb) p->size = (size_t)p->glb.total;
    if (r != XYL_OK) plan_free(p);
    return r;
}

/* The exact output size into p->size: a GLB's came with its layout; OBJ text is counted by
 * rendering it. On failure the plan is freed. */
static xyl_result size_output(const xyl_mesh *m, plan *p)
{
    if (p->format == XYL_MESH_FORMAT_GLB) return XYL_OK;
    sink count = {NULL, 0, false, 0, NULL};
    render_obj(m, uv_mesh(m, p), &count);
    p->size = count.len;
    if (!count.overflow) return XYL_OK;
    plan_free(p);
    return XYL_ERR_OUT_OF_MEMORY; /* the OBJ text would not fit in memory */
}

/* Writes exactly p->size bytes (and a NUL after OBJ text, whose room the caller checked). */
static void emit(const xyl_mesh *m, const plan *p, unsigned char *out)
{
    sink fill = {out, 0, false, 0, NULL};
    if (p->format == XYL_MESH_FORMAT_GLB) {
        emit_glb(uv_mesh(m, p), &p->glb, &fill);
    } else {
        render_obj(m, uv_mesh(m, p), &fill);
        out[fill.len] = '\0';
    }
    assert(!fill.overflow && fill.len == p->size);
}

xyl_result xyl_mesh_write_memory(const xyl_mesh *mesh, xyl_mesh_format format,
                                 const xyl_allocator *alloc, void *buffer, size_t capacity,
                                 size_t *needed)
{
    if (!mesh || !format_ok(format) || (!buffer && !needed)) return XYL_ERR_INVALID_ARGUMENT;
    plan p;
    xyl_result r = prepare(mesh, format, alloc, &p, NULL);
    if (r == XYL_OK) r = size_output(mesh, &p);
    if (r != XYL_OK) return r;
    if (needed) *needed = p.size;
    /* OBJ is text and gets a terminating NUL, as xyl_skeleton_write_text; GLB is bytes. */
    size_t room = format == XYL_MESH_FORMAT_OBJ ? p.size + 1 : p.size;
    if (buffer && capacity < room) r = XYL_ERR_INVALID_ARGUMENT;
    else if (buffer) emit(mesh, &p, buffer);
    plan_free(&p);
    return r;
}

xyl_result xyl_mesh_write_file(const xyl_mesh *mesh, const char *path, xyl_mesh_format format,
                               const xyl_allocator *alloc, xyl_diag *diag)
{
    if (!mesh || !path || !*path || !format_ok(format))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "mesh and path must be given and the format must be OBJ or GLB");
    /* OBJ text is rendered once, into a buffer that grows, not counted first: formatting the
     * floats is most of its cost */
    plan p;
    xyl_result r = prepare(mesh, format, alloc, &p, diag);
    if (r != XYL_OK) return r;
    sink out = {NULL, 0, false, 0, alloc};
    if (format == XYL_MESH_FORMAT_OBJ) {
        out.cap = (size_t)1 << 16;
        out.buf = xyl__alloc(alloc, out.cap);
        if (out.buf) render_obj(mesh, uv_mesh(mesh, &p), &out);
    } else {
        out.buf = xyl__alloc(alloc, p.size + 1);
        if (out.buf) emit(mesh, &p, out.buf);
        out.len = p.size;
    }
    plan_free(&p);
    if (!out.buf || out.overflow) {
        xyl__free(alloc, out.buf);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the %s",
                         format == XYL_MESH_FORMAT_OBJ ? "OBJ text" : "GLB");
    }
    r = xyl__write_file_atomic(path, out.buf, out.len, alloc, diag);
    xyl__free(alloc, out.buf);
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

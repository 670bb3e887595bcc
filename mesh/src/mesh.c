/* Meshes: validation, ownership, normals and the triangulated view. */
#include <string.h>

#include "mesh_internal.h"

void xyl__mesh_arrays_free(xyl__mesh_arrays *a, const xyl_allocator *alloc)
{
    xyl__free(alloc, a->positions);
    xyl__free(alloc, a->normals);
    xyl__free(alloc, a->uvs);
    xyl__free(alloc, a->branch_ids);
    xyl__free(alloc, a->quads);
    xyl__free(alloc, a->triangles);
    xyl__free(alloc, a->face_branches);
    xyl__free(alloc, a->uv_wraps);
    memset(a, 0, sizeof *a);
}

/* Adds every face's normal to its n vertices, faces in order (so each vertex sums its faces in
 * the same order whatever the loop looks like). With own (one branch per face and per vertex)
 * only to the vertices of the face's branch. */
static void accumulate_faces(const xyl_vec3 *pos, const uint32_t *idx, size_t count, int n,
                             const uint32_t *own, const uint32_t *vbranch, xyl_vec3 *acc)
{
    for (size_t f = 0; f < count; ++f, idx += n) {
        xyl_vec3 fn = n == 4 ? xyl__quad_normal(pos, idx) : xyl__tri_normal(pos, idx);
        for (int k = 0; k < n; ++k)
            if (!own || own[f] == vbranch[idx[k]]) xyl__add_f3(&acc[idx[k]], fn);
    }
}

/* Adds every face's area-weighted normal to its vertices (own_branch_only: only to vertices of
 * the face's branch). Sums are float: a vertex collects a handful of faces. The quad and
 * triangle loops are separate, and the branch test is decided once, so the hot loop is plain. */
static void accumulate(const xyl__mesh_arrays *a, const uint32_t *face_branch, xyl_vec3 *acc,
                       bool own_branch_only)
{
    bool own = own_branch_only && face_branch && a->branch_ids;
    const uint32_t *fq = own ? face_branch : NULL, *ft = own ? face_branch + a->quad_count : NULL;
    if (fq) accumulate_faces(a->positions, a->quads, a->quad_count, 4, fq, a->branch_ids, acc);
    else accumulate_faces(a->positions, a->quads, a->quad_count, 4, NULL, NULL, acc);
    if (a->triangle_count)
        accumulate_faces(a->positions, a->triangles, a->triangle_count, 3, ft, a->branch_ids, acc);
}

/* A vertex without faces of its own branch ("lonely") takes the normal of all its faces. One
 * pass normalises the others and leaves the lonely sums as they are: a normalised vector always
 * has a direction, so the second pass finds exactly the lonely ones again. */
xyl_result xyl__mesh_normals_finish(const xyl__mesh_arrays *a, bool by_branch,
                                    const xyl_allocator *alloc, xyl_vec3 *out)
{
    bool lonely = false;
    for (size_t v = 0; v < a->vertex_count; ++v) {
        if (by_branch && !xyl__has_direction(out[v])) lonely = true;
        else out[v] = xyl__unit_or_up(out[v]);
    }
    return lonely ? xyl__mesh_normals_lonely(a, alloc, out) : XYL_OK;
}

xyl_result xyl__mesh_normals_lonely(const xyl__mesh_arrays *a, const xyl_allocator *alloc,
                                    xyl_vec3 *out)
{
    xyl_vec3 *all = xyl__calloc(alloc, a->vertex_count, sizeof *all);
    if (!all) return XYL_ERR_OUT_OF_MEMORY;
    accumulate(a, NULL, all, false);
    for (size_t v = 0; v < a->vertex_count; ++v)
        if (!xyl__has_direction(out[v])) out[v] = xyl__unit_or_up(all[v]);
    xyl__free(alloc, all);
    return XYL_OK;
}

xyl_result xyl__mesh_normals(const xyl__mesh_arrays *a, const uint32_t *face_branch,
                             const xyl_allocator *alloc, xyl_vec3 *out)
{
    memset(out, 0, a->vertex_count * sizeof *out);
    accumulate(a, face_branch, out, true);
    return xyl__mesh_normals_finish(a, face_branch != NULL, alloc, out);
}

/* ---- validation ---------------------------------------------------------------------------- */

/* Every array the call reads is there for its count; read with the faces, the view has the
 * count of their triangulation. Reads no array. */
static xyl_result check_arrays(const xyl_mesh *m, unsigned reads, xyl_diag *diag)
{
    size_t nv = m->vertex_count;
    const struct {
        unsigned read;
        const void *array;
        const char *name, *count_name;
        size_t count;
    } need[] = {
        {0, m->positions, "positions", "vertex_count", nv},
        {XYL__MESH_NORMALS, m->normals, "normals", "vertex_count", nv},
        {XYL__MESH_UVS, m->uvs, "uvs", "vertex_count", nv},
        {XYL__MESH_BRANCH_IDS, m->branch_ids, "branch_ids", "vertex_count", nv},
        {XYL__MESH_FACES, m->quads, "quads", "quad_count", m->quad_count},
        {XYL__MESH_FACES, m->triangles, "triangles", "triangle_count", m->triangle_count},
        {XYL__MESH_FACE_BRANCHES, m->face_branches, "face_branches", "quad_count",
         m->quad_count},
        {XYL__MESH_FACE_BRANCHES, m->face_branches, "face_branches", "triangle_count",
         m->triangle_count},
        {XYL__MESH_TRI_VIEW, m->tri_view, "tri_view", "tri_view_count", m->tri_view_count},
    };
    for (size_t i = 0; i < sizeof need / sizeof need[0]; ++i)
        if ((!need[i].read || (reads & need[i].read)) && need[i].count && !need[i].array)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "%s is NULL but %s is %zu",
                             need[i].name, need[i].count_name, need[i].count);
    bool view_of_faces = (reads & XYL__MESH_TRI_VIEW) && (reads & XYL__MESH_FACES);
    if (view_of_faces && (m->quad_count > (SIZE_MAX - m->triangle_count) / 2 ||
                          m->tri_view_count != 2 * m->quad_count + m->triangle_count))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "tri_view_count %zu is not 2 * %zu quads + %zu triangles",
                         m->tri_view_count, m->quad_count, m->triangle_count);
    return XYL_OK;
}

/* The scans first ask only whether anything is wrong, without branches (so the compiler
 * vectorises them: the checked stem build validates every mesh it tests); the checks below them
 * look for the first offender only when there is one. */

/* n floats from p, none an infinity or a NaN (all exponent bits set). */
static bool floats_finite(const void *p, size_t n)
{
    const unsigned char *b = p;
    unsigned bad = 0;
    for (size_t i = 0; i < n; ++i) {
        uint32_t bits;
        memcpy(&bits, b + 4 * i, sizeof bits);
        bad |= (unsigned)((bits & 0x7f800000u) == 0x7f800000u);
    }
    return bad == 0;
}

/* count faces of n corners: every index below vertex_count, none twice in a face. */
static XYL__ALWAYS_INLINE bool faces_ok(const uint32_t *idx, size_t count, int n,
                                        size_t vertex_count)
{
    unsigned bad = 0;
    for (size_t f = 0; f < count; ++f, idx += n)
        for (int k = 0; k < n; ++k) {
            bad |= (unsigned)(idx[k] >= vertex_count);
            for (int j = 0; j < k; ++j) bad |= (unsigned)(idx[j] == idx[k]);
        }
    return bad == 0;
}

static bool finite3(xyl_vec3 v)
{
    return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

/* What of vertex v is not finite: its position, or its normal or UV where the mesh has them. */
static const char *non_finite_part(const xyl_mesh *m, size_t v)
{
    if (!finite3(m->positions[v])) return "position";
    if (m->normals && !finite3(m->normals[v])) return "normal";
    if (m->uvs && !(isfinite(m->uvs[2 * v]) && isfinite(m->uvs[2 * v + 1]))) return "UV";
    return NULL;
}

static xyl_result check_vertices(const xyl_mesh *m, xyl_diag *diag)
{
    size_t nv = m->vertex_count;
    bool fine = nv <= SIZE_MAX / 3 && floats_finite(m->positions, 3 * nv) &&
                (!m->normals || floats_finite(m->normals, 3 * nv)) &&
                (!m->uvs || floats_finite(m->uvs, 2 * nv));
    if (fine) return XYL_OK;
    for (size_t v = 0; v < nv; ++v) {
        const char *bad = non_finite_part(m, v);
        if (bad)
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)v,
                             "vertex %zu has a non-finite %s", v, bad);
    }
    return XYL_OK;
}

/* count faces of n corners, named first, first + 1, ...: vertices in range, none twice. */
static xyl_result check_faces(const uint32_t *idx, size_t count, int n, size_t first,
                              size_t vertex_count, xyl_diag *diag)
{
    if (n == 4 ? faces_ok(idx, count, 4, vertex_count) : faces_ok(idx, count, 3, vertex_count))
        return XYL_OK;
    for (size_t f = 0; f < count; ++f, idx += n)
        for (int k = 0; k < n; ++k) {
            if (idx[k] >= vertex_count)
                return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)(first + f),
                                 "face %zu uses vertex %u of %zu", first + f, idx[k],
                                 vertex_count);
            for (int j = 0; j < k; ++j)
                if (idx[j] == idx[k])
                    return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)(first + f),
                                     "face %zu repeats vertex %u", first + f, idx[k]);
        }
    return XYL_OK;
}

static xyl_result check_uv_wraps(const xyl_mesh *m, xyl_diag *diag)
{
    size_t quads = m->quad_count, faces = quads + m->triangle_count;
    for (size_t f = 0; m->uv_wraps && f < faces; ++f)
        if (m->uv_wraps[f] & (uint8_t)~XYL__WRAP_BITS(f < quads ? 4 : 3))
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)f,
                             "face %zu has uv wrap bits 0x%x beyond its %d corners", f,
                             (unsigned)m->uv_wraps[f], f < quads ? 4 : 3);
    return XYL_OK;
}

static xyl_result check_tri_view(const xyl_mesh *m, xyl_diag *diag)
{
    const uint32_t *t = m->tri_view;
    uint32_t top = 0;
    size_t n = m->tri_view_count <= SIZE_MAX / 3 ? 3 * m->tri_view_count : 0;
    for (size_t k = 0; k < n; ++k) top = t[k] > top ? t[k] : top;
    if (m->tri_view_count == 0 || (n && top < m->vertex_count)) return XYL_OK;
    for (size_t i = 0; i < m->tri_view_count; ++i, t += 3)
        for (int k = 0; k < 3; ++k)
            if (t[k] >= m->vertex_count)
                return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)i,
                                 "view triangle %zu uses vertex %u of %zu", i, t[k],
                                 m->vertex_count);
    return XYL_OK;
}

xyl_result xyl__mesh_validate(const xyl_mesh *m, unsigned reads, xyl_diag *diag)
{
    if (reads & (XYL__MESH_FACE_BRANCHES | XYL__MESH_UV_WRAPS)) reads |= XYL__MESH_FACES;
    xyl_result r = check_arrays(m, reads, diag);
    if (r == XYL_OK && !(isfinite(m->origin[0]) && isfinite(m->origin[1]) && isfinite(m->origin[2])))
        r = xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "the origin is not finite");
    if (r == XYL_OK) r = check_vertices(m, diag);
    if (r == XYL_OK && (reads & XYL__MESH_FACES))
        r = check_faces(m->quads, m->quad_count, 4, 0, m->vertex_count, diag);
    if (r == XYL_OK && (reads & XYL__MESH_FACES))
        r = check_faces(m->triangles, m->triangle_count, 3, m->quad_count, m->vertex_count, diag);
    if (r == XYL_OK && (reads & XYL__MESH_UV_WRAPS)) r = check_uv_wraps(m, diag);
    if (r == XYL_OK && (reads & XYL__MESH_TRI_VIEW)) r = check_tri_view(m, diag);
    return r;
}

/* ---- the public mesh ---------------------------------------------------------------------- */

/* The desc's own limits, from its counts alone. */
static xyl_result check_limits(const xyl_mesh_desc *d, xyl_diag *diag)
{
    uint64_t max_v = d->limits.max_vertices ? d->limits.max_vertices
                                            : XYL__MESH_DEFAULT_MAX_VERTICES;
    uint64_t max_f = d->limits.max_faces ? d->limits.max_faces : XYL__MESH_DEFAULT_MAX_FACES;
    if ((uint64_t)d->vertex_count > max_v || d->vertex_count > UINT32_MAX ||
        (uint64_t)d->quad_count + d->triangle_count > max_f)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu vertices and %zu faces exceed the limits (%llu, %llu)",
                         d->vertex_count, d->quad_count + d->triangle_count,
                         (unsigned long long)max_v, (unsigned long long)max_f);
    return XYL_OK;
}

/* Copies count * size bytes of src (or zeroes when src is NULL) into a new zeroed array of room
 * >= count elements. */
static void *dup_with_room(const xyl_allocator *a, const void *src, size_t count, size_t room,
                           size_t size, bool *ok)
{
    void *p = xyl__calloc(a, room ? room : 1, size);
    if (!p) *ok = false;
    else if (src && count) memcpy(p, src, count * size);
    return p;
}

static void *dup_or_zero(const xyl_allocator *a, const void *src, size_t count, size_t size,
                         bool *ok)
{
    return dup_with_room(a, src, count, count, size, ok);
}

xyl_result xyl_mesh_create(const xyl_mesh_desc *desc, xyl_mesh **out, xyl_diag *diag)
{
    if (!desc || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "desc and out must not be NULL");
    xyl_mesh view = XYL__MESH_VIEW_OF(desc);
    xyl_result r = check_limits(desc, diag);
    if (r == XYL_OK) r = xyl__mesh_validate(&view, XYL__MESH_FACES | XYL__MESH_UV_WRAPS, diag);
    if (r) return r;
    const xyl_allocator *al = &desc->alloc;
    bool ok = true;
    xyl__mesh_arrays a;
    memset(&a, 0, sizeof a);
    a.vertex_count = desc->vertex_count;
    a.quad_count = desc->quad_count;
    a.triangle_count = desc->triangle_count;
    memcpy(a.origin, desc->origin, sizeof a.origin);
    a.positions = dup_or_zero(al, desc->positions, a.vertex_count, sizeof *a.positions, &ok);
    if (desc->normals) a.normals = dup_or_zero(al, desc->normals, a.vertex_count, sizeof *a.normals, &ok);
    a.uvs = dup_or_zero(al, desc->uvs, a.vertex_count, 2 * sizeof *a.uvs, &ok);
    a.branch_ids = dup_or_zero(al, desc->branch_ids, a.vertex_count, sizeof *a.branch_ids, &ok);
    a.quads = dup_or_zero(al, desc->quads, a.quad_count, 4 * sizeof *a.quads, &ok);
    a.triangles = dup_or_zero(al, desc->triangles, a.triangle_count, 3 * sizeof *a.triangles, &ok);
    a.face_branches = dup_or_zero(al, desc->face_branches, a.quad_count + a.triangle_count,
                                  sizeof *a.face_branches, &ok);
    a.uv_wraps = dup_or_zero(al, desc->uv_wraps, a.quad_count + a.triangle_count,
                             sizeof *a.uv_wraps, &ok);
    if (!ok) {
        xyl__mesh_arrays_free(&a, al);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the mesh");
    }
    /* the mesh promises unit normals: caller normals are normalised (zero ones become +y) */
    for (size_t v = 0; a.normals && v < a.vertex_count; ++v)
        a.normals[v] = xyl__to_f3(xyl__d3_normalize_or(xyl__from_f3(a.normals[v]), xyl__d3(0, 1, 0)));
    return xyl__mesh_adopt(&a, al, out, diag);
}

static uint32_t *triangulate(const xyl__mesh_arrays *a, const xyl_allocator *alloc)
{
    size_t tris = 2 * a->quad_count + a->triangle_count;
    uint32_t *t = xyl__alloc_array(alloc, tris, 3 * sizeof *t); /* filled below */
    if (!t) return NULL;
    uint32_t *w = t;
    for (size_t f = 0; f < a->quad_count; ++f) {
        const uint32_t *q = a->quads + 4 * f;
        const uint32_t split[6] = {q[0], q[1], q[2], q[0], q[2], q[3]};
        memcpy(w, split, sizeof split);
        w += 6;
    }
    if (a->triangle_count) memcpy(w, a->triangles, a->triangle_count * 3 * sizeof *t);
    return t;
}

xyl_result xyl__mesh_adopt(xyl__mesh_arrays *a, const xyl_allocator *alloc, xyl_mesh **out,
                           xyl_diag *diag)
{
    return xyl__mesh_adopt_view(a, NULL, alloc, out, diag);
}

xyl_result xyl__mesh_adopt_view(xyl__mesh_arrays *a, uint32_t *tri_view,
                                const xyl_allocator *alloc, xyl_mesh **out, xyl_diag *diag)
{
    xyl__mesh *m = xyl__calloc(alloc, 1, sizeof *m);
    uint32_t *tv = tri_view;
    if (m && !tv) tv = triangulate(a, alloc);
    bool ok = m && tv;
    if (ok && !a->face_branches) {
        size_t faces = a->quad_count + a->triangle_count;
        a->face_branches = xyl__calloc(alloc, faces ? faces : 1, sizeof *a->face_branches);
        ok = a->face_branches != NULL;
    }
    if (ok && !a->uv_wraps) {
        size_t faces = a->quad_count + a->triangle_count;
        a->uv_wraps = xyl__calloc(alloc, faces ? faces : 1, sizeof *a->uv_wraps);
        ok = a->uv_wraps != NULL;
    }
    if (ok && !a->normals) {
        /* xyl__mesh_normals zeroes it first */
        a->normals = xyl__alloc_array(alloc, a->vertex_count, sizeof *a->normals);
        ok = a->normals && xyl__mesh_normals(a, NULL, alloc, a->normals) == XYL_OK;
    }
    if (!ok) {
        xyl__free(alloc, m);
        xyl__free(alloc, tv);
        xyl__mesh_arrays_free(a, alloc);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the mesh");
    }
    if (alloc) m->alloc = *alloc;
    m->a = *a;
    m->tri_view = tv;
    xyl_mesh *p = &m->pub;
    p->positions = a->positions;
    p->normals = a->normals;
    p->uvs = a->uvs;
    p->branch_ids = a->branch_ids;
    p->vertex_count = a->vertex_count;
    p->quads = a->quads;
    p->quad_count = a->quad_count;
    p->triangles = a->triangles;
    p->triangle_count = a->triangle_count;
    p->face_branches = a->face_branches;
    p->tri_view = tv;
    p->tri_view_count = 2 * a->quad_count + a->triangle_count;
    p->uv_wraps = a->uv_wraps;
    memcpy(p->origin, a->origin, sizeof p->origin);
    memset(a, 0, sizeof *a);
    *out = p;
    xyl__diag_ok(diag);
    return XYL_OK;
}

void xyl_mesh_destroy(xyl_mesh *mesh)
{
    if (!mesh) return;
    xyl__mesh *m = (xyl__mesh *)mesh;
    xyl_allocator al = m->alloc;
    xyl__mesh_arrays_free(&m->a, &al);
    xyl__free(&al, m->tri_view);
    xyl__free(&al, m);
}

/* ---- seams split ---------------------------------------------------------------------------- */

enum { USED_PLAIN = 1, USED_WRAPPED = 2 };

/* How each vertex is used: USED_PLAIN and/or USED_WRAPPED, from every face corner. */
static void mark_uses(const xyl_mesh *m, uint8_t *use)
{
    for (size_t f = 0; f < m->quad_count + m->triangle_count; ++f) {
        int n;
        const uint32_t *c = xyl__mesh_face(m, f, &n);
        uint8_t w = m->uv_wraps ? m->uv_wraps[f] : 0;
        for (int k = 0; k < n; ++k) use[c[k]] |= (w >> k & 1u) ? USED_WRAPPED : USED_PLAIN;
    }
}

/* Faces with every wrapped corner sent to its vertex's copy (where the vertex has one). */
static void remap_faces(const uint32_t *src, size_t count, int n, const uint8_t *wraps,
                        const uint32_t *copy, uint32_t *dst)
{
    for (size_t f = 0; f < count; ++f)
        for (int k = 0; k < n; ++k) {
            uint32_t v = src[(size_t)n * f + (size_t)k];
            bool wrapped = wraps && (wraps[f] >> k & 1u);
            dst[(size_t)n * f + (size_t)k] = wrapped && copy[v] != UINT32_MAX ? copy[v] : v;
        }
}

xyl_result xyl_mesh_split_seams(const xyl_mesh *m, const xyl_allocator *alloc, xyl_mesh **out,
                                xyl_diag *diag)
{
    if (!m || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "mesh and out must not be NULL");
    xyl_result r = xyl__mesh_validate(m, XYL__SPLIT_SEAMS_READS, diag);
    return r ? r : xyl__mesh_split_seams(m, alloc, out, diag);
}

xyl_result xyl__mesh_split_seams(const xyl_mesh *m, const xyl_allocator *alloc, xyl_mesh **out,
                                 xyl_diag *diag)
{
    size_t nv = m->vertex_count, nf = m->quad_count + m->triangle_count, copies = 0;
    uint8_t *use = xyl__calloc(alloc, nv ? nv : 1, 1);
    uint32_t *copy = xyl__alloc_array(alloc, nv ? nv : 1, sizeof *copy);
    if (!use || !copy) {
        xyl__free(alloc, use);
        xyl__free(alloc, copy);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the seams");
    }
    mark_uses(m, use);
    for (size_t v = 0; v < nv; ++v) copies += use[v] == (USED_PLAIN | USED_WRAPPED);
    if (nv + copies > UINT32_MAX) {
        xyl__free(alloc, use);
        xyl__free(alloc, copy);
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "splitting the seams gives %zu vertices, more than 32-bit indices hold",
                         nv + copies);
    }
    size_t total = nv + copies;
    bool ok = true;
    xyl__mesh_arrays a;
    memset(&a, 0, sizeof a);
    a.vertex_count = total;
    a.quad_count = m->quad_count;
    a.triangle_count = m->triangle_count;
    memcpy(a.origin, m->origin, sizeof a.origin);
    a.positions = dup_with_room(alloc, m->positions, nv, total, sizeof *a.positions, &ok);
    a.normals = dup_with_room(alloc, m->normals, nv, total, sizeof *a.normals, &ok);
    a.uvs = dup_with_room(alloc, m->uvs, nv, total, 2 * sizeof *a.uvs, &ok);
    a.branch_ids = dup_with_room(alloc, m->branch_ids, nv, total, sizeof *a.branch_ids, &ok);
    a.quads = xyl__alloc_array(alloc, m->quad_count ? m->quad_count : 1, 4 * sizeof *a.quads);
    a.triangles = xyl__alloc_array(alloc, m->triangle_count ? m->triangle_count : 1,
                                   3 * sizeof *a.triangles);
    a.face_branches = dup_or_zero(alloc, m->face_branches, nf, sizeof *a.face_branches, &ok);
    a.uv_wraps = xyl__calloc(alloc, nf ? nf : 1, sizeof *a.uv_wraps);
    ok = ok && a.quads && a.triangles && a.uv_wraps;
    if (!ok) {
        xyl__free(alloc, use);
        xyl__free(alloc, copy);
        xyl__mesh_arrays_free(&a, alloc);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the mesh");
    }
    size_t next = nv;
    for (size_t v = 0; v < nv; ++v) {
        copy[v] = UINT32_MAX;
        if (use[v] == USED_WRAPPED) {
            a.uvs[2 * v] += 1.0f; /* only ever used wrapped: no copy needed */
        } else if (use[v] == (USED_PLAIN | USED_WRAPPED)) {
            copy[v] = (uint32_t)next;
            a.positions[next] = m->positions[v];
            a.normals[next] = m->normals[v];
            a.uvs[2 * next] = m->uvs[2 * v] + 1.0f;
            a.uvs[2 * next + 1] = m->uvs[2 * v + 1];
            a.branch_ids[next] = m->branch_ids[v];
            ++next;
        }
    }
    remap_faces(m->quads, m->quad_count, 4, m->uv_wraps, copy, a.quads);
    const uint8_t *tri_wraps = m->uv_wraps ? m->uv_wraps + m->quad_count : NULL;
    remap_faces(m->triangles, m->triangle_count, 3, tri_wraps, copy, a.triangles);
    xyl__free(alloc, use);
    xyl__free(alloc, copy);
    return xyl__mesh_adopt(&a, alloc, out, diag);
}

void xyl_mesh_bounds(const xyl_mesh *mesh, float lo[3], float hi[3])
{
    for (int k = 0; k < 3; ++k) lo[k] = hi[k] = 0.0f;
    if (!mesh || !mesh->vertex_count || !mesh->positions) return;
    const xyl_vec3 p0 = mesh->positions[0];
    lo[0] = hi[0] = p0.x, lo[1] = hi[1] = p0.y, lo[2] = hi[2] = p0.z;
    for (size_t v = 1; v < mesh->vertex_count; ++v) {
        const float p[3] = {mesh->positions[v].x, mesh->positions[v].y, mesh->positions[v].z};
        for (int k = 0; k < 3; ++k) {
            lo[k] = p[k] < lo[k] ? p[k] : lo[k];
            hi[k] = p[k] > hi[k] ? p[k] : hi[k];
        }
    }
}

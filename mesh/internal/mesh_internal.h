/* Mesh internals shared by stems/ (mesher, subdivision, exporters, checks). Not installed. */
#ifndef XYL_MESH_INTERNAL_H
#define XYL_MESH_INTERNAL_H

#include <math.h>

#include "xyl_internal.h"
#include "xylem/xyl_mesh.h"

#define XYL__MESH_DEFAULT_MAX_VERTICES (UINT64_C(1) << 26)
#define XYL__MESH_DEFAULT_MAX_FACES (UINT64_C(1) << 26)

/* The arrays a mesh owns, before it is wrapped. normals may be NULL (computed by adopt). */
typedef struct xyl__mesh_arrays {
    xyl_vec3 *positions;
    xyl_vec3 *normals;
    float *uvs;
    uint32_t *branch_ids;
    size_t vertex_count;
    uint32_t *quads;
    size_t quad_count;
    uint32_t *triangles;
    size_t triangle_count;
    uint32_t *face_branches; /* one per face, quads first */
    uint8_t *uv_wraps;       /* one per face, quads first; NULL: adopt makes them 0 */
} xyl__mesh_arrays;

/* The public view comes first so a xyl_mesh* is a xyl__mesh*. */
typedef struct xyl__mesh {
    xyl_mesh pub;
    xyl__mesh_arrays a;
    uint32_t *tri_view;
    xyl_allocator alloc;
} xyl__mesh;

/* Frees every array of a (allocated with alloc) and zeroes it. */
void xyl__mesh_arrays_free(xyl__mesh_arrays *a, const xyl_allocator *alloc);

/* Takes ownership of a's arrays (freed on failure too): computes smooth normals when a->normals
 * is NULL, builds the triangulated view and wraps them. The arrays must be valid. */
xyl_result xyl__mesh_adopt(xyl__mesh_arrays *a, const xyl_allocator *alloc, xyl_mesh **out,
                           xyl_diag *diag);
/* xyl__mesh_adopt with the triangulated view already built by the caller (quads split as
 * {0, 1, 2, 0, 2, 3}, then the triangles), from alloc; taken over (freed on failure too). */
xyl_result xyl__mesh_adopt_view(xyl__mesh_arrays *a, uint32_t *tri_view,
                                const xyl_allocator *alloc, xyl_mesh **out, xyl_diag *diag);

/* Face f of a mesh (quads first, then triangles): its vertex indices, and their number in *n. */
static inline const uint32_t *xyl__mesh_face(const xyl_mesh *m, size_t f, int *n)
{
    if (f < m->quad_count) {
        *n = 4;
        return m->quads + 4 * f;
    }
    *n = 3;
    return m->triangles + 3 * (f - m->quad_count);
}

/* xyl_mesh_create's face checks on a view (the caller's, perhaps): XYL_ERR_INVALID_ARGUMENT,
 * diag.index = the face, where a face uses a vertex out of range or one twice. The arrays must
 * be there for the counts. */
xyl_result xyl__check_mesh_faces(const xyl_mesh *m, xyl_diag *diag);

/* Every intersecting triangle pair of a mesh's triangulated view, as xyl_mesh_self_intersections
 * finds them, in one pass: *pairs (from alloc, NULL for malloc; i << 32 | j with i < j, sorted;
 * free with xyl__free(alloc, .)) and *count. Errors: those of xyl_mesh_self_intersections. */
xyl_result xyl__mesh_intersecting_pairs(const xyl_mesh *mesh, const xyl_allocator *alloc,
                                        uint64_t **pairs, size_t *count, xyl_diag *diag);

/* Bit c of a face's uv_wraps set: corner c's u is its vertex's u + 1. The bits a face of n
 * corners may use. */
#define XYL__WRAP_BITS(n) ((uint8_t)((1u << (n)) - 1u))

/* XYL_ERR_INVALID_ARGUMENT (diag.index = the face) where a face's wrap bits name a corner it does
 * not have; NULL wraps are none. */
xyl_result xyl__check_uv_wraps(const uint8_t *wraps, size_t quads, size_t triangles,
                               xyl_diag *diag);

/* The wrap bits of a face of n <= 4 corners whose u's lie on a circle of circumference 1 (a
 * cylindrical map): the cut at the widest gap, which leaves the corners the shortest span,
 * corners below the cut moved by 1. No bits where the wrap-around gap is the widest (ties keep
 * the face as it is; between inner gaps, the lowest cut wins). */
static inline uint8_t xyl__uv_wraps_of(const float *u, int n)
{
    /* u sorted by a network of min/max pairs (n = 3 or 4: the missing fourth is +inf) */
    float v0 = u[0], v1 = u[1], v2 = u[2], v3 = n == 4 ? u[3] : INFINITY, t;
#define XYL__SORT2(a, b) (t = (a) < (b) ? (a) : (b), (b) = (a) < (b) ? (b) : (a), (a) = t)
    XYL__SORT2(v0, v1);
    XYL__SORT2(v2, v3);
    XYL__SORT2(v0, v2);
    XYL__SORT2(v1, v3);
    XYL__SORT2(v1, v2);
#undef XYL__SORT2
    float top = n == 4 ? v3 : v2;
    /* the widest gap between neighbours, against the wrap-around gap; ties: the lowest cut */
    double best = 1.0 - ((double)top - v0), g;
    float cut = 0.0f;
    bool wrap = false;
    if ((g = (double)v1 - v0) > best) best = g, cut = v0, wrap = true;
    if ((g = (double)v2 - v1) > best) best = g, cut = v1, wrap = true;
    if (n == 4 && (g = (double)v3 - v2) > best) best = g, cut = v2, wrap = true;
    uint8_t bits = 0;
    for (int c = 0; wrap && c < n; ++c)
        if (u[c] <= cut) bits |= (uint8_t)(1u << c);
    return bits;
}

/* Twice the area-weighted normal of a quad (the cross of its diagonals) and of a triangle (of
 * two edges), in double and rounded once to float: every normal sum in stems/ adds these, so a
 * sum built while meshing has the same bits as one built afterwards. */
static inline xyl_vec3 xyl__quad_normal(const xyl_vec3 *p, const uint32_t *f)
{
    xyl__dvec3 a = xyl__from_f3(p[f[0]]), b = xyl__from_f3(p[f[1]]), c = xyl__from_f3(p[f[2]]);
    xyl__dvec3 d = xyl__from_f3(p[f[3]]);
    return xyl__to_f3(xyl__d3_cross(xyl__d3_sub(c, a), xyl__d3_sub(d, b)));
}
static inline xyl_vec3 xyl__tri_normal(const xyl_vec3 *p, const uint32_t *f)
{
    xyl__dvec3 a = xyl__from_f3(p[f[0]]), b = xyl__from_f3(p[f[1]]), c = xyl__from_f3(p[f[2]]);
    return xyl__to_f3(xyl__d3_cross(xyl__d3_sub(b, a), xyl__d3_sub(c, a)));
}
static inline void xyl__add_f3(xyl_vec3 *acc, xyl_vec3 v)
{
    acc->x += v.x;
    acc->y += v.y;
    acc->z += v.z;
}

/* A normal sum with a direction (else the vertex falls back: to all its faces, or to +y). */
static inline bool xyl__has_direction(xyl_vec3 v)
{
    return (double)v.x * v.x + (double)v.y * v.y + (double)v.z * v.z > XYL__EPS_NORMALIZE;
}
static inline xyl_vec3 xyl__unit_or_up(xyl_vec3 sum)
{
    return xyl__to_f3(xyl__d3_normalize_or(xyl__from_f3(sum), xyl__d3(0, 1, 0)));
}

/* Area-weighted vertex normals into out (vertex_count entries). With face_branch (one entry per
 * face, quads first, then triangles) a vertex averages only the faces of its own branch
 * (a->branch_ids), falling back to all its faces when none is; without, all faces. A vertex
 * without usable faces gets (0, 1, 0). Fails only with XYL_ERR_OUT_OF_MEMORY. */
xyl_result xyl__mesh_normals(const xyl__mesh_arrays *a, const uint32_t *face_branch,
                             const xyl_allocator *alloc, xyl_vec3 *out);

/* The second half of xyl__mesh_normals, for a caller that summed the face normals itself (in the
 * same face order): out holds the sums and becomes unit normals. by_branch: the sums were of
 * own-branch faces only, so a vertex without any takes the sum of all its faces. */
xyl_result xyl__mesh_normals_finish(const xyl__mesh_arrays *a, bool by_branch,
                                    const xyl_allocator *alloc, xyl_vec3 *out);
/* The last step of both: every vertex of out without a direction (those, and only those, still
 * hold a sum without direction; the rest are unit) takes the normal of all its faces. */
xyl_result xyl__mesh_normals_lonely(const xyl__mesh_arrays *a, const xyl_allocator *alloc,
                                    xyl_vec3 *out);

#endif

/* Mesh internals shared by the mesh module's files, stems/ and tessellate/ (validation, ownership,
 * normals). Not installed. */
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
    double origin[3];        /* the positions' origin (xyl_mesh.origin) */
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

/* ---- validation: one check of a mesh for every call that reads one ------------------------- */

/* What a call reads of a mesh besides its positions (always read), for xyl__mesh_validate. */
enum {
    XYL__MESH_NORMALS = 1u << 0,
    XYL__MESH_UVS = 1u << 1,
    XYL__MESH_BRANCH_IDS = 1u << 2,
    XYL__MESH_FACES = 1u << 3,         /* quads and triangles */
    XYL__MESH_FACE_BRANCHES = 1u << 4, /* read with the faces */
    XYL__MESH_UV_WRAPS = 1u << 5,      /* read with the faces; NULL means none */
    XYL__MESH_TRI_VIEW = 1u << 6       /* the triangulated view */
};

/* A mesh a caller may have built, checked before a call reads it: every array the call reads
 * (reads: XYL__MESH_* flags) is there for its count; positions, and normals and UVs wherever
 * they are given, are finite; faces use vertices in range, none twice; wrap bits name corners
 * the face has; the view's indices are in range and, read with the faces, it has 2 q + t
 * triangles. Checks that need only the counts come first, so a call's own limits, checked
 * before this, refuse an oversized mesh without reading its arrays. Errors:
 * XYL_ERR_INVALID_ARGUMENT (diag.index: the face or view triangle, -1 for an array or a count),
 * XYL_ERR_NON_FINITE (diag.index: the vertex). */
xyl_result xyl__mesh_validate(const xyl_mesh *m, unsigned reads, xyl_diag *diag);

/* A read-only xyl_mesh over anything with xyl_mesh_desc's field names (a desc,
 * xyl__mesh_arrays), without a triangulated view: `xyl_mesh v = XYL__MESH_VIEW_OF(&desc);` */
#define XYL__MESH_VIEW_OF(s)                                                                   \
    {(s)->positions, (s)->normals, (s)->uvs, (s)->branch_ids, (s)->vertex_count, (s)->quads,   \
     (s)->quad_count, (s)->triangles, (s)->triangle_count, (s)->face_branches, NULL, 0,        \
     (s)->uv_wraps, {(s)->origin[0], (s)->origin[1], (s)->origin[2]}}

/* What xyl_mesh_split_seams reads; xyl__mesh_split_seams is the call for a mesh that has passed
 * xyl__mesh_validate with these. */
#define XYL__SPLIT_SEAMS_READS                                                                 \
    (XYL__MESH_NORMALS | XYL__MESH_UVS | XYL__MESH_BRANCH_IDS | XYL__MESH_FACE_BRANCHES |      \
     XYL__MESH_UV_WRAPS)
xyl_result xyl__mesh_split_seams(const xyl_mesh *m, const xyl_allocator *alloc, xyl_mesh **out,
                                 xyl_diag *diag);

/* Every intersecting triangle pair of a mesh's triangulated view, as xyl_mesh_self_intersections
 * finds them, in one pass: *pairs (from alloc, NULL for the default allocator; i << 32 | j with
 * i < j, sorted; free with xyl__free(alloc, .)) and *count. Errors: those of
 * xyl_mesh_self_intersections. */
xyl_result xyl__mesh_intersecting_pairs(const xyl_mesh *mesh, const xyl_allocator *alloc,
                                        uint64_t **pairs, size_t *count, xyl_diag *diag);

/* The area at or below which the intersection test skips a triangle as degenerate: a relative
 * epsilon times the squared diagonal of the view's bounding box. */
double xyl__mesh_area_tolerance(const xyl_mesh *m);

/* The same, but only the pairs with at least one triangle marked (marked[t] != 0, one byte per
 * triangle of the view): the hierarchy is built over every triangle, and only subtrees that
 * hold a marked one are opened against each other. marked NULL: every pair. */
xyl_result xyl__mesh_intersecting_pairs_marked(const xyl_mesh *mesh, const uint8_t *marked,
                                               const xyl_allocator *alloc, uint64_t **pairs,
                                               size_t *count, xyl_diag *diag);

/* Bit c of a face's uv_wraps set: corner c's u is its vertex's u + 1. The bits a face of n
 * corners may use. */
#define XYL__WRAP_BITS(n) ((uint8_t)((1u << (n)) - 1u))

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

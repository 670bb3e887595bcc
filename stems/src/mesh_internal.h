/* Mesh internals shared by stems/ (mesher, subdivision, exporters, checks). Not installed. */
#ifndef XYL_MESH_INTERNAL_H
#define XYL_MESH_INTERNAL_H

#include "xyl_internal.h"
#include "xylem/xyl_stems.h"

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

/* Area-weighted vertex normals into out (vertex_count entries). With face_branch (one entry per
 * face, quads first, then triangles) a vertex averages only the faces of its own branch
 * (a->branch_ids), falling back to all its faces when none is; without, all faces. A vertex
 * without usable faces gets (0, 1, 0). Fails only with XYL_ERR_OUT_OF_MEMORY. */
xyl_result xyl__mesh_normals(const xyl__mesh_arrays *a, const uint32_t *face_branch,
                             const xyl_allocator *alloc, xyl_vec3 *out);

#endif

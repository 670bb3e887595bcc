/* xyl_mesh.h: polygon meshes of quads and triangles: checks, self-intersection test, one level
 * of subdivision (OpenSubdiv), UV seam split, OBJ and glTF binary export.
 *
 * How to use
 *     xyl_mesh_desc d = {0};
 *     d.positions = pos; d.vertex_count = n;         // normals NULL: smooth normals computed
 *     d.quads = quads; d.quad_count = q;
 *     xyl_mesh *m = NULL;
 *     if (xyl_mesh_create(&d, &m, &diag) != XYL_OK) puts(diag.message);
 *     xyl_mesh_report r;
 *     xyl_mesh_check(m, NULL, &r, &diag);            // r.closed_manifold, r.euler, ...
 *     xyl_mesh_write_file(m, "out.glb", XYL_MESH_FORMAT_GLB, NULL, &diag);
 *     xyl_mesh_destroy(m);
 *
 * World coordinates: positions are floats relative to a local origin held in double
 * (xyl_mesh.origin; the stem mesher takes the skeleton's), so a tree far from (0, 0, 0) keeps
 * the precision of a tree at it. The OBJ writer prints world positions (origin + position,
 * summed in double), the GLB writer puts the origin in the node's translation. An origin of 0
 * changes nothing.
 *
 * Every call is reentrant; a mesh is immutable once made, so threads may read it at once. Every
 * allocation of a call comes from its allocator: desc.alloc, or an `alloc` argument where NULL
 * (or a zero-filled one) means the default allocator; a mesh is freed with the allocator it was
 * made from. (OpenSubdiv's own topology tables, inside xyl_mesh_subdivide, are the exception:
 * docs/memory.md.) A call may be given a mesh the caller built (an xyl_mesh of its own arrays): it
 * checks what it reads first (arrays there for their counts, numbers finite, indices in range,
 * as xyl_mesh_create checks a desc).
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_MESH_H
#define XYL_MESH_H

#include <xylem/xyl_core.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- meshes ---------------------------------------------------------------------------------
 *
 * A polygon mesh of quads and triangles (stems are quads; Loop subdivision gives triangles) with
 * per-vertex position, normal, UV and branch id, and a triangulated view of every face for
 * PN-triangles and exporters. Faces are counter-clockwise seen from outside. A quad (a, b, c, d)
 * is triangulated as (a, b, c), (a, c, d). The arrays belong to the mesh.
 *
 * UV seams: u runs around each branch and closes where a ring's last vertex meets its first
 * again ((k - 1)/k back to 0). The vertex there is shared, so the mesh stays closed; the faces
 * that close the ring instead mark the corner in uv_wraps, and a corner's UV is (u + 1, v) when
 * its bit is set. Texturing needs those corner UVs: exporters write them (OBJ as extra vt
 * entries, GLB through xyl_mesh_split_seams), and a renderer can draw the split mesh. */

typedef struct xyl_mesh {
    const xyl_vec3 *positions;
    const xyl_vec3 *normals;      /* unit, one per vertex */
    const float *uvs;             /* 2 per vertex: u around the branch, v along it */
    const uint32_t *branch_ids;   /* one per vertex */
    size_t vertex_count;
    const uint32_t *quads;        /* 4 vertex indices per quad */
    size_t quad_count;
    const uint32_t *triangles;    /* 3 vertex indices per triangle face */
    size_t triangle_count;
    const uint32_t *face_branches; /* one per face, quads first, then triangles */
    const uint32_t *tri_view;     /* 3 indices per triangle: quads split, then the triangles */
    size_t tri_view_count;        /* 2 * quad_count + triangle_count */
    const uint8_t *uv_wraps;      /* one per face, quads first: bit c set means corner c's u is
                                     its vertex's u + 1 (see above); NULL in a view a caller
                                     built means none */
    double origin[3];             /* world position of the local (0, 0, 0): world = origin +
                                     position, in double; 0 in a view built without it */
} xyl_mesh;

typedef struct xyl_mesh_limits {
    uint64_t max_vertices; /* default (0): 1 << 26 */
    uint64_t max_faces;    /* default (0): 1 << 26 */
} xyl_mesh_limits;

typedef struct xyl_mesh_desc {
    const xyl_vec3 *positions;  /* required when vertex_count > 0 */
    const xyl_vec3 *normals;    /* optional: NULL computes area-weighted smooth normals */
    const float *uvs;           /* optional: NULL means all 0 */
    const uint32_t *branch_ids; /* optional: NULL means all 0 */
    size_t vertex_count;
    const uint32_t *quads;
    size_t quad_count;
    const uint32_t *triangles;
    size_t triangle_count;
    const uint32_t *face_branches; /* optional: NULL means all 0 */
    const uint8_t *uv_wraps;       /* optional, one per face: NULL means none (xyl_mesh) */
    xyl_mesh_limits limits;
    xyl_allocator alloc;
    double origin[3];              /* default (0): world position the positions are relative
                                      to; finite. Copied to xyl_mesh.origin */
} xyl_mesh_desc;

/* Validates (indices in range, finite numbers, no face repeating a vertex, wrap bits within a
 * face's corners), copies, and builds the triangulated view. Errors: XYL_ERR_INVALID_ARGUMENT
 * (NULL arrays with counts, an index out of range or repeated within a face, a wrap bit beyond a
 * face's corners: diag.index is the face, quads first), XYL_ERR_NON_FINITE (diag.index is the
 * vertex; -1 for an origin that is not finite), XYL_ERR_LIMIT_EXCEEDED, XYL_ERR_OUT_OF_MEMORY. On failure *out is untouched. */
XYL_API xyl_result xyl_mesh_create(const xyl_mesh_desc *desc, xyl_mesh **out, xyl_diag *diag);
XYL_API void xyl_mesh_destroy(xyl_mesh *mesh);

/* The mesh with its UV seams split, for renderers and formats that keep one UV per vertex: a
 * vertex that some face uses with its u + 1 (uv_wraps) gets a copy with that UV, appended after
 * the original vertices in the order of the originals (a vertex used only so is not copied: its
 * u moves by 1). Faces, their order and branches, positions, normals and branch ids are kept; the
 * split mesh's uv_wraps are all 0. Its seams are open by index (an edge along a seam is used once
 * by each side's vertices) but closed by position, so it is for drawing and export, not for
 * xyl_mesh_check, subdivision or the intersection test. A mesh without wraps comes back as a
 * copy; the origin is kept. Errors: XYL_ERR_INVALID_ARGUMENT (NULL arguments or arrays, an index out of range or
 * repeated within a face, a wrap bit beyond a face's corners: diag.index is the face),
 * XYL_ERR_NON_FINITE (diag.index is the vertex), XYL_ERR_LIMIT_EXCEEDED (more than 2^32 - 1
 * vertices), XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_mesh_split_seams(const xyl_mesh *mesh, const xyl_allocator *alloc,
                                        xyl_mesh **out, xyl_diag *diag);

/* Axis-aligned bounds of all positions, relative to the origin (for framing a camera:
 * xyl_tess_camera_frame). A NULL
 * or empty mesh gives lo = hi = 0. */
XYL_API void xyl_mesh_bounds(const xyl_mesh *mesh, float lo[3], float hi[3]);

/* ---- subdivision (OpenSubdiv) -------------------------------------------------------------- */

typedef enum xyl_subdivision {
    XYL_SUBDIVIDE_NONE = 0,
    XYL_SUBDIVIDE_CATMARK = 1, /* Catmull-Clark: every face becomes quads */
    XYL_SUBDIVIDE_LOOP = 2     /* Loop: triangles only (quads are triangulated first) */
} xyl_subdivision;

typedef struct xyl_subdivide_desc {
    xyl_subdivision scheme;   /* NONE copies the mesh */
    bool keep_control_points; /* default false: the refined vertices are moved to their limit
                                 positions and get the limit normals, so the mesh interpolates
                                 the smooth surface (what PN refinement wants); true keeps the
                                 level-1 control points (to subdivide further) and smooth face
                                 normals */
    xyl_mesh_limits limits;   /* of the refined mesh */
    xyl_allocator alloc;
} xyl_subdivide_desc;

/* One uniform level of refinement through OpenSubdiv Far. Positions and UVs are interpolated
 * (vertex and varying), then positions moved to the limit surface (unless keep_control_points),
 * face branch ids are inherited from the parent face, vertex branch ids follow the rules of
 * docs/subdivision.md; normals are the limit normals (or, with keep_control_points, recomputed
 * smooth); the origin is kept. Errors:
 * XYL_ERR_INVALID_ARGUMENT, XYL_ERR_NON_FINITE, XYL_ERR_UNSUPPORTED (topology OpenSubdiv refuses),
 * XYL_ERR_LIMIT_EXCEEDED, XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_mesh_subdivide(const xyl_mesh *mesh, const xyl_subdivide_desc *desc,
                                      xyl_mesh **out, xyl_diag *diag);

/* ---- export -------------------------------------------------------------------------------- */

typedef enum xyl_mesh_format {
    XYL_MESH_FORMAT_OBJ = 0, /* Wavefront OBJ with v/vt/vn and quad and triangle faces */
    XYL_MESH_FORMAT_GLB = 1  /* glTF 2.0 binary: POSITION, NORMAL, TEXCOORD_0, _BRANCH_ID, indices */
} xyl_mesh_format;

/* Count-then-fill, as xyl_skeleton_write_text (bytes; GLB output is binary). A mesh with UV
 * seams is split for the UVs on the way (xyl_mesh_split_seams), from alloc (NULL: the default
 * allocator). Errors: XYL_ERR_INVALID_ARGUMENT (NULL arguments, a buffer too small, a broken
 * view as xyl_mesh_split_seams has it, a triangulated view that is not 2 q + t triangles in
 * range; a GLB of vertices without faces), XYL_ERR_NON_FINITE, XYL_ERR_LIMIT_EXCEEDED (a GLB
 * over 4 GiB or with branch ids above 2^24), XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_mesh_write_memory(const xyl_mesh *mesh, xyl_mesh_format format,
                                         const xyl_allocator *alloc, void *buffer,
                                         size_t capacity, size_t *needed);
/* Writes through a temporary file and a rename; path is never half-written. The file is
 * rendered in memory from alloc (NULL: the default allocator). Errors: those of
 * xyl_mesh_write_memory, and XYL_ERR_IO. */
XYL_API xyl_result xyl_mesh_write_file(const xyl_mesh *mesh, const char *path,
                                       xyl_mesh_format format, const xyl_allocator *alloc,
                                       xyl_diag *diag);

/* ---- checks -------------------------------------------------------------------------------- */

typedef struct xyl_mesh_report {
    size_t vertices, edges, faces;
    int64_t euler;                 /* V - E + F */
    size_t components;             /* connected by shared edges */
    size_t boundary_edges;         /* used by one face */
    size_t nonmanifold_edges;      /* used by three or more faces */
    size_t misoriented_edges;      /* used twice in the same direction */
    size_t nonmanifold_vertices;   /* whose faces do not form one fan */
    size_t degenerate_faces;       /* zero area (relative to the mesh size) */
    size_t duplicate_faces;        /* the same vertex set as another face */
    size_t unused_vertices;        /* in no face */
    bool closed_manifold;          /* all of the counts above that must be 0 are 0 */
} xyl_mesh_report;

/* Topology and geometry statistics of a mesh (definitions and the one tolerance:
 * docs/mesh-checks.md). Scratch memory comes from alloc (NULL: the default allocator). Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL arguments or arrays, a bad index or a vertex repeated in a
 * face: diag.index = the face), XYL_ERR_NON_FINITE (a position, or a normal or UV where the mesh
 * has them: diag.index = the vertex), XYL_ERR_LIMIT_EXCEEDED, XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_mesh_check(const xyl_mesh *mesh, const xyl_allocator *alloc,
                                  xyl_mesh_report *report, xyl_diag *diag);

/* Pairs of triangles of the triangulated view whose intersection is more than the vertices they
 * share (robust triangle-triangle test, BVH broad phase; docs/mesh-checks.md). Writes the pairs
 * (i, j), i < j, sorted, 2 indices each: the first `capacity` of them into pairs (NULL with
 * capacity 0 only counts), and the total into *count. Reads positions and the view only (a
 * view index out of range: diag.index = the view triangle). Scratch memory comes from alloc
 * (NULL: the default allocator). Errors: as xyl_mesh_check, plus XYL_ERR_INVALID_ARGUMENT for
 * pairs NULL with capacity > 0. */
XYL_API xyl_result xyl_mesh_self_intersections(const xyl_mesh *mesh, const xyl_allocator *alloc,
                                               uint32_t *pairs, size_t capacity, size_t *count,
                                               xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif /* XYL_MESH_H */

/* xyl_stems.h: branch skeletons (and, later, the stem mesh built from them).
 *
 * How to use
 *   A skeleton is a forest of nodes. Node i has a position, a radius, and a parent index that is
 *   smaller than i (or -1 for a root), so an array walk visits parents before children. Segments
 *   join a node to its parent. Branch ids and orders are derived: at a node with several
 *   children the child with the largest radius (first one on ties) continues the parent's branch
 *   and order; each other child starts a new branch of order + 1.
 *
 *     // from your own arrays
 *     xyl_skeleton_desc d = {0};
 *     d.nodes = my_nodes; d.node_count = n;          // pos, radius, parent; branch/order ignored
 *     xyl_skeleton *s = NULL;
 *     if (xyl_skeleton_create(&d, &s, &diag) != XYL_OK) puts(diag.message);
 *     ...
 *     xyl_skeleton_destroy(s);
 *
 *     // from / to the .skel text format (docs/skeleton-format.md)
 *     xyl_skeleton_read_file("tree.skel", NULL, &s, &diag);
 *     xyl_skeleton_write_file(s, "tree.skel", XYL_SKEL_FORMAT_SKEL, &diag);
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_STEMS_H
#define XYL_STEMS_H

#include <xylem/xyl_common.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct xyl_skel_node {
    xyl_vec3 pos;      /* world units */
    float radius;      /* > 0, finite */
    int32_t parent;    /* index of the parent node (< own index), or -1 for a root */
    uint32_t branch;   /* derived: branch id, 0..branch_count-1, roots' branches first seen first */
    uint32_t order;    /* derived: 0 for a root's branch, +1 for each lateral fork */
} xyl_skel_node;

typedef struct xyl_skel_leaf {
    xyl_vec3 pos;      /* attachment point */
    xyl_vec3 heading;  /* unit: the turtle's heading when the leaf was placed */
    xyl_vec3 left;     /* unit, orthogonal to heading */
    xyl_vec3 up;       /* unit, heading x left */
    float size;        /* > 0, leaf length in world units */
    int32_t node;      /* node the leaf hangs from, or -1 if placed before any node */
} xyl_skel_leaf;

/* Read-only view; the arrays belong to the skeleton. */
typedef struct xyl_skeleton {
    const xyl_skel_node *nodes;
    size_t node_count;
    const xyl_skel_leaf *leaves;
    size_t leaf_count;
    uint32_t branch_count;
    uint32_t root_count;
    uint32_t max_order;
    uint32_t clamped_forks;  /* forks whose Murray angles were clamped (0 unless Murray mode) */
} xyl_skeleton;

typedef struct xyl_skeleton_limits {
    uint64_t max_nodes;  /* default (0): 1 << 24 */
    uint64_t max_leaves; /* default (0): 1 << 24 */
} xyl_skeleton_limits;

typedef struct xyl_skeleton_desc {
    const xyl_skel_node *nodes; /* pos, radius, parent are read; branch/order are recomputed */
    size_t node_count;
    const xyl_skel_leaf *leaves; /* may be NULL when leaf_count == 0 */
    size_t leaf_count;
    xyl_skeleton_limits limits;
    xyl_allocator alloc;
} xyl_skeleton_desc;

/* Validates and copies the arrays, then derives branch ids and orders. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL desc/out, NULL arrays with a count),
 * XYL_ERR_NON_FINITE (a NaN/inf anywhere; diag.index = node or leaf),
 * XYL_ERR_INVALID_SKELETON (parent >= own index or < -1, radius <= 0, leaf size <= 0,
 *                          leaf node out of range),
 * XYL_ERR_LIMIT_EXCEEDED, XYL_ERR_OUT_OF_MEMORY. On failure *out is left untouched. */
XYL_API xyl_result xyl_skeleton_create(const xyl_skeleton_desc *desc, xyl_skeleton **out,
                                       xyl_diag *diag);

/* NULL is fine. */
XYL_API void xyl_skeleton_destroy(xyl_skeleton *skeleton);

typedef enum xyl_skel_format {
    XYL_SKEL_FORMAT_SKEL = 0, /* the line-based text format, read back by xyl_skeleton_read_* */
    XYL_SKEL_FORMAT_OBJ = 1   /* Wavefront OBJ polylines ('l'), one vertex per node; write only */
} xyl_skel_format;

typedef struct xyl_skeleton_read_desc {
    xyl_skeleton_limits limits;
    xyl_allocator alloc;
} xyl_skeleton_read_desc;

/* Parses .skel text (docs/skeleton-format.md). desc may be NULL (defaults). Errors:
 * XYL_ERR_PARSE (line/column in diag), XYL_ERR_TRUNCATED (fewer records than announced or no
 * 'end' line), plus those of xyl_skeleton_create. */
XYL_API xyl_result xyl_skeleton_read_text(const char *text, size_t length,
                                          const xyl_skeleton_read_desc *desc,
                                          xyl_skeleton **out, xyl_diag *diag);
XYL_API xyl_result xyl_skeleton_read_file(const char *path, const xyl_skeleton_read_desc *desc,
                                          xyl_skeleton **out, xyl_diag *diag);

/* Count-then-fill: with buffer == NULL (or too small) sets *needed to the byte count
 * (without the terminating NUL) and returns XYL_OK / XYL_ERR_INVALID_ARGUMENT respectively;
 * otherwise writes NUL-terminated text. A caller-built view that breaks the skeleton's
 * invariants gives XYL_ERR_NON_FINITE or XYL_ERR_INVALID_SKELETON, as xyl_skeleton_create. */
XYL_API xyl_result xyl_skeleton_write_text(const xyl_skeleton *skeleton, xyl_skel_format format,
                                           char *buffer, size_t capacity, size_t *needed);

/* Writes to path.tmp-XXXXXX next to path and renames it over path, so path is never
 * half-written. Errors: XYL_ERR_IO (diag says which call failed and errno text). */
XYL_API xyl_result xyl_skeleton_write_file(const xyl_skeleton *skeleton, const char *path,
                                           xyl_skel_format format, xyl_diag *diag);

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
} xyl_mesh_desc;

/* Validates (indices in range, finite numbers, no face repeating a vertex), copies, and builds
 * the triangulated view. Errors: XYL_ERR_INVALID_ARGUMENT (NULL arrays with counts, an index out
 * of range or repeated within a face: diag.index is the face, quads first), XYL_ERR_NON_FINITE,
 * XYL_ERR_LIMIT_EXCEEDED, XYL_ERR_OUT_OF_MEMORY. On failure *out is untouched. */
XYL_API xyl_result xyl_mesh_create(const xyl_mesh_desc *desc, xyl_mesh **out, xyl_diag *diag);
XYL_API void xyl_mesh_destroy(xyl_mesh *mesh);

/* The mesh with its UV seams split, for renderers and formats that keep one UV per vertex: a
 * vertex that some face uses with its u + 1 (uv_wraps) gets a copy with that UV, appended after
 * the original vertices in the order of the originals (a vertex used only so is not copied: its
 * u moves by 1). Faces, their order and branches, positions, normals and branch ids are kept; the
 * split mesh's uv_wraps are all 0. Its seams are open by index (an edge along a seam is used once
 * by each side's vertices) but closed by position, so it is for drawing and export, not for
 * xyl_mesh_check, subdivision or the intersection test. A mesh without wraps comes back as a
 * copy. Errors: XYL_ERR_INVALID_ARGUMENT (NULL arguments or arrays, an index out of range or
 * repeated within a face, a wrap bit beyond a face's corners: diag.index is the face), XYL_ERR_LIMIT_EXCEEDED (more than 2^32 - 1 vertices),
 * XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_mesh_split_seams(const xyl_mesh *mesh, const xyl_allocator *alloc,
                                        xyl_mesh **out, xyl_diag *diag);

/* Axis-aligned bounds of all positions (for framing a camera: xyl_tess_camera_frame). A NULL
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
 * smooth). Errors:
 * XYL_ERR_INVALID_ARGUMENT, XYL_ERR_NON_FINITE, XYL_ERR_UNSUPPORTED (topology OpenSubdiv refuses),
 * XYL_ERR_LIMIT_EXCEEDED, XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_mesh_subdivide(const xyl_mesh *mesh, const xyl_subdivide_desc *desc,
                                      xyl_mesh **out, xyl_diag *diag);

/* ---- export -------------------------------------------------------------------------------- */

typedef enum xyl_mesh_format {
    XYL_MESH_FORMAT_OBJ = 0, /* Wavefront OBJ with v/vt/vn and quad and triangle faces */
    XYL_MESH_FORMAT_GLB = 1  /* glTF 2.0 binary: POSITION, NORMAL, TEXCOORD_0, _BRANCH_ID, indices */
} xyl_mesh_format;

/* Count-then-fill, as xyl_skeleton_write_text (bytes; GLB output is binary). */
XYL_API xyl_result xyl_mesh_write_memory(const xyl_mesh *mesh, xyl_mesh_format format,
                                         void *buffer, size_t capacity, size_t *needed);
/* Writes through a temporary file and a rename; path is never half-written. */
XYL_API xyl_result xyl_mesh_write_file(const xyl_mesh *mesh, const char *path,
                                       xyl_mesh_format format, xyl_diag *diag);

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
 * docs/mesh-checks.md). Errors: XYL_ERR_INVALID_ARGUMENT (NULL arguments or arrays, a bad index
 * or a vertex repeated in a face: diag.index = the face), XYL_ERR_NON_FINITE,
 * XYL_ERR_LIMIT_EXCEEDED, XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_mesh_check(const xyl_mesh *mesh, xyl_mesh_report *report, xyl_diag *diag);

/* Pairs of triangles of the triangulated view whose intersection is more than the vertices they
 * share (robust triangle-triangle test, BVH broad phase; docs/mesh-checks.md). Writes the pairs
 * (i, j), i < j, sorted, 2 indices each: the first `capacity` of them into pairs (NULL with
 * capacity 0 only counts), and the total into *count. Errors: as xyl_mesh_check, plus
 * XYL_ERR_INVALID_ARGUMENT for pairs NULL with capacity > 0. */
XYL_API xyl_result xyl_mesh_self_intersections(const xyl_mesh *mesh, uint32_t *pairs,
                                               size_t capacity, size_t *count, xyl_diag *diag);

/* ---- stems: the mesh of a skeleton ---------------------------------------------------------- */

typedef enum xyl_normal_mode {
    XYL_NORMALS_BRANCH = 0, /* a vertex averages only its own branch's faces (Skjermo 2008) */
    XYL_NORMALS_SMOOTH = 1  /* a vertex averages all its faces */
} xyl_normal_mode;

/* Whether xyl_stems_build checks its mesh at the joints (docs/stems.md, "Checked joints"). */
typedef enum xyl_joint_check {
    XYL_JOINTS_CHECKED = 0,  /* default: the mesh is tested for intersecting triangle pairs; for
                                each pair at a joint (every pair but those where the skeleton
                                overlaps itself) a lateral starts a node later, a second, or at
                                last is left out with all that grows from it, and the mesh is
                                built again, until no pair at a joint is left. The test runs
                                before subdivision, on the mesh at the skeleton's radii; a
                                subdivided mesh makes the same changes */
    XYL_JOINTS_UNCHECKED = 1 /* the construction alone, without the test: faster
                                (docs/BENCHMARKS.md); the presets then have pairs at joints */
} xyl_joint_check;

/* What a checked build did (all 0 but builds when unchecked). Face counts are of the mesh
 * before subdivision. */
typedef struct xyl_stems_stats {
    uint32_t builds;           /* meshes built: 1, plus one per round of laterals left out,
                                  plus one to subdivide */
    uint32_t laterals_started_later; /* laterals that start a node or two further out */
    uint32_t branches_dropped; /* laterals left out, with all that grows from them */
    size_t faces_first;        /* faces of the first mesh built */
    size_t faces_checked;      /* faces of the mesh that passed, to compare */
    size_t joint_pairs_first;  /* intersecting pairs at joints in the first mesh */
    size_t joint_pairs_left;   /* in the mesh that passed: 0, unless only a root could give way
                                  (a root's own tube, two roots that cross; then diag gets a
                                  warning) */
    size_t skeleton_pairs;     /* intersecting pairs of the mesh that passed that the skeleton's
                                  own overlaps explain */
} xyl_stems_stats;

typedef struct xyl_stems_desc {
    uint32_t sides;               /* ring sides k, 3..32; default (0): 4. Even k gives quads
                                     only; odd k one triangle per cap and per bridge */
    xyl_normal_mode normals;
    xyl_subdivision subdivision;  /* one level of pre-subdivision; default none */
    bool keep_control_radius;     /* default false: before subdivision, rings are inflated so
                                     the limit surface's MEAN radius is the skeleton's (1.522
                                     for k = 4 with Catmull-Clark; docs/stems.md), and inner
                                     ring centres are moved against the limit's pull towards
                                     the centre of curvature on bends */
    bool keep_control_points;     /* default false: subdivided vertices sit on the limit
                                     surface (see xyl_subdivide_desc) */
    xyl_joint_check joints;
    xyl_stems_stats *stats;       /* optional: filled when the build succeeds */
    xyl_mesh_limits limits;
    xyl_allocator alloc;
} xyl_stems_desc;

/* One closed quad mesh around the whole skeleton: a tube per branch, children grown out of their
 * parent (docs/stems.md). desc may be NULL. Errors: XYL_ERR_INVALID_ARGUMENT,
 * XYL_ERR_LIMIT_EXCEEDED, XYL_ERR_OUT_OF_MEMORY, and those of xyl_mesh_subdivide. */
XYL_API xyl_result xyl_stems_build(const xyl_skeleton *skeleton, const xyl_stems_desc *desc,
                                   xyl_mesh **out, xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif /* XYL_STEMS_H */

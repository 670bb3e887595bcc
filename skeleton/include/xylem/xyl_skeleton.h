/* xyl_skeleton.h: branch skeletons, their .skel text format and OBJ polylines.
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
 *   World coordinates: positions are floats relative to a local origin held in double
 *   (xyl_skeleton.origin), so a tree far from (0, 0, 0) keeps the precision of a tree at it.
 *   Put the tree's own coordinates in the nodes and its place in the world in desc.origin; the
 *   .skel reader takes the first root's position as the origin, the writers print world
 *   positions (origin + local, docs/skeleton-format.md). An origin of 0 changes nothing.
 *
 *     // from / to the .skel text format (docs/skeleton-format.md)
 *     xyl_skeleton_read_file("tree.skel", NULL, &s, &diag);
 *     xyl_skeleton_write_file(s, "tree.skel", XYL_SKEL_FORMAT_SKEL, NULL, &diag);
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_SKELETON_H
#define XYL_SKELETON_H

#include <xylem/xyl_core.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct xyl_skel_node {
    xyl_vec3 pos;      /* world units, relative to the skeleton's origin */
    float radius;      /* > 0, finite */
    int32_t parent;    /* index of the parent node (< own index), or -1 for a root */
    uint32_t branch;   /* derived: branch id, 0..branch_count-1, roots' branches first seen first */
    uint32_t order;    /* derived: 0 for a root's branch, +1 for each lateral fork */
} xyl_skel_node;

typedef struct xyl_skel_leaf {
    xyl_vec3 pos;      /* attachment point, relative to the skeleton's origin */
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
    double origin[3];        /* world position of the local (0, 0, 0): node and leaf positions
                                are relative to it; world = origin + pos, in double */
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
    double origin[3]; /* default (0): the world position the node and leaf positions are
                         relative to; finite. Copied to xyl_skeleton.origin */
} xyl_skeleton_desc;

/* Validates and copies the arrays, then derives branch ids and orders. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL desc/out, NULL arrays with a count),
 * XYL_ERR_NON_FINITE (a NaN/inf anywhere, the origin included; diag.index = node or leaf, -1
 *                    for the origin),
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

/* Parses .skel text (docs/skeleton-format.md). desc may be NULL (defaults). Positions are read
 * in double; the first node's position becomes the skeleton's origin and every position is
 * stored relative to it (an empty skeleton has origin 0). Errors:
 * XYL_ERR_PARSE (line/column in diag), XYL_ERR_TRUNCATED (fewer records than announced or no
 * 'end' line), plus those of xyl_skeleton_create. */
XYL_API xyl_result xyl_skeleton_read_text(const char *text, size_t length,
                                          const xyl_skeleton_read_desc *desc,
                                          xyl_skeleton **out, xyl_diag *diag);
XYL_API xyl_result xyl_skeleton_read_file(const char *path, const xyl_skeleton_read_desc *desc,
                                          xyl_skeleton **out, xyl_diag *diag);

/* Count-then-fill: with buffer == NULL (or too small) sets *needed to the byte count
 * (without the terminating NUL) and returns XYL_OK / XYL_ERR_INVALID_ARGUMENT respectively;
 * otherwise writes NUL-terminated text. Positions are written in world coordinates: with origin
 * 0 each float as the shortest text that reads back as it, else origin + pos summed in double
 * and written as the shortest text that reads back as that double. A caller-built view that
 * breaks the skeleton's invariants gives XYL_ERR_NON_FINITE or XYL_ERR_INVALID_SKELETON, as
 * xyl_skeleton_create. */
XYL_API xyl_result xyl_skeleton_write_text(const xyl_skeleton *skeleton, xyl_skel_format format,
                                           char *buffer, size_t capacity, size_t *needed);

/* Writes to path.tmp-XXXXXX next to path and renames it over path, so path is never
 * half-written. The text and the temporary name come from alloc (NULL: the default
 * allocator). Errors: those of xyl_skeleton_write_text, XYL_ERR_OUT_OF_MEMORY, XYL_ERR_IO (diag
 * says which call failed and errno text). */
XYL_API xyl_result xyl_skeleton_write_file(const xyl_skeleton *skeleton, const char *path,
                                           xyl_skel_format format, const xyl_allocator *alloc,
                                           xyl_diag *diag);

/* ---- twig pruning ----------------------------------------------------------------------------
 *
 * A coarser skeleton at a known world error, for stem LODs (xyl_stems_lods_build in
 * xyl_stems.h): every subtree thinner than a width goes.
 *
 *     xyl_skeleton *coarse = NULL;
 *     xyl_skeleton_prune_stats st;
 *     xyl_skeleton_prune(s, 0.02f, NULL, &coarse, &st, &diag);  // twigs under 2 cm wide go
 *     // st.max_removed_width: the world error of the coarse tree
 */

typedef struct xyl_skeleton_prune_desc {
    xyl_allocator alloc; /* the pruned skeleton and the call's scratch; default: malloc */
} xyl_skeleton_prune_desc;

typedef struct xyl_skeleton_prune_stats {
    size_t nodes_removed;
    size_t subtrees_removed;  /* removed nodes whose parent stays: the cuts */
    float max_removed_width;  /* the largest diameter 2 r of a removed node, world units; 0 when
                                 nothing was removed. Below min_width: the pruned tree's world
                                 error (a removed twig is at most this wide) */
    size_t leaves_moved;      /* leaves whose node was removed, now hanging from its nearest
                                 kept ancestor */
} xyl_skeleton_prune_stats;

/* A new skeleton without every node whose whole subtree (the node and all its descendants) has
 * a largest diameter 2 r below min_width, except that every root keeps its root node and the
 * next node of its branch (its child of largest radius, first on ties): the trunk is never
 * removed, though the thin tail of any branch, the trunk's included, is. The kept nodes keep
 * their order, positions and radii (parents renumbered, branch ids and orders derived again);
 * every leaf is kept where it was, one hanging from a removed node now hanging from its nearest
 * kept ancestor, so the foliage of the pruned tree is the same. The origin and clamped_forks are
 * carried over. min_width 0 removes nothing (a copy). desc may be NULL (the default allocator);
 * stats may be NULL, else filled on success. Time and memory O(nodes + leaves).
 * Errors: XYL_ERR_INVALID_ARGUMENT (NULL skeleton or out; min_width NaN, infinite or negative),
 * XYL_ERR_NON_FINITE and XYL_ERR_INVALID_SKELETON (a caller-built view that breaks the
 * skeleton's invariants, as xyl_skeleton_create), XYL_ERR_OUT_OF_MEMORY. On failure *out and
 * *stats are untouched and nothing is left allocated. */
XYL_API xyl_result xyl_skeleton_prune(const xyl_skeleton *skeleton, float min_width,
                                      const xyl_skeleton_prune_desc *desc, xyl_skeleton **out,
                                      xyl_skeleton_prune_stats *stats, xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif /* XYL_SKELETON_H */

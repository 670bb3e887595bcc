/* Skeleton internals shared by stems/ and the modules above it (lsystem's turtle). */
#ifndef XYL_SKELETON_INTERNAL_H
#define XYL_SKELETON_INTERNAL_H

#include "xyl_internal.h"
#include "xylem/xyl_skeleton.h"

/* Documented defaults of xyl_skeleton_limits (xyl_skeleton.h), shared by every producer. */
#define XYL__SKEL_DEFAULT_MAX_NODES (UINT64_C(1) << 24)
#define XYL__SKEL_DEFAULT_MAX_LEAVES (UINT64_C(1) << 24)

/* The public view comes first so a xyl_skeleton* is a xyl__skeleton*. */
typedef struct xyl__skeleton {
    xyl_skeleton pub;
    xyl_skel_node *nodes;
    xyl_skel_leaf *leaves;
    xyl_allocator alloc;
} xyl__skeleton;

/* Runs the checks of xyl_skeleton_create without copying. */
xyl_result xyl__skeleton_validate(const xyl_skeleton_desc *desc, xyl_diag *diag);

/* A skeleton view (public, so possibly built by the caller) checked like a desc, without
 * limits: what the writers and the pruning walk rely on (parents before children ...). */
xyl_result xyl__skeleton_check_view(const xyl_skeleton *sk, xyl_diag *diag);

/* Takes ownership of nodes/leaves (allocated with alloc; freed on failure too), derives branch
 * ids and orders and wraps them in a skeleton whose positions are relative to origin (NULL: 0).
 * The arrays and the origin must already be valid. */
xyl_result xyl__skeleton_adopt(xyl_skel_node *nodes, size_t node_count, xyl_skel_leaf *leaves,
                               size_t leaf_count, const double *origin,
                               const xyl_allocator *alloc, xyl_skeleton **out, xyl_diag *diag);

/* Float precision of positions relative to the origin: where the spacing of floats at a node's
 * position exceeds this fraction of its radius (1/128: under 1 % of the radius), its rings lose
 * visible detail, and the calls that make or mesh a skeleton warn. */
#define XYL__SKEL_PRECISION_WARN (1.0 / 128.0)

/* The spacing of floats at a position: the unit in the last place of its largest coordinate
 * (0 at the origin). */
double xyl__skel_float_spacing(xyl_vec3 p);

/* Raises one warning on diag, with the figures, when some node's position is too coarse for its
 * radius (XYL__SKEL_PRECISION_WARN); what names the call ("the skeleton", "the stem mesh"). */
void xyl__skeleton_warn_precision(const xyl_skel_node *nodes, size_t count, const char *what,
                                  xyl_diag *diag);

#endif

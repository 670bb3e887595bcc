/* What the files of foliage/ share: resolved limits, the leaf rules, and the tolerances. Not
 * installed; the tests include it. */
#ifndef XYL_FOLIAGE_INTERNAL_H
#define XYL_FOLIAGE_INTERNAL_H

#include "xyl_internal.h"
#include "xylem/xyl_foliage.h"

#define XYL__FOLIAGE_MAX_LEAVES ((uint64_t)1 << 24)     /* default of limits.max_leaves */
#define XYL__FOLIAGE_MAX_LEAVES_CAP ((uint64_t)1 << 30) /* 2n - 1 leaves fit an int32 index */
#define XYL__FOLIAGE_MAX_COORDINATE 1e6                 /* default of limits.max_coordinate */
/* |cosine| up to which a caller's normal, axis and side count as orthogonal. */
#define XYL__LEAF_ORTHO_TOLERANCE 1e-3

typedef struct xyl__foliage_limits {
    uint64_t max_leaves;
    double max_coordinate;
} xyl__foliage_limits;

/* Defaults for zero fields; XYL_ERR_INVALID_ARGUMENT for a limit out of range. */
xyl_result xyl__foliage_limits_resolve(const xyl_foliage_limits *in, xyl__foliage_limits *out,
                                       xyl_diag *diag);
/* The rules of xyl_foliage_check_leaves for leaf i alone (the counts' sum aside). */
xyl_result xyl__leaf_check(const xyl_leaf *leaf, size_t i, const xyl__foliage_limits *limits,
                           xyl_diag *diag);
/* A checked leaf with its defaults filled in (count, uv) and its frame made exactly
 * orthonormal: normal normalised, axis orthogonal to it with its length kept,
 * side = |side| unit(axis x normal). */
xyl_leaf xyl__leaf_tidy(const xyl_leaf *leaf);

/* ---- the GPU record (pack.c) ---- */

/* binary16 bits of f, to nearest with ties to even; beyond 65504 (after rounding) infinity. */
uint16_t xyl__half_from_float(float f);
float xyl__float_from_half(uint16_t h);
/* What a shader reads from a record: centre, half-axes, normalize(cross(side, axis)), texture
 * rectangle; count 1 and node -1, which the record does not hold. For tests. */
xyl_leaf xyl__foliage_unpack_gpu(const xyl_foliage_gpu_leaf *g);

#endif

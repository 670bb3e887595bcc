/* xyl_foliage.h: leaves as quads and their 32-byte GPU record (docs/foliage.md).
 *
 * How to use
 *     xyl_diag diag = {0};
 *     // leaves from a skeleton's leaf attachments: count, then fill
 *     xyl_foliage_leaves_desc ld = {0};            // zero = aspect 0.5, no stalk, no jitter
 *     size_t n = 0;
 *     xyl_foliage_leaves_from_skeleton(sk, &ld, NULL, 0, &n, &diag);
 *     xyl_leaf *leaves = malloc((n ? n : 1) * sizeof *leaves);
 *     if (xyl_foliage_leaves_from_skeleton(sk, &ld, leaves, n, &n, &diag)) puts(diag.message);
 *
 *     // or your own leaves, checked with the rules every call that takes leaves applies
 *     if (xyl_foliage_check_leaves(mine, count, NULL, &diag)) printf("leaf %lld: %s\n",
 *                                                  (long long)diag.index, diag.message);
 *
 *     // 32 bytes a leaf for a GPU buffer (shaders/xyl_foliage_shared.h reads them in GLSL)
 *     xyl_foliage_gpu_leaf *gpu = malloc((n ? n : 1) * sizeof *gpu);
 *     xyl_foliage_pack_gpu(leaves, n, gpu, &diag);
 *
 * Every call is reentrant and allocates nothing here; the same input (seed included) gives
 * bit-identical leaves.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_FOLIAGE_H
#define XYL_FOLIAGE_H

#include <stddef.h>

#include <xylem/xyl_core.h>
#include <xylem/xyl_skeleton.h>
#include "xyl_foliage_shared.h" /* shaders/ in the source tree, next to this file once installed */

#ifdef __cplusplus
extern "C" {
#endif

/* The C view of the GPU leaf record; std430 in GLSL (xyl_foliage_shared.h says what precision
 * each field keeps). */
#if !defined(__cplusplus)
_Static_assert(sizeof(xyl_foliage_gpu_leaf) == XYL_FOLIAGE_GPU_LEAF_SIZE, "one leaf in 32 bytes");
_Static_assert(offsetof(xyl_foliage_gpu_leaf, axis) == 12, "halves follow the vec3 centre");
_Static_assert(offsetof(xyl_foliage_gpu_leaf, side) == 18, "side halves follow axis halves");
_Static_assert(offsetof(xyl_foliage_gpu_leaf, uv) == 24, "unorm16 rectangle in the last 8");
#endif
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "xyl_foliage_gpu_leaf pairs 16-bit fields into little-endian GLSL words"
#endif

/* ---- leaves -----------------------------------------------------------------------------------
 *
 * A leaf is a flat quad: the points center + s side + t axis for s, t in [-1, 1]. (side, axis,
 * normal) is a right-handed frame like (x, y, z): seen from the side the normal points to, the
 * axis runs up from the stalk end to the tip and the side runs to the right, so
 * normal = normalize(cross(side, axis)) and the texture reads the right way round. Corner
 * (s, t) takes the texture coordinate (u0 + (s + 1) / 2 (u1 - u0), v0 + (t + 1) / 2 (v1 - v0)):
 * v0 at the stalk end, v1 at the tip. */
typedef struct xyl_leaf {
    xyl_vec3 center;  /* world units */
    xyl_vec3 normal;  /* unit */
    xyl_vec3 axis;    /* half-axis from the centre towards the tip; |axis| = half the length */
    xyl_vec3 side;    /* half-axis across, along axis x normal; |side| = half the width */
    float uv[4];      /* texture rectangle u0, v0, u1, v1, each in [0, 1]; default (all 0):
                         0, 0, 1, 1 */
    uint32_t count;   /* original leaves this one stands for; default (0): 1 */
    int32_t node;     /* skeleton node the leaf hangs from, -1 if none */
} xyl_leaf;

/* Every bound is explicit; exceeding one is XYL_ERR_LIMIT_EXCEEDED, never a silent cut. */
typedef struct xyl_foliage_limits {
    uint64_t max_leaves;  /* leaves one call takes; default (0): 1 << 24, at most 1 << 30 */
    float max_coordinate; /* "huge": a centre coordinate or a half-axis length above this;
                             default (0): 1e6 world units, where a float centre still resolves
                             1/16 of a unit */
} xyl_foliage_limits;

/* Checks leaves with the rules xyl_foliage_build applies, and writes nothing:
 *   - every number finite (else XYL_ERR_NON_FINITE);
 *   - |axis| > 0 and |side| > 0 (a leaf of size 0 is XYL_ERR_INVALID_ARGUMENT), a normal with
 *     a direction, node >= -1, uv in [0, 1] (else XYL_ERR_INVALID_ARGUMENT);
 *   - normal, axis and side orthogonal within 1e-3 (|cosine| of each pair), and right-handed
 *     (side x axis along +normal); a calling program's leaves that are off by rounding pass, and
 *     the build re-orthogonalises them exactly (normal normalised, axis made orthogonal to it
 *     with its length kept, side = |side| unit(axis x normal)); else XYL_ERR_INVALID_ARGUMENT;
 *   - |centre coordinates|, |axis| and |side| <= limits.max_coordinate, the count of leaves
 *     <= limits.max_leaves, and the counts' sum below 2^32 (else XYL_ERR_LIMIT_EXCEEDED).
 * diag.index names the first bad leaf. Zero leaves are fine (leaves may then be NULL).
 * limits may be NULL (defaults). Coincident leaves and leaves all in one plane are valid. */
XYL_API xyl_result xyl_foliage_check_leaves(const xyl_leaf *leaves, size_t count,
                                            const xyl_foliage_limits *limits, xyl_diag *diag);

/* The shape given to a skeleton's leaf attachments (xyl_skel_leaf: pos, heading, left, up,
 * size). The blade lies in the plane of heading and left, its normal is up, its axis runs along
 * heading; its base is stalk * length past the attachment point along heading. */
typedef struct xyl_leaf_shape {
    float aspect;      /* width / length; default (0): 0.5 */
    float stalk;       /* stalk length as a fraction of the blade length, >= 0; default 0 */
    float size_jitter; /* length = size (1 + size_jitter r), r uniform in [-1, 1) per leaf;
                          [0, 1); default 0 */
    float roll_jitter; /* the blade turns about its axis by roll_jitter r' radians, r' uniform
                          in [-1, 1) per leaf; [0, pi]; default 0 */
    uint64_t seed;     /* the jitter's seed; leaf i's numbers depend on seed and i only */
    float uv[4];       /* every leaf's texture rectangle; default (all 0): 0, 0, 1, 1 */
} xyl_leaf_shape;

typedef struct xyl_foliage_leaves_desc {
    xyl_leaf_shape shape;
    xyl_foliage_limits limits;
} xyl_foliage_leaves_desc;

/* One leaf per attachment of the skeleton, in its order, with count 1 and the attachment's
 * node. Count-then-fill: with leaves == NULL sets *count to skeleton->leaf_count and returns
 * XYL_OK; with capacity < that, XYL_ERR_INVALID_ARGUMENT. A skeleton without leaf attachments
 * gives *count = 0 and XYL_OK. desc may be NULL (defaults). Errors: XYL_ERR_INVALID_ARGUMENT
 * (NULL skeleton or count, a shape option out of range, an attachment of size <= 0 or whose
 * heading or up has no direction or which are parallel), XYL_ERR_NON_FINITE (an option or an
 * attachment that is NaN / inf), XYL_ERR_LIMIT_EXCEEDED (too many leaves, a huge coordinate).
 * diag.index names the attachment. Nothing is written unless every leaf is good. */
XYL_API xyl_result xyl_foliage_leaves_from_skeleton(const xyl_skeleton *skeleton,
                                                    const xyl_foliage_leaves_desc *desc,
                                                    xyl_leaf *leaves, size_t capacity,
                                                    size_t *count, xyl_diag *diag);

/* ---- the GPU record ------------------------------------------------------------------------ */

/* Packs count leaves into out[0 .. count), one 32-byte xyl_foliage_gpu_leaf each (layout and
 * precision in xyl_foliage_shared.h): the centre as is, each half-axis component rounded to the
 * nearest half float (ties to even), each texture coordinate to the nearest unorm16. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL arrays with a count, a texture coordinate outside [0, 1]),
 * XYL_ERR_NON_FINITE, XYL_ERR_LIMIT_EXCEEDED (a half-axis component beyond 65504, the largest
 * half); diag.index names the leaf, and out is untouched. Allocates nothing. */
XYL_API xyl_result xyl_foliage_pack_gpu(const xyl_leaf *leaves, size_t count,
                                        xyl_foliage_gpu_leaf *out, xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif /* XYL_FOLIAGE_H */

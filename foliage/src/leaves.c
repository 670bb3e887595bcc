/* Leaves: the rules a leaf obeys, and leaves made from a skeleton's leaf attachments. */
#include <string.h>

#include "foliage_internal.h"

xyl_result xyl__foliage_limits_resolve(const xyl_foliage_limits *in, xyl__foliage_limits *out,
                                       xyl_diag *diag)
{
    xyl_foliage_limits zero = {0};
    if (!in) in = &zero;
    if (in->max_leaves > XYL__FOLIAGE_MAX_LEAVES_CAP)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "limits.max_leaves is %llu; at most 2^30 are supported",
                         (unsigned long long)in->max_leaves);
    if (!(in->max_coordinate >= 0.0f) || !isfinite(in->max_coordinate))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "limits.max_coordinate must be finite and >= 0 (0: 1e6)");
    out->max_leaves = in->max_leaves ? in->max_leaves : XYL__FOLIAGE_MAX_LEAVES;
    out->max_coordinate = in->max_coordinate > 0.0f ? (double)in->max_coordinate
                                                    : XYL__FOLIAGE_MAX_COORDINATE;
    return XYL_OK;
}

static bool finite3(xyl_vec3 v)
{
    return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

static bool huge(xyl_vec3 c, double max)
{
    return fabs((double)c.x) > max || fabs((double)c.y) > max || fabs((double)c.z) > max;
}

/* |cosine| of the angle between a and b, of lengths la and lb (> 0). */
static double abs_cos(xyl__dvec3 a, xyl__dvec3 b, double la, double lb)
{
    return fabs(xyl__d3_dot(a, b)) / (la * lb);
}

xyl_result xyl__leaf_check(const xyl_leaf *l, size_t i, const xyl__foliage_limits *limits,
                           xyl_diag *diag)
{
    int64_t at = (int64_t)i;
    if (!finite3(l->center) || !finite3(l->normal) || !finite3(l->axis) || !finite3(l->side) ||
        !isfinite(l->uv[0]) || !isfinite(l->uv[1]) || !isfinite(l->uv[2]) || !isfinite(l->uv[3]))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, at, "leaf %zu has a NaN or infinity", i);
    xyl__dvec3 n = xyl__from_f3(l->normal), a = xyl__from_f3(l->axis), s = xyl__from_f3(l->side);
    double ln = xyl__d3_len(n), la = xyl__d3_len(a), ls = xyl__d3_len(s);
    if (huge(l->center, limits->max_coordinate) || la > limits->max_coordinate ||
        ls > limits->max_coordinate)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, at,
                         "leaf %zu has a coordinate or half-axis beyond limits.max_coordinate "
                         "(%g)", i, limits->max_coordinate);
    if (!(la > 0.0) || !(ls > 0.0))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, at,
                         "leaf %zu has size 0 (|axis| %g, |side| %g)", i, la, ls);
    if (!(ln * ln > XYL__EPS_NORMALIZE))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, at,
                         "leaf %zu has a normal without a direction", i);
    if (l->node < -1)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, at,
                         "leaf %zu hangs from node %d; nodes are >= 0, or -1 for none", i,
                         (int)l->node);
    for (int k = 0; k < 4; ++k) {
        if (l->uv[k] < 0.0f || l->uv[k] > 1.0f)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, at,
                             "leaf %zu has texture coordinate %g outside [0, 1]", i,
                             (double)l->uv[k]);
    }
    double worst = fmax(abs_cos(a, s, la, ls), fmax(abs_cos(a, n, la, ln), abs_cos(s, n, ls, ln)));
    if (!(worst <= XYL__LEAF_ORTHO_TOLERANCE))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, at,
                         "leaf %zu: normal, axis and side are not orthogonal (|cos| %g > %g)", i,
                         worst, XYL__LEAF_ORTHO_TOLERANCE);
    if (!(xyl__d3_dot(xyl__d3_cross(s, a), n) > 0.0))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, at,
                         "leaf %zu is mirrored: side x axis must point along the normal", i);
    return XYL_OK;
}

xyl_result xyl_foliage_check_leaves(const xyl_leaf *leaves, size_t count,
                                    const xyl_foliage_limits *limits, xyl_diag *diag)
{
    xyl__foliage_limits lim;
    xyl_result r = xyl__foliage_limits_resolve(limits, &lim, diag);
    if (r != XYL_OK) return r;
    if (count && !leaves)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "leaves is NULL but count is not 0");
    if ((uint64_t)count > lim.max_leaves)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu leaves exceed limits.max_leaves (%llu)", count,
                         (unsigned long long)lim.max_leaves);
    uint64_t represented = 0;
    for (size_t i = 0; i < count; ++i) {
        r = xyl__leaf_check(&leaves[i], i, &lim, diag);
        if (r != XYL_OK) return r;
        represented += leaves[i].count ? leaves[i].count : 1;
        if (represented > UINT32_MAX)
            return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, (int64_t)i,
                             "the leaves' counts add up to 2^32 or more at leaf %zu", i);
    }
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* An all-zero texture rectangle means the default, the whole texture. */
static void default_rect(float uv[4])
{
    if (uv[0] == 0.0f && uv[1] == 0.0f && uv[2] == 0.0f && uv[3] == 0.0f) uv[2] = uv[3] = 1.0f;
}

xyl_leaf xyl__leaf_tidy(const xyl_leaf *l)
{
    xyl_leaf t = *l;
    xyl__dvec3 n = xyl__d3_normalize_or(xyl__from_f3(l->normal), xyl__d3(0, 1, 0));
    xyl__dvec3 a = xyl__from_f3(l->axis);
    double la = xyl__d3_len(a), ls = xyl__d3_len(xyl__from_f3(l->side));
    /* a checked axis is within 1e-3 of orthogonal, so its projection keeps a direction */
    a = xyl__d3_sub(a, xyl__d3_scale(n, xyl__d3_dot(a, n)));
    xyl__dvec3 ad = xyl__d3_normalize_or(a, xyl__d3_any_orthogonal(n));
    xyl__dvec3 sd = xyl__d3_cross(ad, n);
    t.normal = xyl__to_f3(n);
    t.axis = xyl__to_f3(xyl__d3_scale(ad, la));
    t.side = xyl__to_f3(xyl__d3_scale(sd, ls));
    if (t.count == 0) t.count = 1;
    default_rect(t.uv);
    return t;
}

void xyl__leaf_corners(const xyl_leaf *l, xyl__dvec3 out[4])
{
    xyl__dvec3 c = xyl__from_f3(l->center), a = xyl__from_f3(l->axis), s = xyl__from_f3(l->side);
    for (int k = 0; k < 4; ++k)
        out[k] = xyl__d3_add(c, xyl__d3_add(xyl__d3_scale(s, k & 1 ? 1.0 : -1.0),
                                            xyl__d3_scale(a, k & 2 ? 1.0 : -1.0)));
}

float xyl__round_up(double v)
{
    float f = (float)v;
    return (double)f < v ? nextafterf(f, INFINITY) : f;
}

/* ---- leaves from leaf attachments -------------------------------------------------------- */

typedef struct shape {
    double aspect, stalk, size_jitter, roll_jitter;
    uint64_t seed;
    float uv[4];
} shape;

static xyl_result shape_resolve(const xyl_leaf_shape *in, shape *out, xyl_diag *diag)
{
    const float v[8] = {in->aspect, in->stalk, in->size_jitter, in->roll_jitter,
                        in->uv[0], in->uv[1], in->uv[2], in->uv[3]};
    for (int k = 0; k < 8; ++k) {
        if (!isfinite(v[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "a leaf shape option is NaN or infinite");
    }
    if (in->aspect < 0.0f || in->stalk < 0.0f || in->size_jitter < 0.0f ||
        in->size_jitter >= 1.0f || in->roll_jitter < 0.0f || in->roll_jitter > (float)XYL__PI)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "leaf shape: aspect and stalk must be >= 0, size_jitter in [0, 1), "
                         "roll_jitter in [0, pi]");
    for (int k = 0; k < 4; ++k) {
        if (in->uv[k] < 0.0f || in->uv[k] > 1.0f)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                             "leaf shape: texture coordinate %g outside [0, 1]", (double)in->uv[k]);
    }
    out->aspect = in->aspect > 0.0f ? in->aspect : 0.5;
    out->stalk = in->stalk;
    out->size_jitter = in->size_jitter;
    out->roll_jitter = in->roll_jitter;
    out->seed = in->seed;
    memcpy(out->uv, in->uv, sizeof out->uv);
    default_rect(out->uv);
    return XYL_OK;
}

/* SplitMix64's finaliser: leaf i's random numbers depend on (seed, i) only, not on the order
 * leaves are made in. */
static uint64_t mix64(uint64_t z)
{
    z += UINT64_C(0x9e3779b97f4a7c15);
    z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
    return z ^ (z >> 31);
}

/* Uniform in [-1, 1) from the top 53 bits. */
static double symmetric_unit(uint64_t x)
{
    return (double)(x >> 11) * (1.0 / 4503599627370496.0) - 1.0;
}

static xyl_result leaf_from_attachment(const xyl_skel_leaf *at, size_t i, size_t node_count,
                                       const shape *sh, const xyl__foliage_limits *lim,
                                       xyl_leaf *out, xyl_diag *diag)
{
    int64_t idx = (int64_t)i;
    if (!finite3(at->pos) || !finite3(at->heading) || !finite3(at->up) || !isfinite(at->size))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, idx,
                         "leaf attachment %zu has a NaN or infinity", i);
    if (!(at->size > 0.0f))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, idx,
                         "leaf attachment %zu has size %g; sizes must be > 0", i, (double)at->size);
    if (at->node < -1 || (int64_t)at->node >= (int64_t)node_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, idx,
                         "leaf attachment %zu hangs from node %d, which does not exist", i,
                         (int)at->node);
    xyl__dvec3 h, u;
    xyl__dvec3 up = xyl__from_f3(at->up);
    bool ok = xyl__d3_normalize_ok(xyl__from_f3(at->heading), &h);
    if (ok) ok = xyl__d3_normalize_ok(xyl__d3_sub(up, xyl__d3_scale(h, xyl__d3_dot(up, h))), &u);
    if (!ok)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, idx,
                         "leaf attachment %zu: heading and up must have directions and differ", i);
    uint64_t x = mix64(sh->seed ^ mix64((uint64_t)i));
    double length = (double)at->size * (1.0 + sh->size_jitter * symmetric_unit(x));
    double roll = sh->roll_jitter * symmetric_unit(mix64(x));
    if (roll != 0.0) u = xyl__d3_rotate(u, h, roll);
    xyl__dvec3 centre = xyl__d3_add(xyl__from_f3(at->pos), xyl__d3_scale(h, (sh->stalk + 0.5) * length));
    xyl__dvec3 axis = xyl__d3_scale(h, 0.5 * length);
    xyl__dvec3 side = xyl__d3_scale(xyl__d3_cross(h, u), 0.5 * sh->aspect * length);
    double max = lim->max_coordinate;
    if (!(fabs(centre.x) <= max && fabs(centre.y) <= max && fabs(centre.z) <= max &&
          0.5 * length <= max && 0.5 * sh->aspect * length <= max))
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, idx,
                         "leaf %zu would have a coordinate or half-axis beyond "
                         "limits.max_coordinate (%g)", i, max);
    xyl_leaf l = {0};
    l.center = xyl__to_f3(centre);
    l.normal = xyl__to_f3(u);
    l.axis = xyl__to_f3(axis);
    l.side = xyl__to_f3(side);
    memcpy(l.uv, sh->uv, sizeof l.uv);
    l.count = 1;
    l.node = at->node;
    /* the float leaf obeys the rules every leaf does (an aspect of 1e-40 rounds to size 0) */
    xyl_result r = xyl__leaf_check(&l, i, lim, diag);
    if (r == XYL_OK && out) *out = l;
    return r;
}

xyl_result xyl_foliage_leaves_from_skeleton(const xyl_skeleton *skeleton,
                                            const xyl_foliage_leaves_desc *desc, xyl_leaf *leaves,
                                            size_t capacity, size_t *count, xyl_diag *diag)
{
    if (!skeleton || !count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "skeleton and count must not be NULL");
    xyl_foliage_leaves_desc zero = {0};
    if (!desc) desc = &zero;
    xyl__foliage_limits lim;
    shape sh;
    xyl_result r = xyl__foliage_limits_resolve(&desc->limits, &lim, diag);
    if (r == XYL_OK) r = shape_resolve(&desc->shape, &sh, diag);
    if (r != XYL_OK) return r;
    size_t n = skeleton->leaf_count;
    if (n && !skeleton->leaves)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the skeleton's leaves are NULL but leaf_count is not 0");
    if ((uint64_t)n > lim.max_leaves)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu leaf attachments exceed limits.max_leaves (%llu)", n,
                         (unsigned long long)lim.max_leaves);
    if (leaves && capacity < n)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "capacity %zu is less than the %zu leaves", capacity, n);
    for (size_t i = 0; i < n; ++i) {
        r = leaf_from_attachment(&skeleton->leaves[i], i, skeleton->node_count, &sh, &lim, NULL, diag);
        if (r != XYL_OK) return r;
    }
    for (size_t i = 0; leaves && i < n; ++i)
        leaf_from_attachment(&skeleton->leaves[i], i, skeleton->node_count, &sh, &lim, &leaves[i], diag);
    *count = n;
    xyl__diag_ok(diag);
    return XYL_OK;
}

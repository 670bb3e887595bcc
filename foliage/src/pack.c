/* The 32-byte GPU leaf record: half floats and unorm16 from float leaves, and back. */
#include <string.h>

#include "foliage_internal.h"

uint16_t xyl__half_from_float(float f)
{
    uint32_t x;
    memcpy(&x, &f, sizeof x);
    uint16_t sign = (uint16_t)((x >> 16) & 0x8000u);
    uint32_t ax = x & 0x7fffffffu;
    if (ax > 0x7f800000u) return (uint16_t)(sign | 0x7e00u);  /* NaN */
    if (ax >= 0x477ff000u) return (uint16_t)(sign | 0x7c00u); /* rounds past 65504: inf */
    if (ax >= 0x38800000u) {                                  /* a normal half */
        uint32_t r = ax - 0x38000000u;                        /* exponent bias 127 -> 15 */
        r += 0x0fffu + ((r >> 13) & 1u);                      /* to nearest, ties to even */
        return (uint16_t)(sign | (r >> 13));
    }
    /* below 2^-14: a subnormal half, round(|f| 2^24) */
    uint32_t e = ax >> 23;
    if (e < 102) return sign; /* |f| < 2^-25: rounds to 0 (2^-25 itself ties to even 0) */
    uint32_t m = (ax & 0x7fffffu) | 0x800000u;
    uint32_t shift = 126u - e; /* 14 .. 24 */
    uint32_t q = m >> shift, rem = m & ((1u << shift) - 1u), half = 1u << (shift - 1u);
    if (rem > half || (rem == half && (q & 1u))) ++q;
    return (uint16_t)(sign | q);
}

float xyl__float_from_half(uint16_t h)
{
    uint32_t sign = (uint32_t)(h & 0x8000u) << 16;
    uint32_t e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    uint32_t x;
    if (e == 0x1fu) {
        x = sign | 0x7f800000u | (m << 13);
    } else if (e != 0) {
        x = sign | ((e + 112u) << 23) | (m << 13);
    } else {
        float v = (float)m * (1.0f / 16777216.0f); /* m 2^-24, exact */
        memcpy(&x, &v, sizeof x);
        x |= sign;
    }
    float f;
    memcpy(&f, &x, sizeof f);
    return f;
}

static uint16_t unorm16(float u)
{
    return (uint16_t)floor((double)u * 65535.0 + 0.5);
}

static xyl_result pack_check(const xyl_leaf *l, size_t i, xyl_diag *diag)
{
    const float v[9] = {l->center.x, l->center.y, l->center.z, l->axis.x, l->axis.y,
                         l->axis.z,   l->side.x,   l->side.y,   l->side.z};
    const float *uv = l->uv;
    for (int k = 0; k < 9; ++k) {
        if (!isfinite(v[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)i, "leaf %zu has a NaN or infinity", i);
    }
    for (int k = 3; k < 9; ++k) {
        if (fabsf(v[k]) > 65504.0f)
            return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, (int64_t)i,
                             "leaf %zu has a half-axis component of %g, beyond the largest "
                             "half float (65504)", i, (double)v[k]);
    }
    for (int k = 0; k < 4; ++k) {
        if (!isfinite(uv[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)i, "leaf %zu has a NaN or infinity", i);
        if (!(uv[k] >= 0.0f && uv[k] <= 1.0f))
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)i,
                             "leaf %zu has texture coordinate %g outside [0, 1]", i, (double)uv[k]);
    }
    return XYL_OK;
}

xyl_result xyl_foliage_pack_gpu(const xyl_leaf *leaves, size_t count, xyl_foliage_gpu_leaf *out,
                                xyl_diag *diag)
{
    if (count && (!leaves || !out))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "leaves and out must not be NULL when count is not 0");
    for (size_t i = 0; i < count; ++i) {
        xyl_result r = pack_check(&leaves[i], i, diag);
        if (r != XYL_OK) return r;
    }
    for (size_t i = 0; i < count; ++i) {
        const xyl_leaf *l = &leaves[i];
        xyl_foliage_gpu_leaf g;
        g.center[0] = l->center.x;
        g.center[1] = l->center.y;
        g.center[2] = l->center.z;
        g.axis[0] = xyl__half_from_float(l->axis.x);
        g.axis[1] = xyl__half_from_float(l->axis.y);
        g.axis[2] = xyl__half_from_float(l->axis.z);
        g.side[0] = xyl__half_from_float(l->side.x);
        g.side[1] = xyl__half_from_float(l->side.y);
        g.side[2] = xyl__half_from_float(l->side.z);
        for (int k = 0; k < 4; ++k) g.uv[k] = unorm16(l->uv[k]);
        out[i] = g;
    }
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_leaf xyl__foliage_unpack_gpu(const xyl_foliage_gpu_leaf *g)
{
    xyl_leaf l = {0};
    l.center = (xyl_vec3){g->center[0], g->center[1], g->center[2]};
    l.axis = (xyl_vec3){xyl__float_from_half(g->axis[0]), xyl__float_from_half(g->axis[1]),
                        xyl__float_from_half(g->axis[2])};
    l.side = (xyl_vec3){xyl__float_from_half(g->side[0]), xyl__float_from_half(g->side[1]),
                        xyl__float_from_half(g->side[2])};
    /* as the shader does: normalize(cross(side, axis)) */
    xyl__dvec3 n = xyl__d3_cross(xyl__from_f3(l.side), xyl__from_f3(l.axis));
    l.normal = xyl__to_f3(xyl__d3_normalize_or(n, xyl__d3(0, 0, 1)));
    for (int k = 0; k < 4; ++k) l.uv[k] = (float)((double)g->uv[k] / 65535.0);
    l.count = 1;
    l.node = -1;
    return l;
}

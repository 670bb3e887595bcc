/* CPU reference of shaders/xyl_tess_eval.glsl: the same functions, the same operations in the
 * same order, in float. The library is built with -ffp-contract=off, so nothing is fused here;
 * a GPU may fuse, which is why GPU = CPU is checked to a tolerance and only CPU-side shared edges
 * are required to be bit-identical (the GPU's are identical to each other for the same reason:
 * both sides run the same code on the same operands). */
#include "tess_debug.h"
#include "tess_internal.h"

static tv3 normalize_or(tv3 v, tv3 fallback)
{
    float l2 = tv3_dot(v, v);
    return l2 > 0.0f ? tv3_div(v, sqrtf(l2)) : fallback;
}

static bool precedes(tv3 pa, tv3 na, tv3 pb, tv3 nb)
{
    if (pa.x != pb.x) return pa.x < pb.x;
    if (pa.y != pb.y) return pa.y < pb.y;
    if (pa.z != pb.z) return pa.z < pb.z;
    if (na.x != nb.x) return na.x < nb.x;
    if (na.y != nb.y) return na.y < nb.y;
    return na.z < nb.z;
}

static float clampf(float x, float lo, float hi) { return x < lo ? lo : (x > hi ? hi : x); }

/* xyl_tess_axis_frame / xyl_tess_axis of xyl_tess_shared.h. */
static void axis_frame(tv3 n, tv3 *e1, tv3 *e2)
{
    float s = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (s + n.z);
    float b = n.x * n.y * a;
    *e1 = tv3_make(1.0f + s * n.x * n.x * a, s * b, -s * n.x);
    *e2 = tv3_make(b, s + n.y * n.y * a, -n.y);
}

static tv3 corner_axis(tv3 n, float w)
{
    if (w == 0.0f) return tv3_make(0.0f, 0.0f, 0.0f);
    tv3 e1, e2;
    axis_frame(n, &e1, &e2);
    float ang = w - (float)XYL_TESS_AXIS_BIAS;
    return tv3_add(tv3_mul(e1, cosf(ang)), tv3_mul(e2, sinf(ang)));
}

float xyl__tess_encode_axis(const float n[3], const double axis[3])
{
    tv3 e1, e2;
    axis_frame(tv3_load(n), &e1, &e2);
    double x = axis[0] * e1.x + axis[1] * e1.y + axis[2] * e1.z;
    double y = axis[0] * e2.x + axis[1] * e2.y + axis[2] * e2.z;
    if (!(x * x + y * y > 1e-12)) return 0.0f;
    return (float)(atan2(y, x) + XYL_TESS_AXIS_BIAS);
}

static tv3 arc_dir(tv3 t, float tt, tv3 a, bool *on_axis)
{
    float ta = tv3_dot(t, a);
    *on_axis = tv3_dot(a, a) > 0.0f && fabsf(ta) >= 0.8660254f * sqrtf(tt);
    if (*on_axis) return ta >= 0.0f ? a : tv3_mul(a, -1.0f);
    return tv3_div(t, sqrtf(tt));
}

static tv3 handle(tv3 pi, tv3 ni, tv3 ai, tv3 pj, tv3 nj, tv3 aj, xyl_tess_variant variant)
{
    tv3 d = tv3_sub(pj, pi);
    tv3 t = tv3_sub(d, tv3_mul(ni, tv3_dot(d, ni)));
    if (variant == XYL_TESS_PN) return tv3_add(pi, tv3_mul(t, 1.0f / 3.0f));
    if (variant == XYL_TESS_ROUNDED) return tv3_add(pi, tv3_mul(t, 0.5f));
    float dd = tv3_dot(d, d);
    float tt = tv3_dot(t, t);
    if (!(tt > dd * 1e-12f)) return pi;
    if (variant == XYL_TESS_ARC) {
        tv3 s = tv3_sub(tv3_mul(nj, tv3_dot(d, nj)), d);
        float ss = tv3_dot(s, s);
        bool on_i, on_j = false;
        tv3 ui = arc_dir(t, tt, ai, &on_i);
        tv3 uj = ss > dd * 1e-12f ? arc_dir(s, ss, aj, &on_j) : tv3_make(0.0f, 0.0f, 0.0f);
        if (on_i || on_j) {
            float chalf = sqrtf(fmaxf(0.5f - 0.5f * clampf(tv3_dot(ui, uj), -1.0f, 1.0f), 0.0f));
            float len = (2.0f * sqrtf(dd)) / (3.0f * (1.0f + chalf));
            return tv3_add(pi, tv3_mul(ui, len));
        }
    }
    float chalf = sqrtf(fmaxf(0.5f + 0.5f * clampf(tv3_dot(ni, nj), -1.0f, 1.0f), 0.0f));
    float len = (2.0f * sqrtf(dd)) / (3.0f * (1.0f + chalf));
    return tv3_add(pi, tv3_mul(t, len / sqrtf(tt)));
}

static tv3 edge_normal(tv3 pi, tv3 ni, tv3 pj, tv3 nj)
{
    tv3 d = tv3_sub(pj, pi);
    tv3 s = tv3_add(ni, nj);
    float dd = tv3_dot(d, d);
    float v = dd > 0.0f ? 2.0f * tv3_dot(d, s) / dd : 0.0f;
    return normalize_or(tv3_sub(s, tv3_mul(d, v)), ni);
}

static tv3 bezier3(tv3 a, tv3 b, tv3 c, tv3 d, float t)
{
    float s = 1.0f - t;
    tv3 r = tv3_mul(a, s * s * s);
    r = tv3_add(r, tv3_mul(b, 3.0f * s * s * t));
    r = tv3_add(r, tv3_mul(c, 3.0f * s * t * t));
    return tv3_add(r, tv3_mul(d, t * t * t));
}

static void load_corners(const xyl_tess_patch *p, tv3 c[4], tv3 n[4], tv3 a[4])
{
    for (int i = 0; i < 4; ++i) {
        c[i] = tv3_load(p->p[i]);
        n[i] = tv3_load(p->n[i]);
        a[i] = corner_axis(n[i], p->n[i][3]);
    }
}

uint32_t xyl_tess_patch_kind(const xyl_tess_patch *patch)
{
    return patch->p[0][3] == 3.0f ? XYL_TESS_KIND_TRIANGLE : XYL_TESS_KIND_QUAD;
}

/* ---- edges -------------------------------------------------------------------------------- */

static void eval_edge(tv3 pa, tv3 na, tv3 aa, tv3 pb, tv3 nb, tv3 ab, uint32_t k, uint32_t le,
                      xyl_tess_variant variant, float pos[3], float nrm[3])
{
    if (!precedes(pa, na, pb, nb)) {
        tv3 tp = pa; pa = pb; pb = tp;
        tv3 tn = na; na = nb; nb = tn;
        tv3 ta = aa; aa = ab; ab = ta;
        k = le - k;
    }
    float t = (float)k / (float)le;
    tv3 ha = handle(pa, na, aa, pb, nb, ab, variant);
    tv3 hb = handle(pb, nb, ab, pa, na, aa, variant);
    tv3 p = bezier3(pa, ha, hb, pb, t);
    tv3 ne = edge_normal(pa, na, pb, nb);
    float s = 1.0f - t;
    tv3 ns = tv3_add(tv3_add(tv3_mul(na, s * s), tv3_mul(ne, 2.0f * s * t)), tv3_mul(nb, t * t));
    tv3 n = normalize_or(ns, na);
    pos[0] = p.x; pos[1] = p.y; pos[2] = p.z;
    nrm[0] = n.x; nrm[1] = n.y; nrm[2] = n.z;
}

void xyl_tess_eval_edge(const xyl_tess_patch *patch, xyl_tess_variant variant, uint32_t e,
                        uint32_t k, uint32_t le, float pos[3], float normal[3])
{
    tv3 c[4], n[4], a[4];
    load_corners(patch, c, n, a);
    uint32_t kind = xyl_tess_patch_kind(patch);
    uint32_t e1 = (e + 1u == kind) ? 0u : e + 1u;
    eval_edge(c[e], n[e], a[e], c[e1], n[e1], a[e1], k, le, variant, pos, normal);
}

void xyl__tess_edge_net(const xyl_tess_patch *patch, xyl_tess_variant variant, uint32_t e,
                        tv3 out[4])
{
    tv3 c[4], n[4], a[4];
    load_corners(patch, c, n, a);
    uint32_t e1 = (e + 1u == xyl_tess_patch_kind(patch)) ? 0u : e + 1u;
    tv3 pa = c[e], na = n[e], aa = a[e], pb = c[e1], nb = n[e1], ab = a[e1];
    if (!precedes(pa, na, pb, nb)) {
        tv3 tp = pa; pa = pb; pb = tp;
        tv3 tn = na; na = nb; nb = tn;
        tv3 ta = aa; aa = ab; ab = ta;
    }
    out[0] = pa;
    out[1] = handle(pa, na, aa, pb, nb, ab, variant);
    out[2] = handle(pb, nb, ab, pa, na, aa, variant);
    out[3] = pb;
}

/* ---- interiors ---------------------------------------------------------------------------- */

/* (-4 a + 6 (b + c) - 2 (d + e) + 3 (f + g) - h) / 9: the Coons interior point. */
static tv3 coons(tv3 a, tv3 b, tv3 c, tv3 d, tv3 e, tv3 f, tv3 g, tv3 h)
{
    tv3 r = tv3_mul(a, -4.0f);
    r = tv3_add(r, tv3_mul(tv3_add(b, c), 6.0f));
    r = tv3_sub(r, tv3_mul(tv3_add(d, e), 2.0f));
    r = tv3_add(r, tv3_mul(tv3_add(f, g), 3.0f));
    r = tv3_sub(r, h);
    return tv3_div(r, 9.0f);
}

static void quad_net(const tv3 c[4], const tv3 n[4], const tv3 a[4], xyl_tess_variant variant, tv3 b[16])
{
    b[0] = c[0]; b[3] = c[1]; b[15] = c[2]; b[12] = c[3];
    b[1] = handle(c[0], n[0], a[0], c[1], n[1], a[1], variant);
    b[2] = handle(c[1], n[1], a[1], c[0], n[0], a[0], variant);
    b[7] = handle(c[1], n[1], a[1], c[2], n[2], a[2], variant);
    b[11] = handle(c[2], n[2], a[2], c[1], n[1], a[1], variant);
    b[14] = handle(c[2], n[2], a[2], c[3], n[3], a[3], variant);
    b[13] = handle(c[3], n[3], a[3], c[2], n[2], a[2], variant);
    b[8] = handle(c[3], n[3], a[3], c[0], n[0], a[0], variant);
    b[4] = handle(c[0], n[0], a[0], c[3], n[3], a[3], variant);
    b[5] = coons(b[0], b[4], b[1], b[12], b[3], b[7], b[13], b[15]);
    b[6] = coons(b[3], b[7], b[2], b[15], b[0], b[4], b[14], b[12]);
    b[9] = coons(b[12], b[8], b[13], b[0], b[15], b[11], b[1], b[3]);
    b[10] = coons(b[15], b[11], b[14], b[3], b[12], b[8], b[2], b[0]);
}

/* b300 b030 b003 b210 b120 b021 b012 b102 b201 b111 */
static void tri_net(const tv3 c[4], const tv3 n[4], const tv3 a[4], xyl_tess_variant variant, tv3 b[10])
{
    b[0] = c[0]; b[1] = c[1]; b[2] = c[2];
    b[3] = handle(c[0], n[0], a[0], c[1], n[1], a[1], variant);
    b[4] = handle(c[1], n[1], a[1], c[0], n[0], a[0], variant);
    b[5] = handle(c[1], n[1], a[1], c[2], n[2], a[2], variant);
    b[6] = handle(c[2], n[2], a[2], c[1], n[1], a[1], variant);
    b[7] = handle(c[2], n[2], a[2], c[0], n[0], a[0], variant);
    b[8] = handle(c[0], n[0], a[0], c[2], n[2], a[2], variant);
    tv3 e = tv3_add(tv3_add(tv3_add(tv3_add(tv3_add(b[3], b[4]), b[5]), b[6]), b[7]), b[8]);
    e = tv3_div(e, 6.0f);
    tv3 vc = tv3_div(tv3_add(tv3_add(c[0], c[1]), c[2]), 3.0f);
    b[9] = tv3_add(e, tv3_mul(tv3_sub(e, vc), 0.5f));
}

int xyl__tess_control_net(const xyl_tess_patch *patch, xyl_tess_variant variant, tv3 out[16])
{
    tv3 c[4], n[4], a[4];
    load_corners(patch, c, n, a);
    if (xyl_tess_patch_kind(patch) == XYL_TESS_KIND_QUAD) {
        quad_net(c, n, a, variant, out);
        return 16;
    }
    tri_net(c, n, a, variant, out);
    return 10;
}

static void eval_quad(const tv3 c[4], const tv3 n[4], const tv3 a[4], float u, float v,
                      xyl_tess_variant variant, float pos[3], float nrm[3])
{
    tv3 b[16];
    quad_net(c, n, a, variant, b);
    float su = 1.0f - u, sv = 1.0f - v;
    float bu[4] = {su * su * su, 3.0f * su * su * u, 3.0f * su * u * u, u * u * u};
    float bv[4] = {sv * sv * sv, 3.0f * sv * sv * v, 3.0f * sv * v * v, v * v * v};
    tv3 p = tv3_make(0.0f, 0.0f, 0.0f);
    for (int j = 0; j < 4; ++j) {
        tv3 row = tv3_mul(b[4 * j], bu[0]);
        row = tv3_add(row, tv3_mul(b[4 * j + 1], bu[1]));
        row = tv3_add(row, tv3_mul(b[4 * j + 2], bu[2]));
        row = tv3_add(row, tv3_mul(b[4 * j + 3], bu[3]));
        p = tv3_add(p, tv3_mul(row, bv[j]));
    }

    tv3 m[9];
    m[0] = n[0]; m[2] = n[1]; m[8] = n[2]; m[6] = n[3];
    m[1] = edge_normal(c[0], n[0], c[1], n[1]);
    m[5] = edge_normal(c[1], n[1], c[2], n[2]);
    m[7] = edge_normal(c[2], n[2], c[3], n[3]);
    m[3] = edge_normal(c[3], n[3], c[0], n[0]);
    tv3 es = tv3_add(tv3_add(tv3_add(m[1], m[5]), m[7]), m[3]);
    tv3 cs = tv3_add(tv3_add(tv3_add(m[0], m[2]), m[8]), m[6]);
    m[4] = tv3_sub(tv3_mul(es, 0.5f), tv3_mul(cs, 0.25f));
    float qu[3] = {su * su, 2.0f * su * u, u * u};
    float qv[3] = {sv * sv, 2.0f * sv * v, v * v};
    tv3 ns = tv3_make(0.0f, 0.0f, 0.0f);
    for (int j = 0; j < 3; ++j) {
        tv3 row = tv3_mul(m[3 * j], qu[0]);
        row = tv3_add(row, tv3_mul(m[3 * j + 1], qu[1]));
        row = tv3_add(row, tv3_mul(m[3 * j + 2], qu[2]));
        ns = tv3_add(ns, tv3_mul(row, qv[j]));
    }
    tv3 nn = normalize_or(ns, n[0]);
    pos[0] = p.x; pos[1] = p.y; pos[2] = p.z;
    nrm[0] = nn.x; nrm[1] = nn.y; nrm[2] = nn.z;
}

static void eval_triangle(const tv3 c[4], const tv3 n[4], const tv3 a[4], float w0, float w1, float w2,
                          xyl_tess_variant variant, float pos[3], float nrm[3])
{
    tv3 b[10];
    tri_net(c, n, a, variant, b);
    tv3 p = tv3_mul(c[0], w0 * w0 * w0);
    p = tv3_add(p, tv3_mul(c[1], w1 * w1 * w1));
    p = tv3_add(p, tv3_mul(c[2], w2 * w2 * w2));
    p = tv3_add(p, tv3_mul(b[3], 3.0f * w0 * w0 * w1));
    p = tv3_add(p, tv3_mul(b[4], 3.0f * w0 * w1 * w1));
    p = tv3_add(p, tv3_mul(b[5], 3.0f * w1 * w1 * w2));
    p = tv3_add(p, tv3_mul(b[6], 3.0f * w1 * w2 * w2));
    p = tv3_add(p, tv3_mul(b[7], 3.0f * w2 * w2 * w0));
    p = tv3_add(p, tv3_mul(b[8], 3.0f * w2 * w0 * w0));
    p = tv3_add(p, tv3_mul(b[9], 6.0f * w0 * w1 * w2));
    tv3 n110 = edge_normal(c[0], n[0], c[1], n[1]);
    tv3 n011 = edge_normal(c[1], n[1], c[2], n[2]);
    tv3 n101 = edge_normal(c[2], n[2], c[0], n[0]);
    tv3 ns = tv3_mul(n[0], w0 * w0);
    ns = tv3_add(ns, tv3_mul(n[1], w1 * w1));
    ns = tv3_add(ns, tv3_mul(n[2], w2 * w2));
    ns = tv3_add(ns, tv3_mul(n110, 2.0f * w0 * w1));
    ns = tv3_add(ns, tv3_mul(n011, 2.0f * w1 * w2));
    ns = tv3_add(ns, tv3_mul(n101, 2.0f * w2 * w0));
    tv3 nn = normalize_or(ns, n[0]);
    pos[0] = p.x; pos[1] = p.y; pos[2] = p.z;
    nrm[0] = nn.x; nrm[1] = nn.y; nrm[2] = nn.z;
}

void xyl_tess_eval(const xyl_tess_patch *patch, xyl_tess_variant variant, float u, float v,
                   float pos[3], float normal[3])
{
    tv3 c[4], n[4], a[4];
    load_corners(patch, c, n, a);
    if (xyl_tess_patch_kind(patch) == XYL_TESS_KIND_QUAD)
        eval_quad(c, n, a, u, v, variant, pos, normal);
    else
        eval_triangle(c, n, a, 1.0f - u - v, u, v, variant, pos, normal);
}

/* ---- lattice points ----------------------------------------------------------------------- */

static bool lattice_edge(uint32_t kind, uint32_t l, uint32_t i, uint32_t j, uint32_t *e,
                         uint32_t *idx)
{
    if (j == 0u) { *e = 0u; *idx = i; return true; }
    if (kind == XYL_TESS_KIND_QUAD) {
        if (i == l) { *e = 1u; *idx = j; return true; }
        if (j == l) { *e = 2u; *idx = l - i; return true; }
        if (i == 0u) { *e = 3u; *idx = l - j; return true; }
        return false;
    }
    if (i + j == l) { *e = 1u; *idx = j; return true; }
    if (i == 0u) { *e = 2u; *idx = l - j; return true; }
    return false;
}

void xyl_tess_eval_lattice(const xyl_tess_patch *patch, xyl_tess_variant variant,
                           uint32_t level, uint32_t edge_levels, uint32_t i, uint32_t j,
                           float pos[3], float normal[3])
{
    tv3 c[4], n[4], a[4];
    load_corners(patch, c, n, a);
    uint32_t kind = xyl_tess_patch_kind(patch);
    uint32_t e, idx;
    if (lattice_edge(kind, level, i, j, &e, &idx)) {
        uint32_t le = (edge_levels >> (XYL_TESS_EDGE_LEVEL_BITS * e)) & 0xffu;
        uint32_t e1 = (e + 1u == kind) ? 0u : e + 1u;
        uint32_t k = (2u * idx * le + level) / (2u * level);
        eval_edge(c[e], n[e], a[e], c[e1], n[e1], a[e1], k, le, variant, pos, normal);
        return;
    }
    float fl = (float)level;
    if (kind == XYL_TESS_KIND_QUAD)
        eval_quad(c, n, a, (float)i / fl, (float)j / fl, variant, pos, normal);
    else
        eval_triangle(c, n, a, (float)(level - i - j) / fl, (float)i / fl, (float)j / fl, variant,
                      pos, normal);
}

/* ---- the hardware path's vertices --------------------------------------------------------- */

/* The hardware path's side test (shaders/tess_hw.tese: xyl_side_point). */
static bool side_point(uint32_t kind, const float tc[3], uint32_t *e, float *t)
{
    if (kind == XYL_TESS_KIND_TRIANGLE) {
        if (tc[2] == 0.0f) { *e = 0; *t = tc[1]; return true; }
        if (tc[0] == 0.0f) { *e = 1; *t = tc[2]; return true; }
        if (tc[1] == 0.0f) { *e = 2; *t = tc[0]; return true; }
        return false;
    }
    if (tc[1] == 0.0f) { *e = 0; *t = tc[0]; return true; }
    if (tc[0] == 1.0f) { *e = 1; *t = tc[1]; return true; }
    if (tc[1] == 1.0f) { *e = 2; *t = 1.0f - tc[0]; return true; }
    if (tc[0] == 0.0f) { *e = 3; *t = 1.0f - tc[1]; return true; }
    return false;
}

void xyl__tess_reference_hardware(const xyl_tess_patch *patch, xyl_tess_variant variant,
                                  const float tc[3], uint32_t edge_levels, float pos[3],
                                  float normal[3])
{
    uint32_t kind = xyl_tess_patch_kind(patch), e;
    float t;
    if (side_point(kind, tc, &e, &t)) {
        uint32_t le = (edge_levels >> (XYL_TESS_EDGE_LEVEL_BITS * e)) & 0xffu;
        uint32_t k = (uint32_t)lroundf(t * (float)le);
        xyl_tess_eval_edge(patch, variant, e, k, le, pos, normal);
    } else if (kind == XYL_TESS_KIND_QUAD) {
        xyl_tess_eval(patch, variant, tc[0], tc[1], pos, normal);
    } else {
        xyl_tess_eval(patch, variant, tc[1], tc[2], pos, normal); /* weights (tc0, tc1, tc2) */
    }
}

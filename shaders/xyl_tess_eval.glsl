// xyl_tess_eval.glsl: PN-triangle / PN-quad evaluation, shared by every shader stage that
// refines a patch. tessellate/src/eval.c is the CPU reference and performs the SAME operations
// in the same order; change both together (the GPU = CPU tests compare them).
//
// Needs xyl_tess_shared.h before it. Positions and normals are world space.

// ---- small helpers -------------------------------------------------------------------------

vec3 xyl_normalize_or(vec3 v, vec3 fallback)
{
    float l2 = dot(v, v);
    return l2 > 0.0 ? v / sqrt(l2) : fallback;
}

// Strict lexicographic order on (position, normal): the canonical direction of an edge, so the
// two patches that share it evaluate the same operations on the same operands.
bool xyl_precedes(vec3 pa, vec3 na, vec3 pb, vec3 nb)
{
    if (pa.x != pb.x) return pa.x < pb.x;
    if (pa.y != pb.y) return pa.y < pb.y;
    if (pa.z != pb.z) return pa.z < pb.z;
    if (na.x != nb.x) return na.x < nb.x;
    if (na.y != nb.y) return na.y < nb.y;
    return na.z < nb.z;
}

// The arc variant's handle direction at a corner with axis a (or none, a = 0): along the axis,
// signed towards the edge, where the edge leaves within 30 degrees of it; else the edge's
// tangent-plane direction t (|t|^2 = tt > 0). The flag says which.
vec3 xyl_arc_dir(vec3 t, float tt, vec3 a, out bool on_axis)
{
    float ta = dot(t, a);
    on_axis = dot(a, a) > 0.0 && abs(ta) >= 0.8660254 * sqrt(tt);
    if (on_axis) return ta >= 0.0 ? a : -a;
    return t / sqrt(tt);
}

// The inner control point of edge (pi, pj) next to pi. All variants start from the edge vector
// projected into pi's tangent plane; the circle-exact length (4/3) tan(phi/4) r, with the chord
// c = 2 r sin(phi/2), simplifies to 2c / (3 (1 + cos(phi/2))), which needs no trigonometry and
// tends to c/3 (the PN rule) as phi -> 0. The arc variant turns the handle onto the corner's
// axis (ai, aj: the curve along the branch; 0 where none) where the edge runs along it, and
// takes phi from the two handle directions: on a bent tube the line along the branch is a
// circle whose turn the normals cannot see.
vec3 xyl_handle(vec3 pi, vec3 ni, vec3 ai, vec3 pj, vec3 nj, vec3 aj, uint variant)
{
    vec3 d = pj - pi;
    vec3 t = d - dot(d, ni) * ni;
    if (variant == uint(XYL_TESS_VARIANT_PN)) return pi + t * (1.0 / 3.0);
    if (variant == uint(XYL_TESS_VARIANT_ROUNDED)) return pi + t * 0.5;
    float dd = dot(d, d);
    float tt = dot(t, t);
    if (!(tt > dd * 1e-12)) return pi; // the edge leaves along the normal: no tangent direction
    if (variant == uint(XYL_TESS_VARIANT_ARC)) {
        vec3 s = dot(d, nj) * nj - d; // the edge from pj, in pj's tangent plane
        float ss = dot(s, s);
        bool on_i, on_j = false;
        vec3 ui = xyl_arc_dir(t, tt, ai, on_i);
        vec3 uj = ss > dd * 1e-12 ? xyl_arc_dir(s, ss, aj, on_j) : vec3(0.0);
        if (on_i || on_j) {
            float chalf = sqrt(max(0.5 - 0.5 * clamp(dot(ui, uj), -1.0, 1.0), 0.0));
            float len = (2.0 * sqrt(dd)) / (3.0 * (1.0 + chalf));
            return pi + ui * len;
        }
    }
    float chalf = sqrt(max(0.5 + 0.5 * clamp(dot(ni, nj), -1.0, 1.0), 0.0));
    float len = (2.0 * sqrt(dd)) / (3.0 * (1.0 + chalf));
    return pi + t * (len / sqrt(tt));
}

// Vlachos' mid-edge normal: the average normal reflected in the plane normal to the edge.
// Symmetric in its two ends.
vec3 xyl_edge_normal(vec3 pi, vec3 ni, vec3 pj, vec3 nj)
{
    vec3 d = pj - pi;
    vec3 s = ni + nj;
    float dd = dot(d, d);
    float v = dd > 0.0 ? 2.0 * dot(d, s) / dd : 0.0;
    return xyl_normalize_or(s - v * d, ni);
}

vec3 xyl_bezier3(vec3 a, vec3 b, vec3 c, vec3 d, float t)
{
    float s = 1.0 - t;
    return a * (s * s * s) + b * (3.0 * s * s * t) + c * (3.0 * s * t * t) + d * (t * t * t);
}

// ---- edges ---------------------------------------------------------------------------------

// Point k of le on the edge between corners a and b. The edge is walked in canonical order,
// so both patches sharing it produce bit-identical results.
void xyl_eval_edge(vec3 pa, vec3 na, vec3 aa, vec3 pb, vec3 nb, vec3 ab, uint k, uint le,
                   uint variant, out vec3 pos, out vec3 nrm)
{
    if (!xyl_precedes(pa, na, pb, nb)) {
        vec3 tp = pa; pa = pb; pb = tp;
        vec3 tn = na; na = nb; nb = tn;
        vec3 ta = aa; aa = ab; ab = ta;
        k = le - k;
    }
    float t = float(k) / float(le);
    vec3 ha = xyl_handle(pa, na, aa, pb, nb, ab, variant);
    vec3 hb = xyl_handle(pb, nb, ab, pa, na, aa, variant);
    pos = xyl_bezier3(pa, ha, hb, pb, t);
    vec3 ne = xyl_edge_normal(pa, na, pb, nb);
    float s = 1.0 - t;
    nrm = xyl_normalize_or(na * (s * s) + ne * (2.0 * s * t) + nb * (t * t), na);
}

// ---- interiors -----------------------------------------------------------------------------

// PN-quad at (u, v): bicubic Bezier with PN edge points and Coons interior points, biquadratic
// normals with a Coons centre normal. Corners 0..3 sit at (0,0), (1,0), (1,1), (0,1).
void xyl_eval_quad(vec3 c[4], vec3 n[4], vec3 a[4], float u, float v, uint variant,
                   out vec3 pos, out vec3 nrm)
{
    vec3 b[16]; // b[i + 4 j], i along u, j along v
    b[0] = c[0]; b[3] = c[1]; b[15] = c[2]; b[12] = c[3];
    b[1] = xyl_handle(c[0], n[0], a[0], c[1], n[1], a[1], variant);
    b[2] = xyl_handle(c[1], n[1], a[1], c[0], n[0], a[0], variant);
    b[7] = xyl_handle(c[1], n[1], a[1], c[2], n[2], a[2], variant);
    b[11] = xyl_handle(c[2], n[2], a[2], c[1], n[1], a[1], variant);
    b[14] = xyl_handle(c[2], n[2], a[2], c[3], n[3], a[3], variant);
    b[13] = xyl_handle(c[3], n[3], a[3], c[2], n[2], a[2], variant);
    b[8] = xyl_handle(c[3], n[3], a[3], c[0], n[0], a[0], variant);
    b[4] = xyl_handle(c[0], n[0], a[0], c[3], n[3], a[3], variant);
    b[5] = (-4.0 * b[0] + 6.0 * (b[4] + b[1]) - 2.0 * (b[12] + b[3]) + 3.0 * (b[7] + b[13]) - b[15]) / 9.0;
    b[6] = (-4.0 * b[3] + 6.0 * (b[7] + b[2]) - 2.0 * (b[15] + b[0]) + 3.0 * (b[4] + b[14]) - b[12]) / 9.0;
    b[9] = (-4.0 * b[12] + 6.0 * (b[8] + b[13]) - 2.0 * (b[0] + b[15]) + 3.0 * (b[11] + b[1]) - b[3]) / 9.0;
    b[10] = (-4.0 * b[15] + 6.0 * (b[11] + b[14]) - 2.0 * (b[3] + b[12]) + 3.0 * (b[8] + b[2]) - b[0]) / 9.0;

    float su = 1.0 - u, sv = 1.0 - v;
    float bu[4] = float[4](su * su * su, 3.0 * su * su * u, 3.0 * su * u * u, u * u * u);
    float bv[4] = float[4](sv * sv * sv, 3.0 * sv * sv * v, 3.0 * sv * v * v, v * v * v);
    pos = vec3(0.0);
    for (int j = 0; j < 4; ++j) {
        vec3 row = b[4 * j] * bu[0] + b[4 * j + 1] * bu[1] + b[4 * j + 2] * bu[2] + b[4 * j + 3] * bu[3];
        pos = pos + row * bv[j];
    }

    vec3 m[9]; // m[i + 3 j]
    m[0] = n[0]; m[2] = n[1]; m[8] = n[2]; m[6] = n[3];
    m[1] = xyl_edge_normal(c[0], n[0], c[1], n[1]);
    m[5] = xyl_edge_normal(c[1], n[1], c[2], n[2]);
    m[7] = xyl_edge_normal(c[2], n[2], c[3], n[3]);
    m[3] = xyl_edge_normal(c[3], n[3], c[0], n[0]);
    m[4] = (m[1] + m[5] + m[7] + m[3]) * 0.5 - (m[0] + m[2] + m[8] + m[6]) * 0.25;
    float qu[3] = float[3](su * su, 2.0 * su * u, u * u);
    float qv[3] = float[3](sv * sv, 2.0 * sv * v, v * v);
    vec3 ns = vec3(0.0);
    for (int j = 0; j < 3; ++j) {
        vec3 row = m[3 * j] * qu[0] + m[3 * j + 1] * qu[1] + m[3 * j + 2] * qu[2];
        ns = ns + row * qv[j];
    }
    nrm = xyl_normalize_or(ns, n[0]);
}

// PN-triangle with weights (w0, w1, w2) of corners 0, 1, 2 (Vlachos et al. 2001).
void xyl_eval_triangle(vec3 c[4], vec3 n[4], vec3 a[4], float w0, float w1, float w2, uint variant,
                       out vec3 pos, out vec3 nrm)
{
    vec3 b210 = xyl_handle(c[0], n[0], a[0], c[1], n[1], a[1], variant);
    vec3 b120 = xyl_handle(c[1], n[1], a[1], c[0], n[0], a[0], variant);
    vec3 b021 = xyl_handle(c[1], n[1], a[1], c[2], n[2], a[2], variant);
    vec3 b012 = xyl_handle(c[2], n[2], a[2], c[1], n[1], a[1], variant);
    vec3 b102 = xyl_handle(c[2], n[2], a[2], c[0], n[0], a[0], variant);
    vec3 b201 = xyl_handle(c[0], n[0], a[0], c[2], n[2], a[2], variant);
    vec3 e = (b210 + b120 + b021 + b012 + b102 + b201) / 6.0;
    vec3 vc = (c[0] + c[1] + c[2]) / 3.0;
    vec3 b111 = e + (e - vc) * 0.5;
    pos = c[0] * (w0 * w0 * w0) + c[1] * (w1 * w1 * w1) + c[2] * (w2 * w2 * w2)
        + b210 * (3.0 * w0 * w0 * w1) + b120 * (3.0 * w0 * w1 * w1)
        + b021 * (3.0 * w1 * w1 * w2) + b012 * (3.0 * w1 * w2 * w2)
        + b102 * (3.0 * w2 * w2 * w0) + b201 * (3.0 * w2 * w0 * w0)
        + b111 * (6.0 * w0 * w1 * w2);
    vec3 n110 = xyl_edge_normal(c[0], n[0], c[1], n[1]);
    vec3 n011 = xyl_edge_normal(c[1], n[1], c[2], n[2]);
    vec3 n101 = xyl_edge_normal(c[2], n[2], c[0], n[0]);
    vec3 ns = n[0] * (w0 * w0) + n[1] * (w1 * w1) + n[2] * (w2 * w2)
            + n110 * (2.0 * w0 * w1) + n011 * (2.0 * w1 * w2) + n101 * (2.0 * w2 * w0);
    nrm = xyl_normalize_or(ns, n[0]);
}

// ---- lattice points (what the instanced path evaluates) ------------------------------------

// Which edge a lattice point (i, j) of a level-l pattern lies on, and its index counted from
// the edge's first corner; false for interior points. Corners take the first edge that holds
// them, which yields the corner itself.
bool xyl_lattice_edge(uint kind, uint l, uint i, uint j, out uint e, out uint idx)
{
    e = 0u; idx = 0u;
    if (j == 0u) { e = 0u; idx = i; return true; }
    if (kind == uint(XYL_TESS_KIND_QUAD)) {
        if (i == l) { e = 1u; idx = j; return true; }
        if (j == l) { e = 2u; idx = l - i; return true; }
        if (i == 0u) { e = 3u; idx = l - j; return true; }
        return false;
    }
    if (i + j == l) { e = 1u; idx = j; return true; }
    if (i == 0u) { e = 2u; idx = l - j; return true; }
    return false;
}

// Snaps index idx of a level-l edge to the coarser edge level le <= l (round half up): monotone,
// onto 0..le, so both sides of an edge produce exactly the points k / le.
uint xyl_snap(uint idx, uint l, uint le)
{
    return (2u * idx * le + l) / (2u * l);
}

void xyl_eval_lattice(vec3 c[4], vec3 n[4], vec3 a[4], uint kind, uint l, uint edge_levels, uint i, uint j,
                      uint variant, out vec3 pos, out vec3 nrm)
{
    uint e, idx;
    if (xyl_lattice_edge(kind, l, i, j, e, idx)) {
        uint le = (edge_levels >> (XYL_TESS_EDGE_LEVEL_BITS * e)) & 0xffu;
        uint e1 = (e + 1u == kind) ? 0u : e + 1u;
        xyl_eval_edge(c[e], n[e], a[e], c[e1], n[e1], a[e1], xyl_snap(idx, l, le), le, variant,
                      pos, nrm);
        return;
    }
    float fl = float(l);
    if (kind == uint(XYL_TESS_KIND_QUAD)) {
        xyl_eval_quad(c, n, a, float(i) / fl, float(j) / fl, variant, pos, nrm);
    } else {
        xyl_eval_triangle(c, n, a, float(l - i - j) / fl, float(i) / fl, float(j) / fl, variant, pos, nrm);
    }
}

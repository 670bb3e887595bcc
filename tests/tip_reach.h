/* Where the skeleton's tips are against a stem mesh (docs/stems.md, "Tips"): for every tip (a
 * node without children) the distance to the mesh's surface and whether it lies inside (the
 * generalised winding number of the closed mesh, van Oosterom and Strackee's solid angle per
 * triangle). A tip is reached when it lies within `slack` times its radius of the surface; one
 * that is not lies either outside (a twig with no geometry to its end) or inside (its branch
 * buried in another). Brute force over the triangulated view: for measurements and tests on
 * trees of some 10^4 triangles. Needs no cmocka. */
#ifndef XYL_TIP_REACH_H
#define XYL_TIP_REACH_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

#include <xylem/xyl_mesh.h>
#include <xylem/xyl_skeleton.h>

typedef struct tr_tally {
    size_t tips;
    size_t reached;     /* within slack r of the surface */
    size_t outside;     /* outside the mesh, further than slack r */
    size_t inside;      /* inside the mesh, further than slack r from its surface */
    double worst_out;   /* the largest distance / r of an outside tip */
    int32_t worst_node; /* that tip's node, or -1 */
} tr_tally;

static inline double tr_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Squared distance from p to triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5). */
static inline double tr_dist2(const double p[3], const double a[3], const double b[3],
                              const double c[3])
{
    double ab[3], ac[3], ap[3], q[3];
    for (int i = 0; i < 3; ++i) ab[i] = b[i] - a[i], ac[i] = c[i] - a[i], ap[i] = p[i] - a[i];
    double d1 = tr_dot(ab, ap), d2 = tr_dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) {
        for (int i = 0; i < 3; ++i) q[i] = a[i];
    } else {
        double bp[3], cp[3];
        for (int i = 0; i < 3; ++i) bp[i] = p[i] - b[i], cp[i] = p[i] - c[i];
        double d3 = tr_dot(ab, bp), d4 = tr_dot(ac, bp), d5 = tr_dot(ab, cp), d6 = tr_dot(ac, cp);
        double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d3 >= 0 && d4 <= d3) {
            for (int i = 0; i < 3; ++i) q[i] = b[i];
        } else if (d6 >= 0 && d5 <= d6) {
            for (int i = 0; i < 3; ++i) q[i] = c[i];
        } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
            double v = d1 / (d1 - d3);
            for (int i = 0; i < 3; ++i) q[i] = a[i] + v * ab[i];
        } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
            double w = d2 / (d2 - d6);
            for (int i = 0; i < 3; ++i) q[i] = a[i] + w * ac[i];
        } else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
            double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            for (int i = 0; i < 3; ++i) q[i] = b[i] + w * (c[i] - b[i]);
        } else {
            double den = 1.0 / (va + vb + vc), v = vb * den, w = vc * den;
            for (int i = 0; i < 3; ++i) q[i] = a[i] + ab[i] * v + ac[i] * w;
        }
    }
    double d[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
    return tr_dot(d, d);
}

/* The solid angle of triangle (a, b, c) seen from p, signed by its winding. */
static inline double tr_solid_angle(const double p[3], const double a[3], const double b[3],
                                    const double c[3])
{
    double x[3], y[3], z[3];
    for (int i = 0; i < 3; ++i) x[i] = a[i] - p[i], y[i] = b[i] - p[i], z[i] = c[i] - p[i];
    double lx = sqrt(tr_dot(x, x)), ly = sqrt(tr_dot(y, y)), lz = sqrt(tr_dot(z, z));
    double cr[3] = {y[1] * z[2] - y[2] * z[1], y[2] * z[0] - y[0] * z[2], y[0] * z[1] - y[1] * z[0]};
    double num = tr_dot(x, cr);
    double den = lx * ly * lz + tr_dot(x, y) * lz + tr_dot(y, z) * lx + tr_dot(z, x) * ly;
    return 2.0 * atan2(num, den);
}

typedef enum tr_place { TR_REACHED, TR_INSIDE, TR_OUTSIDE } tr_place;

/* Where point p of radius r lies against m; *d gets its distance to the surface over r. */
static inline tr_place tr_classify(const xyl_mesh *m, xyl_vec3 p, float r, double slack,
                                   double *d)
{
    double q[3] = {p.x, p.y, p.z}, best = INFINITY, wind = 0.0;
    size_t tris = 2 * m->quad_count + m->triangle_count;
    for (size_t f = 0; f < tris; ++f) {
        double v[3][3];
        for (int c = 0; c < 3; ++c) {
            xyl_vec3 x = m->positions[m->tri_view[3 * f + c]];
            v[c][0] = x.x, v[c][1] = x.y, v[c][2] = x.z;
        }
        best = fmin(best, tr_dist2(q, v[0], v[1], v[2]));
        wind += tr_solid_angle(q, v[0], v[1], v[2]);
    }
    *d = sqrt(best) / r;
    if (*d <= slack) return TR_REACHED;
    /* inside where the winding number (wind / 4 pi) is above 1/2 */
    return fabs(wind) > 2.0 * 3.14159265358979323846 ? TR_INSIDE : TR_OUTSIDE;
}

/* place (may be NULL): per node, where each tip lies (other nodes untouched). */
static inline tr_tally tr_measure(const xyl_skeleton *sk, const xyl_mesh *m, double slack,
                                  tr_place *place)
{
    tr_tally t = {0, 0, 0, 0, 0.0, -1};
    bool *parent = calloc(sk->node_count ? sk->node_count : 1, sizeof *parent);
    if (!parent) abort();
    for (size_t i = 0; i < sk->node_count; ++i)
        if (sk->nodes[i].parent >= 0) parent[sk->nodes[i].parent] = true;
    for (size_t i = 0; i < sk->node_count; ++i) {
        if (parent[i]) continue;
        double d;
        ++t.tips;
        tr_place at = tr_classify(m, sk->nodes[i].pos, sk->nodes[i].radius, slack, &d);
        if (place) place[i] = at;
        switch (at) {
        case TR_REACHED: ++t.reached; break;
        case TR_INSIDE: ++t.inside; break;
        case TR_OUTSIDE:
            ++t.outside;
            if (d > t.worst_out) t.worst_out = d, t.worst_node = (int32_t)i;
            break;
        }
    }
    free(parent);
    return t;
}

/* Of the tips tr_measure placed outside m (place), those of one-segment laterals with no face
 * in m (a fork's twig of one node that the construction left out): the cause docs/stems.md
 * names. */
static inline size_t tr_one_segment_laterals_outside(const xyl_skeleton *sk, const xyl_mesh *m,
                                                     const tr_place *place)
{
    bool *meshed = calloc(sk->branch_count ? sk->branch_count : 1, sizeof *meshed);
    if (!meshed) abort();
    for (size_t f = 0; f < m->quad_count + m->triangle_count; ++f)
        meshed[m->face_branches[f]] = true;
    size_t n = 0;
    for (size_t i = 0; i < sk->node_count; ++i) {
        const xyl_skel_node *x = &sk->nodes[i];
        n += place[i] == TR_OUTSIDE && !meshed[x->branch] && x->parent >= 0 &&
             sk->nodes[x->parent].branch != x->branch;
    }
    free(meshed);
    return n;
}

#endif /* XYL_TIP_REACH_H */

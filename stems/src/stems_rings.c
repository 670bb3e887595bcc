/* A branch's tube: its stations, ring frames, ring vertices, bands and caps, built in turn. */
#include <string.h>

#include "stems_internal.h"

/* ---- stations ------------------------------------------------------------------------------ */

static xyl_result collect_chain(stems *s, uint32_t start)
{
    s->nchain = 0;
    for (uint32_t n = start; n != UINT32_MAX; n = xyl__stems_main_child(s, n)) {
        if (!xyl__grow(&s->alloc, (void **)&s->chain, &s->ccap, s->nchain, s->nchain + 1,
                       sizeof *s->chain))
            return xyl__stems_oom(s);
        s->chain[s->nchain++] = n;
    }
    return XYL_OK;
}

size_t xyl__stems_lateral_count(const stems *s, const stems_station *st)
{
    size_t n = 0;
    for (uint32_t i = st->first; i <= st->last; ++i) {
        uint32_t node = s->chain[i];
        n += s->child_start[node + 1] - s->child_start[node];
        n -= xyl__stems_main_child(s, node) != UINT32_MAX;
    }
    return n;
}

/* Stations along the chain: coincident nodes share one; nodes not clearly ahead of a child's
 * bridge ring are merged into the first station that is (docs/stems.md). */
static xyl_result make_stations(stems *s, const stems_ring *bridge)
{
    s->nstations = 0;
    size_t first = 0;
    for (size_t i = 0; i < s->nchain; ++i) {
        xyl__dvec3 p = xyl__stems_node_pos(s, s->chain[i]);
        double r = s->sk->nodes[s->chain[i]].radius;
        /* only the chain's start can be behind: a branch that curls back later keeps its nodes */
        bool behind = bridge && !s->nstations &&
                      xyl__d3_dot(xyl__d3_sub(p, bridge->centre), bridge->tangent) < bridge->radius;
        bool same = s->nstations &&
                    xyl__d3_len(xyl__d3_sub(p, s->stations[s->nstations - 1].p)) <= 1e-6 * r;
        if (behind && i + 1 < s->nchain) continue;
        if (same) {
            s->stations[s->nstations - 1].last = (uint32_t)i;
            first = i + 1;
            continue;
        }
        if (behind) p = xyl__d3_add(bridge->centre, xyl__d3_scale(bridge->tangent, 2 * bridge->radius));
        if (!xyl__grow(&s->alloc, (void **)&s->stations, &s->scap, s->nstations,
                       s->nstations + 1, sizeof *s->stations))
            return xyl__stems_oom(s);
        stems_station st = {p, r, (uint32_t)first, (uint32_t)i};
        /* a stub stands for none of the child's nodes, so it need not have their radius: at it,
         * a knob wider than the bridge ring (whose radius the patch limits) stood out beside
         * the fork, across its siblings' tubes. It keeps the bridge ring's radius, unless
         * laterals of the nodes it absorbed hang from it: their patches need the width */
        if (behind && !xyl__stems_lateral_count(s, &st)) st.r = bridge->radius;
        s->stations[s->nstations++] = st;
        first = i + 1;
    }
    return XYL_OK;
}

/* A root chain that collapsed to one station still gets a tube: a second, node-less station
 * one diameter further on; so does a lateral's one station with laterals, whose fork rings
 * need a segment ahead. */
static xyl_result ensure_two_stations(stems *s, xyl__dvec3 dir)
{
    if (s->nstations >= 2) return XYL_OK;
    if (!xyl__grow(&s->alloc, (void **)&s->stations, &s->scap, s->nstations, 2, sizeof *s->stations))
        return xyl__stems_oom(s);
    stems_station *a = &s->stations[0];
    stems_station b = {xyl__d3_add(a->p, xyl__d3_scale(dir, 2.0 * a->r)), a->r, UINT32_MAX, 0};
    s->stations[s->nstations++] = b;
    return XYL_OK;
}

/* ---- ring frames --------------------------------------------------------------------------- */

/* Rotation-minimising frame transport (double reflection, Wang et al. 2008): the reference
 * vector u at (x0, t0) carried to (x1, t1). */
static xyl__dvec3 transport(xyl__dvec3 u, xyl__dvec3 x0, xyl__dvec3 t0, xyl__dvec3 x1,
                            xyl__dvec3 t1)
{
    xyl__dvec3 v1 = xyl__d3_sub(x1, x0);
    double c1 = xyl__d3_dot(v1, v1);
    xyl__dvec3 uL = u, tL = t0;
    if (c1 > XYL__EPS_NORMALIZE) {
        uL = xyl__d3_sub(u, xyl__d3_scale(v1, 2.0 / c1 * xyl__d3_dot(v1, u)));
        tL = xyl__d3_sub(t0, xyl__d3_scale(v1, 2.0 / c1 * xyl__d3_dot(v1, t0)));
    }
    xyl__dvec3 v2 = xyl__d3_sub(t1, tL);
    double c2 = xyl__d3_dot(v2, v2);
    if (c2 > XYL__EPS_NORMALIZE) uL = xyl__d3_sub(uL, xyl__d3_scale(v2, 2.0 / c2 * xyl__d3_dot(v2, uL)));
    /* re-orthogonalise against t1: rounding must not tilt the ring plane */
    uL = xyl__d3_sub(uL, xyl__d3_scale(t1, xyl__d3_dot(uL, t1)));
    double l2 = xyl__d3_dot(uL, uL);
    /* reflections keep the length: a unit u stays unit up to rounding, and dividing by the
     * square root would put the slowest operations on the chain that carries u along the
     * branch; only a u that has drifted is scaled back */
    if (fabs(l2 - 1.0) <= 1e-12) return uL;
    if (!(l2 > XYL__EPS_NORMALIZE) || !isfinite(l2)) return xyl__d3_any_orthogonal(t1);
    return xyl__d3_scale(uL, 1.0 / sqrt(l2));
}

/* Plans a ring: its frame (the reference direction carried from the previous ring of this
 * branch) and texture v. Its vertices and the band to it come later, from emit_rings: the
 * frames form one long chain of dependent sqrt and divisions along the branch, which runs
 * faster on its own than interleaved with the vertex and quad stores. */
xyl_result xyl__stems_add_ring(stems *s, xyl__dvec3 c, xyl__dvec3 t, double r)
{
    if (!xyl__grow(&s->alloc, (void **)&s->rings, &s->rcap, s->nrings, s->nrings + 1,
                   sizeof *s->rings))
        return xyl__stems_oom(s);
    /* filled in place: a ring built on the stack and copied in as a whole stalled on store
     * forwarding (its fields written in pieces, read back in 16-byte blocks) */
    stems_ring *ring = &s->rings[s->nrings], *prev = s->nrings ? ring - 1 : NULL;
    ring->first = UINT32_MAX;
    ring->centre = c;
    ring->tangent = t;
    ring->radius = r;
    ring->band = UINT32_MAX;
    if (prev) {
        ring->u = transport(prev->u, prev->centre, prev->tangent, c, t);
        double mean_r = 0.5 * (prev->radius + r);
        /* v is arc length in units of the circumference; a tube of radius 0 (a bridge ring
         * on a patch without height, and the stub that keeps its radius) has none, and its
         * length would give 0 / 0 or an infinite v: it adds nothing */
        double along = xyl__d3_len(xyl__d3_sub(c, prev->centre));
        double dv = mean_r > 0.0 ? along / (2.0 * XYL__PI * mean_r) : 0.0;
        /* a segment longer than XYL__STEMS_MAX_DV circumferences (length / radius above 4e5;
         * valid, but no bark texture could show it) is textured as if it were that long, so v
         * stays finite for every valid skeleton (length / radius up to 1e39 and beyond would
         * give an infinite v) */
        ring->v = prev->v + (dv < XYL__STEMS_MAX_DV ? dv : XYL__STEMS_MAX_DV);
    } else {
        ring->u = xyl__d3_any_orthogonal(t);
        ring->v = 0.0;
    }
    s->nrings++;
    return XYL_OK;
}

/* Directions of the segments into and out of station i; the first and last take their one, a
 * segment without direction takes start_dir (in) or the incoming one (out). *seg carries the
 * direction of segment i -> i + 1 (and *seg_ok whether it has one) to station i + 1, whose
 * incoming direction it is: each segment is normalised once. */
static void station_frame(const stems *s, size_t i, xyl__dvec3 start_dir, xyl__dvec3 *seg,
                          bool *seg_ok, xyl__dvec3 *t_in, xyl__dvec3 *t_out)
{
    const stems_station *st = s->stations;
    *t_in = i && *seg_ok ? *seg : start_dir;
    *seg_ok = i + 1 < s->nstations && xyl__d3_normalize_ok(xyl__d3_sub(st[i + 1].p, st[i].p), seg);
    *t_out = *seg_ok ? *seg : *t_in;
}

/* Rings for every station of the current chain; forks get extra rings. Records the ring span
 * of each fork in spans (capacity nstations). */
static xyl_result branch_rings(stems *s, xyl__dvec3 start_dir, stems_fork_span *spans,
                               size_t *nspans)
{
    *nspans = 0;
    xyl__dvec3 seg = start_dir;
    bool seg_ok = false;
    for (size_t i = 0; i < s->nstations; ++i) {
        xyl__dvec3 t_in, t_out;
        station_frame(s, i, start_dir, &seg, &seg_ok, &t_in, &t_out);
        xyl__dvec3 t = xyl__d3_normalize_or(xyl__d3_add(t_in, t_out), t_in);
        const stems_station *st = &s->stations[i];
        size_t laterals = st->first == UINT32_MAX ? 0 : xyl__stems_lateral_count(s, st);
        size_t lo = s->nrings;
        xyl_result r = laterals ? xyl__stems_fork_rings(s, i, t_in, t, t_out, laterals)
                                : xyl__stems_add_ring(s, st->p, t, st->r);
        if (r) return r;
        if (laterals) {
            stems_fork_span sp = {i, lo, s->nrings - 1};
            spans[(*nspans)++] = sp;
        }
    }
    return XYL_OK;
}

/* Before subdivision the limit surface at ring i lies, along the branch, at
 * (c[i-1] + 4 c[i] + c[i+1]) / 6 (the cubic B-spline of Catmull-Clark on the tube's regular
 * grid, and Loop's limit on the split bands): on a bend it is pulled towards the centre of
 * curvature by (c[i-1] - 2 c[i] + c[i+1]) / 6. Moving each inner ring's centre by minus that
 * leaves the limit within (the fourth difference) / 36 of the skeleton. The first ring (a
 * bridge, fixed to the parent's patch, or the root's cap) and the last (the tip's cap) stay. */
static void limit_centres(stems *s)
{
    if (s->nrings < 3) return;
    xyl__dvec3 prev = s->rings[0].centre, cur = s->rings[1].centre;
    for (size_t i = 1; i + 1 < s->nrings; ++i) {
        xyl__dvec3 next = s->rings[i + 1].centre;
        xyl__dvec3 bend = xyl__d3_add(xyl__d3_sub(prev, xyl__d3_scale(cur, 2.0)), next);
        s->rings[i].centre = xyl__d3_sub(cur, xyl__d3_scale(bend, 1.0 / 6.0));
        prev = cur;
        cur = next;
    }
}

/* ---- ring vertices, bands and caps --------------------------------------------------------- */

#ifdef XYL__SSE2
/* One coordinate of two ring vertices, c + (u (r cos) + w (r sin)), rounded to floats in the
 * low two lanes: xyl__d3_add(c, xyl__d3_add(scale(u, ...), scale(w, ...))) per lane. */
static XYL__ALWAYS_INLINE __m128 ring_coord(double c, double u, double w, __m128d rcos,
                                            __m128d rsin)
{
    __m128d along = _mm_add_pd(_mm_mul_pd(_mm_set1_pd(u), rcos), _mm_mul_pd(_mm_set1_pd(w), rsin));
    return _mm_cvtpd_ps(_mm_add_pd(_mm_set1_pd(c), along));
}
#endif

/* k vertices around centre c in the plane of unit tangent t, starting along unit u (u . t = 0),
 * counter-clockwise seen from +t. Returns the first vertex index. */
static XYL__ALWAYS_INLINE uint32_t put_ring_k(stems *s, xyl__dvec3 c, xyl__dvec3 t,
                                              xyl__dvec3 u, double r, double v, uint32_t branch,
                                              uint32_t k)
{
    /* locals: stores through the output pointers could otherwise alias s->nv and force reloads */
    size_t first = s->nv;
    xyl_vec3 *pos = s->pos + first;
    float *uv = s->uv + 2 * first, fv = (float)v;
    uint32_t *vb = s->vbranch + first;
    xyl__dvec3 w = xyl__d3_cross(t, u);
    double rr = r * s->inflate;
    uint32_t j = 0;
#ifdef XYL__SSE2
    /* two vertices per instruction, the same operations in the same order: the same bits */
    __m128d vr = _mm_set1_pd(rr);
    for (; j + 2 <= k; j += 2) {
        __m128d ca = _mm_mul_pd(vr, _mm_loadu_pd(s->cos_a + j));
        __m128d sa = _mm_mul_pd(vr, _mm_loadu_pd(s->sin_a + j));
        __m128 fx = ring_coord(c.x, u.x, w.x, ca, sa), fy = ring_coord(c.y, u.y, w.y, ca, sa);
        xyl__store_pair(fx, fy, ring_coord(c.z, u.z, w.z, ca, sa), pos + j);
    }
#endif
    for (; j < k; ++j) {
        xyl__dvec3 p = xyl__d3_add(c, xyl__d3_add(xyl__d3_scale(u, rr * s->cos_a[j]),
                                                  xyl__d3_scale(w, rr * s->sin_a[j])));
        pos[j] = xyl__to_f3(p);
    }
    for (j = 0; j < k; ++j) {
        uv[2 * j] = s->u_of[j];
        uv[2 * j + 1] = fv;
        vb[j] = branch;
    }
    if (s->nrm) {
        xyl_vec3 *n = s->nrm + first, zero = {0.0f, 0.0f, 0.0f};
        for (uint32_t i = 0; i < k; ++i) n[i] = zero;
    }
    s->nv = first + k;
    return (uint32_t)first;
}

uint32_t xyl__stems_put_ring(stems *s, xyl__dvec3 c, xyl__dvec3 t, xyl__dvec3 u, double r,
                             double v, uint32_t branch)
{
    return put_ring_k(s, c, t, u, r, v, branch, s->k);
}

#ifdef XYL__SSE2
/* The normals of the k band quads from ring pa to ring pb (even k), as xyl__quad_normal of quad
 * j = (a + j, a + j1, b + j1, b + j): the cross product of the diagonals b + j1 - (a + j) and
 * b + j - (a + j1) in doubles, rounded to floats, for quads j and j + 1 in the two lanes. */
static XYL__ALWAYS_INLINE void quad_normals_sse2(const xyl_vec3 *pa, const xyl_vec3 *pb,
                                                 uint32_t k, xyl_vec3 *fn)
{
    for (uint32_t j = 0; j < k; j += 2) {
        uint32_t j1 = j + 1, j2 = j + 2 < k ? j + 2 : 0;
        __m128d a0[3], a1[3], b0[3], b1[3], d1[3], d2[3];
        xyl__load_pair(pa, j, j1, a0);
        xyl__load_pair(pa, j1, j2, a1);
        xyl__load_pair(pb, j, j1, b0);
        xyl__load_pair(pb, j1, j2, b1);
        for (int i = 0; i < 3; ++i) {
            d1[i] = _mm_sub_pd(b1[i], a0[i]);
            d2[i] = _mm_sub_pd(b0[i], a1[i]);
        }
        __m128 nx = _mm_cvtpd_ps(_mm_sub_pd(_mm_mul_pd(d1[1], d2[2]), _mm_mul_pd(d1[2], d2[1])));
        __m128 ny = _mm_cvtpd_ps(_mm_sub_pd(_mm_mul_pd(d1[2], d2[0]), _mm_mul_pd(d1[0], d2[2])));
        __m128 nz = _mm_cvtpd_ps(_mm_sub_pd(_mm_mul_pd(d1[0], d2[1]), _mm_mul_pd(d1[1], d2[0])));
        xyl__store_pair(nx, ny, nz, fn + j);
    }
}
#endif

/* Adds the normals of the band quads q0 .. q0 + k - 1 (from ring a to ring b) to their vertices.
 * Vertex j of either ring is in quads j - 1 and j (vertex 0: quads 0 and k - 1) and gets their
 * normals in that, the quads', order, as two adds in registers. A ring's vertices share one
 * branch (put_ring), so one test per ring replaces the per-vertex ones. The *_k helpers are
 * inlined into emit_rings with a constant k for the usual ring sides, so that their loops
 * unroll: the same operations in the same order, so the same bits. */
static XYL__ALWAYS_INLINE void sum_band_normals_k(stems *s, uint32_t a, uint32_t b,
                                                  uint32_t branch, size_t q0, uint32_t k)
{
    if (s->vbranch[a] != branch || s->vbranch[b] != branch) {
        for (uint32_t j = 0; j < k; ++j)
            xyl__stems_sum_quad_normal(s, s->quads + 4 * (q0 + j), branch);
        return;
    }
    /* quad j is (a + j, a + j1, b + j1, b + j), j1 = j + 1 mod k: xyl__quad_normal's diagonals
     * are b + j1 - (a + j) and b + j - (a + j1) */
    const xyl_vec3 *pa = s->pos + a, *pb = s->pos + b;
    xyl_vec3 fn[32];
#ifdef XYL__SSE2
    if (k % 2 == 0) { /* two quads per instruction: the same operations, so the same bits */
        quad_normals_sse2(pa, pb, k, fn);
    } else
#endif
    for (uint32_t j = 0; j < k; ++j) {
        uint32_t j1 = j + 1 < k ? j + 1 : 0;
        xyl__dvec3 d1 = xyl__d3_sub(xyl__from_f3(pb[j1]), xyl__from_f3(pa[j]));
        xyl__dvec3 d2 = xyl__d3_sub(xyl__from_f3(pb[j]), xyl__from_f3(pa[j1]));
        fn[j] = xyl__to_f3(xyl__d3_cross(d1, d2));
    }
    xyl_vec3 *acc[2] = {s->nrm + a, s->nrm + b};
    for (int r = 0; r < 2; ++r) {
        xyl_vec3 *n = acc[r];
        for (uint32_t j = 0; j < k; ++j) {
            xyl_vec3 first = fn[j ? j - 1 : 0], second = fn[j ? j : k - 1];
            n[j].x = (n[j].x + first.x) + second.x;
            n[j].y = (n[j].y + first.y) + second.y;
            n[j].z = (n[j].z + first.z) + second.z;
        }
    }
}

/* Quads between ring a (behind) and ring b (ahead), both counter-clockwise seen from ahead.
 * Ring vertex j has u = j/k (put_ring_k), so quad j spans 1/k in u, and the last, which closes
 * the ring from (k - 1)/k back to 0, wraps its corners 1 and 2 (vertex 0 of both rings): what
 * face_wraps would find, without the search. */
static XYL__ALWAYS_INLINE void put_band_k(stems *s, uint32_t a, uint32_t b, uint32_t branch,
                                          uint32_t k)
{
    uint32_t last = k - 1;
    size_t n = s->nq;
    uint32_t *q = s->quads + 4 * n, *fb = s->fbranch + n;
    uint8_t *wr = s->qwrap + n;
    for (uint32_t j = 0; j < last; ++j, q += 4) {
        q[0] = a + j;
        q[1] = a + j + 1;
        q[2] = b + j + 1;
        q[3] = b + j;
        fb[j] = branch;
        wr[j] = 0;
    }
    q[0] = a + last;
    q[1] = a;
    q[2] = b;
    q[3] = b + last;
    fb[last] = branch;
    wr[last] = 1u << 1 | 1u << 2;
    s->nq = n + last + 1;
    if (s->nrm) sum_band_normals_k(s, a, b, branch, n, k);
}

/* Closes a ring with (k - 2) / 2 quads fanned from its first vertex; forward = true for a ring
 * the tube leaves behind it (a tip), false for one it starts from (a root). */
static xyl_result put_flat_cap(stems *s, uint32_t ring, bool forward, uint32_t branch)
{
    uint32_t j = 1;
    for (; j + 2 < s->k; j += 2) {
        uint32_t a = ring, b = ring + j, c = ring + j + 1, d = ring + j + 2;
        if (forward) xyl__stems_put_quad(s, a, b, c, d, branch);
        else xyl__stems_put_quad(s, a, d, c, b, branch);
    }
    if (j + 1 < s->k) { /* odd k: vertices 0, j, j + 1 are left for one triangle */
        uint32_t a = ring, b = ring + j, c = ring + j + 1;
        return forward ? xyl__stems_put_tri(s, a, b, c, branch)
                       : xyl__stems_put_tri(s, a, c, b, branch);
    }
    return XYL_OK;
}

/* The apex of a domed cap. A tip's: a quarter of the ring's radius beyond its centre, outwards.
 * A root's: a tenth of the radius inwards, so the base is a shallow inward cone that no point
 * of passes below the root's plane (the tree stands on its root ring). */
static uint32_t put_apex(stems *s, const stems_ring *ring, bool forward, uint32_t branch)
{
    double h = (forward ? 0.25 : XYL__STEMS_BASE_DEPTH) * ring->radius * s->inflate;
    size_t v = s->nv;
    s->pos[v] = xyl__to_f3(xyl__d3_add(ring->centre, xyl__d3_scale(ring->tangent, h)));
    s->uv[2 * v] = 0.5f;
    /* a ring of radius 0 (a bridge on a patch without height) has its apex on it */
    double along = ring->radius > 0.0 ? h / (2.0 * XYL__PI * ring->radius) : 0.0;
    s->uv[2 * v + 1] = (float)(ring->v + along);
    s->vbranch[v] = branch;
    if (s->nrm) memset(s->nrm + v, 0, sizeof *s->nrm);
    s->nv = v + 1;
    return (uint32_t)v;
}

/* Closes a ring of k >= 5 with a low dome: k / 2 quads around an apex (odd k: and one
 * triangle). A flat cap of three or more triangles has two that share one vertex and lie in
 * one plane, which no test can tell from touching once rounding makes them almost, not
 * exactly, coplanar; the dome's faces meet at an angle. */
static xyl_result put_dome_cap(stems *s, const stems_ring *ring, bool forward, uint32_t branch)
{
    uint32_t a = put_apex(s, ring, forward, branch), f = ring->first, k = s->k;
    for (uint32_t j = 0; j + 1 < k; j += 2) {
        uint32_t b = f + j, c = f + j + 1, d = j + 2 < k ? f + j + 2 : f;
        if (forward) xyl__stems_put_quad(s, a, b, c, d, branch);
        else xyl__stems_put_quad(s, a, d, c, b, branch);
    }
    if (k % 2 == 0) return XYL_OK;
    return forward ? xyl__stems_put_tri(s, a, f + k - 1, f, branch)
                   : xyl__stems_put_tri(s, a, f, f + k - 1, branch);
}

/* The cap of ring i of the branch being built (its root or its tip). */
static xyl_result put_cap(stems *s, size_t i, bool forward, uint32_t branch)
{
    const stems_ring *ring = &s->rings[i];
    if (!forward && s->open_base) return XYL_OK;
    if (!forward) { /* a closed base: its ring is a crease when subdivided */
        if (!xyl__grow(&s->alloc, (void **)&s->bases, &s->bcap, s->nbase, s->nbase + 1,
                       sizeof *s->bases))
            return xyl__stems_oom(s);
        s->bases[s->nbase].first = ring->first;
        s->bases[s->nbase].k = s->k;
        s->bases[s->nbase++].up = ring->tangent;
    }
    if (s->k < 5) return put_flat_cap(s, ring->first, forward, branch);
    xyl_result r = put_dome_cap(s, ring, forward, branch);
    if (s->unit_per_branch) s->apex[forward] = (uint32_t)s->nv - 1;
    return r;
}

/* Vertices of the planned rings from .. nrings - 1 and the band from each ring to the next. */
static XYL__ALWAYS_INLINE xyl_result emit_rings_k(stems *s, size_t from, uint32_t branch,
                                                 uint32_t k)
{
    for (size_t i = from; i < s->nrings; ++i) {
        if (!xyl__stems_reserve(s, s->nv + k, s->nq + k)) return xyl__stems_oom(s);
        stems_ring *ring = &s->rings[i];
        ring->first = put_ring_k(s, ring->centre, ring->tangent, ring->u, ring->radius, ring->v,
                                 branch, k);
        if (i) {
            stems_ring *prev = ring - 1;
            prev->band = (uint32_t)s->nq;
            put_band_k(s, prev->first, ring->first, branch, k);
        }
    }
    return XYL_OK;
}

/* emit_rings_k with a constant k for the usual ring sides, so that the per-vertex loops unroll:
 * the same operations in the same order, so the same bits. */
static xyl_result emit_rings(stems *s, size_t from, uint32_t branch)
{
    switch (s->k) {
    case 4: return emit_rings_k(s, from, branch, 4);
    case 6: return emit_rings_k(s, from, branch, 6);
    case 8: return emit_rings_k(s, from, branch, 8);
    default: return emit_rings_k(s, from, branch, s->k);
    }
}

/* ---- a branch ------------------------------------------------------------------------------ */

/* Turns a root's first ring square to its first segment, so that the base lies in the root's
 * plane (the ring faced the direction to the chain's end, tilted wherever the trunk bends: 22.5
 * degrees above a 90-degree kink). Its frame is carried back from the second ring; the rings
 * after it keep the frames carried from the tilted ring, so the rest of the tube, and every
 * lateral placed on it, stays as it was. A root that forks at its first station keeps
 * its fork's rings. */
static void square_root_ring(stems *s, const stems_fork_span *spans, size_t nspans)
{
    if (s->nstations < 2 || s->nrings < 2 || (nspans && spans[0].station == 0)) return;
    stems_ring *ring = &s->rings[0];
    xyl__dvec3 t;
    if (!xyl__d3_normalize_ok(xyl__d3_sub(s->stations[1].p, s->stations[0].p), &t)) return;
    if (memcmp(&t, &ring->tangent, sizeof t) == 0) return;
    /* carried back from the ring after it, so that the first band is not twisted */
    const stems_ring *next = &s->rings[1];
    ring->u = transport(next->u, next->centre, next->tangent, ring->centre, t);
    ring->tangent = t;
}

/* Root flare (docs/stems.md, "Root flare"): rings at these multiples of the root's radius up
 * the first segment carry the flare's curve, where the segment has room for them. */
static const double flare_rings[] = {0.35, 0.8, 1.4, 2.2, 3.3};
#define FLARE_RINGS (sizeof flare_rings / sizeof flare_rings[0])

/* Widens a root's rings by 1 + flare e^(-d / r0) (d: distance from the root along the ring
 * centres), after adding rings where the curve needs them: in the first gap between rings that
 * follows the root's own fork rings (a root forking at its base keeps those), at the distances
 * of flare_rings past the gap's start, where the gap has room clear of its end ring (two of its
 * radii) and of its first half's end. Fork spans after the added rings move with them. */
static xyl_result flare_root(stems *s, stems_fork_span *spans, size_t nspans)
{
    if (!(s->root_flare > 0.0) || s->nrings < 2) return XYL_OK;
    const double r0 = s->rings[0].radius;
    if (!(r0 > 0.0)) return XYL_OK;
    const size_t g = nspans && spans[0].lo == 0 ? spans[0].hi : 0; /* the gap g -> g + 1 */
    if (g + 1 < s->nrings) {
        const stems_ring a = s->rings[g], b = s->rings[g + 1];
        double from = 0.0; /* distance of ring g from the root */
        for (size_t i = 1; i <= g; ++i)
            from += xyl__d3_len(xyl__d3_sub(s->rings[i].centre, s->rings[i - 1].centre));
        xyl__dvec3 t;
        double len = xyl__d3_len(xyl__d3_sub(b.centre, a.centre));
        double at[FLARE_RINGS];
        size_t add = 0;
        if (xyl__d3_normalize_ok(xyl__d3_sub(b.centre, a.centre), &t))
            for (size_t j = 0; j < FLARE_RINGS; ++j) {
                double d = flare_rings[j] * r0 - from; /* past ring g */
                if (d >= 0.25 * r0 && d <= 0.5 * len && d <= len - 2.0 * fmax(b.radius, r0))
                    at[add++] = d;
            }
        if (add) {
            if (!xyl__grow(&s->alloc, (void **)&s->rings, &s->rcap, s->nrings, s->nrings + add,
                           sizeof *s->rings))
                return xyl__stems_oom(s);
            memmove(s->rings + g + 1 + add, s->rings + g + 1,
                    (s->nrings - g - 1) * sizeof *s->rings);
            for (size_t j = 0; j < add; ++j) {
                double w = at[j] / len;
                stems_ring *rg = &s->rings[g + 1 + j];
                const stems_ring *prev = &s->rings[g + j];
                memset(rg, 0, sizeof *rg);
                rg->first = rg->band = UINT32_MAX;
                rg->centre = xyl__d3_add(a.centre, xyl__d3_scale(t, at[j]));
                rg->tangent = t;
                rg->radius = a.radius + w * (b.radius - a.radius);
                rg->u = transport(prev->u, prev->centre, prev->tangent, rg->centre, t);
                rg->v = a.v + w * (b.v - a.v);
            }
            s->nrings += add;
            for (size_t f = 0; f < nspans; ++f)
                if (spans[f].lo > g) spans[f].lo += add, spans[f].hi += add;
        }
    }
    double d = 0.0;
    for (size_t i = 0; i < s->nrings; ++i) {
        if (i) d += xyl__d3_len(xyl__d3_sub(s->rings[i].centre, s->rings[i - 1].centre));
        double grow = s->root_flare * exp(-d / r0);
        if (grow < 1e-6) break;
        s->rings[i].radius *= 1.0 + grow;
    }
    return XYL_OK;
}

xyl_result xyl__stems_build_branch(stems *s, uint32_t start, const stems_ring *from,
                                   uint32_t k)
{
    uint32_t branch = s->sk->nodes[start].branch;
    if (k != s->k) xyl__stems_set_sides(s, k);
    s->by_sides[k]++;
    xyl_result r = collect_chain(s, start);
    if (r) return r;
    double widest = 0.0; /* the ring error's radius, as budget_sides takes it */
    for (size_t i = 0; i < s->nchain; ++i) {
        const xyl_skel_node *n = &s->sk->nodes[s->chain[i]];
        widest = fmax(widest, (double)n->radius * (n->parent < 0 ? 1.0 + s->root_flare : 1.0));
    }
    s->ring_error_max = fmax(s->ring_error_max, widest * xyl__stems_ring_error(k, s->sides_refined));
    r = make_stations(s, from);
    if (r) return r;
    xyl__dvec3 dir = from ? from->tangent : xyl__d3(0, 1, 0);
    if (!from && s->nchain > 1)
        dir = xyl__dir_between(xyl__stems_node_pos(s, s->chain[0]),
                               xyl__stems_node_pos(s, s->chain[s->nchain - 1]), dir);
    /* a lateral's tube already has a ring, its bridge ring: one station without laterals is
     * its tip, and a node-less station beyond it would only stick out past the child's end */
    if (!from || s->nstations > 1 || xyl__stems_lateral_count(s, &s->stations[0]))
        r = ensure_two_stations(s, dir);
    if (r) return r;
    if (from) {
        dir = xyl__stems_first_direction(s, from);
        r = xyl__stems_add_elbow(s, from);
        if (r) return r;
    }
    s->nrings = 0;
    if (from) { /* the bridge ring is this branch's first ring */
        if (!xyl__grow(&s->alloc, (void **)&s->rings, &s->rcap, 0, 1, sizeof *s->rings))
            return xyl__stems_oom(s);
        s->rings[0] = *from;
        s->nrings = 1;
    }
    /* one buffer for all branches: children are built after their parent's build_branch */
    if (!xyl__grow(&s->alloc, (void **)&s->spans, &s->spcap, 0, s->nstations, sizeof *s->spans))
        return xyl__stems_oom(s);
    stems_fork_span *spans = s->spans;
    size_t nspans = 0;
    r = branch_rings(s, dir, spans, &nspans);
    if (!r && !from) square_root_ring(s, spans, nspans);
    if (!r && !from) r = flare_root(s, spans, nspans);
    if (!r && s->limit_centres) limit_centres(s);
    if (!r) r = emit_rings(s, from ? 1 : 0, branch);
    if (!r && !xyl__stems_reserve(s, s->nv + 2, s->nq + s->k)) /* the caps */
        r = xyl__stems_oom(s);
    s->apex[0] = s->apex[1] = UINT32_MAX;
    if (!r && !from) r = put_cap(s, 0, false, branch);
    if (!r) r = put_cap(s, s->nrings - 1, true, branch);
    if (!r && s->sum_normals) xyl__stems_flatten_ring_normals(s, from != NULL);
    if (!r && s->unit_per_branch) xyl__stems_unit_branch_normals(s);
    for (size_t f = 0; f < nspans && !r; ++f)
        r = xyl__stems_attach_laterals(s, spans[f].station, spans[f].lo, spans[f].hi);
    return r;
}

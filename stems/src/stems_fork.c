/* Forks: the rings around one, the patch and bridge of each lateral, a lateral's first band. */
#include <string.h>

#include "stems_internal.h"

/* ---- rings around a fork ------------------------------------------------------------------- */

/* Rings a fork adds around its own: twice the patches its lateral children need, so each still
 * has a choice; never a fixed cap, so a fork can always hold all its children. */
size_t xyl__stems_fork_extra_rings(uint32_t per_band, size_t laterals)
{
    size_t want = (2 * laterals + per_band - 1) / per_band;
    return want < 2 ? 2 : want;
}

/* The patches a band of the branch being built offers the laterals of station st: a patch is
 * as wide as the widest of their strips (their sides, no more than the parent's). */
static uint32_t station_per_band(const stems *s, const stems_station *st)
{
    uint32_t strip = 1;
    for (uint32_t c = st->first; c <= st->last; ++c) {
        uint32_t node = s->chain[c], main = xyl__stems_main_child(s, node);
        for (uint32_t j = s->child_start[node]; j < s->child_start[node + 1]; ++j)
            if (s->child_list[j] != main) {
                uint32_t w = xyl__stems_strip(xyl__stems_lateral_sides(s, s->child_list[j]));
                strip = w > strip ? w : strip;
            }
    }
    return s->k / strip;
}

/* The unit direction a fraction f of the way from unit a to unit b (normalised lerp); a and b
 * themselves at the ends, and where they agree. */
static xyl__dvec3 blend(xyl__dvec3 a, xyl__dvec3 b, double f)
{
    if (f <= 0.0 || (a.x == b.x && a.y == b.y && a.z == b.z)) return a;
    if (f >= 1.0) return b;
    xyl__dvec3 m = xyl__d3_add(xyl__d3_scale(a, 1.0 - f), xyl__d3_scale(b, f));
    return xyl__d3_normalize_or(m, b);
}

/* The spacing of `count` rings that turn in even steps through a half bend of sine sin_half on
 * a segment seg long, from spacing d: neighbouring rings are a step apart in angle and cross
 * each other unless spaced by at least rr sin(step) (64 thin laterals on a bend: 1e-4 apart,
 * steps of 2 degrees on a ring 0.1 wide), so they take that spacing where the segment has the
 * room (0.45 of it over the rings). */
static double turned_spacing(double d, double rr, double sin_half, size_t count, double seg)
{
    if (!count || !(seg > 0.0)) return d;
    double step = asin(fmin(sin_half, 1.0)) / (double)count;
    return fmin(fmax(d, rr * sin(step)), fmax(d, 0.45 * seg / (double)count));
}

/* Rings at a fork: `behind` rings before the node, its own ring, `ahead` rings after, spaced by
 * delta, so the bands between them offer patches to the lateral children. */
xyl_result xyl__stems_fork_rings(stems *s, size_t i, xyl__dvec3 t_in, xyl__dvec3 t,
                                 xyl__dvec3 t_out, size_t laterals)
{
    const stems_station *st = &s->stations[i];
    size_t want = xyl__stems_fork_extra_rings(station_per_band(s, st), laterals);
    double seg_in = i ? xyl__d3_len(xyl__d3_sub(st->p, s->stations[i - 1].p)) : 0.0;
    double seg_out = i + 1 < s->nstations ? xyl__d3_len(xyl__d3_sub(s->stations[i + 1].p, st->p)) : 0.0;
    /* without a segment of any length on either side (coordinates so large that the station
     * after it rounds onto it), the laterals still need their bands: all go ahead */
    size_t behind = seg_in > 0.0 ? (seg_out > 0.0 ? want / 2 : want) : 0;
    size_t ahead = want - behind;
    double lat_r = 0.0;
    for (uint32_t c = st->first; c <= st->last; ++c) {
        uint32_t node = s->chain[c];
        for (uint32_t j = s->child_start[node]; j < s->child_start[node + 1]; ++j)
            if (s->sk->nodes[s->child_list[j]].radius > lat_r) lat_r = s->sk->nodes[s->child_list[j]].radius;
    }
    double d_in = behind ? fmin(lat_r, 0.45 * seg_in / (double)behind) : 0.0;
    double d_out = !ahead ? 0.0 : seg_out > 0.0 ? fmin(lat_r, 0.45 * seg_out / (double)ahead) : lat_r;
    xyl_result r = XYL_OK;
    /* a ring delta from the node ring whose plane is turned by the half bend against the node
     * ring's crosses it on the inside of the bend when delta < r sin(half bend); the rings on
     * that side then turn from t_in to t_out in even steps instead */
    double rr = 1.05 * st->r * s->inflate;
    double sin_in = xyl__d3_len(xyl__d3_cross(t_in, t)), sin_out = xyl__d3_len(xyl__d3_cross(t, t_out));
    bool turn_in = d_in < rr * sin_in;
    bool turn_out = d_out < rr * sin_out;
    if (turn_in) d_in = turned_spacing(d_in, rr, sin_in, behind, seg_in);
    if (turn_out) d_out = turned_spacing(d_out, rr, sin_out, ahead, seg_out);
    for (size_t m = behind; m >= 1 && !r; --m) {
        xyl__dvec3 tm = turn_in ? blend(t_in, t, (double)(behind - m) / (double)behind) : t_in;
        xyl__dvec3 c = xyl__d3_sub(st->p, xyl__d3_scale(t_in, d_in * (double)m));
        r = xyl__stems_add_ring(s, c, tm, st->r);
    }
    if (!r) r = xyl__stems_add_ring(s, st->p, t, st->r);
    for (size_t m = 1; m <= ahead && !r; ++m) {
        xyl__dvec3 tm = turn_out ? blend(t, t_out, (double)m / (double)ahead) : t_out;
        xyl__dvec3 c = xyl__d3_add(st->p, xyl__d3_scale(t_out, d_out * (double)m));
        r = xyl__stems_add_ring(s, c, tm, st->r);
    }
    return r;
}

/* ---- patches and bridges ------------------------------------------------------------------- */

/* The quads of band b, columns c .. c + strip - 1 (mod k). */
static uint32_t strip_quad(const stems *s, uint32_t band, uint32_t c, uint32_t j)
{
    uint32_t col = c + j; /* c, j < k: a subtraction instead of a division by a run-time k */
    return band + (col < s->k ? col : col - s->k);
}

static bool strip_free(const stems *s, uint32_t band, uint32_t c, uint32_t strip)
{
    for (uint32_t j = 0; j < strip; ++j)
        if (s->taken[strip_quad(s, band, c, j)]) return false;
    return true;
}

static xyl__dvec3 strip_normal(const stems *s, uint32_t band, uint32_t c, uint32_t strip)
{
    xyl__dvec3 n = xyl__d3(0, 0, 0);
    for (uint32_t j = 0; j < strip; ++j) {
        const uint32_t *q = s->quads + 4 * strip_quad(s, band, c, j);
        xyl__dvec3 a = xyl__from_f3(s->pos[q[0]]), b = xyl__from_f3(s->pos[q[1]]);
        xyl__dvec3 cc = xyl__from_f3(s->pos[q[2]]), d = xyl__from_f3(s->pos[q[3]]);
        n = xyl__d3_add(n, xyl__d3_cross(xyl__d3_sub(cc, a), xyl__d3_sub(d, b)));
    }
    return xyl__d3_normalize_or(n, xyl__d3(0, 1, 0));
}

/* The strip's outline, counter-clockwise seen from outside: ring a's vertices c .. c + strip,
 * then ring b's back from c + strip to c (rings of the parent's k sides). */
static void strip_loop(const stems *s, uint32_t ring_a, uint32_t ring_b, uint32_t c,
                       uint32_t strip, uint32_t *loop)
{
    uint32_t n = 0;
    for (uint32_t j = 0; j <= strip; ++j) loop[n++] = ring_a + (c + j) % s->k;
    for (uint32_t j = strip + 1; j-- > 0;) loop[n++] = ring_b + (c + j) % s->k;
}

typedef struct patch {
    uint32_t ring;   /* index into s->rings of the ring behind the band */
    uint32_t column;
    double score;
} patch;

static xyl__dvec3 strip_centre(const stems *s, uint32_t band, uint32_t c, uint32_t strip)
{
    xyl__dvec3 sum = xyl__d3(0, 0, 0);
    for (uint32_t j = 0; j < strip; ++j) {
        const uint32_t *q = s->quads + 4 * strip_quad(s, band, c, j);
        for (int v = 0; v < 4; ++v) sum = xyl__d3_add(sum, xyl__from_f3(s->pos[q[v]]));
    }
    return xyl__d3_scale(sum, 1.0 / (4.0 * strip));
}

/* Where a child's bridge from patch p goes: the patch outline, its centroid and normal, and the
 * child's first ring. */
typedef struct bridge_geom {
    uint32_t loop[66];
    xyl__dvec3 centroid, n;
    stems_ring ring;
} bridge_geom;

/* The strip is the child's (kc sides, its ring's), its quads the parent's (s->k sides). */
static void plan_bridge(const stems *s, patch p, uint32_t child, uint32_t kc, double parent_r,
                        bridge_geom *g)
{
    uint32_t strip = xyl__stems_strip(kc);
    const stems_ring *a = &s->rings[p.ring], *b = &s->rings[p.ring + 1];
    strip_loop(s, a->first, b->first, p.column, strip, g->loop);
    xyl__dvec3 n = strip_normal(s, a->band, p.column, strip), centroid = xyl__d3(0, 0, 0);
    for (uint32_t j = 0; j < kc; ++j) centroid = xyl__d3_add(centroid, xyl__from_f3(s->pos[g->loop[j]]));
    centroid = xyl__d3_scale(centroid, 1.0 / (double)kc);
    /* the bridge ring must fit inside its patch, or neighbouring bridges overlap; the child's
     * tube widens to its own radius over its first segment */
    double height = xyl__d3_len(xyl__d3_sub(b->centre, a->centre));
    double width = 2.0 * parent_r * sin(XYL__PI * (double)strip / (double)s->k);
    double r = fmin(s->sk->nodes[child].radius, 0.45 * fmin(height, width));
    /* a strip of several quads bulges out past its centroid (by 1 - cos(pi strip / k) of the
     * parent radius): the ring goes beyond the bulge, or the bridge folds back into the parent */
    double bulge = 0.0;
    for (uint32_t j = 0; j < 2 * strip + 2; ++j)
        bulge = fmax(bulge, xyl__d3_dot(xyl__d3_sub(xyl__from_f3(s->pos[g->loop[j]]), centroid), n));
    /* a quarter of the parent's radius keeps the bridge from lying flat on a thick parent,
     * but not past the child's first node: that must stay a station, r ahead of the ring */
    double room = xyl__d3_dot(xyl__d3_sub(xyl__stems_node_pos(s, child), centroid), n) - 2.0 * r;
    double h = fmax(fmin(fmax(r, 0.25 * parent_r), room), bulge + r);
    stems_ring *ring = &g->ring;
    memset(ring, 0, sizeof *ring);
    ring->centre = xyl__d3_add(centroid, xyl__d3_scale(n, h));
    ring->tangent = n;
    xyl__dvec3 to0 = xyl__d3_sub(xyl__from_f3(s->pos[g->loop[0]]), centroid);
    to0 = xyl__d3_sub(to0, xyl__d3_scale(n, xyl__d3_dot(to0, n)));
    if (!xyl__d3_normalize_ok(to0, &ring->u)) ring->u = xyl__d3_any_orthogonal(n);
    ring->radius = r;
    ring->band = UINT32_MAX;
    g->centroid = centroid;
    g->n = n;
}

/* The first segment of child's tube if it bridges from patch p: from its bridge ring to its
 * first station as make_stations will place it. *reaches: that station is one of the child's
 * nodes, not a stub in front of the ring (every node behind it). */
static xyl__stems_cone first_cone(const stems *s, patch p, uint32_t child, uint32_t kc,
                                  double parent_r, bool *reaches)
{
    bridge_geom g;
    plan_bridge(s, p, child, kc, parent_r, &g);
    const stems_ring *ring = &g.ring;
    xyl__stems_cone c = {ring->centre, xyl__d3_add(ring->centre, xyl__d3_scale(ring->tangent, 2 * ring->radius)),
                         ring->radius, ring->radius};
    *reaches = false;
    for (uint32_t n = child; n != UINT32_MAX; n = xyl__stems_main_child(s, n)) {
        xyl__dvec3 q = xyl__stems_node_pos(s, n);
        c.r1 = s->sk->nodes[n].radius;
        if (xyl__d3_dot(xyl__d3_sub(q, ring->centre), ring->tangent) >= ring->radius) {
            c.p1 = q;
            *reaches = true;
            break;
        }
    }
    return c;
}

static bool clashes(const stems *s, const xyl__stems_cone *c)
{
    for (size_t i = 0; i < s->ncones; ++i)
        if (xyl__cones_clash(c, &s->cones[i])) return true;
    return false;
}

/* Best free patch for direction d among the bands between rings lo .. hi: the one facing d
 * most, and lying in direction d from the fork node (so a child leaning forward takes a band
 * ahead of the node, one leaning back a band behind), among those whose first segment does not
 * run into a sibling's placed before (s->cones). Such a patch must still face the child and
 * reach its nodes, or the child would become a stub on the wrong side; if there is none, the
 * best of all. */
static patch choose_patch(const stems *s, size_t lo, size_t hi, xyl__dvec3 node, xyl__dvec3 d,
                          uint32_t child, uint32_t kc, double parent_r)
{
    uint32_t strip = xyl__stems_strip(kc);
    patch best = {UINT32_MAX, 0, -4.0}, fallback = best;
    for (size_t r = lo; r < hi; ++r) {
        uint32_t band = s->rings[r].band;
        for (uint32_t c = 0; c < s->k; ++c) {
            if (!strip_free(s, band, c, strip)) continue;
            double facing = xyl__d3_dot(strip_normal(s, band, c, strip), d);
            /* the second term is a dot of unit vectors, at most 1 (+ rounding): a patch that
             * cannot beat the best even so is skipped before its centre is normalised */
            if (facing + (1.0 + 1e-9) < best.score) continue;
            xyl__dvec3 to = xyl__d3_normalize_or(xyl__d3_sub(strip_centre(s, band, c, strip), node), d);
            patch p = {(uint32_t)r, c, facing + xyl__d3_dot(to, d)};
            if (p.score <= best.score) continue;
            if (s->ncones) {
                bool reaches;
                xyl__stems_cone cone = first_cone(s, p, child, kc, parent_r, &reaches);
                if (facing <= 0.0 || !reaches || clashes(s, &cone)) {
                    if (p.score > fallback.score) fallback = p;
                    continue;
                }
            }
            best = p;
        }
    }
    return best.ring != UINT32_MAX ? best : fallback;
}

/* Faces from the patch outline loop (n vertices, counter-clockwise from outside) to the child's
 * ring: k quads when n = k; for odd k the outline has k + 1 vertices and its last edge closes
 * with one triangle. Loop edges are used forwards, ring edges backwards, as in a tube band. */
static xyl_result bridge_faces(stems *s, const uint32_t *loop, uint32_t n, uint32_t ring,
                               uint32_t branch)
{
    uint32_t k = s->k;
    for (uint32_t j = 0; j + 1 < k; ++j)
        xyl__stems_put_quad(s, loop[j], loop[j + 1], ring + j + 1, ring + j, branch);
    if (n == k) {
        xyl__stems_put_quad(s, loop[k - 1], loop[0], ring, ring + k - 1, branch);
        return XYL_OK;
    }
    xyl__stems_put_quad(s, loop[k], loop[0], ring, ring + k - 1, branch);
    return xyl__stems_put_tri(s, loop[k - 1], loop[k], ring + k - 1, branch);
}

/* Ring vertex j goes where outline vertex j is, seen around the ring's axis: evenly spaced
 * ring vertices would drift against an outline that is not a regular polygon and twist the
 * bridge (with odd k the outline even has k + 1 vertices; with even k a patch on a bend is
 * skewed). A skewed outline can show two vertices in one direction, or out of order: the ring
 * then keeps its even spacing, as two ring vertices in one place would make a sliver and a
 * step backwards a fold. Steps of more than 1/200 of an even one count (s->align_cos). */
static void align_to_outline(stems *s, const stems_ring *ring, const uint32_t *loop,
                             xyl__dvec3 centroid, double r)
{
    xyl__dvec3 n = ring->tangent, dir[33];
    uint32_t k = s->k;
    for (uint32_t j = 0; j < k; ++j) {
        xyl__dvec3 d = xyl__d3_sub(xyl__from_f3(s->pos[loop[j]]), centroid);
        d = xyl__d3_sub(d, xyl__d3_scale(n, xyl__d3_dot(d, n)));
        if (!xyl__d3_normalize_ok(d, &dir[j])) return; /* keep the even spacing */
    }
    dir[k] = dir[0];
    /* every step, the closing one too, turns counter-clockwise (seen from +n) by more than the
     * smallest step and less than pi, and none after the first passes direction 0 again: the
     * outline goes round once, in order. Signs of cross and dot products, no angles. */
    for (uint32_t j = 0; j < k; ++j) {
        double sj = xyl__d3_dot(xyl__d3_cross(dir[j], dir[j + 1]), n);
        if (!(sj > 0.0 && xyl__d3_dot(dir[j], dir[j + 1]) < s->align_cos)) return;
        if (j && j + 1 < k && xyl__d3_dot(xyl__d3_cross(dir[j], dir[0]), n) > 0.0 &&
            xyl__d3_dot(xyl__d3_cross(dir[0], dir[j + 1]), n) >= 0.0)
            return;
    }
    double rr = r * s->inflate;
    for (uint32_t j = 0; j < k; ++j)
        s->pos[ring->first + j] = xyl__to_f3(xyl__d3_add(ring->centre, xyl__d3_scale(dir[j], rr)));
}

/* Replaces the patch by a bridge to a new ring of the child (kc sides) and queues the child's
 * branch. The ring, its alignment and the bridge faces are the child's: kc sides. */
static xyl_result bridge(stems *s, patch p, uint32_t child, uint32_t kc, double parent_r)
{
    uint32_t strip = xyl__stems_strip(kc), band = s->rings[p.ring].band, kp = s->k;
    uint32_t branch = s->sk->nodes[child].branch;
    bridge_geom g;
    plan_bridge(s, p, child, kc, parent_r, &g);
    for (uint32_t j = 0; j < strip; ++j) s->taken[strip_quad(s, band, p.column, j)] = 1;
    const uint32_t *loop = g.loop;
    xyl__dvec3 n = g.n, centroid = g.centroid;
    stems_ring ring = g.ring;
    double r = ring.radius;
    if (!xyl__stems_reserve(s, s->nv + kc, s->nq + kc)) return xyl__stems_oom(s);
    if (kc != kp) xyl__stems_set_sides(s, kc);
    ring.first = xyl__stems_put_ring(s, ring.centre, n, ring.u, r, 0.0, branch);
    align_to_outline(s, &ring, loop, centroid, r);
    xyl_result res = bridge_faces(s, loop, 2 * strip + 2, ring.first, branch);
    if (kc != kp) xyl__stems_set_sides(s, kp);
    if (res) return res;
    if (!xyl__grow(&s->alloc, (void **)&s->pending, &s->pcap, s->npending, s->npending + 1,
                   sizeof *s->pending))
        return xyl__stems_oom(s);
    stems_pending pend = {child, kc, ring};
    s->pending[s->npending++] = pend;
    return XYL_OK;
}

/* Direction in which a child leaves its fork node: towards its first node that is not at the
 * fork, else any direction across the parent. */
static xyl__dvec3 child_direction(const stems *s, uint32_t fork, uint32_t child,
                                  xyl__dvec3 parent_t)
{
    xyl__dvec3 f = xyl__stems_node_pos(s, fork), dir;
    for (uint32_t n = child; n != UINT32_MAX; n = xyl__stems_main_child(s, n)) {
        xyl__dvec3 d = xyl__d3_sub(xyl__stems_node_pos(s, n), f);
        if (xyl__d3_len(d) > 1e-6 * s->sk->nodes[fork].radius) {
            if (xyl__d3_normalize_ok(d, &dir)) return dir;
            break;
        }
    }
    return xyl__d3_any_orthogonal(parent_t); /* across the parent, only when needed */
}

/* taken[] covers every quad written so far; new entries start free. */
static xyl_result grow_taken(stems *s)
{
    size_t old = s->tcap;
    if (s->qcap <= old) return XYL_OK;
    if (!xyl__grow(&s->alloc, (void **)&s->taken, &s->tcap, old, s->qcap, 1))
        return xyl__stems_oom(s);
    memset(s->taken + old, 0, s->tcap - old);
    return XYL_OK;
}

/* Bridges lateral `child` of `node` (at station st) from the best patch among rings lo .. hi;
 * more: siblings follow, which test their first segments against this one's. */
static xyl_result attach_one(stems *s, const stems_station *st, uint32_t node, uint32_t child,
                             size_t lo, size_t hi, bool more)
{
    xyl__dvec3 d = child_direction(s, node, child, s->rings[lo].tangent);
    uint32_t kc = xyl__stems_lateral_sides(s, child);
    if (s->branch_sides && kc < s->branch_sides[s->sk->nodes[child].branch]) ++s->clamped;
    patch p = choose_patch(s, lo, hi, xyl__stems_node_pos(s, node), d, child, kc, st->r);
    if (p.ring == UINT32_MAX) /* fork_rings made twice the patches needed */
        return xyl__fail(s->diag, XYL_ERR_UNSUPPORTED, 0, 0, (int64_t)node,
                         "internal: no free patch left at node %u", node);
    if (more) {
        if (!xyl__grow(&s->alloc, (void **)&s->cones, &s->cone_cap, s->ncones, s->ncones + 1,
                       sizeof *s->cones))
            return xyl__stems_oom(s);
        bool reaches;
        s->cones[s->ncones++] = first_cone(s, p, child, kc, st->r, &reaches);
    }
    return bridge(s, p, child, kc, st->r);
}

/* Attaches every lateral child of station i to a patch among rings lo .. hi, thickest first
 * (xyl__lateral_before): a thin sibling then keeps clear of the thick one's first segment,
 * which has less room to move. */
xyl_result xyl__stems_attach_laterals(stems *s, size_t i, size_t lo, size_t hi)
{
    const stems_station *st = &s->stations[i];
    xyl_result r = grow_taken(s);
    if (r) return r;
    s->ncones = 0;
    size_t left = st->first == UINT32_MAX ? 0 : xyl__stems_lateral_count(s, st);
    for (uint32_t prev = UINT32_MAX; left && !r; --left) {
        uint32_t child = UINT32_MAX, at = 0; /* the next lateral after prev */
        for (uint32_t c = st->first; c <= st->last; ++c) {
            uint32_t node = s->chain[c], main = xyl__stems_main_child(s, node);
            for (uint32_t j = s->child_start[node]; j < s->child_start[node + 1]; ++j) {
                uint32_t x = s->child_list[j];
                if (x == main || (prev != UINT32_MAX && !xyl__lateral_before(s->sk, prev, x)))
                    continue;
                if (child == UINT32_MAX || xyl__lateral_before(s->sk, x, child)) child = x, at = node;
            }
        }
        r = attach_one(s, st, at, child, lo, hi, left > 1);
        prev = child;
    }
    return r;
}

/* ---- a lateral's first band ---------------------------------------------------------------- */

/* Whether the band from ring a (centre ca, unit tangent ta, radius ra) to ring b ahead of it
 * folds: a vertex of one lies on the wrong side of the other's plane. */
static bool band_folds(xyl__dvec3 ca, xyl__dvec3 ta, double ra, xyl__dvec3 cb, xyl__dvec3 tb,
                       double rb)
{
    double tilt = xyl__d3_len(xyl__d3_cross(ta, tb)); /* the sine of the angle between the planes */
    return xyl__d3_dot(xyl__d3_sub(cb, ca), ta) <= rb * tilt ||
           xyl__d3_dot(xyl__d3_sub(ca, cb), tb) >= -ra * tilt;
}

/* Whether the band from a ring (centre c, unit tangent t, radius r) to the ring of the first
 * station folds when the tube comes into that station along t_in (the station's ring is turned
 * halfway from t_in to the next segment, if there is one, as branch_rings turns it). */
static bool band_to_first_station_folds(const stems *s, xyl__dvec3 c, xyl__dvec3 t, double r,
                                        xyl__dvec3 t_in)
{
    const stems_station *st = s->stations;
    xyl__dvec3 t_out = s->nstations > 1 ? xyl__dir_between(st[0].p, st[1].p, t_in) : t_in;
    xyl__dvec3 t0 = xyl__d3_normalize_or(xyl__d3_add(t_in, t_out), t_in);
    double f = s->inflate;
    return band_folds(c, t, f * r, st[0].p, t0, f * st[0].r);
}

/* Whether a lateral's first band, from its bridge ring to its first station, folds. */
static bool first_band_folds(const stems *s, const stems_ring *bridge, xyl__dvec3 t_in)
{
    return band_to_first_station_folds(s, bridge->centre, bridge->tangent, bridge->radius, t_in);
}

/* The direction a lateral's tube comes into its first station along: the bridge ring's normal,
 * so that the first band's rings face each other. Where the bridge's patch faces away from the
 * child, the station's ring, turned halfway to the next segment, can cross the bridge ring; if
 * it does not with the direction from the bridge ring's centre to the station, that one. Not at
 * a station with laterals, where the ring's frame also places their patches. */
xyl__dvec3 xyl__stems_first_direction(const stems *s, const stems_ring *bridge)
{
    if (xyl__stems_lateral_count(s, &s->stations[0]) ||
        !first_band_folds(s, bridge, bridge->tangent))
        return bridge->tangent;
    xyl__dvec3 seg = xyl__dir_between(bridge->centre, s->stations[0].p, bridge->tangent);
    return first_band_folds(s, bridge, seg) ? bridge->tangent : seg;
}

/* A first station with laterals keeps the bridge ring's normal (first_direction). Where its
 * first band folds along it and the station lies far out to the side (its direction from the
 * bridge ring's centre more than acos 0.2, 78 degrees, off the normal), the band runs along the
 * bridge ring's plane to the station and crosses the bridges of the station's laterals. The
 * tube then goes out along the normal first, to a node-less station (an elbow) 0.4 of the
 * station's distance ahead of the ring and a quarter of the way from the ring's radius to the
 * station's, and turns there to the station; if either band folds then, or the elbow would take
 * the chain past its rings in ring_bound (its nodes plus one), there is none. */
xyl_result xyl__stems_add_elbow(stems *s, const stems_ring *bridge)
{
    const stems_station *st = s->stations;
    if (s->nstations > s->nchain || !xyl__stems_lateral_count(s, &st[0]) ||
        !first_band_folds(s, bridge, bridge->tangent))
        return XYL_OK;
    xyl__dvec3 c = bridge->centre, n = bridge->tangent, to_st = xyl__d3_sub(st[0].p, c);
    double ahead = xyl__d3_dot(to_st, n);
    if (ahead > 0.2 * xyl__d3_len(to_st)) return XYL_OK;
    double f = s->inflate, rb = bridge->radius, re = 0.75 * rb + 0.25 * st[0].r;
    xyl__dvec3 e = xyl__d3_add(c, xyl__d3_scale(n, 0.4 * ahead));
    xyl__dvec3 to = xyl__dir_between(e, st[0].p, n);
    xyl__dvec3 te = xyl__d3_normalize_or(xyl__d3_add(n, to), to);
    if (band_folds(c, n, f * rb, e, te, f * re) || band_to_first_station_folds(s, e, te, re, to))
        return XYL_OK;
    if (!xyl__grow(&s->alloc, (void **)&s->stations, &s->scap, s->nstations, s->nstations + 1,
                   sizeof *s->stations))
        return xyl__stems_oom(s);
    memmove(s->stations + 1, s->stations, s->nstations * sizeof *s->stations);
    stems_station elbow = {e, re, UINT32_MAX, 0};
    s->stations[0] = elbow;
    s->nstations++;
    return XYL_OK;
}

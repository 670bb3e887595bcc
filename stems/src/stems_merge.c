/* Lateral placement: which skeleton nodes are meshed, and from which node each lateral grows. */

/* Which skeleton nodes are meshed, and from where (docs/stems.md, "Laterals inside their
 * parent", "Overlapping siblings").
 *
 * A lateral that starts inside its parent's tube cannot leave it where it forks: its first
 * ring would lie in the parent's surface, or its first segment run along inside it. Its nodes
 * are hidden (not meshed) while they lie in the parent's tube or in a tube placed before it at
 * its fork (a thicker sibling's, or the meshed part of a chain the fork itself is hidden in),
 * and its first clear node grows out of the node of the tube it left nearest to where it comes
 * from. Laterals of hidden nodes are placed in turn, from the meshed node their fork is hidden
 * at. Where the lateral's chain runs into those tubes again further on, it is cut there the
 * same way. A lateral that never clears is not meshed at all: its axis stays within
 * (r_tube + r_own) of the tube's, which covers all of it but a rim thinner than its diameter.
 *
 * Laterals that come to hang from one node this way are siblings again, and are merged as
 * siblings are: the thinner one (of equal ones, the later in node order) into the thicker, if
 * they overlap where it leaves its parent, or if its first segment is still inside the
 * thicker one halfway along. Its nodes up to the first one that clears the thicker sibling's
 * tube are not meshed, and the rest of it grows out of the thicker sibling, from that
 * sibling's node nearest to where they part. A lateral that, where it now hangs, lies in its
 * fork's own tube all along is not meshed either. */
#include "stems_internal.h"

/* Whether a ball at p of radius r overlaps the tube from a (radius ra) to b (radius rb), as the
 * mesher's rings taper it: p is within r of the axis' nearest point plus the radius there. */
static bool ball_meets_cone(xyl__dvec3 p, double r, xyl__dvec3 a, double ra, xyl__dvec3 b,
                            double rb)
{
    xyl__dvec3 ab = xyl__d3_sub(b, a), ap = xyl__d3_sub(p, a);
    double l2 = xyl__d3_dot(ab, ab), t = l2 > XYL__EPS_NORMALIZE ? xyl__d3_dot(ap, ab) / l2 : 0.0;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    xyl__dvec3 e = xyl__d3_sub(ap, xyl__d3_scale(ab, t));
    double reach = r + ra + (rb - ra) * t; /* > 0: radii are */
    return xyl__d3_dot(e, e) < reach * reach;
}

static xyl__dvec3 pos_of(const stems *s, uint32_t n)
{
    return xyl__from_f3(s->sk->nodes[n].pos);
}

static double distance_to(const stems *s, uint32_t n, xyl__dvec3 p)
{
    return xyl__d3_len(xyl__d3_sub(pos_of(s, n), p));
}

/* Whether a ball at p of radius r misses the bounding box of the tubes from node n to its
 * chain's tip (s->tails, 6 per node: low and high corner), so no segment there can overlap it. */
static bool misses_tail(const stems *s, xyl__dvec3 p, double r, uint32_t n)
{
    const double *b = s->tails + 6 * (size_t)n;
    double q[3] = {p.x, p.y, p.z}, d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        double below = b[k] - q[k], above = q[k] - b[k + 3];
        double d = below > 0.0 ? below : above > 0.0 ? above : 0.0;
        d2 += d * d;
    }
    return d2 >= r * r;
}

/* Whether a ball at p of radius r overlaps the tube of the chain that leaves fork through its
 * child `host`: first_r at the fork, each node's own radius after it. Each segment's tail
 * box is tried first: near a fork only a few segments of a long chain need the exact
 * test. */
static bool overlaps_chain(const stems *s, xyl__dvec3 p, double r, uint32_t fork, uint32_t host,
                           double first_r)
{
    const xyl_skel_node *nodes = s->sk->nodes;
    double ra = first_r;
    for (uint32_t a = fork, b = host; b != UINT32_MAX; a = b, b = s->main[b]) {
        if (a != fork && misses_tail(s, p, r, a)) return false;
        if (ball_meets_cone(p, r, pos_of(s, a), ra, pos_of(s, b), nodes[b].radius)) return true;
        ra = nodes[b].radius;
    }
    return false;
}

/* The tail boxes of every node (s->tails): from the tips down, each node's ball's box merged
 * with its main child's. A segment's tube, tapered between its nodes' balls, is their convex
 * hull, so it lies in any box holding both; ball_meets_cone tests balls along the axis inside
 * that hull, so a ball that misses the box misses them. (Boxes: a merge is six minima and
 * maxima where a bounding sphere took a square root and a division, a chain of them along each
 * branch.) */
void xyl__stems_tail_boxes(const stems *s, double *tails)
{
    const xyl_skel_node *nodes = s->sk->nodes;
    for (size_t i = s->sk->node_count; i-- > 0;) {
        xyl__dvec3 c = pos_of(s, (uint32_t)i);
        double r = nodes[i].radius, *t = tails + 6 * i;
        /* a little larger: rounding must not shrink it below what it has to hold */
        double pad = r * (1.0 + 1e-12) + 1e-12 * (fabs(c.x) + fabs(c.y) + fabs(c.z)) + 1e-300;
        t[0] = c.x - pad, t[1] = c.y - pad, t[2] = c.z - pad;
        t[3] = c.x + pad, t[4] = c.y + pad, t[5] = c.z + pad;
        uint32_t m = s->main[i];
        if (m != UINT32_MAX) {
            const double *b = tails + 6 * (size_t)m;
            for (int k = 0; k < 3; ++k) {
                t[k] = b[k] < t[k] ? b[k] : t[k];
                t[k + 3] = b[k + 3] > t[k + 3] ? b[k + 3] : t[k + 3];
            }
        }
    }
}

/* A sibling's tube starts at its own radius: the fork node's is the parent's. */
static bool overlaps_sibling(const stems *s, xyl__dvec3 p, double r, uint32_t fork, uint32_t host)
{
    return overlaps_chain(s, p, r, fork, host, s->sk->nodes[host].radius);
}

static bool has_laterals(const stems *s, uint32_t n)
{
    return s->child_start[n + 1] - s->child_start[n] > (uint32_t)(s->main[n] != UINT32_MAX);
}

/* The node of host's chain nearest to p. */
static uint32_t nearest_on_chain(const stems *s, xyl__dvec3 p, uint32_t host)
{
    uint32_t best = host;
    double best_d = INFINITY;
    for (uint32_t n = host; n != UINT32_MAX; n = s->main[n]) {
        double d = distance_to(s, n, p);
        if (d < best_d) best_d = d, best = n;
    }
    return best;
}

/* Whether a ball at p of radius r overlaps the tube of fork's own branch next to the fork: the
 * segment into the fork (from its parent as meshed, parent_of) and the chain that continues it. */
static bool overlaps_parent(const stems *s, const int32_t *parent_of, xyl__dvec3 p, double r,
                            uint32_t fork)
{
    const xyl_skel_node *nodes = s->sk->nodes;
    int32_t before = parent_of[fork];
    /* on one branch, the tail box of the node before holds all of it */
    if (before >= 0 && s->main[before] == fork && misses_tail(s, p, r, (uint32_t)before))
        return false;
    if (before < 0 && misses_tail(s, p, r, fork)) return false;
    if (before >= 0 && ball_meets_cone(p, r, pos_of(s, (uint32_t)before), nodes[before].radius,
                                       pos_of(s, fork), nodes[fork].radius))
        return true;
    uint32_t main = s->main[fork];
    return main != UINT32_MAX && overlaps_chain(s, p, r, fork, main, nodes[fork].radius);
}

/* Merges lateral `child` of fork into sibling `host` if they overlap where the child leaves
 * its parent's tube (inside it, the parent's rules place the child's first ring), or if the
 * child's first segment is still inside the sibling's tube halfway along: the patches of one
 * fork part two tubes by about a radius, not along a whole segment. The child's nodes up to its
 * first one that clears host (or has children of its own, which need its branch) are not
 * meshed, and that one hangs from host's nearest node. Returns whether it merged. */
static bool merge_into(const stems *s, uint32_t fork, uint32_t host, uint32_t child,
                       int32_t *parent_of)
{
    const xyl_skel_node *nodes = s->sk->nodes;
    uint32_t last = UINT32_MAX, n = child;
    for (; n != UINT32_MAX && overlaps_parent(s, parent_of, pos_of(s, n), nodes[n].radius, fork);
         last = n, n = s->main[n])
        if (has_laterals(s, n)) return false;
    if (n == UINT32_MAX) return false;
    xyl__dvec3 half = xyl__d3_scale(xyl__d3_add(pos_of(s, fork), pos_of(s, n)), 0.5);
    if (n == child && overlaps_sibling(s, half, nodes[n].radius, fork, host) &&
        !overlaps_sibling(s, pos_of(s, n), nodes[n].radius, fork, host)) {
        /* clear of host at its first node: all of it hangs from host's node nearest to it if
         * that is nearer than the fork, but not from host's tip, which has no segment ahead to
         * fork from */
        xyl__dvec3 p = pos_of(s, child);
        uint32_t at = nearest_on_chain(s, p, host);
        if (distance_to(s, at, p) >= distance_to(s, fork, p)) return false;
        parent_of[child] = s->main[at] != UINT32_MAX ? (int32_t)at : -1;
        return true;
    }
    if (!overlaps_sibling(s, pos_of(s, n), nodes[n].radius, fork, host)) return false;
    for (; n != UINT32_MAX; last = n, n = s->main[n]) {
        if (has_laterals(s, n)) break;
        if (!overlaps_sibling(s, pos_of(s, n), nodes[n].radius, fork, host)) break;
    }
    if (last == UINT32_MAX) return false; /* the first node has children */
    parent_of[child] = -1;
    if (n != UINT32_MAX) parent_of[n] = (int32_t)nearest_on_chain(s, pos_of(s, last), host);
    return true;
}

/* Whether every node of lateral `child` of fork lies in the tube of fork's branch around it: the
 * placement moved it here from a tube it cleared, but it has not cleared this one. */
static bool inside_parent_throughout(const stems *s, const int32_t *parent_of, uint32_t fork,
                                     uint32_t child)
{
    for (uint32_t n = child; n != UINT32_MAX; n = s->main[n])
        if (has_laterals(s, n) ||
            !overlaps_parent(s, parent_of, pos_of(s, n), s->sk->nodes[n].radius, fork))
            return false;
    return true;
}

/* Whether lateral a of node p comes before lateral b: its own laterals (children of p in the
 * skeleton) before those that came to hang from it, then xyl__lateral_before. A lateral that
 * was moved here so gives way to one that forks here. */
static bool before(const stems *s, uint32_t p, uint32_t a, uint32_t b)
{
    bool own_a = s->sk->nodes[a].parent == (int32_t)p, own_b = s->sk->nodes[b].parent == (int32_t)p;
    return own_a != own_b ? own_a : xyl__lateral_before(s->sk, a, b);
}

/* The lateral of node p that comes next after prev in `before` order (the first one after
 * UINT32_MAX), or UINT32_MAX. */
static uint32_t next_lateral(const stems *s, uint32_t p, uint32_t prev)
{
    uint32_t child = UINT32_MAX, main = s->main[p];
    for (uint32_t j = s->child_start[p]; j < s->child_start[p + 1]; ++j) {
        uint32_t c = s->child_list[j];
        if (c != main && (prev == UINT32_MAX || before(s, p, prev, c)) &&
            (child == UINT32_MAX || before(s, p, c, child)))
            child = c;
    }
    return child;
}

/* The laterals of fork in `before` order, each tried against those before it that are still
 * meshed from the fork: so a host is never merged away after a thinner sibling joined it. A
 * lateral the placement moved here that lies in fork's own tube all along is not meshed at all
 * (one it did not move left that tube at once, or would have been hidden). */
static bool merge_at(const stems *s, uint32_t fork, int32_t *parent_of)
{
    uint32_t lo = s->child_start[fork], hi = s->child_start[fork + 1], main = s->main[fork];
    bool any = false;
    for (uint32_t child = next_lateral(s, fork, UINT32_MAX); child != UINT32_MAX;
         child = next_lateral(s, fork, child)) {
        bool moved_here = parent_of[child] != s->sk->nodes[child].parent;
        if (moved_here && inside_parent_throughout(s, parent_of, fork, child)) {
            parent_of[child] = -1;
            any = true;
            continue;
        }
        for (uint32_t i = lo; i < hi; ++i) {
            uint32_t host = s->child_list[i];
            if (host == main || !before(s, fork, host, child)) continue;
            if (parent_of[host] != (int32_t)fork) continue; /* merged itself */
            if (merge_into(s, fork, host, child, parent_of)) {
                any = true;
                break;
            }
        }
    }
    return any;
}

/* Whether a lateral of fork is one the placement moved there (merge_at's only case for a fork
 * without siblings). */
static bool has_moved_lateral(const stems *s, uint32_t fork, const int32_t *parent_of)
{
    for (uint32_t j = s->child_start[fork]; j < s->child_start[fork + 1]; ++j) {
        uint32_t c = s->child_list[j];
        if (c != s->main[fork] && parent_of[c] != s->sk->nodes[c].parent) return true;
    }
    return false;
}

bool xyl__stems_merge_siblings(const stems *s, int32_t *parent_of)
{
    size_t n = s->sk->node_count;
    bool any = false;
    for (uint32_t f = 0; f < n; ++f) {
        uint32_t laterals = s->child_start[f + 1] - s->child_start[f] - (s->main[f] != UINT32_MAX);
        if ((laterals >= 2 || (laterals == 1 && has_moved_lateral(s, f, parent_of))) &&
            merge_at(s, f, parent_of))
            any = true;
    }
    return any;
}

/* ---- laterals inside their parent -------------------------------------------------------- */

/* The node of fork's branch, as meshed around it, nearest to p: fork's parent if it is on the
 * same branch, fork, and the chain after it. */
static uint32_t nearest_on_branch(const stems *s, const int32_t *parent_of, xyl__dvec3 p,
                                  uint32_t fork)
{
    uint32_t best = nearest_on_chain(s, p, fork);
    int32_t before = parent_of[fork];
    if (before >= 0 && s->sk->nodes[before].branch == s->sk->nodes[fork].branch &&
        distance_to(s, (uint32_t)before, p) < distance_to(s, best, p))
        best = (uint32_t)before;
    return best;
}

/* Whether a ball at p of radius r overlaps one of the tubes placed before it around its fork:
 * the tube from a chain's parent as meshed through its meshed nodes (placed: the chains' first
 * nodes), at the chain's own radius from the start (the fork node's is the parent's). Returns
 * that first node, or UINT32_MAX. */
static uint32_t overlapping_placed(const stems *s, const int32_t *parent_of, xyl__dvec3 p,
                                   double r, const uint32_t *placed, size_t nplaced)
{
    for (size_t j = 0; j < nplaced; ++j) {
        uint32_t c = placed[j];
        if (overlaps_chain(s, p, r, (uint32_t)parent_of[c], c, s->sk->nodes[c].radius)) return c;
    }
    return UINT32_MAX;
}

/* Per node: hidden ones record where their chain forks off (link: the parent of the chain's
 * first node), the chain's first meshed node (owner, or UINT32_MAX if it has none) and the tube
 * they lie in (tube: a placed chain's first node, or UINT32_MAX for the parent's branch);
 * visible ones have link UINT32_MAX. placed: scratch. */
typedef struct placing {
    int32_t *parent_of;
    uint32_t *link, *owner, *tube, *placed;
    size_t nplaced;
} placing;

/* Whether node x lies in the parent's tube around fork h or in one placed before it; *tube: the
 * placed chain's first node, or UINT32_MAX for the parent's. */
static bool inside(const stems *s, const placing *pl, uint32_t x, uint32_t h, uint32_t *tube)
{
    xyl__dvec3 q = pos_of(s, x);
    double r = s->sk->nodes[x].radius;
    *tube = UINT32_MAX;
    if (overlaps_parent(s, pl->parent_of, q, r, h)) return true;
    *tube = overlapping_placed(s, pl->parent_of, q, r, pl->placed, pl->nplaced);
    return *tube != UINT32_MAX;
}

/* Hides the nodes of a chain of fork p (placed at h) from x on while they lie inside a tube,
 * and `extra` clear nodes more (checked joints: the lateral starts later, from the parent's
 * tube), recording each one's tube; *last and *in become the last hidden node and its tube
 * (unchanged if none is hidden), *clear the first node clear of every tube (UINT32_MAX if
 * none). Returns the first node that is meshed, or UINT32_MAX. */
static uint32_t hide_run(const stems *s, placing *pl, uint32_t x, uint32_t p, uint32_t h,
                         uint32_t *last, uint32_t *in, uint32_t extra, uint32_t *clear)
{
    uint32_t first = x, t;
    *clear = UINT32_MAX;
    for (; x != UINT32_MAX; x = s->main[x]) {
        if (!inside(s, pl, x, h, &t)) {
            if (*clear == UINT32_MAX) *clear = x;
            if (!extra) break;
            --extra, t = UINT32_MAX;
        }
        *last = x, *in = t, pl->tube[x] = t;
    }
    for (uint32_t y = first; y != x; y = s->main[y]) pl->link[y] = p, pl->owner[y] = x;
    return x;
}

/* Hangs the first clear node c of a hidden run from the node of the tube it left (in: a placed
 * chain, or the parent's branch at h) nearest to where it comes from (last). */
static void hang(const stems *s, placing *pl, uint32_t c, uint32_t last, uint32_t in, uint32_t h)
{
    xyl__dvec3 from = pos_of(s, last);
    uint32_t at = in != UINT32_MAX ? nearest_on_chain(s, from, in)
                                   : nearest_on_branch(s, pl->parent_of, from, h);
    /* a placed chain's tube starts at the node it hangs from: that one may be nearer */
    if (in != UINT32_MAX) {
        uint32_t up = (uint32_t)pl->parent_of[in];
        if (distance_to(s, up, from) < distance_to(s, at, from)) at = up;
    }
    pl->parent_of[c] = (int32_t)at;
}

/* What checked joints cost lateral branch b, whose first clear node is `clear` and whose first
 * meshed node is c (UINT32_MAX: none): how far along its own skeleton it now starts later, or
 * that it is hidden whole. */
static void record_shift(const stems *s, uint32_t b, uint32_t clear, uint32_t c)
{
    double d = 0.0;
    for (uint32_t x = clear; x != c && s->main[x] != UINT32_MAX; x = s->main[x])
        d += xyl__d3_len(xyl__d3_sub(pos_of(s, s->main[x]), pos_of(s, x)));
    s->shift[b] = d;
    s->hidden[b] = c == UINT32_MAX;
}

/* Places lateral i of node p at fork h (p itself, or the meshed node p is hidden at): hides its
 * nodes while they lie in the parent's tube or one placed before it, and hangs the first clear
 * one from the nearest node of the tube it left. Returns whether i moved. */
static bool place_lateral(const stems *s, uint32_t i, uint32_t p, uint32_t h, placing *pl)
{
    /* where it comes from: its fork, in the tube the fork is hidden in if it is */
    uint32_t last = p, in = pl->link[p] != UINT32_MAX ? pl->tube[p] : UINT32_MAX;
    /* checked joints (stems_joints.c) may have asked this lateral to start later */
    const uint32_t branch = s->sk->nodes[i].branch;
    uint32_t extra = s->drop ? s->drop[branch] : 0, clear;
    uint32_t c = hide_run(s, pl, i, p, h, &last, &in, extra, &clear);
    if (extra && s->shift && clear != UINT32_MAX) record_shift(s, branch, clear, c);
    if (c != UINT32_MAX) pl->placed[pl->nplaced++] = c;
    if (c == i && h == p) return false; /* leaves its parent at once */
    if (c != i) pl->parent_of[i] = -1;
    if (c != UINT32_MAX) hang(s, pl, c, last, in, h);
    return true; /* a lateral that never clears is not meshed */
}

/* Where a lateral's meshed chain (from its first meshed node c) runs into its parent's tube or
 * a tube placed before it again, away from its joint, it is cut: the nodes inside are hidden
 * and the rest grows out of that tube where it leaves it, as its start does. */
static bool cut_crossings(const stems *s, uint32_t c, uint32_t p, uint32_t h, placing *pl)
{
    bool any = false;
    for (uint32_t x = s->main[c], t; x != UINT32_MAX; x = s->main[x]) {
        if (!inside(s, pl, x, h, &t)) continue;
        uint32_t first = x, last = x, in = t;
        uint32_t clear;
        x = hide_run(s, pl, x, p, h, &last, &in, 0, &clear);
        pl->parent_of[first] = -1;
        any = true;
        if (x == UINT32_MAX) break;
        hang(s, pl, x, last, in, h);
    }
    return any;
}

/* The laterals of p in `before` order, so that a sibling is only ever hidden in a thicker one
 * (or an equal one earlier in node order). If p is hidden, its laterals grow out of the meshed
 * node it is hidden at and keep clear of the meshed parts of the chains p is hidden in. */
static bool place_laterals_of(const stems *s, uint32_t p, placing *pl)
{
    uint32_t h = p;
    pl->nplaced = 0;
    for (; pl->link[h] != UINT32_MAX; h = pl->link[h])
        if (pl->owner[h] != UINT32_MAX) pl->placed[pl->nplaced++] = pl->owner[h];
    bool any = false;
    for (uint32_t prev = UINT32_MAX;;) {
        uint32_t child = next_lateral(s, p, prev);
        if (child == UINT32_MAX) return any;
        size_t placed = pl->nplaced;
        if (place_lateral(s, child, p, h, pl)) any = true;
        if (pl->nplaced > placed) { /* meshed: its crossings, against the tubes before it */
            uint32_t c = pl->placed[--pl->nplaced];
            if (cut_crossings(s, c, p, h, pl)) any = true;
            pl->placed[pl->nplaced++] = c;
        }
        prev = child;
    }
}

bool xyl__stems_place_laterals(const stems *s, int32_t *parent_of, uint32_t *scratch)
{
    const xyl_skel_node *nodes = s->sk->nodes;
    uint32_t n = (uint32_t)s->sk->node_count;
    placing pl = {parent_of, scratch, scratch + n, scratch + 2 * (size_t)n,
                  scratch + 3 * (size_t)n, 0};
    bool any = false;
    for (uint32_t i = 0; i < n; ++i) parent_of[i] = nodes[i].parent, pl.link[i] = UINT32_MAX;
    /* node order: a node's parent, and so where it is meshed, is settled before its laterals */
    for (uint32_t p = 0; p < n; ++p) {
        uint32_t children = s->child_start[p + 1] - s->child_start[p];
        if (children > (uint32_t)(s->main[p] != UINT32_MAX) && place_laterals_of(s, p, &pl))
            any = true;
    }
    return any;
}

/* Closest points of segments p0-p1 and q0-q1 as parameters *s, *t in [0, 1] (Ericson 2005,
 * "Real-Time Collision Detection", 5.1.9). */
void xyl__closest_params(xyl__dvec3 p0, xyl__dvec3 p1, xyl__dvec3 q0, xyl__dvec3 q1, double *s,
                         double *t)
{
    xyl__dvec3 d1 = xyl__d3_sub(p1, p0), d2 = xyl__d3_sub(q1, q0), r = xyl__d3_sub(p0, q0);
    double a = xyl__d3_dot(d1, d1), e = xyl__d3_dot(d2, d2), f = xyl__d3_dot(d2, r);
    const double eps = XYL__EPS_NORMALIZE;
    if (a <= eps) {
        *s = 0.0;
        *t = e <= eps ? 0.0 : fmin(1.0, fmax(0.0, f / e));
        return;
    }
    double c = xyl__d3_dot(d1, r);
    if (e <= eps) {
        *t = 0.0;
        *s = fmin(1.0, fmax(0.0, -c / a));
        return;
    }
    double b = xyl__d3_dot(d1, d2), denom = a * e - b * b;
    double sv = denom > 0.0 ? fmin(1.0, fmax(0.0, (b * f - c * e) / denom)) : 0.0;
    double tv = (b * sv + f) / e;
    if (tv < 0.0) tv = 0.0, sv = fmin(1.0, fmax(0.0, -c / a));
    else if (tv > 1.0) tv = 1.0, sv = fmin(1.0, fmax(0.0, (b - c) / a));
    *s = sv;
    *t = tv;
}

bool xyl__cones_clash(const xyl__stems_cone *a, const xyl__stems_cone *b)
{
    double s, t;
    xyl__closest_params(a->p0, a->p1, b->p0, b->p1, &s, &t);
    xyl__dvec3 pa = xyl__d3_add(a->p0, xyl__d3_scale(xyl__d3_sub(a->p1, a->p0), s));
    xyl__dvec3 pb = xyl__d3_add(b->p0, xyl__d3_scale(xyl__d3_sub(b->p1, b->p0), t));
    double ra = a->r0 + (a->r1 - a->r0) * s, rb = b->r0 + (b->r1 - b->r0) * t;
    return xyl__d3_len(xyl__d3_sub(pa, pb)) < ra + rb;
}

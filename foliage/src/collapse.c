/* Leaf collapse (Hidalgo, Abad, Camahort): repeatedly merge the pair of live leaves with the
 * smallest weighted cost, until one leaf is left or no pair passes the thresholds.
 *
 * No all-pairs search: each live leaf keeps its best partner among its K nearest live leaves,
 * found in a uniform grid by rings of cells around its own (leaf_grid.c); the pairs wait in an
 * indexed 4-ary heap that holds each live leaf's best pair once: a better offer replaces it in
 * place, and it goes when the leaf dies. A merge kills two leaves and makes one: the new leaf
 * finds its K nearest, and each of them that prefers it gets it as its entry. A query stops after a fixed number of leaves, so even a million
 * coincident leaves cost O(1) each. Expected O(n log n) time, O(n) memory. Ties are broken by
 * leaf index: the same input gives the same chain, bit for bit. */
#include <string.h>

#include "foliage_internal.h"

/* ---- cost and merge ------------------------------------------------------------------------ */

static double leaf_area(const xyl_leaf *l)
{
    return 4.0 * xyl__d3_len(xyl__from_f3(l->axis)) * xyl__d3_len(xyl__from_f3(l->side));
}

/* What a pair's cost reads of a leaf, in 40 bytes (the search is bound by memory latency, and
 * a leaf is 72): centre, normal, area, count, and where the centre lies across the trunk axis
 * (its offset from the axis in a frame of two unit vectors orthogonal to it). */
typedef struct cost_leaf {
    float center[3], normal[3];
    float area;
    uint32_t count;
    float radial[2];
} cost_leaf;

/* The cost's units and weights folded into one factor per term, and the frame across the
 * trunk axis. */
typedef struct cost_terms {
    double factor[XYL__COLLAPSE_TERMS];
    xyl__dvec3 origin, e1, e2;
} cost_terms;

static cost_terms cost_terms_of(const xyl__collapse_options *o)
{
    const double unit[XYL__COLLAPSE_TERMS] = {o->scale, XYL__PI, 1.0, 1.0, 2.0 * o->radius};
    cost_terms t;
    for (int k = 0; k < XYL__COLLAPSE_TERMS; ++k) t.factor[k] = o->weights[k] / unit[k];
    t.origin = o->axis_origin;
    t.e1 = xyl__d3_any_orthogonal(o->axis_direction);
    t.e2 = xyl__d3_cross(o->axis_direction, t.e1);
    return t;
}

static cost_leaf cost_leaf_of(const xyl_leaf *l, const cost_terms *t)
{
    xyl__dvec3 d = xyl__d3_sub(xyl__from_f3(l->center), t->origin);
    cost_leaf c = {{l->center.x, l->center.y, l->center.z},
                   {l->normal.x, l->normal.y, l->normal.z},
                   (float)leaf_area(l),
                   l->count,
                   {(float)xyl__d3_dot(d, t->e1), (float)xyl__d3_dot(d, t->e2)}};
    return c;
}

static xyl__dvec3 d3_of(const float v[3])
{
    return xyl__d3(v[0], v[1], v[2]);
}

static double normals_angle(const cost_leaf *p, const cost_leaf *q)
{
    xyl__dvec3 a = d3_of(p->normal), b = d3_of(q->normal);
    return atan2(xyl__d3_len(xyl__d3_cross(a, b)), xyl__d3_dot(a, b));
}

static double axis_distance(xyl__dvec3 x, const xyl__collapse_options *o)
{
    xyl__dvec3 d = xyl__d3_sub(x, o->axis_origin);
    return xyl__d3_len(xyl__d3_sub(d, xyl__d3_scale(o->axis_direction, xyl__d3_dot(d, o->axis_direction))));
}

/* A pair's terms but the angle, weighted: distance, count, area, interiority (a term of
 * weight 0 is 0 and not added). */
typedef struct pair_terms {
    double distance, count, area, radial;
} pair_terms;

static pair_terms pair_terms_of(const cost_leaf *p, const cost_leaf *q, const cost_terms *t)
{
    const double *f = t->factor;
    pair_terms r = {0.0, 0.0, 0.0, 0.0};
    double dx = (double)p->center[0] - q->center[0], dy = (double)p->center[1] - q->center[1];
    double dz = (double)p->center[2] - q->center[2];
    r.distance = f[0] * sqrt(dx * dx + dy * dy + dz * dz);
    double kp = p->count, kq = q->count;
    if (f[2] != 0.0) r.count = f[2] * (fabs(kp - kq) / (kp + kq));
    double ap = p->area, aq = q->area;
    if (f[3] != 0.0) r.area = f[3] * (fabs(ap - aq) / (ap + aq));
    /* the midpoint's distance from the axis, times 2 (folded into f[4]) */
    double r0 = (double)p->radial[0] + q->radial[0], r1 = (double)p->radial[1] + q->radial[1];
    if (f[4] != 0.0) r.radial = f[4] * sqrt(r0 * r0 + r1 * r1);
    return r;
}

/* The cost from the terms and the weighted angle, summed in one fixed order. Rounding is
 * monotone, so with angle 0 it is a lower bound of the cost with any angle >= 0, as float
 * too: the search skips the angle (an atan2) of a pair that cannot win. */
static double pair_sum(const pair_terms *r, double angle, const cost_terms *t)
{
    const double *f = t->factor;
    double cost = r->distance;
    if (f[1] != 0.0) cost += angle;
    if (f[2] != 0.0) cost += r->count;
    if (f[3] != 0.0) cost += r->area;
    if (f[4] != 0.0) cost += r->radial;
    return cost;
}

/* The weighted sum of the five terms. Symmetric to the bit: callers pass the leaf of lower
 * index first. */
static double pair_cost(const cost_leaf *p, const cost_leaf *q, const cost_terms *t)
{
    pair_terms r = pair_terms_of(p, q, t);
    double angle = t->factor[1] != 0.0 ? t->factor[1] * normals_angle(p, q) : 0.0;
    return pair_sum(&r, angle, t);
}

float xyl__collapse_cost(const xyl_leaf *p, const xyl_leaf *q, const xyl__collapse_options *o)
{
    cost_terms t = cost_terms_of(o);
    cost_leaf cp = cost_leaf_of(p, &t), cq = cost_leaf_of(q, &t);
    return (float)pair_cost(&cp, &cq, &t);
}

/* The leaf whose texture and node the merged leaf takes: the larger area, then the larger
 * count, then the lower index (p is the lower). */
static bool q_is_larger(const xyl_leaf *p, double ap, const xyl_leaf *q, double aq)
{
    if (aq != ap) return aq > ap;
    return q->count > p->count;
}

static xyl__dvec3 project(xyl__dvec3 x, xyl__dvec3 c, xyl__dvec3 n)
{
    return xyl__d3_sub(x, xyl__d3_scale(n, xyl__d3_dot(xyl__d3_sub(x, c), n)));
}

/* The main axis of the merged leaf in its plane (unit n through c): through the two projected
 * centres, turned to agree with the count-weighted axis; where the centres coincide, the
 * count-weighted axis itself (then the larger leaf's, then any). */
static xyl__dvec3 main_axis(const xyl_leaf *p, const xyl_leaf *q, double wp, double wq,
                            bool q_larger, xyl__dvec3 c, xyl__dvec3 n, double size)
{
    xyl__dvec3 ap = xyl__d3_normalize_or(xyl__from_f3(p->axis), xyl__d3(0, 1, 0));
    xyl__dvec3 aq = xyl__d3_normalize_or(xyl__from_f3(q->axis), xyl__d3(0, 1, 0));
    xyl__dvec3 weighted = xyl__d3_add(xyl__d3_scale(ap, wp), xyl__d3_scale(aq, wq));
    xyl__dvec3 d = xyl__d3_sub(project(xyl__from_f3(q->center), c, n),
                               project(xyl__from_f3(p->center), c, n));
    xyl__dvec3 a;
    if (xyl__d3_len(d) > 1e-9 * size && xyl__d3_normalize_ok(d, &a)) {
        if (xyl__d3_dot(a, weighted) < 0.0) a = xyl__d3_scale(a, -1.0);
        return a;
    }
    xyl__dvec3 in_plane = xyl__d3_sub(weighted, xyl__d3_scale(n, xyl__d3_dot(weighted, n)));
    if (xyl__d3_normalize_ok(in_plane, &a)) return a;
    xyl__dvec3 larger = q_larger ? aq : ap;
    if (xyl__d3_normalize_ok(xyl__d3_sub(larger, xyl__d3_scale(n, xyl__d3_dot(larger, n))), &a)) return a;
    return xyl__d3_any_orthogonal(n);
}

/* What the distance to a quad needs of it: centre, unit half-axes and normal, half-lengths. */
typedef struct quad_frame {
    xyl__dvec3 center, ua, us, n;
    double la, ls;
} quad_frame;

static quad_frame quad_frame_of(const xyl_leaf *l)
{
    quad_frame f;
    xyl__dvec3 a = xyl__from_f3(l->axis), s = xyl__from_f3(l->side);
    f.la = xyl__d3_len(a), f.ls = xyl__d3_len(s);
    f.ua = xyl__d3_scale(a, 1.0 / f.la), f.us = xyl__d3_scale(s, 1.0 / f.ls);
    f.n = xyl__d3_normalize_or(xyl__d3_cross(f.us, f.ua), xyl__from_f3(l->normal));
    f.center = xyl__from_f3(l->center);
    return f;
}

static double positive_part(double v)
{
    return v > 0.0 ? v : 0.0;
}

/* Distance from x to the quad: the plane distance and how far x lies outside the rectangle
 * along each half-axis. */
static double frame_distance(xyl__dvec3 x, const quad_frame *f)
{
    xyl__dvec3 d = xyl__d3_sub(x, f->center);
    double h = xyl__d3_dot(d, f->n);
    double du = positive_part(fabs(xyl__d3_dot(d, f->ua)) - f->la);
    double dv = positive_part(fabs(xyl__d3_dot(d, f->us)) - f->ls);
    return sqrt(h * h + du * du + dv * dv);
}

static double quad_distance(xyl__dvec3 x, const xyl_leaf *l)
{
    quad_frame f = quad_frame_of(l);
    return frame_distance(x, &f);
}

double xyl__leaf_quad_distance(xyl__dvec3 x, const xyl_leaf *l)
{
    return quad_distance(x, l);
}

xyl_leaf xyl__leaf_merge(const xyl_leaf *p, const xyl_leaf *q, float err_p, float err_q,
                         float *err)
{
    double ap = leaf_area(p), aq = leaf_area(q);
    double kp = p->count, kq = q->count;
    double wp = kp / (kp + kq), wq = kq / (kp + kq);
    bool q_larger = q_is_larger(p, ap, q, aq);
    xyl__dvec3 c = xyl__d3_add(xyl__d3_scale(xyl__from_f3(p->center), wp),
                               xyl__d3_scale(xyl__from_f3(q->center), wq));
    xyl__dvec3 np = xyl__from_f3(p->normal), nq = xyl__from_f3(q->normal);
    xyl__dvec3 n = xyl__d3_normalize_or(xyl__d3_add(xyl__d3_scale(np, wp), xyl__d3_scale(nq, wq)),
                                        q_larger ? nq : np);
    double size = sqrt(ap + aq);
    xyl__dvec3 a = main_axis(p, q, wp, wq, q_larger, c, n, size);
    xyl__dvec3 s = xyl__d3_cross(a, n);
    /* the bounding rectangle of both projected quads along (a, s) */
    xyl__dvec3 pts[8];
    xyl__leaf_corners(p, pts);
    xyl__leaf_corners(q, pts + 4);
    double umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
    for (int k = 0; k < 8; ++k) {
        xyl__dvec3 d = xyl__d3_sub(project(pts[k], c, n), c);
        double u = xyl__d3_dot(d, a), v = xyl__d3_dot(d, s);
        if (u < umin) umin = u;
        if (u > umax) umax = u;
        if (v < vmin) vmin = v;
        if (v > vmax) vmax = v;
    }
    /* area: the mean of the two areas' sum and the rectangle's, by scaling the width; a
       rectangle with (almost) no length (both leaves seen edge-on) scales its length instead */
    double hl = 0.5 * (umax - umin), hw = 0.5 * (vmax - vmin);
    double target = 0.25 * 0.5 * (ap + aq + 4.0 * hl * hw); /* hl hw of the new leaf */
    double floor_len = 1e-2 * sqrt(target);
    if (hl >= floor_len) hw = target / hl;
    else if (hw >= floor_len) hl = target / hw;
    else hl = hw = sqrt(target);
    xyl__dvec3 centre = xyl__d3_add(c, xyl__d3_add(xyl__d3_scale(a, 0.5 * (umin + umax)),
                                                   xyl__d3_scale(s, 0.5 * (vmin + vmax))));
    const xyl_leaf *larger = q_larger ? q : p;
    xyl_leaf m = {0};
    m.center = xyl__to_f3(centre);
    m.normal = xyl__to_f3(n);
    m.axis = xyl__to_f3(xyl__d3_scale(a, hl));
    m.side = xyl__to_f3(xyl__d3_scale(s, hw));
    memcpy(m.uv, larger->uv, sizeof m.uv);
    m.count = p->count + q->count;
    m.node = larger->node;
    if (!err) return m;
    /* every point a child stands for is within its error of its quad, whose points are within
       the corners' largest distance of the new quad (distance to a convex set is convex) */
    double e = 0.0;
    const xyl_leaf *child[2] = {p, q};
    const float child_err[2] = {err_p, err_q};
    quad_frame frame = quad_frame_of(&m);
    for (int k = 0; k < 2; ++k) {
        double worst = 0.0;
        xyl__leaf_corners(child[k], pts);
        for (int j = 0; j < 4; ++j) {
            double dj = frame_distance(pts[j], &frame);
            if (dj > worst) worst = dj;
        }
        double ek = (double)child_err[k] + worst;
        if (ek > e) e = ek;
    }
    *err = xyl__round_up(e);
    return m;
}

/* ---- the heap of candidate pairs ------------------------------------------------------------ */

/* 16 bytes, in a 4-ary heap: a node's four children share one cache line. The cost is rounded
 * to float; ties (more of them than in double, none that matter) go to the lower indices. A
 * cost is never negative, so its bits order as the costs do, and the cost and the lower index
 * make one 64-bit key that one comparison orders (a NaN cost, from leaves too small for a
 * float area, goes last). The heap is indexed: each live leaf has at most one entry, its best
 * pair, which a better offer replaces in place and which goes when the leaf dies, so the heap
 * holds no stale entries and never more than the live leaves. */
typedef struct entry {
    uint64_t key;     /* the cost's bits << 32 | lo */
    uint32_t hi;      /* the pair is (lo, hi), lo < hi */
    uint32_t stamp;   /* the owner's node << 1, | 1 when the owner is hi */
} entry;

static entry entry_of(float cost, uint32_t lo, uint32_t hi, uint32_t stamp)
{
    uint32_t bits;
    cost += 0.0f; /* -0 (a weight of -0) as +0 */
    memcpy(&bits, &cost, sizeof bits);
    entry e = {(uint64_t)bits << 32 | lo, hi, stamp};
    return e;
}

static uint32_t lo_of(const entry *e)
{
    return (uint32_t)e->key;
}

static bool before(const entry *x, const entry *y)
{
    if (x->key != y->key) return x->key < y->key;
    if (x->hi != y->hi) return x->hi < y->hi;
    return x->stamp < y->stamp;
}

/* ---- the collapse state ------------------------------------------------------------------ */

/* What the search touches of a live leaf, in one cache line. A node is a slot that a merged
 * leaf takes over from one of its children, and the first slots go to the leaves in the
 * grid's cell order: neighbours' nodes lie near each other in memory, whose latency bounds the
 * search. */
typedef struct node {
    cost_leaf key;
    float best;       /* the cost of the leaf's entry; INFINITY if none */
    uint32_t alive;
    uint32_t leaf;    /* the leaf in the slot now */
    uint32_t pad[3];
} node;
_Static_assert(sizeof(node) == 64, "a node is one cache line");

typedef struct collapse {
    const xyl__collapse_options *o;
    xyl_leaf *leaves;
    float *error;
    uint32_t *children;
    node *nodes;      /* n slots, 64-byte aligned in nodes_block */
    void *nodes_block;
    uint32_t *slot;   /* per leaf: its node */
    entry *heap;      /* the root at heap[0], children of k at 4k + 1 .. 4k + 4 */
    void *heap_block;
    uint32_t *at;     /* per node: its entry's place in the heap, NOWHERE if none */
    size_t heap_size, heap_cap;
    cost_terms terms;
    xyl__grid g;
    uint32_t count, live, merges;
    double max_d2;
    xyl__collapse_stats stats;
} collapse;

/* A block of count * size bytes whose element 'first' starts a 64-byte line, from a. */
static void *alloc_lines(const xyl_allocator *a, size_t count, size_t size, size_t first, void **block)
{
    size_t bytes;
    if (!xyl__mul_ok(count, size, &bytes) || bytes > SIZE_MAX - 128) return NULL;
    *block = xyl__alloc(a, bytes + 128);
    if (!*block) return NULL;
    uintptr_t at = (uintptr_t)*block + 64 + first * size;
    at -= at % 64;
    return (void *)(at - first * size);
}

/* The angle threshold, asked by the grid of each candidate (only when there is one). */
typedef struct angle_filter {
    const collapse *c;
    uint32_t self;
} angle_filter;

static bool within_angle(void *ctx, uint32_t j)
{
    const angle_filter *f = ctx;
    const collapse *c = f->c;
    return normals_angle(&c->nodes[c->slot[f->self]].key, &c->nodes[c->slot[j]].key) <= c->o->max_angle;
}

static void nearest(collapse *c, uint32_t i, xyl__nearby *nr)
{
    angle_filter f = {c, i};
    bool angles = c->o->max_angle < INFINITY;
    c->stats.queries++;
    c->stats.cells_scanned += xyl__grid_nearest(&c->g, i, c->leaves[i].center, c->max_d2,
                                                angles ? within_angle : NULL, &f, nr);
    c->stats.leaves_scanned += nr->scanned;
}

/* ---- the chain ----------------------------------------------------------------------------- */

static uint32_t owner_of(const entry *e)
{
    return e->stamp & 1u ? e->hi : lo_of(e);
}

static node *node_of(const collapse *c, uint32_t leaf)
{
    return &c->nodes[c->slot[leaf]];
}

static bool alive(const collapse *c, uint32_t leaf)
{
    const node *n = node_of(c, leaf);
    return n->leaf == leaf && n->alive;
}

#define NOWHERE UINT32_MAX

static void place(collapse *c, size_t i, entry e)
{
    c->heap[i] = e;
    c->at[e.stamp >> 1] = (uint32_t)i;
}

static void sift_up(collapse *c, size_t i)
{
    entry *h = c->heap, e = h[i];
    while (i > 0) {
        size_t p = (i - 1) / 4;
        if (!before(&e, &h[p])) break;
        place(c, i, h[p]);
        i = p;
    }
    place(c, i, e);
}

static void sift_down(collapse *c, size_t i)
{
    entry *h = c->heap, e = h[i];
    size_t size = c->heap_size;
    for (;;) {
        size_t first = 4 * i + 1;
        if (first >= size) break;
        size_t end = first + 4 < size ? first + 4 : size, m = first;
        for (size_t k = first + 1; k < end; ++k)
            if (before(&h[k], &h[m])) m = k;
        if (!before(&h[m], &e)) break;
        place(c, i, h[m]);
        i = m;
    }
    place(c, i, e);
}

/* Takes node s's entry out of the heap, if it has one. */
static void heap_remove(collapse *c, uint32_t s)
{
    uint32_t i = c->at[s];
    if (i == NOWHERE) return;
    c->at[s] = NOWHERE;
    c->nodes[s].best = INFINITY;
    entry last = c->heap[--c->heap_size];
    if (i == c->heap_size) return;
    place(c, i, last);
    sift_up(c, i);
    sift_down(c, c->at[last.stamp >> 1]);
}

/* The owner's entry becomes (owner, partner) at cost: in place of its old one, if any. */
static void push(collapse *c, uint32_t owner, uint32_t partner, float cost)
{
    uint32_t s = c->slot[owner];
    c->nodes[s].best = cost;
    entry e = entry_of(cost, owner < partner ? owner : partner, owner < partner ? partner : owner,
                       s << 1 | (owner > partner));
    size_t i = c->at[s];
    if (i == NOWHERE) i = c->heap_size++;
    place(c, i, e);
    sift_up(c, i);
    sift_down(c, c->at[s]);
}

/* Leaf i's best partner among its nearest (ties: lower index), pushed; with update_others,
 * each of them that prefers i to its own entry gets one for i. A pair whose cost without the
 * angle already loses both ways gets no angle: the same choices, for fewer atan2. */
static void find_partner(collapse *c, uint32_t i, bool update_others)
{
    xyl__nearby nr;
    nearest(c, i, &nr);
    node *cand[XYL__GRID_K];
    for (uint32_t k = 0; k < nr.count; ++k) {
        cand[k] = node_of(c, nr.idx[k]);
        XYL__PREFETCH(cand[k]);
    }
    const cost_leaf *ki = &node_of(c, i)->key;
    const double f1 = c->terms.factor[1];
    float best = INFINITY;
    uint32_t partner = 0;
    for (uint32_t k = 0; k < nr.count; ++k) {
        uint32_t j = nr.idx[k];
        node *nj = cand[k];
        /* on (lower, higher index), so that both orders give the same bits */
        const cost_leaf *lo = i < j ? ki : &nj->key, *hi = i < j ? &nj->key : ki;
        pair_terms r = pair_terms_of(lo, hi, &c->terms);
        float cost = (float)pair_sum(&r, 0.0, &c->terms);
        bool wins = cost < best || (cost == best && j < partner);
        bool offered = update_others && cost < nj->best;
        if (!wins && !offered) continue;
        if (f1 != 0.0) {
            cost = (float)pair_sum(&r, f1 * normals_angle(lo, hi), &c->terms);
            wins = cost < best || (cost == best && j < partner);
            offered = update_others && cost < nj->best;
        }
        if (wins) best = cost, partner = j;
        if (offered) push(c, j, i, cost);
    }
    c->stats.cost_evaluations += nr.count;
    if (nr.count) {
        push(c, i, partner, best);
    } else {
        heap_remove(c, c->slot[i]);
    }
}

/* Puts leaf k in slot s. */
static void settle(collapse *c, uint32_t k, uint32_t s)
{
    node *n = &c->nodes[s];
    memset(n, 0, sizeof *n);
    n->key = cost_leaf_of(&c->leaves[k], &c->terms);
    n->best = INFINITY;
    n->alive = 1;
    n->leaf = k;
    c->slot[k] = s;
}

static void merge(collapse *c, uint32_t p, uint32_t q)
{
    uint32_t k = c->count++;
    c->leaves[k] = xyl__leaf_merge(&c->leaves[p], &c->leaves[q], 0.0f, 0.0f, NULL); /* errors: after the chain */
    c->children[2 * (size_t)c->merges] = p;
    c->children[2 * (size_t)c->merges + 1] = q;
    c->merges++;
    heap_remove(c, c->slot[p]);
    heap_remove(c, c->slot[q]);
    node_of(c, q)->alive = 0;
    xyl__grid_remove(&c->g, p);
    xyl__grid_remove(&c->g, q);
    settle(c, k, c->slot[p]);
    c->live--;
    if (xyl__grid_full(&c->g)) {
        xyl__grid_rebuild(&c->g, c->leaves);
        c->stats.grid_builds++;
    }
    xyl__grid_insert(&c->g, c->leaves, k);
    find_partner(c, k, true);
}

static void run(collapse *c)
{
    xyl__grid_build(&c->g, c->leaves, c->count);
    c->stats.grid_builds++;
    for (uint32_t k = 0; k < c->g.item_count; ++k) settle(c, c->g.items[k].leaf, k);
    /* in the grid's cell order: neighbours one after another keep the search in cache (the
       order of the pushes does not matter, the heap's order is total) */
    for (uint32_t k = 0; k < c->g.item_count; ++k) find_partner(c, c->g.items[k].leaf, false);
    while (c->heap_size > 0) {
        entry e = c->heap[0];
        heap_remove(c, e.stamp >> 1);
        uint32_t owner = owner_of(&e), partner = owner == lo_of(&e) ? e.hi : lo_of(&e);
        if (!alive(c, partner)) {
            find_partner(c, owner, false); /* its partner merged with another: look again */
            continue;
        }
        merge(c, lo_of(&e), e.hi);
    }
}

/* ---- exact errors ---------------------------------------------------------------------------- */

/* An original's corners, as xyl__leaf_corners gives them. */
typedef struct corners {
    xyl__dvec3 p[4];
} corners;

/* The largest squared distance from the corners to the quad of a frame. */
static double corners_distance2(const corners *o, const quad_frame *f)
{
    double worst = 0.0;
    for (int j = 0; j < 4; ++j) {
        xyl__dvec3 d = xyl__d3_sub(o->p[j], f->center);
        double h = xyl__d3_dot(d, f->n);
        double du = positive_part(fabs(xyl__d3_dot(d, f->ua)) - f->la);
        double dv = positive_part(fabs(xyl__d3_dot(d, f->us)) - f->ls);
        double d2 = h * h + du * du + dv * dv;
        if (d2 > worst) worst = d2;
    }
    return worst;
}

#define NO_RUN UINT32_MAX

/* The sum bound of merged leaf x over its children: a child's error plus the largest distance
 * of its corners from x's quad (every point a child stands for is within its error of its
 * quad, whose points are within that distance of x's). */
static double sum_bound(const xyl_leaf *leaves, const float *error, uint32_t c0, uint32_t c1,
                        const quad_frame *f)
{
    double e = 0.0;
    const uint32_t child[2] = {c0, c1};
    for (int k = 0; k < 2; ++k) {
        corners c;
        xyl__leaf_corners(&leaves[child[k]], c.p);
        double ek = (double)error[child[k]] + sqrt(corners_distance2(&c, f));
        if (ek > e) e = ek;
    }
    return e;
}

xyl_result xyl__collapse_errors(const xyl_leaf *leaves, float *error, const uint32_t *children,
                                uint32_t n, uint32_t m, uint64_t budget, const xyl_allocator *a)
{
    size_t total = (size_t)n + m;
    uint32_t *size = xyl__alloc_array(a, total, sizeof *size);
    uint32_t *start = xyl__alloc_array(a, total, sizeof *start);
    corners *run = xyl__alloc_array(a, n ? n : 1, sizeof *run);
    xyl_result r = XYL_ERR_OUT_OF_MEMORY;
    if (size && start && run) {
        for (uint32_t x = 0; x < n; ++x) size[x] = 1;
        for (uint32_t g = 0; g < m; ++g) size[n + g] = size[children[2 * g]] + size[children[2 * g + 1]];
        for (size_t x = 0; x < total; ++x) start[x] = NO_RUN;
        uint32_t next = 0;
        for (uint32_t g = m; g-- > 0;) { /* parents before children */
            uint32_t x = n + g, c0 = children[2 * g], c1 = children[2 * g + 1];
            if (start[x] == NO_RUN) start[x] = next, next += size[x]; /* a root */
            start[c0] = start[x];
            start[c1] = start[x] + size[c0];
        }
        for (uint32_t x = 0; x < n; ++x) {
            if (start[x] == NO_RUN) start[x] = next++; /* never merged */
            xyl__leaf_corners(&leaves[x], run[start[x]].p);
        }
        for (uint32_t x = 0; x < n; ++x) error[x] = 0.0f;
        for (uint32_t g = 0; g < m; ++g) {
            uint32_t x = n + g, c0 = children[2 * g], c1 = children[2 * g + 1];
            quad_frame f = quad_frame_of(&leaves[x]);
            double e;
            if (size[x] <= budget) {
                budget -= size[x];
                double worst = 0.0;
                for (uint32_t k = start[x], end = start[x] + size[x]; k < end; ++k) {
                    double d2 = corners_distance2(&run[k], &f);
                    if (d2 > worst) worst = d2;
                }
                e = sqrt(worst);
                if (error[c0] > e) e = error[c0];
                if (error[c1] > e) e = error[c1];
            } else {
                e = sum_bound(leaves, error, c0, c1, &f);
            }
            error[x] = xyl__round_up(e);
        }
        r = XYL_OK;
    }
    xyl__free(a, size);
    xyl__free(a, start);
    xyl__free(a, run);
    return r;
}

uint64_t xyl__collapse_error_budget(uint32_t n)
{
    uint64_t bits = 0;
    for (uint32_t v = n; v; v >>= 1) ++bits;
    return (uint64_t)n * (4 * bits + 16);
}

xyl_result xyl__collapse(xyl_leaf *leaves, float *error, uint32_t *children, uint32_t n,
                         const xyl__collapse_options *o, const xyl_allocator *a,
                         uint32_t *merges, xyl__collapse_stats *stats, xyl_diag *diag)
{
    collapse c;
    memset(&c, 0, sizeof c);
    c.o = o;
    c.terms = cost_terms_of(o);
    c.leaves = leaves;
    c.error = error;
    c.children = children;
    c.count = c.live = n;
    c.max_d2 = o->max_distance < INFINITY ? o->max_distance * o->max_distance : INFINITY;
    size_t cap = n ? 2 * (size_t)n - 1 : 1;
    c.heap_cap = n ? n : 1; /* an entry a node at most */
    xyl_result r = xyl__grid_init(&c.g, n, a);
    c.nodes = alloc_lines(a, n ? n : 1, sizeof *c.nodes, 0, &c.nodes_block);
    c.slot = xyl__alloc_array(a, cap, sizeof *c.slot);
    c.heap = alloc_lines(a, c.heap_cap, sizeof *c.heap, 1, &c.heap_block);
    c.at = xyl__alloc_array(a, c.heap_cap, sizeof *c.at);
    if (r != XYL_OK || !c.nodes || !c.slot || !c.heap || !c.at) {
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the collapse of %u leaves", n);
    } else {
        for (uint32_t i = 0; i < n; ++i) error[i] = 0.0f;
        for (size_t i = 0; i < c.heap_cap; ++i) c.at[i] = NOWHERE;
        if (n) run(&c);
        c.stats.bytes = (n ? n : 1) * sizeof *c.nodes + cap * sizeof *c.slot +
                        c.heap_cap * (sizeof *c.heap + sizeof *c.at) + 256 + c.g.bytes;
    }
    xyl__free(a, c.nodes_block);
    xyl__free(a, c.slot);
    xyl__free(a, c.heap_block);
    xyl__free(a, c.at);
    xyl__grid_free(&c.g, a);
    /* after the chain's scratch is gone: the peak stays the chain's */
    if (r == XYL_OK &&
        xyl__collapse_errors(leaves, error, children, n, c.merges, xyl__collapse_error_budget(n), a) != XYL_OK)
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the errors of %u leaves", n);
    if (r == XYL_OK) {
        *merges = c.merges;
        if (stats) *stats = c.stats;
    }
    return r;
}

/* ---- defaults -------------------------------------------------------------------------------- */

void xyl__collapse_defaults(const xyl_leaf *leaves, uint32_t n, xyl__collapse_options *o)
{
    static const double weights[XYL__COLLAPSE_TERMS] = XYL__COLLAPSE_WEIGHTS;
    memcpy(o->weights, weights, sizeof weights);
    o->max_distance = INFINITY;
    o->max_angle = INFINITY;
    double total = 0.0;
    xyl__dvec3 sum = xyl__d3(0, 0, 0);
    for (uint32_t i = 0; i < n; ++i) {
        double count = leaves[i].count ? leaves[i].count : 1; /* 0: the default, 1 */
        total += count;
        sum = xyl__d3_add(sum, xyl__d3_scale(xyl__from_f3(leaves[i].center), count));
    }
    o->axis_origin = total > 0.0 ? xyl__d3_scale(sum, 1.0 / total) : xyl__d3(0, 0, 0);
    o->axis_direction = xyl__d3(0, 1, 0);
    xyl__collapse_units(leaves, n, o);
}

void xyl__collapse_units(const xyl_leaf *leaves, uint32_t n, xyl__collapse_options *o)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double largest = 0.0, radius = 0.0;
    for (uint32_t i = 0; i < n; ++i) {
        const float v[3] = {leaves[i].center.x, leaves[i].center.y, leaves[i].center.z};
        for (int k = 0; k < 3; ++k) lo[k] = fmin(lo[k], v[k]), hi[k] = fmax(hi[k], v[k]);
        double l = 2.0 * fmax(xyl__d3_len(xyl__from_f3(leaves[i].axis)),
                              xyl__d3_len(xyl__from_f3(leaves[i].side)));
        largest = fmax(largest, l);
        radius = fmax(radius, axis_distance(xyl__from_f3(leaves[i].center), o));
    }
    double diagonal = n ? xyl__d3_len(xyl__d3(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2])) : 0.0;
    o->scale = fmax(diagonal, largest);
    if (!(o->scale > 0.0)) o->scale = 1.0;
    o->radius = radius > 0.0 ? radius : o->scale;
}

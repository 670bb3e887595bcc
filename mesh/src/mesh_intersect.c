/* Self-intersections of the triangulated view (xyl_mesh_self_intersections): a bounding volume
 * hierarchy over the triangles' boxes finds candidate pairs, and a test built only from sign
 * predicates decides each pair. Definitions and tolerances: docs/mesh-checks.md.
 *
 * Two triangles intersect when their intersection is larger than the convex hull of the vertex
 * indices they share: any contact for disjoint index sets, more than the shared vertex for one,
 * more than the shared edge for two (only possible when they lie flat on each other), never for
 * three. Degenerate triangles (see mesh_check.c) are skipped. */
#include <float.h>
#include <string.h>

#include "mesh_internal.h"

/* Same rule as mesh_check.c: area <= this * (bounding box diagonal)^2 is degenerate. */
#define DEGENERATE_AREA_REL XYL__EPS_REL

/* Error bounds of the sign filters, relative to the "permanent" (the determinant's expansion
 * with every product and coordinate difference taken by absolute value). Evaluated in double,
 * differences included, a 3x3 orientation determinant errs by at most (7 + 56u) u times it and
 * a 2x2 one by (3 + 16u) u (u = DBL_EPSILON / 2; Shewchuk 1997, "Adaptive precision
 * floating-point arithmetic and fast robust geometric predicates"); the bounds below are about
 * twice that. Inputs are floats, so no product comes near double overflow or underflow and the
 * bounds hold everywhere. A determinant inside its bound is taken as exactly 0 (coplanar,
 * collinear): a contact within rounding of touching is reported rather than missed, and exact
 * contacts are found even when the products need more bits than a double has. */
#define ORIENT3D_ERR (8.0 * DBL_EPSILON)
#define ORIENT2D_ERR (4.0 * DBL_EPSILON)

#define LEAF_SIZE 4

typedef struct box {
    float lo[3], hi[3];
} box;

/* An inner node's left child follows it; count == 0 marks an inner node. */
typedef struct bvh_node {
    box b;
    uint32_t right_or_first; /* inner: right child; leaf: first position in the order */
    uint32_t count;          /* triangles in a leaf */
} bvh_node;

typedef struct morton_entry {
    uint64_t code;
    uint32_t id;
} morton_entry;

typedef struct tri_set {
    const xyl_mesh *m;
    morton_entry *order; /* non-degenerate triangles along a Morton curve */
    box *boxes;          /* boxes[k] bounds triangle order[k].id */
    size_t n;
    bvh_node *nodes;
    size_t node_count;
    uint64_t *pairs;     /* the smallest pairs found so far, (i << 32) | j with i < j */
    size_t kept, kept_cap;
    size_t capacity;     /* how many the caller wants: pairs never holds more */
    size_t total;        /* pairs found */
    bool out_of_memory;
    const xyl_allocator *alloc; /* of the scratch and the pairs */
    const uint8_t *marked;      /* per triangle: pairs need one marked triangle; NULL: all */
    uint8_t *node_marked;       /* with marked, per node: a marked triangle lies under it */
} tri_set;

typedef struct p2 {
    double x, y;
} p2;

/* ---- predicates ----------------------------------------------------------------------------- */

/* Sign of det[b - a, c - a, d - a]: +1 when d lies on the side of plane (a, b, c) that its
 * normal (b - a) x (c - a) points to, 0 when it is on the plane within the error bound. */
static int orient3d(xyl__dvec3 a, xyl__dvec3 b, xyl__dvec3 c, xyl__dvec3 d)
{
    xyl__dvec3 u = xyl__d3_sub(b, a), v = xyl__d3_sub(c, a), w = xyl__d3_sub(d, a);
    double m1 = v.y * w.z, m2 = v.z * w.y, m3 = v.z * w.x, m4 = v.x * w.z;
    double m5 = v.x * w.y, m6 = v.y * w.x;
    double det = u.x * (m1 - m2) + u.y * (m3 - m4) + u.z * (m5 - m6);
    double perm = fabs(u.x) * (fabs(m1) + fabs(m2)) + fabs(u.y) * (fabs(m3) + fabs(m4)) +
                  fabs(u.z) * (fabs(m5) + fabs(m6));
    double bound = ORIENT3D_ERR * perm;
    return det > bound ? 1 : det < -bound ? -1 : 0;
}

/* Sign of the 2D cross product (b - a) x (c - a): +1 when c is left of a->b. */
static int orient2d(p2 a, p2 b, p2 c)
{
    double l = (b.x - a.x) * (c.y - a.y), r = (b.y - a.y) * (c.x - a.x);
    double bound = ORIENT2D_ERR * (fabs(l) + fabs(r));
    double det = l - r;
    return det > bound ? 1 : det < -bound ? -1 : 0;
}

/* Three signs that do not include both a +1 and a -1. */
static bool same_side_or_on(int a, int b, int c)
{
    bool pos = a > 0 || b > 0 || c > 0, neg = a < 0 || b < 0 || c < 0;
    return !(pos && neg);
}

/* ---- coplanar case: projected onto the coordinate plane the triangle faces most ------------- */

static int dominant_axis(const xyl__dvec3 t[3])
{
    xyl__dvec3 n = xyl__d3_cross(xyl__d3_sub(t[1], t[0]), xyl__d3_sub(t[2], t[0]));
    double ax = fabs(n.x), ay = fabs(n.y), az = fabs(n.z);
    return ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2;
}

/* Drops one axis; the projection is one-to-one on the plane whose normal is largest there. */
static p2 project(xyl__dvec3 p, int drop)
{
    p2 r = {drop == 0 ? p.y : p.x, drop == 2 ? p.y : p.z};
    return r;
}

/* c, known collinear with a and b, lies on the closed segment a-b. */
static bool within(p2 a, p2 b, p2 c)
{
    return fmin(a.x, b.x) <= c.x && c.x <= fmax(a.x, b.x) && fmin(a.y, b.y) <= c.y &&
           c.y <= fmax(a.y, b.y);
}

/* Closed segments p-q and a-b share a point. */
static bool segments_meet(p2 p, p2 q, p2 a, p2 b)
{
    int d1 = orient2d(p, q, a), d2 = orient2d(p, q, b);
    int d3 = orient2d(a, b, p), d4 = orient2d(a, b, q);
    if (d1 * d2 < 0 && d3 * d4 < 0) return true;
    return (d1 == 0 && within(p, q, a)) || (d2 == 0 && within(p, q, b)) ||
           (d3 == 0 && within(a, b, p)) || (d4 == 0 && within(a, b, q));
}

static bool point_in_triangle(p2 p, const p2 t[3])
{
    return same_side_or_on(orient2d(t[0], t[1], p), orient2d(t[1], t[2], p),
                           orient2d(t[2], t[0], p));
}

static bool segment_meets_triangle_2d(xyl__dvec3 p, xyl__dvec3 q, const xyl__dvec3 t[3])
{
    int drop = dominant_axis(t);
    p2 a = project(p, drop), b = project(q, drop);
    p2 u[3] = {project(t[0], drop), project(t[1], drop), project(t[2], drop)};
    if (point_in_triangle(a, u) || point_in_triangle(b, u)) return true;
    for (int i = 0; i < 3; ++i)
        if (segments_meet(a, b, u[i], u[(i + 1) % 3])) return true;
    return false;
}

/* ---- segment against triangle --------------------------------------------------------------- */

/* Closed segment p-q meets closed triangle t; sp, sq are the orient3d signs of p and q against
 * t's plane. Across the plane, the line through p and q pierces t when it passes no two edges
 * of t on opposite sides (the signs of orient3d(p, q, edge) agree or are 0). */
static bool segment_meets_triangle(xyl__dvec3 p, xyl__dvec3 q, int sp, int sq,
                                   const xyl__dvec3 t[3])
{
    if (sp * sq > 0) return false;
    if (sp == 0 && sq == 0) return segment_meets_triangle_2d(p, q, t);
    if (sp == 0 || sq == 0) return segment_meets_triangle_2d(sp == 0 ? p : q, sp == 0 ? p : q, t);
    return same_side_or_on(orient3d(p, q, t[0], t[1]), orient3d(p, q, t[1], t[2]),
                           orient3d(p, q, t[2], t[0]));
}

/* ---- triangle pairs ------------------------------------------------------------------------- */

static bool strictly_one_side(const int s[3])
{
    return (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0);
}

/* Disjoint index sets. Two closed triangles meet exactly when an edge of one meets the other
 * (an extreme point of their intersection lies on the boundary of one of them). */
static bool triangles_meet(const xyl__dvec3 a[3], const xyl__dvec3 b[3])
{
    int sb[3], sa[3];
    for (int i = 0; i < 3; ++i) sb[i] = orient3d(a[0], a[1], a[2], b[i]);
    if (strictly_one_side(sb)) return false;
    for (int i = 0; i < 3; ++i) sa[i] = orient3d(b[0], b[1], b[2], a[i]);
    if (strictly_one_side(sa)) return false;
    for (int i = 0; i < 3; ++i) {
        int j = (i + 1) % 3;
        if (segment_meets_triangle(a[i], a[j], sa[i], sa[j], b)) return true;
        if (segment_meets_triangle(b[i], b[j], sb[i], sb[j], a)) return true;
    }
    return false;
}

/* One shared vertex, at index 0 of both. Their intersection is convex and holds the shared
 * vertex s, so it holds more than s exactly when the far edge of one meets the other (the
 * intersection runs along the line both planes share, from s to the nearer far edge); a far
 * edge never contains s, so s itself is never counted. */
static bool triangles_meet_beyond_vertex(const xyl__dvec3 a[3], const xyl__dvec3 b[3])
{
    int sb1 = orient3d(a[0], a[1], a[2], b[1]), sb2 = orient3d(a[0], a[1], a[2], b[2]);
    if (sb1 * sb2 > 0) return false; /* b touches a's plane only at s */
    int sa1 = orient3d(b[0], b[1], b[2], a[1]), sa2 = orient3d(b[0], b[1], b[2], a[2]);
    if (sa1 * sa2 > 0) return false;
    return segment_meets_triangle(a[1], a[2], sa1, sa2, b) ||
           segment_meets_triangle(b[1], b[2], sb1, sb2, a);
}

/* One shared edge: vertices 0 and 1 of both, in either order. Out of one plane they meet only
 * along that edge; in one plane they overlap when their third vertices lie on the same side of
 * it (folded flat). */
static bool triangles_meet_beyond_edge(const xyl__dvec3 a[3], const xyl__dvec3 b[3])
{
    if (orient3d(a[0], a[1], a[2], b[2]) != 0) return false;
    int drop = dominant_axis(a);
    p2 e0 = project(a[0], drop), e1 = project(a[1], drop);
    return orient2d(e0, e1, project(a[2], drop)) * orient2d(e0, e1, project(b[2], drop)) > 0;
}

/* Loads triangle t with its corners rotated to start at corner `first`. Rotation keeps the
 * orientation; the tests compare signs only with each other anyway. */
static void load_rotated(const xyl_mesh *m, const uint32_t *t, int first, xyl__dvec3 out[3])
{
    static const int wrap[6] = {0, 1, 2, 0, 1, 2}; /* (first + k) % 3 for first <= 3 */
    for (int k = 0; k < 3; ++k) out[k] = xyl__from_f3(m->positions[t[wrap[first + k]]]);
}

/* Picks the test for the number of vertex indices the two triangles share, with the corners
 * rotated so that a shared vertex comes first (one shared) or the unshared one last (two). */
static bool pair_intersects(const xyl_mesh *m, uint32_t i, uint32_t j)
{
    /* Corner index of the single bit set in a 3-bit mask (masks 1, 2, 4). */
    static const int corner_of_bit[8] = {0, 0, 1, 0, 2, 0, 0, 0};
    const uint32_t *ta = m->tri_view + 3 * (size_t)i, *tb = m->tri_view + 3 * (size_t)j;
    unsigned in_a = 0, in_b = 0; /* bit x: corner x is shared */
    int shared = 0;
    for (int x = 0; x < 3; ++x)
        for (int y = 0; y < 3; ++y)
            if (ta[x] == tb[y]) {
                in_a |= 1u << x;
                in_b |= 1u << y;
                ++shared;
            }
    if (shared >= 3) return false;
    xyl__dvec3 a[3], b[3];
    if (shared == 1) {
        load_rotated(m, ta, corner_of_bit[in_a], a);
        load_rotated(m, tb, corner_of_bit[in_b], b);
        return triangles_meet_beyond_vertex(a, b);
    }
    if (shared == 2) {
        load_rotated(m, ta, corner_of_bit[~in_a & 7u] + 1, a);
        load_rotated(m, tb, corner_of_bit[~in_b & 7u] + 1, b);
        return triangles_meet_beyond_edge(a, b);
    }
    load_rotated(m, ta, 0, a);
    load_rotated(m, tb, 0, b);
    return triangles_meet(a, b);
}

/* ---- boxes -------------------------------------------------------------------------------- */

static bool boxes_overlap(const box *a, const box *b)
{
    /* Closed intervals: boxes that only touch still hold a candidate pair. */
    for (int k = 0; k < 3; ++k)
        if (a->lo[k] > b->hi[k] || b->lo[k] > a->hi[k]) return false;
    return true;
}

static void box_add(box *b, xyl_vec3 p)
{
    const float c[3] = {p.x, p.y, p.z};
    for (int k = 0; k < 3; ++k) {
        b->lo[k] = c[k] < b->lo[k] ? c[k] : b->lo[k];
        b->hi[k] = c[k] > b->hi[k] ? c[k] : b->hi[k];
    }
}

static void box_merge(box *b, const box *o)
{
    for (int k = 0; k < 3; ++k) {
        b->lo[k] = o->lo[k] < b->lo[k] ? o->lo[k] : b->lo[k];
        b->hi[k] = o->hi[k] > b->hi[k] ? o->hi[k] : b->hi[k];
    }
}

/* Inverted, so it grows from the first point. */
static box box_empty(void)
{
    box b = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    return b;
}

static box triangle_box(const xyl_mesh *m, uint32_t t)
{
    box b = box_empty();
    for (size_t k = 0; k < 3; ++k) box_add(&b, m->positions[m->tri_view[3 * (size_t)t + k]]);
    return b;
}

static double box_size(const box *b)
{
    return (double)b->hi[0] - b->lo[0] + (double)b->hi[1] - b->lo[1] + (double)b->hi[2] - b->lo[2];
}

/* ---- triangles along a Morton curve --------------------------------------------------------- */

/* Area tolerance from the bounding box of the vertices the view uses (as in mesh_check.c). */
double xyl__mesh_area_tolerance(const xyl_mesh *m)
{
    box b = box_empty();
    for (size_t k = 0; k < 3 * m->tri_view_count; ++k) box_add(&b, m->positions[m->tri_view[k]]);
    if (m->tri_view_count == 0) return 0.0;
    xyl__dvec3 d = xyl__d3((double)b.hi[0] - b.lo[0], (double)b.hi[1] - b.lo[1],
                           (double)b.hi[2] - b.lo[2]);
    return DEGENERATE_AREA_REL * xyl__d3_dot(d, d);
}

static bool triangle_degenerate(const xyl_mesh *m, size_t t, double tol)
{
    const uint32_t *v = m->tri_view + 3 * t;
    xyl__dvec3 a = xyl__from_f3(m->positions[v[0]]);
    xyl__dvec3 n = xyl__d3_cross(xyl__d3_sub(xyl__from_f3(m->positions[v[1]]), a),
                                 xyl__d3_sub(xyl__from_f3(m->positions[v[2]]), a));
    return 0.5 * xyl__d3_len(n) <= tol;
}

/* Spreads the low 21 bits of x to every third bit (bit i to bit 3i), by halving steps: each
 * step moves the upper half of every group away from the lower one. */
static uint64_t spread3(uint32_t x)
{
    uint64_t v = x & 0x1fffffu;
    v = (v | v << 32) & UINT64_C(0x001f00000000ffff);
    v = (v | v << 16) & UINT64_C(0x001f0000ff0000ff);
    v = (v | v << 8) & UINT64_C(0x100f00f00f00f00f);
    v = (v | v << 4) & UINT64_C(0x10c30c30c30c30c3);
    v = (v | v << 2) & UINT64_C(0x1249249249249249);
    return v;
}

/* Interleaves the low 21 bits of x, y, z (x lowest) into a Morton code. */
static uint64_t interleave(const uint32_t q[3])
{
    return spread3(q[0]) | spread3(q[1]) << 1 | spread3(q[2]) << 2;
}

/* Stable LSD radix sort by code, 11 bits a pass; entries with equal codes keep their order
 * (ascending triangle index), so the result is deterministic. */
static void sort_by_code(morton_entry *e, morton_entry *tmp, size_t n)
{
    enum { BITS = 11, BUCKETS = 1 << BITS };
    size_t count[BUCKETS];
    if (n < 2) return;
    for (unsigned shift = 0; shift < 63; shift += BITS) {
        memset(count, 0, sizeof count);
        for (size_t i = 0; i < n; ++i) count[e[i].code >> shift & (BUCKETS - 1)]++;
        if (count[e[0].code >> shift & (BUCKETS - 1)] == n) continue; /* one digit: no move */
        size_t sum = 0;
        for (size_t b = 0; b < BUCKETS; ++b) {
            size_t c = count[b];
            count[b] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; ++i) tmp[count[e[i].code >> shift & (BUCKETS - 1)]++] = e[i];
        memcpy(e, tmp, n * sizeof *e);
    }
}

/* Lists the non-degenerate triangles (degenerate ones are never candidates) sorted by the
 * Morton code of their box centres, with their boxes in the same order. */
static void order_triangles(tri_set *s, morton_entry *tmp)
{
    const xyl_mesh *m = s->m;
    double tol = xyl__mesh_area_tolerance(m);
    box all = box_empty();
    s->n = 0;
    for (uint32_t t = 0; t < m->tri_view_count; ++t) {
        if (triangle_degenerate(m, t, tol)) continue;
        s->boxes[s->n] = triangle_box(m, t);
        box_merge(&all, &s->boxes[s->n]);
        s->order[s->n++].id = t;
    }
    for (size_t i = 0; i < s->n; ++i) {
        const box *b = &s->boxes[i];
        uint32_t q[3];
        for (int k = 0; k < 3; ++k) {
            double ext = (double)all.hi[k] - all.lo[k];
            double c = 0.5 * ((double)b->lo[k] + b->hi[k]) - all.lo[k];
            q[k] = ext > 0.0 ? (uint32_t)(c / ext * 2097151.0) : 0u;
        }
        s->order[i].code = interleave(q);
    }
    sort_by_code(s->order, tmp, s->n);
    for (size_t i = 0; i < s->n; ++i) s->boxes[i] = triangle_box(m, s->order[i].id);
}

/* ---- the hierarchy -------------------------------------------------------------------------- */

/* Where [first, first + count) splits: at the highest bit in which its codes differ (a spatial
 * midpoint, so boxes stay tight), or in the middle when the codes are all equal. Each split
 * lengthens the shared prefix, so the depth stays below 63 + log2(count). */
static size_t split_point(const tri_set *s, size_t first, size_t count)
{
    uint64_t a = s->order[first].code, diff = a ^ s->order[first + count - 1].code;
    if (diff == 0) return count / 2;
    uint64_t bit = UINT64_C(1) << 63;
    while (!(diff & bit)) bit >>= 1;
    size_t lo = 1, hi = count - 1; /* the answer lies in [lo, hi] */
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (s->order[first + mid].code & bit) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

static uint32_t build(tri_set *s, size_t first, size_t count)
{
    uint32_t me = (uint32_t)s->node_count++;
    bvh_node *nd = &s->nodes[me];
    if (count <= LEAF_SIZE) {
        nd->b = box_empty();
        for (size_t i = 0; i < count; ++i) box_merge(&nd->b, &s->boxes[first + i]);
        nd->right_or_first = (uint32_t)first;
        nd->count = (uint32_t)count;
        if (s->marked) {
            uint8_t any = 0;
            for (size_t i = 0; i < count; ++i) any |= s->marked[s->order[first + i].id];
            s->node_marked[me] = any != 0;
        }
        return me;
    }
    size_t left_count = split_point(s, first, count);
    uint32_t left = build(s, first, left_count);
    uint32_t right = build(s, first + left_count, count - left_count);
    nd->b = s->nodes[left].b;
    box_merge(&nd->b, &s->nodes[right].b);
    nd->right_or_first = right;
    nd->count = 0;
    if (s->marked) s->node_marked[me] = s->node_marked[left] | s->node_marked[right];
    return me;
}

/* ---- traversal ------------------------------------------------------------------------------ */

/* Restores the max-heap order of h[0..n) below position i. */
static void sift_down(uint64_t *h, size_t n, size_t i)
{
    for (;;) {
        size_t big = i, l = 2 * i + 1, r = l + 1;
        if (l < n && h[l] > h[big]) big = l;
        if (r < n && h[r] > h[big]) big = r;
        if (big == i) return;
        uint64_t t = h[i];
        h[i] = h[big];
        h[big] = t;
        i = big;
    }
}

/* Counts a pair and keeps the `capacity` smallest: appended while there is room, then in a
 * max-heap whose root (the largest kept) gives way to anything smaller. Memory stays within
 * what the caller asked for, so counting alone needs none. */
static void record(tri_set *s, uint32_t i, uint32_t j)
{
    uint64_t key = i < j ? (uint64_t)i << 32 | j : (uint64_t)j << 32 | i;
    s->total++;
    if (s->kept < s->capacity) {
        if (!xyl__grow(s->alloc, (void **)&s->pairs, &s->kept_cap, s->kept, s->kept + 1,
                       sizeof *s->pairs)) {
            s->out_of_memory = true;
            return;
        }
        s->pairs[s->kept++] = key;
        if (s->kept == s->capacity)
            for (size_t k = s->kept / 2; k-- > 0;) sift_down(s->pairs, s->kept, k);
        return;
    }
    if (s->kept && key < s->pairs[0]) {
        s->pairs[0] = key;
        sift_down(s->pairs, s->kept, 0);
    }
}

/* Tests positions x and y of the order (their boxes first). */
static void test_pair(tri_set *s, size_t x, size_t y)
{
    if (s->marked && !s->marked[s->order[x].id] && !s->marked[s->order[y].id]) return;
    if (!boxes_overlap(&s->boxes[x], &s->boxes[y])) return;
    if (pair_intersects(s->m, s->order[x].id, s->order[y].id))
        record(s, s->order[x].id, s->order[y].id);
}

/* Every pair with one triangle under node a and one under node b (a != b). */
static void collide(tri_set *s, uint32_t a, uint32_t b)
{
    const bvh_node *na = &s->nodes[a], *nb = &s->nodes[b];
    if (s->marked && !s->node_marked[a] && !s->node_marked[b]) return;
    if (!boxes_overlap(&na->b, &nb->b)) return;
    if (na->count && nb->count) {
        for (uint32_t x = 0; x < na->count; ++x)
            for (uint32_t y = 0; y < nb->count; ++y)
                test_pair(s, na->right_or_first + (size_t)x, nb->right_or_first + (size_t)y);
        return;
    }
    /* Open the inner node, the larger one when both are, so boxes shrink evenly. */
    if (nb->count || (!na->count && box_size(&na->b) >= box_size(&nb->b))) {
        collide(s, a + 1, b);
        collide(s, na->right_or_first, b);
    } else {
        collide(s, a, b + 1);
        collide(s, a, nb->right_or_first);
    }
}

/* Every pair of triangles under node a. */
static void collide_self(tri_set *s, uint32_t a)
{
    const bvh_node *na = &s->nodes[a];
    if (s->marked && !s->node_marked[a]) return;
    if (na->count) {
        for (uint32_t x = 0; x < na->count; ++x)
            for (uint32_t y = x + 1; y < na->count; ++y)
                test_pair(s, na->right_or_first + (size_t)x, na->right_or_first + (size_t)y);
        return;
    }
    collide_self(s, a + 1);
    collide_self(s, na->right_or_first);
    collide(s, a + 1, na->right_or_first);
}

static int u64_compare(const void *pa, const void *pb)
{
    uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;
    return a < b ? -1 : a > b;
}

/* ---- the public call ------------------------------------------------------------------------ */

/* Triangle and node indices are uint32_t (a tree over n triangles has < 2n nodes); the view
 * is all the test reads. */
static xyl_result validate(const xyl_mesh *m, xyl_diag *diag)
{
    if (m->tri_view_count > UINT32_MAX / 2)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu triangles exceed 32-bit indexing", m->tri_view_count);
    return xyl__mesh_validate(m, XYL__MESH_TRI_VIEW, diag);
}

static void tri_set_free(tri_set *s)
{
    xyl__free(s->alloc, s->order);
    xyl__free(s->alloc, s->boxes);
    xyl__free(s->alloc, s->nodes);
    xyl__free(s->alloc, s->pairs);
    xyl__free(s->alloc, s->node_marked);
}

/* Finds every pair into s->pairs, sorted; false when memory ran out. tmp holds one entry per
 * triangle of the view. */
static bool find_pairs(tri_set *s, morton_entry *tmp)
{
    order_triangles(s, tmp);
    if (s->n == 0) return true;
    build(s, 0, s->n);
    collide_self(s, 0);
    if (s->out_of_memory) return false;
    xyl__sort(s->pairs, s->kept, sizeof *s->pairs, u64_compare);
    return true;
}

/* Every intersecting pair of a valid mesh in one pass, into s->pairs (i << 32 | j, sorted; s->kept
 * of them); false when memory ran out, with nothing to free. Memory comes from alloc. */
static bool all_pairs(const xyl_mesh *mesh, const uint8_t *marked, size_t capacity,
                      const xyl_allocator *alloc, tri_set *out)
{
    size_t t = mesh->tri_view_count;
    tri_set s = {.m = mesh,
                 .capacity = capacity,
                 .alloc = alloc,
                 .marked = marked,
                 .order = xyl__calloc(alloc, t, sizeof(morton_entry)),
                 .boxes = xyl__calloc(alloc, t, sizeof(box)),
                 .nodes = xyl__calloc(alloc, t, 2 * sizeof(bvh_node)),
                 .node_marked = marked ? xyl__calloc(alloc, t, 2) : NULL};
    morton_entry *tmp = xyl__calloc(alloc, t, sizeof *tmp);
    bool ok = s.order && s.boxes && s.nodes && tmp && (!marked || s.node_marked) &&
              find_pairs(&s, tmp);
    xyl__free(alloc, tmp);
    if (!ok) tri_set_free(&s);
    *out = s;
    return ok;
}

xyl_result xyl__mesh_intersecting_pairs(const xyl_mesh *mesh, const xyl_allocator *alloc,
                                        uint64_t **pairs, size_t *count, xyl_diag *diag)
{
    return xyl__mesh_intersecting_pairs_marked(mesh, NULL, alloc, pairs, count, diag);
}

xyl_result xyl__mesh_intersecting_pairs_marked(const xyl_mesh *mesh, const uint8_t *marked,
                                               const xyl_allocator *alloc, uint64_t **pairs,
                                               size_t *count, xyl_diag *diag)
{
    xyl_result r = validate(mesh, diag);
    if (r) return r;
    tri_set s;
    if (!all_pairs(mesh, marked, SIZE_MAX, alloc, &s))
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1,
                         "out of memory for the self-intersection test");
    *pairs = s.pairs; /* the caller frees it with xyl__free(alloc, .) */
    *count = s.kept;
    s.pairs = NULL;
    tri_set_free(&s);
    return XYL_OK;
}

xyl_result xyl_mesh_self_intersections(const xyl_mesh *mesh, const xyl_allocator *alloc,
                                       uint32_t *pairs, size_t capacity, size_t *count,
                                       xyl_diag *diag)
{
    if (!mesh || !count || (!pairs && capacity))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "mesh and count must not be NULL, nor pairs with a capacity");
    xyl_result r = validate(mesh, diag);
    if (r) return r;
    tri_set s;
    if (!all_pairs(mesh, NULL, capacity, alloc, &s))
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1,
                         "out of memory for the self-intersection test");
    /* Written only now, so a failure leaves pairs and count untouched. */
    for (size_t k = 0; k < s.kept; ++k) {
        pairs[2 * k] = (uint32_t)(s.pairs[k] >> 32);
        pairs[2 * k + 1] = (uint32_t)s.pairs[k];
    }
    *count = s.total;
    tri_set_free(&s);
    xyl__diag_ok(diag);
    return XYL_OK;
}

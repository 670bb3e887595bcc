/* The joint check and repair: which intersecting pairs lie at joints, which lateral each blames. */

/* Checked joints (docs/stems.md, "Checked joints"): which intersecting triangle pairs of a stem
 * mesh lie at joints, and which lateral to blame for each (to start later, or leave out).
 *
 * A pair is the skeleton's own, and no mesher's to remove, on two branches that are unrelated
 * (neither one forks from the other nor do both fork from one node) and have segments closer
 * than the sum of their radii, or on one branch that folds back onto itself: the far end of a
 * segment within the radii of the next one, away from the node they share. Every other pair is
 * at a joint. The judgement errs towards "at a joint" by a margin: distances are exact here, and
 * the tests judge by sampling each segment 256 times, which can only make a distance longer, by
 * at most 1/512 of the segment; so a pair this file calls the skeleton's, the tests do too. */
#include <stdlib.h>
#include <string.h>

#include "stems_internal.h"

typedef struct judge {
    const xyl_skeleton *sk;
    uint32_t *start, *nodes; /* branch b's nodes: nodes[start[b] .. start[b + 1]) */
    uint32_t *child_start, *child_list; /* node n's children: child_list[child_start[n] ..) */
    uint32_t *faces;         /* per branch: its faces in the mesh */
    size_t *grown;           /* per branch: the faces of it and of all that grows from it */
    uint8_t *bumped;         /* per branch: its level rose in this round */
} judge;

static xyl__dvec3 at(const judge *j, uint32_t n)
{
    return xyl__from_f3(j->sk->nodes[n].pos);
}

/* The radius of the tube of the segment into node n: the larger of its nodes' radii. */
static double seg_radius(const judge *j, uint32_t n)
{
    const xyl_skel_node *nodes = j->sk->nodes;
    return fmax(nodes[n].radius, nodes[nodes[n].parent].radius);
}

/* Whether the far end f of one segment lies within r of segment s-g (s the node they share) at
 * a point more than r from s: a hairpin, not the joint's own overlap. */
static bool folds_onto(xyl__dvec3 f, xyl__dvec3 s, xyl__dvec3 g, double r)
{
    xyl__dvec3 d = xyl__d3_sub(g, s), w = xyl__d3_sub(f, s);
    double dd = xyl__d3_dot(d, d), t = dd > 0.0 ? xyl__d3_dot(w, d) / dd : 0.0;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    xyl__dvec3 e = xyl__d3_sub(w, xyl__d3_scale(d, t));
    const double margin = 1e-9;
    return xyl__d3_len(e) < r * (1.0 - margin) && t * sqrt(dd) > r * (1.0 + margin);
}

/* Whether the segments into nodes x and y (x != y, both with parents) overlap in the skeleton. */
static bool segments_overlap(const judge *j, uint32_t x, uint32_t y)
{
    const xyl_skel_node *nodes = j->sk->nodes;
    uint32_t px = (uint32_t)nodes[x].parent, py = (uint32_t)nodes[y].parent;
    double r = seg_radius(j, x) + seg_radius(j, y);
    xyl__dvec3 x0 = at(j, px), x1 = at(j, x), y0 = at(j, py), y1 = at(j, y);
    if (x != py && y != px && px != py) {
        double s, t;
        xyl__closest_params(x0, x1, y0, y1, &s, &t);
        xyl__dvec3 a = xyl__d3_add(x0, xyl__d3_scale(xyl__d3_sub(x1, x0), s));
        xyl__dvec3 b = xyl__d3_add(y0, xyl__d3_scale(xyl__d3_sub(y1, y0), t));
        double slack = fmax(xyl__d3_len(xyl__d3_sub(x1, x0)), xyl__d3_len(xyl__d3_sub(y1, y0))) / 512.0;
        return xyl__d3_len(xyl__d3_sub(a, b)) + slack < r * (1.0 - 1e-9);
    }
    uint32_t shared = x == py ? x : y == px ? y : px;
    uint32_t fx = shared == x ? px : x, fy = shared == y ? py : y;
    return folds_onto(at(j, fx), at(j, shared), at(j, fy), r) ||
           folds_onto(at(j, fy), at(j, shared), at(j, fx), r);
}

/* The node branch b forks from, or -1 for a root's branch. */
static int32_t fork_of(const judge *j, uint32_t b)
{
    return j->sk->nodes[j->nodes[j->start[b]]].parent;
}

/* Whether one of branches a and b forks from the other, or both from one node. */
static bool related(const judge *j, uint32_t a, uint32_t b)
{
    const xyl_skel_node *nodes = j->sk->nodes;
    int32_t fa = fork_of(j, a), fb = fork_of(j, b);
    return fa == fb || (fa >= 0 && nodes[fa].branch == b) || (fb >= 0 && nodes[fb].branch == a);
}

/* Whether the skeletons of branches a and b (a may be b) overlap themselves. */
static bool skeletons_overlap(const judge *j, uint32_t a, uint32_t b)
{
    if (a != b && related(j, a, b)) return false;
    const xyl_skel_node *nodes = j->sk->nodes;
    for (uint32_t u = j->start[a]; u < j->start[a + 1]; ++u) {
        uint32_t x = j->nodes[u];
        if (nodes[x].parent < 0) continue;
        for (uint32_t v = j->start[b]; v < j->start[b + 1]; ++v) {
            uint32_t y = j->nodes[v];
            if (y != x && nodes[y].parent >= 0 && segments_overlap(j, x, y)) return true;
        }
    }
    return false;
}

/* Whether branch x has less grown from it than branch y (the later of two equal ones). */
static bool less_grown(const judge *j, uint32_t x, uint32_t y)
{
    return j->grown[x] < j->grown[y] || (j->grown[x] == j->grown[y] && x > y);
}

/* The branch to blame for a pair at a joint between branches a and b (a != b), or
 * UINT32_MAX if neither can go: of a child and the branch it forks from, the child; of
 * siblings, and of branches the placement brought together, the one with less grown from it. */
static uint32_t blame_two(const judge *j, uint32_t a, uint32_t b)
{
    const xyl_skel_node *nodes = j->sk->nodes;
    int32_t fa = fork_of(j, a), fb = fork_of(j, b);
    uint32_t pick;
    if (fb >= 0 && nodes[fb].branch == a) pick = b;
    else if (fa >= 0 && nodes[fa].branch == b) pick = a;
    else pick = less_grown(j, a, b) ? a : b;
    return fork_of(j, pick) >= 0 ? pick : UINT32_MAX;
}

/* Of node n's laterals (children on other branches than a) with faces in this mesh, the one
 * with least grown from it, or UINT32_MAX. */
static uint32_t least_grown_lateral(const judge *j, uint32_t n, uint32_t a)
{
    uint32_t pick = UINT32_MAX;
    for (uint32_t v = j->child_start[n]; v < j->child_start[n + 1]; ++v) {
        uint32_t x = j->sk->nodes[j->child_list[v]].branch;
        if (x != a && j->faces[x] && (pick == UINT32_MAX || less_grown(j, x, pick))) pick = x;
    }
    return pick;
}

/* For a pair on one branch a, near point c: a fork's rings crowd the tube there, so the
 * least_grown_lateral of a's node nearest to c that has one, if c is within three of that
 * node's radii; else a itself, unless it is a root's. */
static uint32_t blame_one(const judge *j, uint32_t a, xyl__dvec3 c)
{
    uint32_t pick = UINT32_MAX;
    double best_d = INFINITY;
    for (uint32_t u = j->start[a]; u < j->start[a + 1]; ++u) {
        uint32_t n = j->nodes[u], x;
        double d = xyl__d3_len(xyl__d3_sub(at(j, n), c));
        if (d < best_d && d <= 3.0 * j->sk->nodes[n].radius &&
            (x = least_grown_lateral(j, n, a)) != UINT32_MAX)
            pick = x, best_d = d;
    }
    if (pick != UINT32_MAX) return pick;
    return fork_of(j, a) >= 0 ? a : UINT32_MAX;
}

/* The centre of the six corners of triangles t0 and t1 of m's triangulated view. */
static xyl__dvec3 pair_centre(const xyl_mesh *m, uint32_t t0, uint32_t t1)
{
    xyl__dvec3 sum = xyl__d3(0, 0, 0);
    for (int q = 0; q < 3; ++q) {
        sum = xyl__d3_add(sum, xyl__from_f3(m->positions[m->tri_view[3 * (size_t)t0 + q]]));
        sum = xyl__d3_add(sum, xyl__from_f3(m->positions[m->tri_view[3 * (size_t)t1 + q]]));
    }
    return xyl__d3_scale(sum, 1.0 / 6.0);
}

/* The face of triangle t of the triangulated view: two per quad, then the triangles. */
static size_t face_of(const xyl_mesh *m, uint32_t t)
{
    return t < 2 * m->quad_count ? t / 2 : m->quad_count + (t - 2 * m->quad_count);
}

static int key_compare(const void *pa, const void *pb)
{
    const uint64_t *a = pa, *b = pb; /* key, then pair */
    return a[0] != b[0] ? (a[0] < b[0] ? -1 : 1) : a[1] < b[1] ? -1 : a[1] > b[1];
}

/* Fills the judge's arrays; false when memory ran out. */
static bool judge_make(judge *j, const xyl_skeleton *sk, const xyl_mesh *m,
                       const xyl_allocator *alloc)
{
    size_t nb = sk->branch_count, nn = sk->node_count, nf = m->quad_count + m->triangle_count;
    const xyl_skel_node *nodes = sk->nodes;
    j->sk = sk;
    j->start = xyl__calloc(alloc, nb + 2, sizeof *j->start);
    j->nodes = xyl__alloc_array(alloc, nn ? nn : 1, sizeof *j->nodes);
    j->child_start = xyl__calloc(alloc, nn + 2, sizeof *j->child_start);
    j->child_list = xyl__alloc_array(alloc, nn ? nn : 1, sizeof *j->child_list);
    j->faces = xyl__calloc(alloc, nb ? nb : 1, sizeof *j->faces);
    j->grown = xyl__calloc(alloc, nb ? nb : 1, sizeof *j->grown);
    j->bumped = xyl__calloc(alloc, nb ? nb : 1, 1);
    if (!j->start || !j->nodes || !j->child_start || !j->child_list || !j->faces || !j->grown ||
        !j->bumped)
        return false;
    /* counting sorts: counts at [x + 2], prefix sums, then filling moves [x + 1] to x's end */
    for (size_t i = 0; i < nn; ++i) {
        ++j->start[nodes[i].branch + 2];
        if (nodes[i].parent >= 0) ++j->child_start[nodes[i].parent + 2];
    }
    for (size_t b = 2; b < nb + 2; ++b) j->start[b] += j->start[b - 1];
    for (size_t n = 2; n < nn + 2; ++n) j->child_start[n] += j->child_start[n - 1];
    for (size_t i = 0; i < nn; ++i) {
        j->nodes[j->start[nodes[i].branch + 1]++] = (uint32_t)i;
        if (nodes[i].parent >= 0) j->child_list[j->child_start[nodes[i].parent + 1]++] = (uint32_t)i;
    }
    for (size_t f = 0; f < nf; ++f) ++j->faces[m->face_branches[f]];
    /* a branch's fork node precedes its first node, so branch ids grow down the tree */
    for (size_t b = 0; b < nb; ++b) j->grown[b] = j->faces[b];
    for (size_t b = nb; b-- > 0;) {
        int32_t f = fork_of(j, (uint32_t)b);
        if (f >= 0 && nodes[f].branch < b) j->grown[nodes[f].branch] += j->grown[b];
    }
    return true;
}

static void judge_free(judge *j, const xyl_allocator *alloc)
{
    xyl__free(alloc, j->start);
    xyl__free(alloc, j->nodes);
    xyl__free(alloc, j->child_start);
    xyl__free(alloc, j->child_list);
    xyl__free(alloc, j->faces);
    xyl__free(alloc, j->grown);
    xyl__free(alloc, j->bumped);
}

/* Raises the level of blamed branch b (UINT32_MAX: none can go) once per round. */
static void raise_level(judge *j, uint8_t *drop, uint32_t b, xyl__joint_tally *t)
{
    if (b == UINT32_MAX || j->bumped[b] || drop[b] >= XYL__JOINT_DROP) return;
    j->bumped[b] = 1;
    ++drop[b];
    ++t->marked;
}

/* Pairs at joints, each branch pair judged once (sorted keys, a verdict per run); pairs on one
 * branch are blamed one by one, by where they are. A blamed branch's level rises by one per
 * round, however many pairs blame it. */
xyl_result xyl__stems_judge_joints(const xyl_skeleton *sk, const xyl_mesh *m,
                                   const uint64_t *pairs, size_t count, uint8_t *drop,
                                   const xyl_allocator *alloc, xyl__joint_tally *t, xyl_diag *diag)
{
    memset(t, 0, sizeof *t);
    if (!count) return XYL_OK;
    judge j;
    memset(&j, 0, sizeof j);
    typedef struct keyed {
        uint64_t key; /* a << 32 | b, a <= b */
        uint64_t pair;
    } keyed;
    keyed *keys = xyl__alloc_array(alloc, count, sizeof *keys);
    xyl_result r = XYL_OK;
    if (!keys || !judge_make(&j, sk, m, alloc)) {
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory judging the joints");
        goto done;
    }
    for (size_t i = 0; i < count; ++i) {
        uint64_t a = m->face_branches[face_of(m, (uint32_t)(pairs[i] >> 32))];
        uint64_t b = m->face_branches[face_of(m, (uint32_t)pairs[i])];
        keys[i] = (keyed){a <= b ? a << 32 | b : b << 32 | a, pairs[i]};
    }
    xyl__sort(keys, count, sizeof *keys, key_compare); /* by key, then pair: both are unique */
    for (size_t i = 0, run; i < count; i += run) {
        for (run = 1; i + run < count && keys[i + run].key == keys[i].key; ++run) {}
        uint32_t a = (uint32_t)(keys[i].key >> 32), b = (uint32_t)keys[i].key;
        if (skeletons_overlap(&j, a, b)) {
            t->own += run;
            continue;
        }
        t->joint += run;
        if (a != b) { /* one verdict for the run */
            raise_level(&j, drop, blame_two(&j, a, b), t);
            continue;
        }
        for (size_t p = i; p < i + run; ++p) {
            uint32_t t0 = (uint32_t)(keys[p].pair >> 32), t1 = (uint32_t)keys[p].pair;
            raise_level(&j, drop, blame_one(&j, a, pair_centre(m, t0, t1)), t);
        }
    }
done:
    judge_free(&j, alloc);
    xyl__free(alloc, keys);
    return r;
}

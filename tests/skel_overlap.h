/* Where a skeleton overlaps itself, and which intersecting triangle pairs of its stem mesh that
 * explains (docs/stems.md, "Where the skeleton overlaps itself"). A pair is the skeleton's only
 * on two branches that are unrelated (neither parent and child nor children of one node) and
 * have segments closer than the sum of their radii, or on one branch that folds back onto
 * itself; every other pair is at a joint, the mesher's to avoid. Shared by the suites that
 * judge intersections (test_stems.c); needs no cmocka. */
#ifndef XYL_SKEL_OVERLAP_H
#define XYL_SKEL_OVERLAP_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

#include <xylem/xyl_stems.h>

/* Each branch's nodes in node order: nodes[start[b] .. start[b + 1]). */
typedef struct so_branches {
    uint32_t *start, *nodes;
    uint32_t count;
} so_branches;

/* Returns false when out of memory. */
static inline bool so_branches_make(const xyl_skeleton *sk, so_branches *b)
{
    b->count = sk->branch_count;
    b->start = calloc((size_t)b->count + 2, sizeof *b->start);
    b->nodes = malloc((sk->node_count ? sk->node_count : 1) * sizeof *b->nodes);
    if (!b->start || !b->nodes) {
        free(b->start);
        free(b->nodes);
        return false;
    }
    for (uint32_t i = 0; i < sk->node_count; ++i) ++b->start[sk->nodes[i].branch + 2];
    for (uint32_t i = 2; i < b->count + 2; ++i) b->start[i] += b->start[i - 1];
    for (uint32_t i = 0; i < sk->node_count; ++i) b->nodes[b->start[sk->nodes[i].branch + 1]++] = i;
    return true;
}

static inline void so_branches_free(so_branches *b)
{
    free(b->start);
    free(b->nodes);
}

/* Distance between segments p0-p1 and q0-q1, by sampling p0-p1 finely enough for the test:
 * the skeleton crossings it looks for are deep (a fraction of the radii). */
static inline double so_segment_distance(xyl_vec3 p0, xyl_vec3 p1, xyl_vec3 q0, xyl_vec3 q1)
{
    double best = INFINITY, d[3] = {q1.x - q0.x, q1.y - q0.y, q1.z - q0.z};
    double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    for (int i = 0; i <= 256; ++i) {
        double f = i / 256.0, p[3] = {p0.x + (p1.x - p0.x) * f, p0.y + (p1.y - p0.y) * f,
                                      p0.z + (p1.z - p0.z) * f};
        double w[3] = {p[0] - q0.x, p[1] - q0.y, p[2] - q0.z};
        double t = dd > 0 ? (w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / dd : 0.0;
        t = fmin(1.0, fmax(0.0, t));
        double e[3] = {w[0] - t * d[0], w[1] - t * d[1], w[2] - t * d[2]};
        best = fmin(best, sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]));
    }
    return best;
}

/* Whether the far end f of one segment folds back onto the other, s-g (s the node they share):
 * f lies within r of s-g at a point more than r from s, so not just the joint's own overlap. */
static inline bool so_folds_onto(xyl_vec3 f, xyl_vec3 s, xyl_vec3 g, double r)
{
    double d[3] = {g.x - s.x, g.y - s.y, g.z - s.z}, w[3] = {f.x - s.x, f.y - s.y, f.z - s.z};
    double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double t = dd > 0 ? fmin(1.0, fmax(0.0, (w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / dd)) : 0.0;
    double e[3] = {w[0] - t * d[0], w[1] - t * d[1], w[2] - t * d[2]};
    return sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) < r && t * sqrt(dd) > r;
}

/* Whether segments i and j (each given by its lower node, which has a parent) overlap in the
 * skeleton itself: closer than the sum of their radii where they share no node; where they share
 * one, when either folds back onto the other (a hairpin). */
static inline bool so_segments_overlap(const xyl_skeleton *sk, uint32_t i, uint32_t j)
{
    const xyl_skel_node *n = sk->nodes;
    uint32_t pi = (uint32_t)n[i].parent, pj = (uint32_t)n[j].parent;
    if (i == j) return false;
    double r = fmax(n[i].radius, n[pi].radius) + fmax(n[j].radius, n[pj].radius);
    if (i != pj && pi != j && pi != pj)
        return so_segment_distance(n[pi].pos, n[i].pos, n[pj].pos, n[j].pos) < r;
    uint32_t sh = i == pj ? i : j == pi ? j : pi; /* the shared node */
    uint32_t fi = sh == i ? pi : i, fj = sh == j ? pj : j;
    return so_folds_onto(n[fi].pos, n[sh].pos, n[fj].pos, r) ||
           so_folds_onto(n[fj].pos, n[sh].pos, n[fi].pos, r);
}

/* Whether the skeletons of branches a and b (a may be b) overlap themselves, in a way no
 * mesher can part without moving the skeleton: segments of a and b that overlap
 * (so_segments_overlap), where a and b are the same branch or unrelated (neither parent and
 * child nor children of one node: there the joint is the mesher's to build). seg gets the first
 * such segments (their lower nodes). */
static inline bool so_skeletons_cross(const xyl_skeleton *sk, const so_branches *br, uint32_t a,
                                      uint32_t b, uint32_t seg[2])
{
    const xyl_skel_node *n = sk->nodes;
    if (a != b) {
        int32_t fa = n[br->nodes[br->start[a]]].parent, fb = n[br->nodes[br->start[b]]].parent;
        if (fa == fb || (fa >= 0 && n[fa].branch == b) || (fb >= 0 && n[fb].branch == a))
            return false;
    }
    for (uint32_t x = br->start[a]; x < br->start[a + 1]; ++x) {
        uint32_t i = br->nodes[x];
        if (n[i].parent < 0) continue;
        for (uint32_t y = br->start[b]; y < br->start[b + 1]; ++y) {
            uint32_t j = br->nodes[y];
            if (n[j].parent >= 0 && so_segments_overlap(sk, i, j)) {
                seg[0] = i, seg[1] = j;
                return true;
            }
        }
    }
    return false;
}

/* The branch of triangle t of the mesh's triangulated view (two per quad, then triangles). */
static inline uint32_t so_tri_branch(const xyl_mesh *m, uint32_t t)
{
    size_t face = t < 2 * m->quad_count ? t / 2 : m->quad_count + (t - 2 * m->quad_count);
    return m->face_branches[face];
}

/* The intersecting pairs of a mesh, sorted into those at joints and those where the skeleton
 * overlaps itself. */
typedef struct so_tally {
    size_t pairs, joint, overlap;
    uint32_t joint_branches[2]; /* of the first pair (in pair order) at a joint */
    uint32_t overlap_seg[2];    /* the segments under the first pair the skeleton explains */
} so_tally;

typedef struct so_memo {
    uint64_t key; /* branch a << 32 | branch b */
    size_t pair;  /* its index in the caller's pairs */
    int verdict;  /* 0 joint, 1 overlap */
    uint32_t seg[2];
} so_memo;

static inline int so_memo_cmp(const void *x, const void *y)
{
    uint64_t a = ((const so_memo *)x)->key, b = ((const so_memo *)y)->key;
    if (a != b) return a < b ? -1 : 1;
    size_t i = ((const so_memo *)x)->pair, j = ((const so_memo *)y)->pair;
    return i < j ? -1 : i > j;
}

/* Classifies pairs[0 .. 2 count) (triangle indices, as xyl_mesh_self_intersections returns
 * them), each branch pair once. Returns false when out of memory. */
static inline bool so_classify(const xyl_skeleton *sk, const xyl_mesh *m, const uint32_t *pairs,
                               size_t count, so_tally *t)
{
    *t = (so_tally){count, 0, 0, {0, 0}, {0, 0}};
    so_branches br;
    so_memo *memo = malloc((count ? count : 1) * sizeof *memo);
    if (!memo || !so_branches_make(sk, &br)) {
        free(memo);
        return false;
    }
    for (size_t i = 0; i < count; ++i) {
        uint64_t a = so_tri_branch(m, pairs[2 * i]), b = so_tri_branch(m, pairs[2 * i + 1]);
        memo[i] = (so_memo){a << 32 | b, i, 0, {0, 0}};
    }
    qsort(memo, count, sizeof *memo, so_memo_cmp);
    size_t first_joint = SIZE_MAX, first_overlap = SIZE_MAX;
    for (size_t i = 0; i < count; ++i) {
        so_memo *e = &memo[i];
        if (i && memo[i - 1].key == e->key) {
            e->verdict = memo[i - 1].verdict;
            e->seg[0] = memo[i - 1].seg[0], e->seg[1] = memo[i - 1].seg[1];
        } else {
            uint32_t a = (uint32_t)(e->key >> 32), b = (uint32_t)e->key;
            e->verdict = so_skeletons_cross(sk, &br, a, b, e->seg);
        }
        if (e->verdict) {
            if (e->pair < first_overlap) {
                first_overlap = e->pair;
                t->overlap_seg[0] = e->seg[0], t->overlap_seg[1] = e->seg[1];
            }
            ++t->overlap;
        } else {
            if (e->pair < first_joint) {
                first_joint = e->pair;
                t->joint_branches[0] = (uint32_t)(e->key >> 32);
                t->joint_branches[1] = (uint32_t)e->key;
            }
            ++t->joint;
        }
    }
    so_branches_free(&br);
    free(memo);
    return true;
}

#endif

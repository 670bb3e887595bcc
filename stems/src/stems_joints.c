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

/* Raises the level of blamed branch b (UINT32_MAX: none can go) once per round: to 1, then
 * doubled (1, 2, 4, ... nodes later), so a lateral that must move far takes a few rounds, not
 * one per node; a level as high as the branch has nodes hides all of them, and goes no higher. */
static void raise_level(judge *j, uint32_t *drop, uint32_t b, xyl__joint_tally *t)
{
    if (b == UINT32_MAX || j->bumped[b]) return;
    const uint32_t nodes = j->start[b + 1] - j->start[b];
    if (drop[b] >= nodes) return;
    j->bumped[b] = 1;
    drop[b] = drop[b] ? (drop[b] > nodes / 2 ? nodes : 2 * drop[b]) : 1;
    ++t->marked;
}

/* Pairs at joints, each branch pair judged once (sorted keys, a verdict per run); pairs on one
 * branch are blamed one by one, by where they are. A blamed branch's level rises by one per
 * round, however many pairs blame it. */
xyl_result xyl__stems_judge_joints(const xyl_skeleton *sk, const xyl_mesh *m,
                                   const uint64_t *pairs, size_t count, uint32_t *drop,
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

/* ---- the pairs of a round, from the last round's ------------------------------------------ */

/* A mesh's triangles and vertices by branch: branch b's triangles are tri[tstart[b] ..
 * tstart[b + 1]) in view order, its vertices vert[vstart[b] ..) in index order; trank and vrank
 * give each one's place in its branch's list. */
typedef struct by_branch {
    uint32_t *tstart, *tri, *trank, *vstart, *vert, *vrank;
} by_branch;

static void by_branch_free(by_branch *x, const xyl_allocator *alloc)
{
    xyl__free(alloc, x->tstart);
    xyl__free(alloc, x->tri);
    xyl__free(alloc, x->trank);
    xyl__free(alloc, x->vstart);
    xyl__free(alloc, x->vert);
    xyl__free(alloc, x->vrank);
}

/* The branch of item i: vertex i's with keys (the mesh's branch ids), else triangle i's. */
static uint32_t branch_of(const xyl_mesh *m, const uint32_t *keys, size_t i)
{
    return keys ? keys[i] : m->face_branches[face_of(m, (uint32_t)i)];
}

/* Counting sort of n items by branch (< nb) into start (nb + 2 entries), list and rank. */
static void sort_by_branch(size_t n, size_t nb, const uint32_t *keys, const xyl_mesh *m,
                           uint32_t *start, uint32_t *list, uint32_t *rank)
{
    for (size_t i = 0; i < n; ++i) ++start[branch_of(m, keys, i) + 2];
    for (size_t b = 2; b < nb + 2; ++b) start[b] += start[b - 1];
    for (size_t i = 0; i < n; ++i) list[start[branch_of(m, keys, i) + 1]++] = (uint32_t)i;
    for (size_t b = 0; b < nb; ++b)
        for (uint32_t k = start[b]; k < start[b + 1]; ++k) rank[list[k]] = k - start[b];
}

static bool by_branch_make(by_branch *x, const xyl_mesh *m, size_t nb, const xyl_allocator *alloc)
{
    size_t nt = m->tri_view_count, nv = m->vertex_count;
    x->tstart = xyl__calloc(alloc, nb + 2, sizeof *x->tstart);
    x->vstart = xyl__calloc(alloc, nb + 2, sizeof *x->vstart);
    x->tri = xyl__alloc_array(alloc, nt ? nt : 1, sizeof *x->tri);
    x->trank = xyl__alloc_array(alloc, nt ? nt : 1, sizeof *x->trank);
    x->vert = xyl__alloc_array(alloc, nv ? nv : 1, sizeof *x->vert);
    x->vrank = xyl__alloc_array(alloc, nv ? nv : 1, sizeof *x->vrank);
    if (!x->tstart || !x->vstart || !x->tri || !x->trank || !x->vert || !x->vrank) return false;
    sort_by_branch(nt, nb, NULL, m, x->tstart, x->tri, x->trank);
    sort_by_branch(nv, nb, m->branch_ids, m, x->vstart, x->vert, x->vrank);
    return true;
}

static bool same_position(xyl_vec3 a, xyl_vec3 b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Per branch of m (clean[b] = 1) whether its triangles are those of the last round's mesh p,
 * bit for bit: the same corners in the same order, each at the same position and the same
 * vertex of the same branch (by its place among that branch's vertices, all of which are where
 * they were). A pair of two such triangles intersects in m exactly when it did in p. */
static void clean_branches(const xyl_mesh *p, const by_branch *bp, const xyl_mesh *m,
                           const by_branch *bm, size_t nb, uint8_t *vclean, uint8_t *clean)
{
    for (size_t b = 0; b < nb; ++b) {
        uint32_t n = bm->vstart[b + 1] - bm->vstart[b];
        vclean[b] = n == bp->vstart[b + 1] - bp->vstart[b];
        for (uint32_t i = 0; i < n && vclean[b]; ++i)
            vclean[b] = same_position(p->positions[bp->vert[bp->vstart[b] + i]],
                                      m->positions[bm->vert[bm->vstart[b] + i]]);
    }
    for (size_t b = 0; b < nb; ++b) {
        uint32_t n = bm->tstart[b + 1] - bm->tstart[b];
        clean[b] = n == bp->tstart[b + 1] - bp->tstart[b];
        for (uint32_t i = 0; i < n && clean[b]; ++i) {
            const uint32_t *cp = p->tri_view + 3 * (size_t)bp->tri[bp->tstart[b] + i];
            const uint32_t *cm = m->tri_view + 3 * (size_t)bm->tri[bm->tstart[b] + i];
            for (int q = 0; q < 3 && clean[b]; ++q)
                clean[b] = p->branch_ids[cp[q]] == m->branch_ids[cm[q]] &&
                           vclean[m->branch_ids[cm[q]]] && bp->vrank[cp[q]] == bm->vrank[cm[q]];
        }
    }
}

static int u64_compare(const void *pa, const void *pb)
{
    uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;
    return a < b ? -1 : a > b;
}

/* Whether triangle t of m has at most the area a (the test skips triangles at or below an area
 * set by the whole mesh's box, xyl__mesh_area_tolerance). */
static bool area_at_most(const xyl_mesh *m, size_t t, double a)
{
    const uint32_t *v = m->tri_view + 3 * t;
    xyl__dvec3 o = xyl__from_f3(m->positions[v[0]]);
    xyl__dvec3 n = xyl__d3_cross(xyl__d3_sub(xyl__from_f3(m->positions[v[1]]), o),
                                 xyl__d3_sub(xyl__from_f3(m->positions[v[2]]), o));
    return 0.5 * xyl__d3_len(n) <= a;
}

/* Pairs of m: those of the last round between two clean branches, moved to m's triangle
 * indices, and those the test finds with a triangle of a changed branch. Where the mesh's box,
 * and with it the degenerate area, changed, a triangle near that area is tested again too. */
static xyl_result pairs_since(const xyl_mesh *p, const uint64_t *pp, size_t pcount,
                              const xyl_mesh *m, size_t nb, const xyl_allocator *alloc,
                              uint64_t **pairs, size_t *count, xyl_diag *diag)
{
    const double tp = xyl__mesh_area_tolerance(p), tm = xyl__mesh_area_tolerance(m);
    const double near = tp != tm ? 2.0 * fmax(tp, tm) : -1.0;
    by_branch bp, bm;
    memset(&bp, 0, sizeof bp);
    memset(&bm, 0, sizeof bm);
    uint8_t *vclean = xyl__calloc(alloc, nb ? nb : 1, 1);
    uint8_t *clean = xyl__calloc(alloc, nb ? nb : 1, 1);
    uint8_t *marked = xyl__calloc(alloc, m->tri_view_count ? m->tri_view_count : 1, 1);
    uint64_t *fresh = NULL, *all = NULL;
    size_t nfresh = 0, n = 0;
    xyl_result r = XYL_OK;
    if (!vclean || !clean || !marked || !by_branch_make(&bp, p, nb, alloc) ||
        !by_branch_make(&bm, m, nb, alloc)) {
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory checking the joints");
        goto done;
    }
    clean_branches(p, &bp, m, &bm, nb, vclean, clean);
    for (size_t t = 0; t < m->tri_view_count; ++t)
        marked[t] = !clean[m->face_branches[face_of(m, (uint32_t)t)]] ||
                    (near >= 0.0 && area_at_most(m, t, near));
    r = xyl__mesh_intersecting_pairs_marked(m, marked, alloc, &fresh, &nfresh, diag);
    if (r) goto done;
    all = xyl__alloc_array(alloc, nfresh + pcount ? nfresh + pcount : 1, sizeof *all);
    if (!all) {
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory checking the joints");
        goto done;
    }
    if (nfresh) memcpy(all, fresh, nfresh * sizeof *all);
    n = nfresh;
    for (size_t i = 0; i < pcount; ++i) {
        uint32_t t[2] = {(uint32_t)(pp[i] >> 32), (uint32_t)pp[i]};
        uint32_t b0 = p->face_branches[face_of(p, t[0])], b1 = p->face_branches[face_of(p, t[1])];
        if (!clean[b0] || !clean[b1]) continue; /* found again, or gone */
        uint64_t u = bm.tri[bm.tstart[b0] + bp.trank[t[0]]];
        uint64_t v = bm.tri[bm.tstart[b1] + bp.trank[t[1]]];
        if (marked[u] || marked[v]) continue; /* found again */
        all[n++] = u < v ? u << 32 | v : v << 32 | u;
    }
    xyl__sort(all, n, sizeof *all, u64_compare);
done:
    if (r) {
        xyl__free(alloc, all);
        all = NULL;
        n = 0;
    }
    by_branch_free(&bp, alloc);
    by_branch_free(&bm, alloc);
    xyl__free(alloc, vclean);
    xyl__free(alloc, clean);
    xyl__free(alloc, marked);
    xyl__free(alloc, fresh);
    *pairs = all;
    *count = n;
    return r;
}

xyl_result xyl__stems_joint_pairs(const xyl_skeleton *sk, const xyl_mesh *prev,
                                  const uint64_t *prev_pairs, size_t prev_count,
                                  const xyl_mesh *m, const xyl_allocator *alloc, uint64_t **pairs,
                                  size_t *count, xyl_diag *diag)
{
    *pairs = NULL;
    *count = 0;
    if (!prev) return xyl__mesh_intersecting_pairs(m, alloc, pairs, count, diag);
    return pairs_since(prev, prev_pairs, prev_count, m, sk->branch_count, alloc, pairs, count,
                       diag);
}

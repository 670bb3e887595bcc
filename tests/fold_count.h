/* Folds of a stem mesh (docs/stems.md, "Folds"): edges whose two faces' normals differ by more
 * than 150 degrees, where the surface turns back on itself (a fin, a blade, a shelf). A quad's
 * normal is the cross product of its diagonals, a triangle's that of two sides. Each fold is
 * sorted by where it lies, from the mesh's own marks (face branches, vertex branches, UVs) and
 * the skeleton. Shared by the suites that hold fold counts (test_stems.c); needs no cmocka. */
#ifndef XYL_FOLD_COUNT_H
#define XYL_FOLD_COUNT_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <xylem/xyl_mesh.h>
#include <xylem/xyl_skeleton.h>

#include "skel_overlap.h"

/* cos 150 degrees: normals further apart than this fold */
#define FC_COS_FOLD (-0.86602540378443865)

/* Where a fold lies, by its two faces: first the one whose rule matches first. */
typedef enum fc_cause {
    FC_ROOT_CAP,      /* a face of a root's cap */
    FC_TWIG_TIP_CAP,  /* the tip cap of a lateral of one band (bridge ring, then its tip ring) */
    FC_TIP_CAP,       /* any other tip cap */
    FC_BRIDGE_PARENT, /* a bridge face against its parent's band (the patch's rim) */
    FC_BRIDGE_BRIDGE, /* two faces of one bridge */
    FC_BRIDGE_BAND,   /* a bridge face against its lateral's first band */
    FC_FIRST_BAND,    /* two faces of a lateral's first band (one touches the bridge ring) */
    FC_FORK_RINGS,    /* two band faces on a ring nearest a fork node (one with laterals) */
    FC_BEND_RINGS,    /* two band faces on a ring nearest a node without laterals */
    FC_OTHER,
    FC_CAUSES
} fc_cause;

static const char *const fc_cause_names[FC_CAUSES] = {
    "root cap", "tip cap of a one-band twig", "other tip cap", "bridge against parent band",
    "bridge against bridge", "bridge against first band", "lateral's first band",
    "band rings at a fork", "band rings at a bend", "other"};

typedef struct fc_tally {
    size_t edges;              /* manifold edges (two faces) */
    size_t folds;              /* of them, folds */
    size_t by_cause[FC_CAUSES];
    size_t overlapped;         /* folds near a place where the skeleton overlaps itself */
    uint32_t first_branch[FC_CAUSES]; /* the branch of the first fold of each cause */
} fc_tally;

typedef struct fc_edge {
    uint64_t key; /* min vertex << 32 | max vertex */
    uint32_t face;
} fc_edge;

static inline int fc_edge_cmp(const void *x, const void *y)
{
    const fc_edge *a = x, *b = y;
    if (a->key != b->key) return a->key < b->key ? -1 : 1;
    return a->face < b->face ? -1 : a->face > b->face;
}

static inline uint32_t fc_corners(const xyl_mesh *m, size_t f, const uint32_t **idx)
{
    if (f < m->quad_count) {
        *idx = m->quads + 4 * f;
        return 4;
    }
    *idx = m->triangles + 3 * (f - m->quad_count);
    return 3;
}

/* A face's normal (unnormalised, in double). */
static inline void fc_normal(const xyl_mesh *m, size_t f, double n[3])
{
    const uint32_t *c;
    uint32_t nc = fc_corners(m, f, &c);
    const xyl_vec3 *p = m->positions;
    double e[3], g[3];
    if (nc == 4) {
        e[0] = p[c[2]].x - p[c[0]].x, e[1] = p[c[2]].y - p[c[0]].y, e[2] = p[c[2]].z - p[c[0]].z;
        g[0] = p[c[3]].x - p[c[1]].x, g[1] = p[c[3]].y - p[c[1]].y, g[2] = p[c[3]].z - p[c[1]].z;
    } else {
        e[0] = p[c[1]].x - p[c[0]].x, e[1] = p[c[1]].y - p[c[0]].y, e[2] = p[c[1]].z - p[c[0]].z;
        g[0] = p[c[2]].x - p[c[0]].x, g[1] = p[c[2]].y - p[c[0]].y, g[2] = p[c[2]].z - p[c[0]].z;
    }
    n[0] = e[1] * g[2] - e[2] * g[1];
    n[1] = e[2] * g[0] - e[0] * g[2];
    n[2] = e[0] * g[1] - e[1] * g[0];
}

/* Whether the normals of faces f and g are more than 150 degrees apart (a face without area has
 * no normal and folds nowhere). */
static inline bool fc_folds(const xyl_mesh *m, size_t f, size_t g)
{
    double a[3], b[3];
    fc_normal(m, f, a);
    fc_normal(m, g, b);
    double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    if (!(la > 0.0) || !(lb > 0.0)) return false;
    return (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb) < FC_COS_FOLD;
}

/* The mesh's edges, sorted, each once per face that uses it; NULL when out of memory. */
static inline fc_edge *fc_edges(const xyl_mesh *m, size_t *count)
{
    size_t faces = m->quad_count + m->triangle_count, n = 4 * m->quad_count + 3 * m->triangle_count;
    fc_edge *e = malloc((n ? n : 1) * sizeof *e);
    if (!e) return NULL;
    size_t w = 0;
    for (size_t f = 0; f < faces; ++f) {
        const uint32_t *c;
        uint32_t nc = fc_corners(m, f, &c);
        for (uint32_t i = 0; i < nc; ++i) {
            uint64_t a = c[i], b = c[(i + 1) % nc];
            e[w++] = (fc_edge){a < b ? a << 32 | b : b << 32 | a, (uint32_t)f};
        }
    }
    qsort(e, w, sizeof *e, fc_edge_cmp);
    *count = w;
    return e;
}

/* The number of folds of a mesh: edges shared by exactly two faces whose normals differ by more
 * than 150 degrees. Returns SIZE_MAX when out of memory. */
static inline size_t fc_count(const xyl_mesh *m)
{
    size_t n = 0, folds = 0;
    fc_edge *e = fc_edges(m, &n);
    if (!e) return SIZE_MAX;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && e[j].key == e[i].key) ++j;
        if (j - i == 2 && fc_folds(m, e[i].face, e[i + 1].face)) ++folds;
        i = j;
    }
    free(e);
    return folds;
}

/* ---- causes -------------------------------------------------------------------------------- */

typedef enum fc_kind { FC_BAND, FC_CAP, FC_BRIDGE } fc_kind;

/* A bridge face holds a vertex of another branch (its parent's patch rim); a cap has three or
 * more corners on one ring (one v: a flat cap, or a dome's ring corners beside its apex), or is
 * a triangle not on a bridge; a band quad has two on each of its rings. */
static inline fc_kind fc_face_kind(const xyl_mesh *m, size_t f)
{
    const uint32_t *c;
    uint32_t nc = fc_corners(m, f, &c), b = m->face_branches[f];
    for (uint32_t i = 0; i < nc; ++i)
        if (m->branch_ids[c[i]] != b) return FC_BRIDGE;
    if (nc == 3) return FC_CAP; /* bands are quads; odd k's one triangle is a cap's or a bridge's */
    for (uint32_t i = 0; i < nc; ++i) {
        uint32_t same = 0;
        for (uint32_t j = 0; j < nc; ++j) same += m->uvs[2 * c[j] + 1] == m->uvs[2 * c[i] + 1];
        if (same >= 3) return FC_CAP;
    }
    return FC_BAND;
}

typedef struct fc_ctx {
    const xyl_skeleton *sk;
    const xyl_mesh *m;
    uint32_t k;            /* ring sides */
    float *vmin;           /* per branch: the least v of its vertices (its first ring) */
    uint32_t *ring_verts;  /* per branch: its vertices with v on a ring (caps' apexes left out) */
    bool *root_branch;     /* per branch */
    bool *fork;            /* per node: a node with a child on another branch */
} fc_ctx;

static inline void fc_ctx_free(fc_ctx *c)
{
    free(c->vmin);
    free(c->ring_verts);
    free(c->root_branch);
    free(c->fork);
}

static inline bool fc_ctx_make(const xyl_skeleton *sk, const xyl_mesh *m, uint32_t k, fc_ctx *c)
{
    size_t nb = sk->branch_count ? sk->branch_count : 1;
    *c = (fc_ctx){sk, m, k, malloc(nb * sizeof(float)), calloc(nb, sizeof(uint32_t)),
                  calloc(nb, sizeof(bool)), calloc(sk->node_count ? sk->node_count : 1, 1)};
    if (!c->vmin || !c->ring_verts || !c->root_branch || !c->fork) {
        fc_ctx_free(c);
        return false;
    }
    for (size_t b = 0; b < nb; ++b) c->vmin[b] = INFINITY;
    for (uint32_t i = 0; i < sk->node_count; ++i) {
        int32_t p = sk->nodes[i].parent;
        if (p < 0) c->root_branch[sk->nodes[i].branch] = true;
        else if (sk->nodes[p].branch != sk->nodes[i].branch) c->fork[p] = true;
    }
    for (size_t v = 0; v < m->vertex_count; ++v) {
        uint32_t b = m->branch_ids[v];
        if (b < nb && m->uvs[2 * v + 1] < c->vmin[b]) c->vmin[b] = m->uvs[2 * v + 1];
    }
    /* a dome cap's apex is the one vertex that no band or bridge face uses */
    size_t faces = m->quad_count + m->triangle_count;
    bool *on_ring = calloc(m->vertex_count ? m->vertex_count : 1, 1);
    if (!on_ring) {
        fc_ctx_free(c);
        return false;
    }
    for (size_t f = 0; f < faces; ++f) {
        if (fc_face_kind(m, f) == FC_CAP) continue;
        const uint32_t *cc;
        uint32_t nc = fc_corners(m, f, &cc);
        for (uint32_t i = 0; i < nc; ++i) on_ring[cc[i]] = true;
    }
    for (size_t v = 0; v < m->vertex_count; ++v)
        if (on_ring[v] && m->branch_ids[v] < nb) ++c->ring_verts[m->branch_ids[v]];
    free(on_ring);
    return true;
}

/* Whether the shared edge a-b of two band faces of branch b lies on its first ring. */
static inline bool fc_touches_first_ring(const fc_ctx *c, uint32_t b, uint32_t a, uint32_t e)
{
    return c->m->uvs[2 * a + 1] == c->vmin[b] || c->m->uvs[2 * e + 1] == c->vmin[b];
}

/* The node of branch b nearest to point q. */
static inline uint32_t fc_nearest_node(const xyl_skeleton *sk, uint32_t b, const double q[3])
{
    uint32_t best = UINT32_MAX;
    double bd = INFINITY;
    for (uint32_t i = 0; i < sk->node_count; ++i) {
        if (sk->nodes[i].branch != b) continue;
        double d[3] = {sk->nodes[i].pos.x - q[0], sk->nodes[i].pos.y - q[1],
                       sk->nodes[i].pos.z - q[2]};
        double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if (dd < bd) bd = dd, best = i;
    }
    return best;
}

static inline fc_cause fc_classify(const fc_ctx *c, uint32_t f, uint32_t g, uint32_t a,
                                   uint32_t e)
{
    const xyl_mesh *m = c->m;
    fc_kind kf = fc_face_kind(m, f), kg = fc_face_kind(m, g);
    uint32_t bf = m->face_branches[f], bg = m->face_branches[g];
    for (int s = 0; s < 2; ++s) {
        uint32_t face = s ? g : f, b = s ? bg : bf;
        if ((s ? kg : kf) != FC_CAP) continue;
        const uint32_t *cc;
        fc_corners(m, face, &cc);
        if (c->root_branch[b] && m->uvs[2 * cc[0] + 1] == c->vmin[b]) return FC_ROOT_CAP;
    }
    for (int s = 0; s < 2; ++s) {
        uint32_t b = s ? bg : bf;
        if ((s ? kg : kf) != FC_CAP) continue;
        /* a lateral of one band has two rings: its bridge ring and its tip ring */
        return !c->root_branch[b] && c->ring_verts[b] == 2 * c->k ? FC_TWIG_TIP_CAP : FC_TIP_CAP;
    }
    if (kf == FC_BRIDGE && kg == FC_BRIDGE) return FC_BRIDGE_BRIDGE;
    if (kf == FC_BRIDGE || kg == FC_BRIDGE) return bf == bg ? FC_BRIDGE_BAND : FC_BRIDGE_PARENT;
    if (bf != bg) return FC_OTHER;
    if (!c->root_branch[bf] && fc_touches_first_ring(c, bf, a, e)) return FC_FIRST_BAND;
    const xyl_vec3 *p = m->positions;
    double q[3] = {0.5 * ((double)p[a].x + p[e].x), 0.5 * ((double)p[a].y + p[e].y),
                   0.5 * ((double)p[a].z + p[e].z)};
    uint32_t node = fc_nearest_node(c->sk, bf, q);
    if (node == UINT32_MAX) return FC_OTHER;
    return c->fork[node] ? FC_FORK_RINGS : FC_BEND_RINGS;
}

/* Whether branches a and b are related: one the other's parent, or both children of one node
 * (where the joint is the mesher's to build, docs/stems.md). */
static inline bool fc_related(const xyl_skeleton *sk, const uint32_t *first, uint32_t a, uint32_t b)
{
    int32_t fa = sk->nodes[first[a]].parent, fb = sk->nodes[first[b]].parent;
    return fa == fb || (fa >= 0 && sk->nodes[fa].branch == b) ||
           (fb >= 0 && sk->nodes[fb].branch == a);
}

/* Whether the skeleton overlaps itself near point q, as docs/stems.md ("Where the skeleton
 * overlaps itself") says: the segment nearest q (by its lower node) overlaps another segment
 * (so_segments_overlap) of its own branch or of an unrelated one. first: each branch's first
 * node. */
static inline bool fc_overlap_near(const xyl_skeleton *sk, const uint32_t *first, const double q[3])
{
    const xyl_skel_node *n = sk->nodes;
    uint32_t near = UINT32_MAX;
    double bd = INFINITY;
    xyl_vec3 qf = {(float)q[0], (float)q[1], (float)q[2]};
    for (uint32_t i = 0; i < sk->node_count; ++i) {
        if (n[i].parent < 0) continue;
        double d = so_segment_distance(n[n[i].parent].pos, n[i].pos, qf, qf);
        if (d < bd) bd = d, near = i;
    }
    if (near == UINT32_MAX) return false;
    const xyl_vec3 a = n[n[near].parent].pos, b = n[near].pos;
    double ra = fmax(n[near].radius, n[n[near].parent].radius);
    double la = 0.5 * sqrt(((double)b.x - a.x) * (b.x - a.x) + ((double)b.y - a.y) * (b.y - a.y) +
                           ((double)b.z - a.z) * (b.z - a.z));
    for (uint32_t j = 0; j < sk->node_count; ++j) {
        if (n[j].parent < 0 || j == near) continue;
        if (n[j].branch != n[near].branch && fc_related(sk, first, n[j].branch, n[near].branch))
            continue;
        const xyl_vec3 c = n[n[j].parent].pos, e = n[j].pos;
        double rb = fmax(n[j].radius, n[n[j].parent].radius);
        double lb = 0.5 * sqrt(((double)e.x - c.x) * (e.x - c.x) +
                               ((double)e.y - c.y) * (e.y - c.y) + ((double)e.z - c.z) * (e.z - c.z));
        double m[3] = {0.5 * ((double)a.x + b.x - c.x - e.x), 0.5 * ((double)a.y + b.y - c.y - e.y),
                       0.5 * ((double)a.z + b.z - c.z - e.z)};
        /* the segments are at least this far apart: skip the fine test */
        if (sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]) - la - lb > ra + rb) continue;
        if (so_segments_overlap(sk, near, j)) return true;
    }
    return false;
}

/* Counts and sorts the folds of mesh m (ring sides k) of skeleton sk. Returns false when out of
 * memory. */
static inline bool fc_tally_of(const xyl_skeleton *sk, const xyl_mesh *m, uint32_t k, fc_tally *t)
{
    memset(t, 0, sizeof *t);
    fc_ctx c;
    size_t n = 0;
    if (!fc_ctx_make(sk, m, k, &c)) return false;
    fc_edge *e = fc_edges(m, &n);
    uint32_t *first = malloc((sk->branch_count ? sk->branch_count : 1) * sizeof *first);
    if (!e || !first) {
        free(e);
        free(first);
        fc_ctx_free(&c);
        return false;
    }
    for (uint32_t i = sk->node_count; i-- > 0;) first[sk->nodes[i].branch] = i;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && e[j].key == e[i].key) ++j;
        if (j - i == 2) {
            ++t->edges;
            if (fc_folds(m, e[i].face, e[i + 1].face)) {
                uint32_t a = (uint32_t)(e[i].key >> 32), b = (uint32_t)e[i].key;
                fc_cause cause = fc_classify(&c, e[i].face, e[i + 1].face, a, b);
                if (!t->by_cause[cause]) t->first_branch[cause] = m->face_branches[e[i].face];
                ++t->by_cause[cause];
                ++t->folds;
                const xyl_vec3 *p = m->positions;
                double q[3] = {0.5 * ((double)p[a].x + p[b].x), 0.5 * ((double)p[a].y + p[b].y),
                               0.5 * ((double)p[a].z + p[b].z)};
                t->overlapped += fc_overlap_near(sk, first, q);
            }
        }
        i = j;
    }
    free(e);
    free(first);
    fc_ctx_free(&c);
    return true;
}

#endif

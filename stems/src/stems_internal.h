/* The stem mesher's state and what its files (stems_*.c) share. Not installed. */
#ifndef XYL_STEMS_INTERNAL_H
#define XYL_STEMS_INTERNAL_H

#include "mesh_internal.h"
#include "xylem/xyl_stems.h"

/* The SSE2 loops stand for scalar ones with the same operations in the same order, and give the
 * same bits; XYL_NO_SIMD compiles the scalar ones alone (tests/stems_scalar.c builds the mesher
 * so, to check that). */
#if defined(__SSE2__) && !defined(XYL_NO_SIMD)
#define XYL__SSE2 1
#include <emmintrin.h>
#endif

/* The linkage of the functions below that the mesher's files share. tests/stems_scalar.c
 * compiles those files once more, without SSE2, in one translation unit and defines this as
 * static there: its copy then neither clashes with the library's nor stands in for any of it.
 * (stems_merge.c and stems_joints.c have no SIMD loops; the copy calls the library's.) */
#ifndef XYL__STEMS_SHARED
#define XYL__STEMS_SHARED
#endif

/* One ring of a branch tube, and the patch bookkeeping of the band that follows it. */
typedef struct stems_ring {
    uint32_t first;     /* first of its k vertices */
    xyl__dvec3 centre, tangent, u;
    double radius;
    double v;           /* texture v: arc length / (2 pi radius) along the branch */
    uint32_t band;      /* first quad of the band from this ring to the next */
} stems_ring;

/* A closed base: its ring's first vertex and the root's axis, into the tree. */
typedef struct stems_base {
    uint32_t first;
    uint32_t k;         /* its ring's sides */
    xyl__dvec3 up;
} stems_base;

/* A place along a branch where a ring goes: one or more coincident skeleton nodes. */
typedef struct stems_station {
    xyl__dvec3 p;
    double r;
    uint32_t first, last; /* chain indices of the nodes merged here */
} stems_station;

/* A lateral child waiting for its branch to be built from its bridge ring. */
typedef struct stems_pending {
    uint32_t node;      /* the child's first skeleton node */
    uint32_t k;         /* its ring sides */
    stems_ring bridge;  /* the ring its bridge ends in */
} stems_pending;

/* The rings lo .. hi around the fork at station `station` of the branch being built. */
typedef struct stems_fork_span {
    size_t station, lo, hi;
} stems_fork_span;

/* The first segment of a lateral child's tube: from its bridge ring to its first station. */
typedef struct xyl__stems_cone {
    xyl__dvec3 p0, p1;
    double r0, r1;
} xyl__stems_cone;

/* What ring vertices of k sides need: their directions, texture u, and the factors that
 * depend on k (docs/stems.md, "Ring sides per branch"). */
typedef struct stems_sides {
    double cos_a[32], sin_a[32]; /* ring vertex directions, j = 0 .. k - 1 */
    float u_of[32];              /* texture u of ring vertex j: j / k */
    double align_cos;            /* cos of the smallest step align_to_outline takes */
    double inflate;              /* ring radius factor before subdivision */
} stems_sides;

typedef struct stems {
    const xyl_skeleton *sk;
    uint32_t k;         /* ring sides of the branch being built (xyl__stems_set_sides) */
    uint32_t kmax;      /* xyl_stems_desc.sides: the most any branch gets */
    const uint8_t *branch_sides; /* per skeleton branch, the sides error_world gives it, or
                                    NULL: every branch gets kmax */
    uint32_t per_band_min; /* the fewest patches a band offers any lateral (ring_bound) */
    uint32_t by_sides[33]; /* branch tubes built with k sides, at [k] */
    uint32_t clamped;      /* laterals that got fewer sides than their budget's */
    bool sides_refined;    /* xyl_stems_desc.sides_refined: the model of ring_error_max */
    double ring_error_max; /* the largest radial ring error of a tube built: its widest node's
                              radius times the model's error of its k */
    stems_sides tab[33];   /* per k in use */
    double inflate;     /* ring radius factor before Catmull-Clark: 1 / mean limit radius */
    bool limit_centres; /* before subdivision: ring centres moved against the limit's pull */
    xyl_allocator alloc;
    xyl_diag *diag;
    uint64_t max_vertices, max_faces;

    /* children of every node: child_list[child_start[n] .. child_start[n + 1]) */
    uint32_t *child_start, *child_list;
    uint32_t *main;      /* per node: the child continuing its branch, or UINT32_MAX */
    const double *cos_a, *sin_a; /* tab[k]'s, for the branch being built */
    const float *u_of;
    double align_cos;

    /* output */
    xyl_vec3 *pos;
    float *uv;
    uint32_t *vbranch;
    xyl_vec3 *nrm;  /* branch normals without subdivision: each vertex's sum of own-branch quad
                       normals, added as the quads are made (NULL otherwise) */
    bool sum_normals;   /* branch normals, no subdivision: nrm is summed while meshing */
    bool unit_per_branch; /* nrm of a branch's vertices is normalised once it is built */
    bool lonely;        /* some vertex has no own-branch face normal (see xyl__mesh_normals) */
    uint32_t apex[2];   /* the domed caps' apexes of the branch being built (root, tip), or
                           UINT32_MAX (k < 5, no root cap) */
    bool open_base;     /* roots get no cap (XYL_STEMS_BASE_OPEN) */
    double root_flare;  /* xyl_stems_desc.root_flare */
    stems_base *bases;  /* each capped root ring, whose k edges subdivision keeps as creases
                           (docs/stems.md, "The base") */
    size_t nbase, bcap;
    size_t nv, vcap;
    uint32_t *quads, *fbranch;
    uint8_t *qwrap; /* per quad: its uv_wraps bits, set as it is made */
    size_t nq, qcap;
    uint32_t *tris, *tbranch; /* odd k only: one triangle per cap and per bridge */
    uint8_t *twrap;
    size_t nt, tcap3;
    uint8_t *taken; /* per quad: replaced by a child's bridge */
    size_t tcap;

    /* the branch being built */
    uint32_t *chain;
    size_t nchain, ccap;
    stems_station *stations;
    size_t nstations, scap;
    stems_ring *rings;
    size_t nrings, rcap;

    stems_fork_span *spans; /* the forks of the branch being built */
    size_t spcap;

    stems_pending *pending;
    size_t npending, pcap;

    xyl__stems_cone *cones; /* the laterals placed so far at the fork being attached */
    size_t ncones, cone_cap;

    double *tails; /* while indexing: per node, the box around its chain's tubes from it on */
    const uint32_t *drop; /* per skeleton branch, or NULL: checked joints' level, the nodes a
                             lateral hides at its start beyond those the placement hides */
    double *shift;   /* with drop, per skeleton branch, or NULL: how far a raised lateral now
                        starts beyond where the placement would start it, along its skeleton */
    uint8_t *hidden; /* with shift: 1 where a raised lateral has no node left to mesh */
} stems;

/* Fills tails (6 per node: low and high corner) with the bounding box of each node's ball and
 * the tubes of its chain after it (stems_merge.c). Needs main. */
void xyl__stems_tail_boxes(const stems *s, double *tails);

/* Whether lateral a comes before lateral b where siblings are ordered: thicker first, then in
 * node order. */
static inline bool xyl__lateral_before(const xyl_skeleton *sk, uint32_t a, uint32_t b)
{
    float ra = sk->nodes[a].radius, rb = sk->nodes[b].radius;
    return ra != rb ? ra > rb : a < b;
}

/* Which nodes are meshed, and from where (stems_merge.c): fills parent_of (node_count entries)
 * with each node's parent as meshed. A lateral's nodes are hidden while they lie in its
 * parent's tube or in one placed before it there (a thicker sibling's, or the meshed part of a
 * chain its fork is hidden in); its first node is then detached (-1) and its first clear one
 * hangs from the nearest node of the tube it left. Laterals of hidden nodes grow out of the
 * meshed node their fork is hidden at. scratch: 4 node_count entries. Needs child_start,
 * child_list and main of the skeleton's own tree. Returns whether any lateral moved. */
bool xyl__stems_place_laterals(const stems *s, int32_t *parent_of, uint32_t *scratch);

/* Overlapping laterals of one node of the tree as meshed (stems_merge.c): updates parent_of:
 * a lateral merged into a sibling is detached (-1) and the rest of it hangs from the sibling;
 * a lateral the placement moved that lies in its new fork's tube all along is detached too.
 * Needs child_start, child_list and main of the tree parent_of describes. Returns whether
 * anything merged. */
bool xyl__stems_merge_siblings(const stems *s, int32_t *parent_of);

/* Whether two cones come closer than their radii at their axes' closest points: a cheap test
 * for two lateral tubes that would cross (stems_merge.c). */
bool xyl__cones_clash(const xyl__stems_cone *a, const xyl__stems_cone *b);

/* Closest points of segments p0-p1 and q0-q1 as parameters *s, *t in [0, 1] (stems_merge.c). */
void xyl__closest_params(xyl__dvec3 p0, xyl__dvec3 p1, xyl__dvec3 q0, xyl__dvec3 q1, double *s,
                         double *t);

/* The most v grows along one segment, in circumferences (docs/stems.md, "Normals, UVs and
 * seams"). */
#define XYL__STEMS_MAX_DV 65536.0

/* How far a closed base's apex (k >= 5) lies inside the root ring, in ring radii: enough for
 * its faces to meet at an angle (a flat fan's coplanar faces sharing a vertex cannot be told
 * from touching once rounded), little enough to look flat. */
#define XYL__STEMS_BASE_DEPTH 0.1

/* What xyl__stems_judge_joints found in one mesh. */
typedef struct xyl__joint_tally {
    size_t joint;   /* intersecting pairs at joints */
    size_t own;     /* intersecting pairs that the skeleton's own overlaps explain */
    uint32_t marked; /* levels raised in drop (at most one per branch and round) */
} xyl__joint_tally;

/* Sorts the intersecting pairs of mesh m, built from sk, into those at joints and those where
 * the skeleton overlaps itself (docs/stems.md, "Checked joints"), and raises in drop (one level
 * per skeleton branch) the level of a lateral blamed for each pair at a joint (stems_joints.c).
 * pairs: i << 32 | j triangle indices of m's triangulated view. Errors: XYL_ERR_OUT_OF_MEMORY. */
xyl_result xyl__stems_judge_joints(const xyl_skeleton *sk, const xyl_mesh *m,
                                   const uint64_t *pairs, size_t count, uint32_t *drop,
                                   const xyl_allocator *alloc, xyl__joint_tally *t, xyl_diag *diag);

/* Every intersecting pair of mesh m (as xyl__mesh_intersecting_pairs gives them: i << 32 | j,
 * sorted, from alloc) for a round of checked joints. With the last round's mesh prev and its
 * pairs, only triangles of branches whose triangles changed are tested (against all), and the
 * last round's pairs between unchanged branches are carried over: the same pairs a full test
 * finds, at a fraction of its cost when a round moves a few laterals. prev NULL: the full test.
 * Errors: those of xyl__mesh_intersecting_pairs. */
xyl_result xyl__stems_joint_pairs(const xyl_skeleton *sk, const xyl_mesh *prev,
                                  const uint64_t *prev_pairs, size_t prev_count,
                                  const xyl_mesh *m, const xyl_allocator *alloc, uint64_t **pairs,
                                  size_t *count, xyl_diag *diag);

/* ---- small inline functions of the mesher's files ------------------------------------------ */

#ifdef XYL__SSE2
/* Lanes (v[i].x, v[i1].x) and so on as doubles, built in registers: stores of single floats
 * read back as a pair would stall on store forwarding. */
static XYL__ALWAYS_INLINE void xyl__load_pair(const xyl_vec3 *v, uint32_t i, uint32_t i1,
                                              __m128d *out)
{
    out[0] = _mm_set_pd((double)v[i1].x, (double)v[i].x);
    out[1] = _mm_set_pd((double)v[i1].y, (double)v[i].y);
    out[2] = _mm_set_pd((double)v[i1].z, (double)v[i].z);
}

/* The low two lanes of x, y and z (floats) as out[0] and out[1]. */
static XYL__ALWAYS_INLINE void xyl__store_pair(__m128 x, __m128 y, __m128 z, xyl_vec3 *out)
{
    out[0].x = _mm_cvtss_f32(x);
    out[0].y = _mm_cvtss_f32(y);
    out[0].z = _mm_cvtss_f32(z);
    out[1].x = _mm_cvtss_f32(_mm_shuffle_ps(x, x, 1));
    out[1].y = _mm_cvtss_f32(_mm_shuffle_ps(y, y, 1));
    out[1].z = _mm_cvtss_f32(_mm_shuffle_ps(z, z, 1));
}
#endif

/* The child that continues n's branch (same branch id), or UINT32_MAX at a tip. */
static inline uint32_t xyl__stems_main_child(const stems *s, uint32_t n)
{
    return s->main[n];
}

static inline xyl__dvec3 xyl__stems_node_pos(const stems *s, uint32_t n)
{
    return xyl__from_f3(s->sk->nodes[n].pos);
}

/* The unit direction from a to b; fallback where they coincide. */
static inline xyl__dvec3 xyl__dir_between(xyl__dvec3 a, xyl__dvec3 b, xyl__dvec3 fallback)
{
    return xyl__d3_normalize_or(xyl__d3_sub(b, a), fallback);
}

/* ---- output (stems_build.c; the usual cases inline) ---------------------------------------- */

/* Room in the output arrays for verts vertices and quads quads; false when out of memory. The
 * usual case, reserved up front, is decided inline; xyl__stems_reserve_slow grows the arrays. */
XYL__STEMS_SHARED bool xyl__stems_reserve_slow(stems *s, size_t verts, size_t quads);
static inline bool xyl__stems_reserve(stems *s, size_t verts, size_t quads)
{
    if (verts <= s->vcap && quads <= s->qcap) return true;
    return xyl__stems_reserve_slow(s, verts, quads);
}

/* Adds quad q's normal to the sums of its vertices of its branch. Quads are made in index order
 * and their vertices are final by then, so each vertex sums the same faces in the same order as
 * xyl__mesh_normals would, while they are still in cache. */
static inline void xyl__stems_sum_quad_normal(stems *s, const uint32_t *q, uint32_t branch)
{
    xyl_vec3 fn = xyl__quad_normal(s->pos, q);
    for (int k = 0; k < 4; ++k)
        if (s->vbranch[q[k]] == branch) xyl__add_f3(&s->nrm[q[k]], fn);
}

/* The uv_wraps bits of a face of n corners (idx), by the rule of xyl__uv_wraps_of. Band quads
 * do not come here (put_band_k knows theirs); caps and bridge faces do. */
static inline uint8_t xyl__stems_face_wraps(const stems *s, const uint32_t *idx, int n)
{
    float u[4];
    for (int c = 0; c < n; ++c) u[c] = s->uv[2 * idx[c]];
    return xyl__uv_wraps_of(u, n);
}

/* Appends a quad; its branch is the branch being built. */
static inline void xyl__stems_put_quad(stems *s, uint32_t a, uint32_t b, uint32_t c, uint32_t d,
                                       uint32_t branch)
{
    size_t n = s->nq;
    uint32_t *q = s->quads + 4 * n;
    q[0] = a;
    q[1] = b;
    q[2] = c;
    q[3] = d;
    s->fbranch[n] = branch;
    s->qwrap[n] = xyl__stems_face_wraps(s, q, 4);
    s->nq = n + 1;
    if (s->nrm) xyl__stems_sum_quad_normal(s, q, branch);
}

/* XYL_ERR_OUT_OF_MEMORY, told to s->diag. */
XYL__STEMS_SHARED xyl_result xyl__stems_oom(stems *s);

/* Appends a triangle (odd k: caps and bridges have one). */
XYL__STEMS_SHARED xyl_result xyl__stems_put_tri(stems *s, uint32_t a, uint32_t b, uint32_t c,
                                                uint32_t branch);

/* ---- the tree as meshed (stems_tree.c) ----------------------------------------------------- */

/* Indexes the children and main child of every node (child_start, child_list, main) of the tree
 * as meshed: laterals placed out of their parent's tube, overlapping siblings merged, and the
 * branches s->drop leaves out detached. */
XYL__STEMS_SHARED xyl_result xyl__stems_index_tree(stems *s);

/* ---- a branch's tube (stems_rings.c) ------------------------------------------------------- */

/* The worst radial error of a unit ring of k sides (xyl_stems_ring_error's model). */
XYL__STEMS_SHARED double xyl__stems_ring_error(uint32_t k, bool refined);

/* Builds the branch that starts at node start with rings of k sides: its tube, caps and the
 * bridges of its laterals, whose branches it queues in s->pending. from: the bridge ring a
 * lateral's tube starts from; NULL for a root. */
XYL__STEMS_SHARED xyl_result xyl__stems_build_branch(stems *s, uint32_t start,
                                                     const stems_ring *from, uint32_t k);

/* k vertices around centre c in the plane of unit tangent t, starting along unit u (u . t = 0),
 * radius r (times s->inflate), texture v. Returns the first vertex index. */
XYL__STEMS_SHARED uint32_t xyl__stems_put_ring(stems *s, xyl__dvec3 c, xyl__dvec3 t, xyl__dvec3 u,
                                               double r, double v, uint32_t branch);

/* Plans the next ring of the branch being built: centre c, unit tangent t, radius r. */
XYL__STEMS_SHARED xyl_result xyl__stems_add_ring(stems *s, xyl__dvec3 c, xyl__dvec3 t, double r);

/* Lateral children of the nodes merged into station st. */
XYL__STEMS_SHARED size_t xyl__stems_lateral_count(const stems *s, const stems_station *st);

/* ---- forks (stems_fork.c) ------------------------------------------------------------------ */

/* Rings a fork with `laterals` lateral children adds around its own, when a band of the
 * parent's quads offers per_band patches. */
XYL__STEMS_SHARED size_t xyl__stems_fork_extra_rings(uint32_t per_band, size_t laterals);

/* Quads in the patch of a lateral of k sides: its outline has 2 strip + 2 vertices, k for even
 * k, k + 1 for odd. */
static inline uint32_t xyl__stems_strip(uint32_t k)
{
    return k % 2 ? (k - 1) / 2 : k / 2 - 1;
}

/* The ring sides of lateral `child` of the branch being built: its budget's, but no more than
 * the parent's (its patch is a strip of the parent's quads). */
static inline uint32_t xyl__stems_lateral_sides(const stems *s, uint32_t child)
{
    if (!s->branch_sides) return s->k;
    uint32_t k = s->branch_sides[s->sk->nodes[child].branch];
    return k < s->k ? k : s->k;
}

/* Makes k the ring sides of what is built next (s->tab[k] must be filled). */
static inline void xyl__stems_set_sides(stems *s, uint32_t k)
{
    const stems_sides *t = &s->tab[k];
    s->k = k;
    s->cos_a = t->cos_a;
    s->sin_a = t->sin_a;
    s->u_of = t->u_of;
    s->align_cos = t->align_cos;
    s->inflate = t->inflate;
}

/* The rings of station i, a fork with `laterals` lateral children: its own ring, turned to t,
 * and the extra rings around it, which the tube comes into along t_in and leaves along t_out. */
XYL__STEMS_SHARED xyl_result xyl__stems_fork_rings(stems *s, size_t i, xyl__dvec3 t_in,
                                                   xyl__dvec3 t, xyl__dvec3 t_out,
                                                   size_t laterals);

/* Bridges every lateral child of station i from a patch in the bands between rings lo .. hi,
 * and queues its branch in s->pending. */
XYL__STEMS_SHARED xyl_result xyl__stems_attach_laterals(stems *s, size_t i, size_t lo, size_t hi);

/* The direction a lateral's tube comes into its first station along from its bridge ring (its
 * stations made). */
XYL__STEMS_SHARED xyl__dvec3 xyl__stems_first_direction(const stems *s, const stems_ring *bridge);

/* Puts a node-less station (an elbow) between a lateral's bridge ring and its first station
 * where the band between them would cross the bridges of that station's laterals. */
XYL__STEMS_SHARED xyl_result xyl__stems_add_elbow(stems *s, const stems_ring *bridge);

/* ---- normals (stems_normals.c) ------------------------------------------------------------- */

/* Makes the normals summed for the branch just built (its rings and cap apexes) unit;
 * k even, while they are still in cache. */
XYL__STEMS_SHARED void xyl__stems_unit_branch_normals(stems *s);
/* Takes from each ring vertex's normal sum its component around the ring (all rings of the
 * branch just built but a lateral's bridge ring). */
XYL__STEMS_SHARED void xyl__stems_flatten_ring_normals(stems *s, bool lateral);

/* The vertex normals of the mesh as it stood before bridges replaced their patches, finished
 * from the sums in s->nrm, which it hands over as *out. */
XYL__STEMS_SHARED xyl_result xyl__stems_normals_with_patches(stems *s, xyl_vec3 **out);

/* Replaces the limit normals in a->normals by branch normals at the seams between branches. */
XYL__STEMS_SHARED xyl_result xyl__stems_branch_normals_on_limit(stems *s, xyl__mesh_arrays *a);

#endif

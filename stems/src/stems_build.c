/* The stem mesher's driver: checks the desc, builds every branch, hands the mesh over. */

/* The stem mesher wraps a whole skeleton in one closed quad mesh (docs/stems.md). Every branch is
 * a tube of k-vertex rings (rotation-minimising frames, caps at both ends). A lateral child is
 * grown out of its parent by Euler operators that keep a closed oriented genus-0 manifold so:
 * rings are inserted around the fork (loop insertion), the child takes a patch of parent quads
 * whose boundary has k vertices and the patch is replaced by a bridge to the child's first ring
 * (face extrusion). Topology is therefore right by construction; geometry (where the rings go)
 * decides only whether surfaces intersect.
 *
 * Its files: stems_tree.c indexes the tree as meshed (stems_merge.c places and merges the
 * laterals), stems_rings.c builds a branch's tube, stems_fork.c the rings around its forks and
 * its laterals' bridges, stems_normals.c the normals, stems_joints.c judges a mesh's
 * intersecting pairs for checked joints, and this file drives them. */
#include <float.h>
#include <string.h>

#include "mesh_internal.h"
#include "skeleton_internal.h"
#include "stems_internal.h"
#include "subdivide.h"

/* ---- output buffers ------------------------------------------------------------------------ */

bool xyl__stems_reserve_slow(stems *s, size_t verts, size_t quads)
{
    const xyl_allocator *a = &s->alloc;
    /* the first reservation (from the bound in build_all) is exact, not rounded up to a power
     * of two: a smaller footprint leaves more of the allocator's cache for the next build */
    size_t c0 = s->vcap ? s->vcap : verts, c1 = c0, c2 = c0, c3 = c0;
    size_t q0 = s->qcap ? s->qcap : quads, q1 = q0, q2 = q0;
    if (verts > s->vcap) {
        if (!xyl__grow(a, (void **)&s->pos, &c0, s->nv, verts, sizeof *s->pos) ||
            !xyl__grow(a, (void **)&s->uv, &c1, s->nv, verts, 2 * sizeof *s->uv) ||
            !xyl__grow(a, (void **)&s->vbranch, &c2, s->nv, verts, sizeof *s->vbranch) ||
            (s->sum_normals && !xyl__grow(a, (void **)&s->nrm, &c3, s->nv, verts, sizeof *s->nrm)))
            return false;
        s->vcap = c0;
    }
    if (quads > s->qcap) {
        if (!xyl__grow(a, (void **)&s->quads, &q0, s->nq, quads, 4 * sizeof *s->quads) ||
            !xyl__grow(a, (void **)&s->fbranch, &q1, s->nq, quads, sizeof *s->fbranch) ||
            !xyl__grow(a, (void **)&s->qwrap, &q2, s->nq, quads, sizeof *s->qwrap))
            return false;
        s->qcap = q0;
    }
    return true;
}

xyl_result xyl__stems_oom(stems *s)
{
    return xyl__fail(s->diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the stem mesh");
}

xyl_result xyl__stems_put_tri(stems *s, uint32_t a, uint32_t b, uint32_t c, uint32_t branch)
{
    size_t c0 = s->tcap3, c1 = s->tcap3, c2 = s->tcap3;
    if (!xyl__grow(&s->alloc, (void **)&s->tris, &c0, s->nt, s->nt + 1, 3 * sizeof *s->tris) ||
        !xyl__grow(&s->alloc, (void **)&s->tbranch, &c1, s->nt, s->nt + 1, sizeof *s->tbranch) ||
        !xyl__grow(&s->alloc, (void **)&s->twrap, &c2, s->nt, s->nt + 1, sizeof *s->twrap))
        return xyl__stems_oom(s);
    s->tcap3 = c0;
    uint32_t *t = s->tris + 3 * s->nt;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    s->twrap[s->nt] = xyl__stems_face_wraps(s, t, 3);
    s->tbranch[s->nt++] = branch;
    return XYL_OK;
}

/* ---- building ------------------------------------------------------------------------------ */

/* Upper bounds on the rings (each k vertices) and on the branch chains of the mesh: a chain's
 * stations are at most its nodes plus one (ensure_two_stations, add_elbow), a fork station adds
 * fork_extra_rings for the laterals merged into it (no more than the sum over its nodes), and
 * each lateral child adds its bridge ring. Faces: k per band and per bridge, at most k per
 * chain for the caps, so k (rings + chains) covers quads and triangles together; vertices: k
 * per ring and two cap apexes per chain. */
static void ring_bound(const stems *s, size_t *rings, size_t *chains)
{
    size_t n = s->sk->node_count, r = 16, c = 0;
    for (size_t i = 0; i < n; ++i) {
        size_t laterals = s->child_start[i + 1] - s->child_start[i] - (s->main[i] != UINT32_MAX);
        r += 1 + (laterals ? xyl__stems_fork_extra_rings(s->per_band_min, laterals) + laterals : 0);
        c += laterals + (s->sk->nodes[i].parent < 0);
    }
    *rings = r + c;
    *chains = c;
}

static double limit_mean_radius(uint32_t k);

/* The tables of rings of k sides: directions, texture u, the alignment step, the inflation
 * (inflate: before subdivision, else 1). */
static void fill_sides(stems_sides *t, uint32_t k, bool inflate)
{
    for (uint32_t j = 0; j < k; ++j) {
        double a = 2.0 * XYL__PI * (double)j / (double)k;
        t->cos_a[j] = cos(a);
        t->sin_a[j] = sin(a);
        t->u_of[j] = (float)((double)j / (double)k);
    }
    t->align_cos = cos(0.005 * 2.0 * XYL__PI / (double)k);
    t->inflate = inflate ? 1.0 / limit_mean_radius(k) : 1.0;
}

static xyl_result build_all(stems *s, bool inflate)
{
    xyl_result r = xyl__stems_index_tree(s);
    /* every k a branch can get: kmax alone, or 3..kmax with an error budget */
    const uint32_t kmin = s->branch_sides ? 3 : s->kmax;
    s->per_band_min = UINT32_MAX;
    for (uint32_t k = kmin; k <= s->kmax; ++k) {
        fill_sides(&s->tab[k], k, inflate);
        uint32_t per_band = k / xyl__stems_strip(k);
        if (per_band < s->per_band_min) s->per_band_min = per_band;
    }
    xyl__stems_set_sides(s, s->kmax);
    /* reserving once avoids regrowth copies; a tight bound keeps the footprint small, so the
     * allocator can hand the same pages back on the next build instead of fresh ones */
    size_t rings = 0, chains = 0;
    if (!r) ring_bound(s, &rings, &chains);
    if (!r && !xyl__stems_reserve(s, rings * s->kmax + 2 * chains, (rings + chains) * s->kmax))
        r = xyl__stems_oom(s);
    for (size_t i = 0; i < s->sk->node_count && !r; ++i) {
        if (s->sk->nodes[i].parent >= 0) continue;
        uint32_t k = s->branch_sides ? s->branch_sides[s->sk->nodes[i].branch] : s->kmax;
        r = xyl__stems_build_branch(s, (uint32_t)i, NULL, k);
        while (!r && s->npending) {
            stems_pending p = s->pending[--s->npending];
            r = xyl__stems_build_branch(s, p.node, &p.bridge, p.k);
        }
        if (!r && (uint64_t)s->nv > s->max_vertices)
            r = xyl__fail(s->diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                          "the stem mesh needs more than %llu vertices",
                          (unsigned long long)s->max_vertices);
    }
    return r;
}

/* ---- inflation for the limit surface ------------------------------------------------------- */

/* Mean radius of the Catmull-Clark limit of an infinitely long prism whose k-gon rings have
 * radius 1. Its cross-section is the uniform cubic B-spline of the k-gon; by symmetry one span
 * (between ring vertices 0 and 1) gives the mean, integrated with Simpson's rule. At the ring
 * vertices the limit radius is (4 + 2 cos(2pi/k)) / 6; between them it is smaller, so inflating
 * by the inverse of the vertex value would leave the mean too small (by 1.4 % for k = 4).
 * Loop's limit of the split rings is the same curve: on data constant along the tube its
 * valence-6 vertex rule, 10/16 p + (2 p[i-1] + 2 p[i] + 2 p[i+1]) / 16, is the B-spline's
 * (p[i-1] + 6 p[i] + p[i+1]) / 8 (tests/test_subdivide.c measures both on OpenSubdiv's limit). */
static double limit_mean_radius(uint32_t k)
{
    double p[4][2];
    for (int i = 0; i < 4; ++i) {
        double a = 2.0 * XYL__PI * (double)(i - 1) / (double)k;
        p[i][0] = cos(a);
        p[i][1] = sin(a);
    }
    const int n = 64; /* even */
    double sum = 0.0;
    for (int i = 0; i <= n; ++i) {
        double t = (double)i / n, u = 1.0 - t;
        double b[4] = {u * u * u, 3 * t * t * t - 6 * t * t + 4, -3 * t * t * t + 3 * t * t + 3 * t + 1,
                       t * t * t};
        double x = 0.0, y = 0.0;
        for (int j = 0; j < 4; ++j) {
            x += b[j] * p[j][0] / 6.0;
            y += b[j] * p[j][1] / 6.0;
        }
        double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        sum += w * sqrt(x * x + y * y);
    }
    return sum / (3.0 * n);
}

/* ---- public entry -------------------------------------------------------------------------- */

static xyl_result check_desc(const xyl_skeleton *sk, const xyl_stems_desc *d, xyl_mesh **out,
                             xyl_diag *diag)
{
    if (!sk || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "skeleton and out must not be NULL");
    uint32_t k = d->sides ? d->sides : 4;
    if (k < 3 || k > 32)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "sides must be 3..32, not %u", k);
    if ((unsigned)d->normals > XYL_NORMALS_SMOOTH || (unsigned)d->subdivision > XYL_SUBDIVIDE_LOOP ||
        (unsigned)d->joints > XYL_JOINTS_UNCHECKED || (unsigned)d->base > XYL_STEMS_BASE_OPEN)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "unknown normal mode, scheme, joint check or base");
    if (!(d->root_flare >= 0.0f && d->root_flare <= XYL_STEMS_MAX_ROOT_FLARE))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "root_flare must be 0..%g, not %g", (double)XYL_STEMS_MAX_ROOT_FLARE,
                         (double)d->root_flare);
    if (!(d->error_world >= 0.0f && isfinite(d->error_world)))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "error_world must be 0 (off) or a finite radial error budget above 0, "
                         "not %g", (double)d->error_world);
    return XYL_OK;
}

/* The triangulated view of n quads: (a, b, c) and (a, c, d) for each quad (a, b, c, d). */
static void triangulate_quads(const uint32_t *q, size_t n, uint32_t *t)
{
    size_t i = 0;
#ifdef XYL__SSE2
    for (; i < n; ++i, q += 4, t += 6) { /* one load, two shuffles, two stores per quad */
        __m128i v = _mm_loadu_si128((const __m128i *)(const void *)q);
        _mm_storeu_si128((__m128i *)(void *)t, _mm_shuffle_epi32(v, _MM_SHUFFLE(0, 2, 1, 0)));
        _mm_storel_epi64((__m128i *)(void *)(t + 4), _mm_shuffle_epi32(v, _MM_SHUFFLE(3, 3, 3, 2)));
    }
#endif
    for (; i < n; ++i, q += 4, t += 6) {
        t[0] = q[0], t[1] = q[1], t[2] = q[2];
        t[3] = q[0], t[4] = q[2], t[5] = q[3];
    }
}

/* Drops the quads that became bridges and hands the arrays over. With tv (room for 2 nq + nt
 * triangles) the triangulated view is written in the same pass, while each quad is at hand. */
static void take_arrays(stems *s, xyl__mesh_arrays *a, uint32_t *tv)
{
    /* taken quads are few (a patch per lateral): move the runs between them whole */
    size_t w = 0, q = 0, nq = s->nq, ntaken = s->tcap < nq ? s->tcap : nq;
    while (q < nq) {
        const uint8_t *next = q < ntaken ? memchr(s->taken + q, 1, ntaken - q) : NULL;
        size_t end = next ? (size_t)(next - s->taken) : nq, run = end - q;
        if (w != q) { /* w < q: the run moves down */
            memmove(s->quads + 4 * w, s->quads + 4 * q, run * 4 * sizeof *s->quads);
            memmove(s->fbranch + w, s->fbranch + q, run * sizeof *s->fbranch);
            memmove(s->qwrap + w, s->qwrap + q, run * sizeof *s->qwrap);
        }
        if (tv) triangulate_quads(s->quads + 4 * w, run, tv + 6 * w);
        w += run;
        q = end + 1;
    }
    if (tv && s->nt) memcpy(tv + 6 * w, s->tris, 3 * s->nt * sizeof *s->tris);
    memset(a, 0, sizeof *a);
    a->positions = s->pos;
    a->uvs = s->uv;
    a->branch_ids = s->vbranch;
    a->vertex_count = s->nv;
    a->quads = s->quads;
    a->quad_count = w;
    a->face_branches = s->fbranch;
    a->uv_wraps = s->qwrap;
    if (s->nt) { /* face branches and wraps: quads first, then triangles */
        memcpy(s->fbranch + w, s->tbranch, s->nt * sizeof *s->tbranch);
        memcpy(s->qwrap + w, s->twrap, s->nt * sizeof *s->twrap);
        a->triangles = s->tris;
        a->triangle_count = s->nt;
        s->tris = NULL;
    }
    s->pos = NULL;
    s->uv = NULL;
    s->vbranch = NULL;
    s->quads = NULL;
    s->fbranch = NULL;
    s->qwrap = NULL;
}

static void free_state(stems *s)
{
    void *arrays[] = {s->child_start, s->child_list, s->main,  s->pos,      s->uv,
                      s->vbranch,     s->nrm,        s->quads, s->fbranch,  s->qwrap,
                      s->tris,        s->tbranch,    s->twrap, s->taken,    s->chain,
                      s->stations,    s->rings,      s->spans, s->pending,  s->cones};
    for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; ++i) xyl__free(&s->alloc, arrays[i]);
}

/* The edges of every capped root ring as vertex pairs (from s->alloc; NULL with *count 0 when
 * there are none): subdivision keeps them infinitely sharp, so the ring and its cap stay in the
 * root's plane instead of being rounded off and lifted (docs/stems.md, "The base"). */
static xyl_result base_creases(stems *s, uint32_t **pairs, size_t *count)
{
    *pairs = NULL;
    *count = 0;
    for (size_t b = 0; b < s->nbase; ++b) *count += s->bases[b].k;
    if (*count == 0) return XYL_OK;
    *pairs = xyl__alloc_array(&s->alloc, *count, 2 * sizeof **pairs);
    if (!*pairs) return xyl__stems_oom(s);
    uint32_t *p = *pairs;
    for (size_t b = 0; b < s->nbase; ++b)
        for (uint32_t j = 0, k = s->bases[b].k; j < k; ++j) {
            *p++ = s->bases[b].first + j;
            *p++ = s->bases[b].first + (j + 1 < k ? j + 1 : 0);
        }
    return XYL_OK;
}

/* A refined vertex's place on the creased root rings: 0 for none, else 1 + its slot (ring b's
 * vertex point j at 2 K b + j, its edge point from j to j + 1 at 2 K b + K + j, K = kmax, j
 * below ring b's own k); PENDING marks a vertex next to one vertex point so far (1 + that slot
 * below it). */
#define BASE_PENDING 0x80000000u

/* Tags the refined vertices of the creased root rings in tag (0 elsewhere): the vertex points
 * keep their control vertices' indices (vertex points come first), and the edge point of ring
 * edge (j, j + 1) is the one refined vertex that shares a face side with both of their vertex
 * points (a vertex point's sides all lead to edge points of its own edges). */
static void tag_base_rings(const stems *s, const xyl__mesh_arrays *a, uint32_t *tag)
{
    const uint32_t k = s->kmax;
    for (size_t b = 0; b < s->nbase; ++b)
        for (uint32_t j = 0; j < s->bases[b].k; ++j)
            tag[s->bases[b].first + j] = (uint32_t)(2 * k * b + j) + 1;
    for (size_t f = 0; f < a->quad_count + a->triangle_count; ++f) {
        const bool quad = f < a->quad_count;
        const int n = quad ? 4 : 3;
        const uint32_t *fv = quad ? a->quads + 4 * f : a->triangles + 3 * (f - a->quad_count);
        for (int c = 0; c < n; ++c) {
            const uint32_t t = tag[fv[c]];
            if (t == 0 || t & BASE_PENDING || (t - 1) % (2 * k) >= k)
                continue; /* not a vertex point */
            const uint32_t nb[2] = {fv[(c + 1) % n], fv[(c + n - 1) % n]};
            for (int i = 0; i < 2; ++i) {
                uint32_t *w = &tag[nb[i]];
                if (*w == 0) {
                    *w = BASE_PENDING | t;
                    continue;
                }
                if (!(*w & BASE_PENDING) || (*w & ~BASE_PENDING) == t) continue;
                const uint32_t p = (*w & ~BASE_PENDING) - 1, q = t - 1; /* two vertex points */
                if (p / (2 * k) != q / (2 * k)) continue;
                const uint32_t jp = p % (2 * k), jq = q % (2 * k), kb = s->bases[p / (2 * k)].k;
                const uint32_t lo = (jp + 1) % kb == jq ? jp : (jq + 1) % kb == jp ? jq : kb;
                if (lo < kb) *w = p - jp + k + lo + 1;
            }
        }
    }
}

/* Face f of a: its corners and their number. */
static const uint32_t *arrays_face(const xyl__mesh_arrays *a, size_t f, int *n)
{
    const bool quad = f < a->quad_count;
    *n = quad ? 4 : 3;
    return quad ? a->quads + 4 * f : a->triangles + 3 * (f - a->quad_count);
}

/* Whether refined ring points of slots p and q are neighbours along their ring's crease (a
 * vertex point j and the edge point of (j - 1, j) or (j, j + 1)); slots of stride k (kmax), the
 * ring of kb sides. */
static bool along_crease(const stems *s, uint32_t p, uint32_t q)
{
    const uint32_t k = s->kmax;
    if (p / (2 * k) != q / (2 * k)) return false;
    uint32_t jp = p % (2 * k), jq = q % (2 * k), kb = s->bases[p / (2 * k)].k;
    if ((jp < k) == (jq < k)) return false;
    uint32_t j = jp < k ? jp : jq, e = (jp < k ? jq : jp) - k;
    return e == j || (e + 1) % kb == j;
}

/* The band-side normal of ring point u (slot su) from its faces (face[0..m)): the faces split
 * into fans where they meet across a side that is not the crease, the cap's fan is the one
 * that faces furthest down the root's axis, and the others' area-weighted normals are summed.
 * False where the faces do not split (the normal then stays as it is). */
static bool band_normal(const stems *s, const xyl__mesh_arrays *a, const uint32_t *tag,
                        uint32_t u, uint32_t su, const uint32_t *face, int m, xyl__dvec3 *out)
{
    int fan[64];
    xyl__dvec3 fn[64], sum[64];
    if (m > 64) return false;
    for (int i = 0; i < m; ++i) {
        int n;
        const uint32_t *fv = arrays_face(a, face[i], &n);
        fan[i] = i;
        fn[i] = xyl__from_f3(n == 4 ? xyl__quad_normal(a->positions, fv)
                                    : xyl__tri_normal(a->positions, fv));
        sum[i] = xyl__d3(0, 0, 0);
    }
    for (int i = 0; i < m; ++i) /* faces that share a side u-w off the crease: one fan */
        for (int j = i + 1; j < m; ++j) {
            int ni, nj;
            const uint32_t *fi = arrays_face(a, face[i], &ni), *fj = arrays_face(a, face[j], &nj);
            int ci = 0, cj = 0;
            while (fi[ci] != u) ++ci;
            while (fj[cj] != u) ++cj;
            const uint32_t wi[2] = {fi[(ci + 1) % ni], fi[(ci + ni - 1) % ni]};
            const uint32_t wj[2] = {fj[(cj + 1) % nj], fj[(cj + nj - 1) % nj]};
            for (int x = 0; x < 2; ++x) {
                const uint32_t w = wi[x], tw = tag[w];
                if (w != wj[1 - x]) continue;
                if (tw && !(tw & BASE_PENDING) && along_crease(s, su, tw - 1)) continue;
                const int from = fan[j], to = fan[i];
                for (int z = 0; z < m; ++z)
                    if (fan[z] == from) fan[z] = to;
            }
        }
    for (int i = 0; i < m; ++i) sum[fan[i]] = xyl__d3_add(sum[fan[i]], fn[i]);
    const xyl__dvec3 up = s->bases[su / (2 * s->kmax)].up;
    int cap = -1, fans = 0;
    double lowest = INFINITY;
    for (int i = 0; i < m; ++i) {
        if (fan[i] != i) continue;
        ++fans;
        const double l = xyl__d3_len(sum[i]), d = l > 0.0 ? xyl__d3_dot(sum[i], up) / l : 0.0;
        if (d < lowest) lowest = d, cap = i;
    }
    if (fans < 2) return false;
    *out = xyl__d3(0, 0, 0);
    for (int i = 0; i < m; ++i)
        if (fan[i] != cap) *out = xyl__d3_add(*out, fn[i]);
    return true;
}

/* Subdivided, the points of a creased root ring take the normal of the band above it. On the
 * limit surface OpenSubdiv's crease tangents span one side of the crease, the cap's at some
 * points and the band's at others, and a face average would lean half-way to the cap; a
 * shaded or PN-refined base wants the band's. */
static xyl_result base_ring_normals(stems *s, xyl__mesh_arrays *a)
{
    const size_t slots = 2 * (size_t)s->kmax * s->nbase, nf = a->quad_count + a->triangle_count;
    uint32_t *tag = xyl__calloc(&s->alloc, a->vertex_count ? a->vertex_count : 1, sizeof *tag);
    uint32_t *start = xyl__calloc(&s->alloc, slots + 1, sizeof *start);
    uint32_t *vertex = xyl__calloc(&s->alloc, slots, sizeof *vertex);
    uint32_t *face = NULL;
    xyl_result r = tag && start && vertex ? XYL_OK : xyl__stems_oom(s);
    if (!r) {
        tag_base_rings(s, a, tag);
        for (size_t f = 0; f < nf; ++f) { /* each ring point's faces, by slot */
            int n;
            const uint32_t *fv = arrays_face(a, f, &n);
            for (int c = 0; c < n; ++c)
                if (tag[fv[c]] && !(tag[fv[c]] & BASE_PENDING)) ++start[tag[fv[c]]];
        }
        for (size_t i = 0; i < slots; ++i) start[i + 1] += start[i];
        face = xyl__alloc_array(&s->alloc, start[slots] ? start[slots] : 1, sizeof *face);
        if (!face) r = xyl__stems_oom(s);
    }
    if (!r) {
        for (size_t f = 0; f < nf; ++f) { /* start[t - 1] runs up to slot t - 1's end */
            int n;
            const uint32_t *fv = arrays_face(a, f, &n);
            for (int c = 0; c < n; ++c) {
                const uint32_t t = tag[fv[c]];
                if (!t || t & BASE_PENDING) continue;
                face[start[t - 1]++] = (uint32_t)f;
                vertex[t - 1] = fv[c];
            }
        }
        for (size_t i = slots; i > 0; --i) start[i] = start[i - 1];
        start[0] = 0;
        for (size_t i = 0; i < slots; ++i) {
            xyl__dvec3 band;
            const uint32_t u = vertex[i];
            const int m = (int)(start[i + 1] - start[i]);
            if (m == 0 || !band_normal(s, a, tag, u, (uint32_t)i, face + start[i], m, &band))
                continue;
            a->normals[u] = xyl__to_f3(xyl__d3_normalize_or(band, xyl__from_f3(a->normals[u])));
        }
    }
    xyl__free(&s->alloc, tag);
    xyl__free(&s->alloc, start);
    xyl__free(&s->alloc, vertex);
    xyl__free(&s->alloc, face);
    return r;
}

static xyl_result finish(stems *s, const xyl_stems_desc *d, xyl__mesh_arrays *a, uint32_t *tv,
                         const xyl__creases *creases, xyl_mesh **out)
{
    xyl_result r = XYL_OK;
    /* the mesh's positions are the skeleton's local coordinates */
    memcpy(a->origin, s->sk->origin, sizeof a->origin);
    if (a->normals) return xyl__mesh_adopt_view(a, tv, &s->alloc, out, s->diag);
    if (d->subdivision != XYL_SUBDIVIDE_NONE) {
        xyl__mesh_arrays fine;
        r = xyl__subdivide_creased(a, creases, d->subdivision, !d->keep_control_points,
                                   &d->limits, XYL__SUBDIVIDE_ANY, &s->alloc, &fine, s->diag);
        xyl__mesh_arrays_free(a, &s->alloc);
        if (r) return r;
        *a = fine;
        memcpy(a->origin, s->sk->origin, sizeof a->origin);
    }
    if (a->normals && d->normals == XYL_NORMALS_BRANCH) {
        r = xyl__stems_branch_normals_on_limit(s, a);
    } else if (!a->normals) { /* limit normals are the smooth normals */
        a->normals = xyl__alloc_array(&s->alloc, a->vertex_count, sizeof *a->normals); /* zeroed there */
        if (!a->normals) r = xyl__stems_oom(s);
        if (!r) {
            const uint32_t *fb = d->normals == XYL_NORMALS_BRANCH ? a->face_branches : NULL;
            if (xyl__mesh_normals(a, fb, &s->alloc, a->normals) != XYL_OK) r = xyl__stems_oom(s);
        }
    }
    if (!r && creases->count) r = base_ring_normals(s, a);
    if (r) {
        xyl__mesh_arrays_free(a, &s->alloc);
        return r;
    }
    return xyl__mesh_adopt(a, &s->alloc, out, s->diag);
}

/* The built mesh's arrays into a (with its normals and, when they are final, *tv, the
 * triangulated view), or an error with nothing handed over. */
static xyl_result hand_over(stems *s, xyl__mesh_arrays *a, uint32_t **tv)
{
    xyl_vec3 *normals = NULL;
    /* face branches and wraps run over quads, then triangles: room for both */
    size_t fcap = s->qcap, wcap = s->qcap;
    if (s->nt && (!xyl__grow(&s->alloc, (void **)&s->fbranch, &fcap, s->nq, s->nq + s->nt,
                             sizeof *s->fbranch) ||
                  !xyl__grow(&s->alloc, (void **)&s->qwrap, &wcap, s->nq, s->nq + s->nt,
                             sizeof *s->qwrap)))
        return xyl__stems_oom(s);
    if (s->sum_normals) {
        xyl_result r = xyl__stems_normals_with_patches(s, &normals);
        if (r) return r;
        *tv = xyl__alloc_array(&s->alloc, 2 * s->nq + s->nt, 3 * sizeof **tv);
        if (!*tv) {
            xyl__free(&s->alloc, normals);
            return xyl__stems_oom(s);
        }
    }
    take_arrays(s, a, *tv);
    a->normals = normals;
    return XYL_OK;
}

/* Every position and UV of the built mesh is finite, or the error names this stage and where in
 * the skeleton it failed: positions plus radii (inflated for subdivision) can leave the float
 * range although every number of the skeleton is in it. */
static xyl_result check_finite(const stems *s)
{
    for (size_t v = 0; v < s->nv; ++v) {
        const xyl_vec3 p = s->pos[v];
        if (isfinite(p.x) && isfinite(p.y) && isfinite(p.z) && isfinite(s->uv[2 * v]) &&
            isfinite(s->uv[2 * v + 1]))
            continue;
        return xyl__fail(s->diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)v,
                         "the stem mesher: vertex %zu (branch %u) leaves the float range: the "
                         "skeleton's positions plus its radii%s pass %g there",
                         v, s->vbranch[v], s->limit_centres ? " (inflated for subdivision)" : "",
                         (double)FLT_MAX);
    }
    return XYL_OK;
}

/* One mesh of the skeleton, with checked joints' levels per branch in drop (NULL: none); with
 * shift and hidden (per branch, or NULL) what the levels cost each raised lateral. */
static xyl_result build_once(const xyl_skeleton *skeleton, const xyl_stems_desc *desc,
                             const uint8_t *branch_sides, const uint32_t *drop, double *shift,
                             uint8_t *hidden, xyl_mesh **out, xyl_stems_stats *st,
                             xyl_diag *diag)
{
    xyl_result r;
    stems s;
    memset(&s, 0, sizeof s);
    s.sk = skeleton;
    s.drop = drop;
    s.shift = shift;
    s.hidden = hidden;
    s.kmax = desc->sides ? desc->sides : 4;
    s.branch_sides = branch_sides;
    s.alloc = desc->alloc;
    s.diag = diag;
    s.max_vertices = desc->limits.max_vertices ? desc->limits.max_vertices : XYL__MESH_DEFAULT_MAX_VERTICES;
    s.max_faces = desc->limits.max_faces ? desc->limits.max_faces : XYL__MESH_DEFAULT_MAX_FACES;
    bool inflate = desc->subdivision != XYL_SUBDIVIDE_NONE && !desc->keep_control_radius;
    /* smooth normals and subdivided meshes see the final surface, so only these are summed on
     * the way */
    s.sum_normals = desc->normals == XYL_NORMALS_BRANCH && desc->subdivision == XYL_SUBDIVIDE_NONE;
    /* index_children may still veto; with an error budget some branch may have odd k, whose
     * triangles add to the sums after every branch is built */
    s.unit_per_branch = s.sum_normals && s.kmax % 2 == 0 && !branch_sides;
    s.limit_centres = inflate;
    s.open_base = desc->base == XYL_STEMS_BASE_OPEN;
    s.root_flare = desc->root_flare;
    s.sides_refined = desc->sides_refined;
    r = build_all(&s, inflate);
    if (!r && st) {
        memcpy(st->branches_by_sides, s.by_sides, sizeof st->branches_by_sides);
        st->sides_clamped = s.clamped;
        st->ring_error_max = s.ring_error_max;
    }
    if (!r) r = check_finite(&s);
    if (!r && (uint64_t)s.nq > s.max_faces)
        r = xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                      "the stem mesh needs more than %llu faces", (unsigned long long)s.max_faces);
    xyl__mesh_arrays a;
    uint32_t *tv = NULL;
    xyl__creases creases = {NULL, 0};
    uint32_t *pairs = NULL;
    if (!r && desc->subdivision != XYL_SUBDIVIDE_NONE) r = base_creases(&s, &pairs, &creases.count);
    creases.pairs = pairs;
    if (!r) r = hand_over(&s, &a, &tv);
    free_state(&s);
    if (!r) r = finish(&s, desc, &a, tv, &creases, out);
    xyl__free(&s.alloc, pairs);
    xyl__free(&s.alloc, s.bases);
    return r;
}

/* One round's test: the intersecting pairs of mesh m (from those of the last round's mesh, if
 * any), kept in *pairs for the next round; *t counts them, and drop has the levels raised for
 * those at joints (stems_joints.c). */
typedef struct round_pairs {
    xyl_mesh *mesh;  /* the last round's mesh, or NULL */
    uint64_t *pairs; /* its intersecting pairs */
    size_t count;
} round_pairs;

static xyl_result judge_mesh(const xyl_skeleton *sk, xyl_mesh *m, round_pairs *last,
                             uint32_t *drop, const xyl_allocator *alloc, xyl__joint_tally *t,
                             xyl_diag *diag)
{
    uint64_t *pairs = NULL;
    size_t count = 0;
    xyl_result r = xyl__stems_joint_pairs(sk, last->mesh, last->pairs, last->count, m, alloc,
                                          &pairs, &count, diag);
    if (!r) r = xyl__stems_judge_joints(sk, m, pairs, count, drop, alloc, t, diag);
    xyl_mesh_destroy(last->mesh);
    xyl__free(alloc, last->pairs);
    last->mesh = m;
    last->pairs = pairs;
    last->count = count;
    return r;
}

/* The stats of a checked build from its last plain mesh m: per branch its level (drop), how
 * far a raised lateral moved (shift) and whether it has no node left (hidden). A lateral without
 * faces that no level hid lies wholly inside another tube by its skeleton (the placement and the
 * sibling merge leave it out). */
static xyl_result count_laterals(const xyl_skeleton *sk, const xyl_mesh *m, const uint32_t *drop,
                                 const double *shift, const uint8_t *hidden,
                                 const xyl_allocator *alloc, xyl_stems_stats *st, xyl_diag *diag)
{
    const size_t nb = sk->branch_count, nf = m->quad_count + m->triangle_count;
    uint8_t *meshed = xyl__calloc(alloc, nb ? nb : 1, 1);
    uint8_t *lateral = xyl__calloc(alloc, nb ? nb : 1, 1);
    if (!meshed || !lateral) {
        xyl__free(alloc, meshed);
        xyl__free(alloc, lateral);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    }
    for (size_t f = 0; f < nf; ++f) meshed[m->face_branches[f]] = 1;
    for (size_t n = 0; n < sk->node_count; ++n) {
        const int32_t p = sk->nodes[n].parent;
        if (p >= 0 && sk->nodes[p].branch != sk->nodes[n].branch) lateral[sk->nodes[n].branch] = 1;
    }
    for (size_t b = 0; b < nb; ++b) {
        if (!lateral[b]) continue;
        if (drop[b] && hidden[b]) {
            ++st->laterals_hidden;
        } else if (drop[b] && meshed[b]) {
            ++st->laterals_started_later;
            st->lateral_shift_sum += shift[b];
            st->lateral_shift_max = fmax(st->lateral_shift_max, shift[b]);
        } else if (!meshed[b]) {
            ++st->laterals_inside;
        }
    }
    xyl__free(alloc, meshed);
    xyl__free(alloc, lateral);
    return XYL_OK;
}

/* Checked joints (docs/stems.md): builds, tests the mesh for intersecting pairs, and for each
 * pair at a joint raises one lateral's level (stems_joints.c): it starts a node later than the
 * placement would start it, then another, and so on; one with no node left is not meshed, and
 * what grows from it grows from its fork. Then it builds again, until a mesh has no pair at a
 * joint. Each round raises at least one level, levels only rise and none passes its branch's
 * node count, so this ends. The test runs on the mesh before subdivision, at the skeleton's
 * radii; a subdivided mesh is then built once more with the same levels. */
static xyl_result build_checked(const xyl_skeleton *skeleton, const xyl_stems_desc *desc,
                                const uint8_t *sides, xyl_mesh **out, xyl_stems_stats *st,
                                xyl_diag *diag)
{
    const size_t nb = skeleton->branch_count ? skeleton->branch_count : 1;
    uint32_t *drop = xyl__calloc(&desc->alloc, nb, sizeof *drop);
    double *shift = xyl__calloc(&desc->alloc, nb, sizeof *shift);
    uint8_t *hidden = xyl__calloc(&desc->alloc, nb, 1);
    xyl_mesh *m = NULL;
    xyl_result r = XYL_OK;
    if (!drop || !shift || !hidden)
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    xyl_stems_desc plain = *desc;
    plain.subdivision = XYL_SUBDIVIDE_NONE;
    bool any = false; /* some level was raised */
    round_pairs last = {NULL, NULL, 0};
    while (!r) {
        memset(shift, 0, nb * sizeof *shift);
        memset(hidden, 0, nb);
        r = build_once(skeleton, &plain, sides, drop, shift, hidden, &m, st, diag);
        if (r) break;
        if (++st->builds == 1) st->faces_first = m->quad_count + m->triangle_count;
        xyl__joint_tally t;
        r = judge_mesh(skeleton, m, &last, drop, &desc->alloc, &t, diag);
        if (r) {
            m = NULL; /* last's now */
            break;
        }
        if (st->builds == 1) st->joint_pairs_first = t.joint;
        if (!t.marked) {
            st->joint_pairs_left = t.joint;
            st->skeleton_pairs = t.own;
            st->faces_checked = m->quad_count + m->triangle_count;
            r = count_laterals(skeleton, m, drop, shift, hidden, &desc->alloc, st, diag);
            last.mesh = NULL; /* m, handed out below */
            break;
        }
        any = true;
        m = NULL; /* kept in last for the next round */
    }
    xyl_mesh_destroy(last.mesh);
    xyl__free(&desc->alloc, last.pairs);
    if (!r && desc->subdivision != XYL_SUBDIVIDE_NONE) {
        xyl_mesh_destroy(m);
        m = NULL;
        r = build_once(skeleton, desc, sides, any ? drop : NULL, NULL, NULL, &m, st, diag);
        ++st->builds;
    }
    xyl__free(&desc->alloc, drop);
    xyl__free(&desc->alloc, shift);
    xyl__free(&desc->alloc, hidden);
    if (r) {
        xyl_mesh_destroy(m);
        return r;
    }
    xyl__diag_ok(diag);
    if (st->joint_pairs_left)
        xyl__warn(diag, "%zu intersecting triangle pairs at joints are left where only a root's "
                  "tube could give way (the check moves laterals only)", st->joint_pairs_left);
    *out = m;
    return XYL_OK;
}

/* ---- ring sides per branch (docs/stems.md, "Ring sides per branch") ------------------------ */

/* |B(t)| - 1 on the cubic arc from angle 0 to phi around the unit circle with handles h long
 * (the circle rule's (4/3) tan(phi / 4)). */
static double arc_radius_error(double phi, double h, double t)
{
    const double c = cos(phi), sn = sin(phi), u = 1.0 - t;
    const double b0 = u * u * u, b1 = 3.0 * u * u * t, b2 = 3.0 * u * t * t, b3 = t * t * t;
    const double x = b0 + b1 + b2 * (c + h * sn) + b3 * c;
    const double y = b1 * h + b2 * (sn - h * c) + b3 * sn;
    return sqrt(x * x + y * y) - 1.0;
}

/* The worst radial error of a unit ring of k sides (xyl_stems_ring_error). Refined: the arc is
 * symmetric about t = 1/2, where the circle rule makes it exact, and it lies outside the circle
 * in between; the worst point is found by sampling [0, 1/2] and a golden-section search around
 * the best sample (unimodal there), to about 1e-12 of the radius. */
XYL__STEMS_SHARED double xyl__stems_ring_error(uint32_t k, bool refined)
{
    const double phi = 2.0 * XYL__PI / (double)k;
    if (!refined) return 1.0 - cos(0.5 * phi);
    const double h = 4.0 / 3.0 * tan(0.25 * phi);
    const int n = 64;
    int best = 0;
    double worst = 0.0;
    for (int i = 0; i <= n; ++i) {
        double e = fabs(arc_radius_error(phi, h, 0.5 * i / n));
        if (e > worst) worst = e, best = i;
    }
    double a = 0.5 * (best > 0 ? best - 1 : 0) / n, b = 0.5 * (best < n ? best + 1 : n) / n;
    const double g = 0.5 * (sqrt(5.0) - 1.0);
    for (int it = 0; it < 60; ++it) {
        double x1 = b - g * (b - a), x2 = a + g * (b - a);
        if (fabs(arc_radius_error(phi, h, x1)) >= fabs(arc_radius_error(phi, h, x2))) b = x2;
        else a = x1;
    }
    return fmax(worst, fabs(arc_radius_error(phi, h, 0.5 * (a + b))));
}

xyl_result xyl_stems_ring_error(uint32_t sides, bool refined, double *error)
{
    if (sides < 3 || sides > 32 || !error)
        return xyl__fail(NULL, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "sides must be 3..32 and error not NULL");
    *error = xyl__stems_ring_error(sides, refined);
    return XYL_OK;
}

/* Per skeleton branch, the fewest sides in 3..kmax whose radial error at the branch's widest
 * ring is within desc->error_world, or kmax (from desc->alloc; NULL when error_world is 0: every
 * branch gets kmax). The widest ring is the widest node's, or a root's flared base ring. */
static xyl_result budget_sides(const xyl_skeleton *sk, const xyl_stems_desc *d, uint8_t **out,
                               xyl_diag *diag)
{
    *out = NULL;
    if (d->error_world == 0.0f) return XYL_OK;
    const size_t nb = sk->branch_count ? sk->branch_count : 1;
    const uint32_t kmax = d->sides ? d->sides : 4;
    double *widest = xyl__calloc(&d->alloc, nb, sizeof *widest);
    uint8_t *sides = xyl__alloc_array(&d->alloc, nb, 1);
    if (!widest || !sides) {
        xyl__free(&d->alloc, widest);
        xyl__free(&d->alloc, sides);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    }
    for (size_t i = 0; i < sk->node_count; ++i) {
        const xyl_skel_node *n = &sk->nodes[i];
        double r = (double)n->radius * (n->parent < 0 ? 1.0 + (double)d->root_flare : 1.0);
        widest[n->branch] = fmax(widest[n->branch], r);
    }
    double e[33];
    for (uint32_t k = 3; k <= kmax; ++k) e[k] = xyl__stems_ring_error(k, d->sides_refined);
    for (size_t b = 0; b < nb; ++b) {
        uint32_t k = 3;
        while (k < kmax && !(widest[b] * e[k] <= (double)d->error_world)) ++k;
        sides[b] = (uint8_t)k;
    }
    xyl__free(&d->alloc, widest);
    *out = sides;
    return XYL_OK;
}

/* ---- public entry -------------------------------------------------------------------------- */

xyl_result xyl_stems_build(const xyl_skeleton *skeleton, const xyl_stems_desc *desc,
                           xyl_mesh **out, xyl_stems_stats *stats, xyl_diag *diag)
{
    static const xyl_stems_desc zero;
    if (!desc) desc = &zero;
    xyl_result r = check_desc(skeleton, desc, out, diag);
    if (r) return r;
    xyl_stems_stats st;
    memset(&st, 0, sizeof st);
    uint8_t *sides = NULL;
    r = budget_sides(skeleton, desc, &sides, diag);
    if (r) return r;
    if (desc->joints == XYL_JOINTS_UNCHECKED) {
        r = build_once(skeleton, desc, sides, NULL, NULL, NULL, out, &st, diag);
        st.builds = 1;
    } else {
        r = build_checked(skeleton, desc, sides, out, &st, diag);
    }
    xyl__free(&desc->alloc, sides);
    if (!r && stats) *stats = st;
    if (!r) xyl__skeleton_warn_precision(skeleton->nodes, skeleton->node_count, "the stem mesh", diag);
    return r;
}

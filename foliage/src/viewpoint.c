/* The viewpoint-driven collapse: the least visible live leaf merges with the candidate near it
 * whose merge changes the mutual information between the 20 dodecahedron views and the leaves
 * least (Sulan Zhang's viewpoint-driven simplification, with the merged leaf of the Hidalgo
 * collapse; visible areas from a z-buffer per view).
 *
 * With a_vl the pixels of leaf l visible from view v, A_v = sum_l a_vl, a_l = sum_v a_vl and
 * T = sum_v A_v: p(v) = A_v / T (views weighted by the area they see), p(l|v) = a_vl / A_v,
 * p(l) = sum_v p(v) p(l|v) = a_l / T (a leaf's visibility), and
 *     I(V, L) = sum_v p(v) sum_l p(l|v) log(p(l|v) / p(l))
 *             = (S1 + T log T - sum_v A_v log A_v - sum_l a_l log a_l) / T,  S1 = sum a_vl log a_vl,
 * so the four sums, kept up to date, give I after a merge in O(views).
 *
 * Rendering the 20 views after every merge would cost O(n (n + pixels)). Between renders, the
 * merged leaf's visible pixels in view v are estimated: its children's visible fraction of
 * their projected area ((a_vp + a_vq) / (P_vp + P_vq), P the unoccluded projected area) times
 * its own projected area P_vr; every leaf else keeps its pixels. The views are rendered again
 * after every max(live / 16, 8) merges (or every `refresh`), which replaces every estimate by
 * the truth: O(log n) renders down to 128 leaves, then one per 8 merges. */
#include <string.h>

#include "foliage_internal.h"

typedef struct entry {
    double key; /* a_l: the leaf's visible pixels over all views */
    uint32_t leaf;
} entry;

typedef struct vp {
    xyl_leaf *leaves;
    float *error;
    uint32_t *children;
    const xyl__viewpoint_options *o;
    uint32_t n, count, merges, live, since_render;
    float *vis;       /* XYL__VIEWS rows of cap: a_vl */
    double *total;    /* per leaf: a_l */
    uint8_t *alive;
    entry *heap;
    uint32_t heap_count;
    size_t cap;
    double A[XYL__VIEWS], T, S1, SA, SL;
    xyl__ortho_view views[XYL__VIEWS];
    double pixel_area; /* world area of a pixel */
    xyl__raster r;
    xyl__grid g;
    xyl__viewpoint_stats stats;
} vp;

static double xlogx(double x)
{
    return x > 0.0 ? x * log(x) : 0.0;
}

static double information(double T, double S1, double SA, double SL)
{
    return T > 0.0 ? (S1 + xlogx(T) - SA - SL) / T : 0.0;
}

/* ---- the heap of leaves by visibility (least first; ties: lower index) ----------------------- */

static bool before(const entry *a, const entry *b)
{
    return a->key < b->key || (a->key == b->key && a->leaf < b->leaf);
}

static void heap_push(vp *c, double key, uint32_t leaf)
{
    uint32_t i = c->heap_count++;
    entry e = {key, leaf};
    while (i > 0) {
        uint32_t parent = (i - 1) / 2;
        if (!before(&e, &c->heap[parent])) break;
        c->heap[i] = c->heap[parent];
        i = parent;
    }
    c->heap[i] = e;
}

static entry heap_pop(vp *c)
{
    entry top = c->heap[0], last = c->heap[--c->heap_count];
    uint32_t i = 0;
    for (;;) {
        uint32_t k = 2 * i + 1;
        if (k >= c->heap_count) break;
        if (k + 1 < c->heap_count && before(&c->heap[k + 1], &c->heap[k])) ++k;
        if (!before(&c->heap[k], &last)) break;
        c->heap[i] = c->heap[k];
        i = k;
    }
    if (c->heap_count) c->heap[i] = last;
    return top;
}

/* ---- visibility ------------------------------------------------------------------------------ */

static float *row(const vp *c, int v)
{
    return c->vis + (size_t)v * c->cap;
}

/* Renders the live leaves from every view, counts each one's pixels, and starts the sums and
 * the heap afresh. */
static void render(vp *c)
{
    for (int v = 0; v < XYL__VIEWS; ++v) {
        float *a = row(c, v);
        xyl__raster_clear(&c->r);
        for (uint32_t l = 0; l < c->count; ++l) {
            a[l] = 0.0f;
            if (c->alive[l]) xyl__raster_leaf(&c->r, &c->views[v], &c->leaves[l], l, 0.0f);
        }
        size_t px = (size_t)c->r.width * c->r.height;
        for (size_t k = 0; k < px; ++k)
            if (c->r.id[k] != XYL__RASTER_NONE) a[c->r.id[k]] += 1.0f;
    }
    c->S1 = c->SA = c->SL = c->T = 0.0;
    c->heap_count = 0;
    for (int v = 0; v < XYL__VIEWS; ++v) c->A[v] = 0.0;
    for (uint32_t l = 0; l < c->count; ++l) {
        if (!c->alive[l]) continue;
        double t = 0.0;
        for (int v = 0; v < XYL__VIEWS; ++v) {
            double a = row(c, v)[l];
            t += a, c->A[v] += a, c->S1 += xlogx(a);
        }
        c->total[l] = t;
        c->SL += xlogx(t);
        heap_push(c, t, l);
    }
    for (int v = 0; v < XYL__VIEWS; ++v) c->SA += xlogx(c->A[v]), c->T += c->A[v];
    c->since_render = 0;
    c->stats.renders++;
}

/* The unoccluded projected area of a leaf in view v, in pixels. */
static double projected(const vp *c, const xyl_leaf *l, int v)
{
    double area = 4.0 * xyl__d3_len(xyl__from_f3(l->axis)) * xyl__d3_len(xyl__from_f3(l->side));
    return area * fabs(xyl__d3_dot(xyl__from_f3(l->normal), c->views[v].toward)) / c->pixel_area;
}

/* The estimated pixels of r, the merge of p and q, in each view. */
static void estimate(const vp *c, uint32_t p, uint32_t q, const xyl_leaf *r, double out[XYL__VIEWS])
{
    for (int v = 0; v < XYL__VIEWS; ++v) {
        double seen = (double)row(c, v)[p] + row(c, v)[q];
        double proj = projected(c, &c->leaves[p], v) + projected(c, &c->leaves[q], v);
        out[v] = proj > 0.0 ? seen / proj * projected(c, r, v) : seen;
    }
}

/* I(V, L) after replacing p and q by a leaf of pixels ar[]; the new sums into s[] (S1, SA, SL,
 * T) and the views' totals into A[]. */
static double information_after(const vp *c, uint32_t p, uint32_t q, const double ar[XYL__VIEWS],
                                double A[XYL__VIEWS], double s[4])
{
    double S1 = c->S1, SA = 0.0, T = 0.0, t = 0.0;
    for (int v = 0; v < XYL__VIEWS; ++v) {
        double ap = row(c, v)[p], aq = row(c, v)[q];
        S1 += xlogx(ar[v]) - xlogx(ap) - xlogx(aq);
        A[v] = fmax(0.0, c->A[v] + ar[v] - ap - aq);
        SA += xlogx(A[v]);
        T += A[v];
        t += ar[v];
    }
    double SL = c->SL + xlogx(t) - xlogx(c->total[p]) - xlogx(c->total[q]);
    s[0] = S1, s[1] = SA, s[2] = SL, s[3] = T;
    return information(T, S1, SA, SL);
}

/* ---- the chain ------------------------------------------------------------------------------- */

static bool passes(const vp *c, uint32_t p, uint32_t q)
{
    if (c->o->max_angle < INFINITY) {
        double cosine = xyl__d3_dot(xyl__from_f3(c->leaves[p].normal), xyl__from_f3(c->leaves[q].normal));
        if (acos(fmax(-1.0, fmin(1.0, cosine))) > c->o->max_angle) return false;
    }
    return true;
}

/* Merges p with the candidate that changes I(V, L) least; false when none passes. */
static bool merge_least_visible(vp *c, uint32_t p)
{
    xyl__nearby near;
    double max_d2 = c->o->max_distance < INFINITY ? c->o->max_distance * c->o->max_distance : INFINITY;
    xyl__grid_nearest(&c->g, p, c->leaves[p].center, max_d2, NULL, NULL, &near);
    c->stats.queries++;
    double I = information(c->T, c->S1, c->SA, c->SL);
    double best = INFINITY, best_ar[XYL__VIEWS], best_A[XYL__VIEWS], best_s[4] = {0, 0, 0, 0};
    uint32_t best_q = UINT32_MAX;
    xyl_leaf best_leaf;
    float best_err = 0.0f;
    uint32_t take = near.count < c->o->cell_leaves ? near.count : c->o->cell_leaves;
    for (uint32_t k = 0; k < take; ++k) {
        uint32_t q = near.idx[k];
        if (!passes(c, p, q)) continue;
        uint32_t lo = p < q ? p : q, hi = p < q ? q : p;
        float err;
        xyl_leaf r = xyl__leaf_merge(&c->leaves[lo], &c->leaves[hi], c->error[lo], c->error[hi], &err);
        double ar[XYL__VIEWS], A[XYL__VIEWS], s[4];
        estimate(c, p, q, &r, ar);
        double change = fabs(information_after(c, p, q, ar, A, s) - I);
        c->stats.candidates++;
        if (change < best) { /* ties: the nearer candidate, then the lower index */
            best = change, best_q = q, best_leaf = r, best_err = err;
            memcpy(best_ar, ar, sizeof ar), memcpy(best_A, A, sizeof A), memcpy(best_s, s, sizeof s);
        }
    }
    if (best_q == UINT32_MAX) return false;
    uint32_t q = best_q, k = c->count++;
    c->leaves[k] = best_leaf;
    c->error[k] = best_err;
    c->children[2 * (size_t)c->merges] = p < q ? p : q;
    c->children[2 * (size_t)c->merges + 1] = p < q ? q : p;
    c->merges++;
    c->alive[p] = c->alive[q] = 0;
    c->alive[k] = 1;
    double t = 0.0;
    for (int v = 0; v < XYL__VIEWS; ++v) row(c, v)[k] = (float)best_ar[v], t += best_ar[v];
    c->total[k] = t;
    memcpy(c->A, best_A, sizeof best_A);
    c->S1 = best_s[0], c->SA = best_s[1], c->SL = best_s[2], c->T = best_s[3];
    c->live--;
    xyl__grid_remove(&c->g, p);
    xyl__grid_remove(&c->g, q);
    if (xyl__grid_full(&c->g)) xyl__grid_rebuild(&c->g, c->leaves);
    xyl__grid_insert(&c->g, c->leaves, k);
    heap_push(c, t, k);
    c->since_render++;
    return true;
}

static void run(vp *c)
{
    xyl__grid_build(&c->g, c->leaves, c->n);
    render(c);
    while (c->live > 1 && c->heap_count > 0) {
        uint32_t period = c->o->refresh ? c->o->refresh : (c->live / 16 > 8 ? c->live / 16 : 8);
        if (c->since_render >= period) render(c);
        entry e = heap_pop(c);
        if (!c->alive[e.leaf]) continue;
        merge_least_visible(c, e.leaf); /* a leaf without a partner leaves the heap */
    }
}

/* The sphere of the views: the box of the leaves' corners, the farthest corner. */
static void sphere(const xyl_leaf *l, uint32_t n, xyl__dvec3 *center, double *radius)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    xyl__dvec3 k[4];
    for (uint32_t i = 0; i < n; ++i) {
        xyl__leaf_corners(&l[i], k);
        for (int j = 0; j < 4; ++j) {
            const double v[3] = {k[j].x, k[j].y, k[j].z};
            for (int d = 0; d < 3; ++d) lo[d] = fmin(lo[d], v[d]), hi[d] = fmax(hi[d], v[d]);
        }
    }
    *center = xyl__d3(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    double r = 0.0;
    for (uint32_t i = 0; i < n; ++i) {
        xyl__leaf_corners(&l[i], k);
        for (int j = 0; j < 4; ++j) r = fmax(r, xyl__d3_len(xyl__d3_sub(k[j], *center)));
    }
    *radius = r;
}

static void release(vp *c, const xyl_allocator *a)
{
    xyl__free(a, c->vis);
    xyl__free(a, c->total);
    xyl__free(a, c->alive);
    xyl__free(a, c->heap);
    xyl__raster_free(&c->r, a);
    xyl__grid_free(&c->g, a);
}

xyl_result xyl__collapse_viewpoint(xyl_leaf *leaves, float *error, uint32_t *children, uint32_t n,
                                   const xyl__viewpoint_options *o, const xyl_allocator *a,
                                   uint32_t *merges, xyl__viewpoint_stats *stats, xyl_diag *diag)
{
    *merges = 0;
    for (uint32_t i = 0; i < n; ++i) error[i] = 0.0f;
    if (n < 2) {
        if (stats) memset(stats, 0, sizeof *stats);
        return XYL_OK;
    }
    vp c;
    memset(&c, 0, sizeof c);
    c.leaves = leaves, c.error = error, c.children = children, c.o = o;
    c.n = c.count = c.live = n;
    c.cap = 2 * (size_t)n - 1;
    c.vis = xyl__alloc_array(a, c.cap * XYL__VIEWS, sizeof *c.vis);
    c.total = xyl__alloc_array(a, c.cap, sizeof *c.total);
    c.alive = xyl__calloc(a, c.cap, sizeof *c.alive);
    c.heap = xyl__alloc_array(a, 2 * (size_t)n, sizeof *c.heap);
    xyl_result r = c.vis && c.total && c.alive && c.heap ? XYL_OK : XYL_ERR_OUT_OF_MEMORY;
    if (r == XYL_OK) r = xyl__raster_init(&c.r, o->resolution, o->resolution, a);
    if (r == XYL_OK) r = xyl__grid_init(&c.g, n, a);
    if (r != XYL_OK) {
        release(&c, a);
        return xyl__fail(diag, r, 0, 0, -1, "out of memory for the viewpoint collapse of %u leaves", n);
    }
    memset(c.alive, 1, n);
    xyl__dvec3 center;
    double radius;
    sphere(leaves, n, &center, &radius);
    xyl__dodecahedron_views(center, radius, c.views);
    double pixel = 2.0 * radius / o->resolution;
    c.pixel_area = pixel * pixel;
    run(&c);
    *merges = c.merges;
    c.stats.bytes = c.cap * (XYL__VIEWS * sizeof *c.vis + sizeof *c.total + sizeof *c.alive) +
                    2 * (size_t)n * sizeof *c.heap + (size_t)o->resolution * o->resolution * 12 + c.g.bytes;
    if (stats) *stats = c.stats;
    release(&c, a);
    return XYL_OK;
}

/* The uniform grid of live leaf centres that the collapse asks for nearest neighbours.
 *
 * A build sorts the live leaves by cell into one array of (centre, leaf) items, so a cell's
 * items lie together and a ring of cells is a few runs of memory: the search is bound by
 * memory latency, not arithmetic. A dead leaf's item gives its place to its cell's last one;
 * a leaf made after the build goes to its cell's doubly linked list of extra items. So a cell
 * holds live leaves only, and a query that stops after a fixed number of them does a bounded
 * amount of work even where a million leaves share one cell. The collapse rebuilds the grid
 * whenever a quarter of the live leaves at the last build are new, so cells keep about two
 * live leaves each and the extra lists stay short. */
#include <string.h>

#include "foliage_internal.h"

#define DEAD UINT32_MAX
#define EXTRA_BIT 0x80000000u /* in slot[]: the item is an extra one */

xyl_result xyl__grid_init(xyl__grid *g, uint32_t n, const xyl_allocator *a)
{
    memset(g, 0, sizeof *g);
    size_t leaves = n ? 2 * (size_t)n - 1 : 1;
    g->cell_cap = (size_t)n / 2 + 8;
    g->item_cap = n ? n : 1;
    g->extra_cap = n / 4 + 8;
    g->range = xyl__alloc_array(a, g->cell_cap, sizeof *g->range);
    g->items = xyl__alloc_array(a, g->item_cap, sizeof *g->items);
    g->sort = xyl__alloc_array(a, g->item_cap, sizeof *g->sort);
    g->extra = xyl__alloc_array(a, g->extra_cap, sizeof *g->extra);
    g->slot = xyl__alloc_array(a, leaves, sizeof *g->slot);
    g->live = xyl__alloc_array(a, g->item_cap, sizeof *g->live);
    g->bytes = g->cell_cap * sizeof *g->range +
               g->item_cap * (sizeof *g->items + sizeof *g->sort + sizeof *g->live) +
               g->extra_cap * sizeof *g->extra + leaves * sizeof *g->slot;
    if (g->range && g->items && g->sort && g->extra && g->slot && g->live)
        return XYL_OK;
    xyl__grid_free(g, a);
    return XYL_ERR_OUT_OF_MEMORY;
}

void xyl__grid_free(xyl__grid *g, const xyl_allocator *a)
{
    xyl__free(a, g->range);
    xyl__free(a, g->items);
    xyl__free(a, g->sort);
    xyl__free(a, g->extra);
    xyl__free(a, g->slot);
    xyl__free(a, g->live);
    memset(g, 0, sizeof *g);
}

static void cell_coords(const xyl__grid *g, const float p[3], int32_t out[3])
{
    for (int k = 0; k < 3; ++k) {
        double t = ((double)p[k] - g->min[k]) * g->inv_h;
        out[k] = t > 0.0 ? (t < (double)g->dim[k] ? (int32_t)t : g->dim[k] - 1) : 0;
    }
}

static uint32_t cell_index(const xyl__grid *g, const int32_t c[3])
{
    return (uint32_t)(((size_t)c[2] * (size_t)g->dim[1] + (size_t)c[1]) * (size_t)g->dim[0] +
                      (size_t)c[0]);
}

static uint32_t cell_of(const xyl__grid *g, const float p[3])
{
    int32_t cc[3];
    cell_coords(g, p, cc);
    return cell_index(g, cc);
}

/* Cubic cells of side h, about two live leaves a cell: h from the volume, or from the area or
 * length where the leaves span fewer dimensions; never more cells than cell_cap. */
static void grid_size(xyl__grid *g, const double ext[3], uint32_t live)
{
    double target = fmax(1.0, 0.5 * live);
    double e[3] = {ext[0], ext[1], ext[2]}; /* sorted, smallest first */
    for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j)
            if (e[j] < e[i]) {
                double t = e[i];
                e[i] = e[j];
                e[j] = t;
            }
    double h = 0.0;
    if (e[2] > 0.0) {
        h = cbrt(e[0] * e[1] * e[2] / target);
        if (!(e[0] >= h)) h = sqrt(e[1] * e[2] / target);
        if (!(e[1] >= h)) h = e[2] / target;
    }
    if (!(h > 0.0) || !isfinite(h)) h = e[2] > 0.0 ? e[2] : 1.0;
    for (;;) {
        double cells = 1.0;
        for (int k = 0; k < 3; ++k) {
            double d = fmax(1.0, ceil(ext[k] / h));
            g->dim[k] = (int32_t)fmin(d, (double)INT32_MAX);
            cells *= d;
        }
        if (cells <= (double)g->cell_cap) break;
        h *= 1.25;
    }
    g->h = h;
    g->inv_h = 1.0 / h;
}

/* The 26 neighbours of a cell, nearest kinds first: faces, edges, corners. */
static const int8_t ring1[26][3] = {
    {-1, 0, 0},  {1, 0, 0},   {0, -1, 0},  {0, 1, 0},   {0, 0, -1},  {0, 0, 1},
    {-1, -1, 0}, {1, -1, 0},  {-1, 1, 0},  {1, 1, 0},   {-1, 0, -1}, {1, 0, -1},
    {-1, 0, 1},  {1, 0, 1},   {0, -1, -1}, {0, 1, -1},  {0, -1, 1},  {0, 1, 1},
    {-1, -1, -1}, {1, -1, -1}, {-1, 1, -1}, {1, 1, -1}, {-1, -1, 1}, {1, -1, 1},
    {-1, 1, 1},  {1, 1, 1},
};

static void build(xyl__grid *g, const xyl_leaf *leaves, const uint32_t *live, uint32_t count)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t k = 0; k < count; ++k) {
        const xyl_vec3 c = leaves[live[k]].center;
        const float v[3] = {c.x, c.y, c.z};
        for (int d = 0; d < 3; ++d) lo[d] = fmin(lo[d], v[d]), hi[d] = fmax(hi[d], v[d]);
    }
    double ext[3];
    for (int d = 0; d < 3; ++d) {
        g->min[d] = count ? lo[d] : 0.0;
        ext[d] = count ? hi[d] - lo[d] : 0.0;
    }
    grid_size(g, ext, count);
    for (int n = 0; n < 26; ++n)
        g->ring1_step[n] = ring1[n][0] + ring1[n][1] * (int64_t)g->dim[0] +
                           ring1[n][2] * (int64_t)g->dim[0] * g->dim[1];
    size_t cells = (size_t)g->dim[0] * (size_t)g->dim[1] * (size_t)g->dim[2];
    g->cells = cells;
    for (size_t k = 0; k < cells; ++k) g->range[k] = (xyl__cell_range){0, 0, -1};
    /* counting sort by cell; within a cell, the order of live[] */
    for (uint32_t k = 0; k < count; ++k) {
        const xyl_vec3 c = leaves[live[k]].center;
        const float p[3] = {c.x, c.y, c.z};
        g->sort[k] = cell_of(g, p);
        g->range[g->sort[k]].end++; /* a count for now */
    }
    for (size_t k = 0, at = 0; k < cells; ++k) {
        g->range[k].start = (uint32_t)at;
        at += g->range[k].end;
        g->range[k].end = g->range[k].start;
    }
    for (uint32_t k = 0; k < count; ++k) {
        uint32_t at = g->range[g->sort[k]].end++;
        const xyl_vec3 c = leaves[live[k]].center;
        g->items[at] = (xyl__grid_item){{c.x, c.y, c.z}, live[k]};
        g->slot[live[k]] = at;
    }
    g->item_count = count;
    g->extra_count = 0;
    g->built_live = count;
}

void xyl__grid_build(xyl__grid *g, const xyl_leaf *leaves, uint32_t count)
{
    for (uint32_t k = 0; k < count; ++k) g->live[k] = k;
    build(g, leaves, g->live, count);
}

void xyl__grid_rebuild(xyl__grid *g, const xyl_leaf *leaves)
{
    uint32_t count = 0;
    for (size_t c = 0; c < g->cells; ++c)
        for (uint32_t k = g->range[c].start; k < g->range[c].end; ++k) g->live[count++] = g->items[k].leaf;
    for (uint32_t k = 0; k < g->extra_count; ++k)
        if (g->extra[k].item.leaf != DEAD) g->live[count++] = g->extra[k].item.leaf;
    build(g, leaves, g->live, count);
}

bool xyl__grid_full(const xyl__grid *g)
{
    return g->extra_count >= g->built_live / 4 || g->extra_count == g->extra_cap;
}

void xyl__grid_insert(xyl__grid *g, const xyl_leaf *leaves, uint32_t leaf)
{
    const xyl_vec3 c = leaves[leaf].center;
    const float p[3] = {c.x, c.y, c.z};
    uint32_t cell = cell_of(g, p), at = g->extra_count++;
    int32_t first = g->range[cell].extra;
    g->extra[at] = (xyl__grid_extra){{{c.x, c.y, c.z}, leaf}, first, -1};
    if (first >= 0) g->extra[first].prev = (int32_t)at;
    g->range[cell].extra = (int32_t)at;
    g->slot[leaf] = at | EXTRA_BIT;
}

void xyl__grid_remove(xyl__grid *g, uint32_t leaf)
{
    uint32_t s = g->slot[leaf];
    if (s & EXTRA_BIT) {
        uint32_t at = s & ~EXTRA_BIT;
        xyl__grid_extra *x = &g->extra[at];
        if (x->prev >= 0) g->extra[x->prev].next = x->next;
        else g->range[cell_of(g, x->item.p)].extra = x->next;
        if (x->next >= 0) g->extra[x->next].prev = x->prev;
        x->item.leaf = DEAD;
        return;
    }
    uint32_t cell = cell_of(g, g->items[s].p), last = --g->range[cell].end;
    g->items[s] = g->items[last];
    g->slot[g->items[s].leaf] = s;
}

/* ---- nearest neighbours -------------------------------------------------------------------- */

typedef struct query {
    const xyl__grid *g;
    uint32_t self;
    double p[3], max_d2;
    double limit;              /* max_d2, or the K-th nearest's d2 once K are found */
    double below[3], above[3]; /* from the point to its cell's lower and upper faces */
    xyl__accept_fn accept;
    void *ctx;
    uint64_t cells;
    xyl__nearby nr;            /* the answer so far, here rather than behind a pointer */
} query;

static void keep(xyl__nearby *nr, uint32_t j, double d2)
{
    uint32_t k = nr->count < XYL__GRID_K ? nr->count++ : XYL__GRID_K;
    if (k == XYL__GRID_K) {
        uint32_t last = XYL__GRID_K - 1;
        if (d2 > nr->d2[last] || (d2 == nr->d2[last] && j > nr->idx[last])) return;
        k = last;
    }
    while (k > 0 && (d2 < nr->d2[k - 1] || (d2 == nr->d2[k - 1] && j < nr->idx[k - 1]))) {
        nr->d2[k] = nr->d2[k - 1];
        nr->idx[k] = nr->idx[k - 1];
        --k;
    }
    nr->d2[k] = d2;
    nr->idx[k] = j;
}

/* Looks at one item; false once XYL__GRID_SCAN_CAP live leaves have been looked at. */
static XYL__ALWAYS_INLINE bool look(query *q, const xyl__grid_item *it)
{
    uint32_t j = it->leaf;
    if (j == q->self) return true;
    double dx = it->p[0] - q->p[0], dy = it->p[1] - q->p[1], dz = it->p[2] - q->p[2];
    double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 <= q->limit && (!q->accept || q->accept(q->ctx, j))) {
        keep(&q->nr, j, d2);
        if (q->nr.count == XYL__GRID_K) {
            double kth = q->nr.d2[XYL__GRID_K - 1];
            q->limit = kth < q->max_d2 ? kth : q->max_d2;
        }
    }
    return ++q->nr.scanned < XYL__GRID_SCAN_CAP;
}

/* A cell's items from a place that depends on the asking leaf, wrapping round: where more
 * leaves than a query looks at share a cell (coincident leaves), each leaf then sees its own
 * part of them, and they do not all choose the same partner, which would make every one of
 * them look again once that partner is gone. */
static XYL__ALWAYS_INLINE bool scan_cell(query *q, uint32_t cell)
{
    const xyl__grid *g = q->g;
    q->cells++;
    uint32_t begin = g->range[cell].start, size = g->range[cell].end - begin;
    uint32_t first = (uint32_t)(((uint64_t)(q->self * 0x9e3779b1u) * size) >> 32);
    for (uint32_t k = first; k < size; ++k)
        if (!look(q, &g->items[begin + k])) return false;
    for (uint32_t k = 0; k < first; ++k)
        if (!look(q, &g->items[begin + k])) return false;
    for (int32_t k = g->range[cell].extra; k >= 0; k = g->extra[k].next)
        if (!look(q, &g->extra[k].item)) return false;
    return true;
}

static int32_t clamp_lo(int32_t v)
{
    return v > 0 ? v : 0;
}

static int32_t clamp_hi(int32_t v, int32_t dim)
{
    return v < dim - 1 ? v : dim - 1;
}

/* The squared distance along axis k from the point to the cells of index c (c0 its own). */
static double gap2(const query *q, int k, int32_t c, int32_t c0)
{
    double d = c < c0 ? q->below[k] + (double)(c0 - c - 1) * q->g->h
             : c > c0 ? q->above[k] + (double)(c - c0 - 1) * q->g->h
                      : 0.0;
    return d * d;
}

/* Whether a cell at squared distance d2 can hold a leaf nearer than the K found. */
static bool worth(const query *q, double d2)
{
    return d2 <= q->limit;
}


/* Ring 1 in two passes: first the cells worth a look, with their ranges and first items
 * asked for ahead (their cache misses then overlap), then the scan, which drops the cells the
 * leaves found meanwhile put out of reach. */
static bool scan_ring1(query *q, const int32_t c0[3])
{
    const xyl__grid *g = q->g;
    /* per axis and offset -1, 0, 1: the squared gap to those cells (gap2's values), whether
       they exist, and the step of the cell index */
    double gap[3][3];
    bool exists[3][3];
    for (int k = 0; k < 3; ++k) {
        gap[k][0] = q->below[k] * q->below[k];
        gap[k][1] = 0.0;
        gap[k][2] = q->above[k] * q->above[k];
        exists[k][0] = c0[k] > 0;
        exists[k][1] = true;
        exists[k][2] = c0[k] < g->dim[k] - 1;
    }
    const bool interior = exists[0][0] && exists[0][2] && exists[1][0] && exists[1][2] &&
                          exists[2][0] && exists[2][2];
    const int64_t home = (int64_t)cell_index(g, c0);
    uint32_t cells[26];
    double dist2[26];
    int count = 0;
    for (int n = 0; n < 26; ++n) {
        const int x = ring1[n][0] + 1, y = ring1[n][1] + 1, z = ring1[n][2] + 1;
        if (!interior && (!exists[0][x] || !exists[1][y] || !exists[2][z])) continue;
        double d2 = gap[0][x] + gap[1][y] + gap[2][z];
        if (!worth(q, d2)) continue;
        cells[count] = (uint32_t)(home + g->ring1_step[n]);
        dist2[count++] = d2;
        XYL__PREFETCH(&g->range[cells[count - 1]]);
    }
    for (int n = 0; n < count; ++n) XYL__PREFETCH(&g->items[g->range[cells[n]].start]);
    for (int n = 0; n < count; ++n)
        if (worth(q, dist2[n]) && !scan_cell(q, cells[n])) return false;
    return true;
}

/* The cells at Chebyshev distance r from c0 (the shell of the cube of side 2r + 1), less those
 * farther than the K nearest found so far. */
static bool scan_ring(query *q, const int32_t c0[3], int32_t r)
{
    if (r == 1) return scan_ring1(q, c0);
    const int32_t *dim = q->g->dim;
    int32_t x0 = clamp_lo(c0[0] - r), x1 = clamp_hi(c0[0] + r, dim[0]);
    for (int32_t z = clamp_lo(c0[2] - r), z1 = clamp_hi(c0[2] + r, dim[2]); z <= z1; ++z) {
        double gz = gap2(q, 2, z, c0[2]);
        for (int32_t y = clamp_lo(c0[1] - r), y1 = clamp_hi(c0[1] + r, dim[1]); y <= y1; ++y) {
            double gzy = gz + gap2(q, 1, y, c0[1]);
            if (!worth(q, gzy)) continue;
            bool face = r == 0 || z == c0[2] - r || z == c0[2] + r || y == c0[1] - r ||
                        y == c0[1] + r;
            int32_t cc[3] = {0, y, z};
            for (cc[0] = face ? x0 : c0[0] - r; cc[0] <= (face ? x1 : c0[0] + r);
                 cc[0] += face ? 1 : 2 * r) {
                /* inside the cube's faces only the two ends of an x row are on the shell */
                if (cc[0] < 0 || cc[0] >= dim[0] || !worth(q, gzy + gap2(q, 0, cc[0], c0[0]))) continue;
                if (!scan_cell(q, cell_index(q->g, cc))) return false;
            }
        }
    }
    return true;
}

uint64_t xyl__grid_nearest(const xyl__grid *g, uint32_t self, xyl_vec3 centre, double max_d2,
                           xyl__accept_fn accept, void *ctx, xyl__nearby *out)
{
    query q = {g, self, {centre.x, centre.y, centre.z}, max_d2, max_d2, {0}, {0}, accept, ctx, 0, {0}};
    const float p[3] = {centre.x, centre.y, centre.z};
    int32_t c0[3];
    cell_coords(g, p, c0);
    int32_t rmax = 0;
    for (int k = 0; k < 3; ++k) {
        int32_t span = c0[k] > g->dim[k] - 1 - c0[k] ? c0[k] : g->dim[k] - 1 - c0[k];
        if (span > rmax) rmax = span;
    }
    /* how far the point lies inside its own cell, from each face and from the nearest one */
    double inside = INFINITY;
    for (int k = 0; k < 3; ++k) {
        double lo = g->min[k] + c0[k] * g->h, t = (double)p[k];
        double below = t - lo, above = lo + g->h - t;
        q.below[k] = below > 0.0 ? below : 0.0;
        q.above[k] = above > 0.0 ? above : 0.0;
        if (c0[k] > 0 && q.below[k] < inside) inside = q.below[k];
        if (c0[k] < g->dim[k] - 1 && q.above[k] < inside) inside = q.above[k];
    }
    if (!(inside < INFINITY)) inside = 0.0;
    for (int32_t r = 0; r <= rmax; ++r) {
        if (!scan_ring(&q, c0, r)) break;
        /* every cell left is at least that far away */
        double reach = (double)r * g->h + inside;
        if (q.nr.count == XYL__GRID_K && q.nr.d2[XYL__GRID_K - 1] <= reach * reach) break;
        if (reach * reach > max_d2) break;
    }
    *out = q.nr;
    return q.cells;
}

/* The linear LOD array: one collapse chain reordered so that every LOD draws as two ranges.
 *
 * A chain in cost order does not in general have the property: a merged leaf would have to
 * die in the order leaves were made. Reordering the merges as the reverse breadth-first order
 * of the merge forest (roots' merges last; roots, and the two children of a merge, in cost
 * order) gives it: a breadth-first queue holds a merge after its parent's, so of two merges A
 * before B in the chain, A's parent comes at or before B's, and merged leaves die in the order
 * they were made. The live merged leaves after i merges are then one range of the leaves made
 * so far; the originals, stored by decreasing step of death, are a prefix. */
#include <string.h>

#include "foliage_internal.h"

#define NONE UINT32_MAX

typedef struct order {
    uint32_t *parent; /* per leaf: the cost-order merge that took it, NONE for a root */
    uint32_t *queue;  /* the merges breadth first; the chain is its reverse */
    uint32_t *death;  /* per leaf: after how many chain merges it is gone, m + 1 never */
    uint32_t *dest;   /* per leaf: its place in the array */
    uint32_t *bucket; /* counting sort of the originals by death */
} order;

static void breadth_first(order *o, const uint32_t *children, uint32_t n, uint32_t m)
{
    for (uint32_t x = 0; x < n + m; ++x) o->parent[x] = NONE;
    for (uint32_t g = 0; g < m; ++g) o->parent[children[2 * g]] = o->parent[children[2 * g + 1]] = g;
    uint32_t tail = 0;
    for (uint32_t g = m; g-- > 0;) /* the roots, last made first: reversed, in cost order */
        if (o->parent[n + g] == NONE) o->queue[tail++] = g;
    for (uint32_t head = 0; head < tail; ++head) {
        uint32_t g = o->queue[head], c0 = children[2 * g], c1 = children[2 * g + 1];
        uint32_t first = c0 > c1 ? c0 : c1, second = c0 > c1 ? c1 : c0;
        if (first >= n) o->queue[tail++] = first - n;
        if (second >= n) o->queue[tail++] = second - n;
    }
}

/* Each leaf's step of death and place in the array. */
static void places(order *o, uint32_t n, uint32_t m)
{
    uint32_t *pos = o->bucket; /* borrowed: the chain position of each merge */
    for (uint32_t k = 0; k < m; ++k) pos[o->queue[m - 1 - k]] = k;
    for (uint32_t x = 0; x < n + m; ++x) o->death[x] = o->parent[x] == NONE ? m + 1 : pos[o->parent[x]] + 1;
    for (uint32_t g = 0; g < m; ++g) o->dest[n + g] = n + pos[g];
    /* originals by decreasing death, ties by index: a counting sort over deaths 1 .. m + 1 */
    memset(o->bucket, 0, ((size_t)m + 2) * sizeof *o->bucket);
    for (uint32_t x = 0; x < n; ++x) o->bucket[o->death[x]]++;
    uint32_t at = 0;
    for (uint32_t d = m + 2; d-- > 0;) {
        uint32_t count = o->bucket[d];
        o->bucket[d] = at;
        at += count;
    }
    for (uint32_t x = 0; x < n; ++x) o->dest[x] = o->bucket[o->death[x]]++;
}

static void write_links(const order *o, const uint32_t *children, uint32_t n, uint32_t m,
                        uint32_t base, const float *error, const uint32_t *source,
                        xyl_leaf_link *links)
{
    for (uint32_t x = 0; x < n + m; ++x) {
        xyl_leaf_link *l = &links[o->dest[x]];
        l->children[0] = l->children[1] = -1;
        l->parent = o->parent[x] == NONE ? -1 : (int32_t)(base + o->dest[n + o->parent[x]]);
        l->error = error[x];
        l->source = x < n ? source[x] : NONE;
    }
    for (uint32_t g = 0; g < m; ++g) {
        uint32_t a = o->dest[children[2 * g]], b = o->dest[children[2 * g + 1]];
        xyl_leaf_link *l = &links[o->dest[n + g]];
        l->children[0] = (int32_t)(base + (a < b ? a : b));
        l->children[1] = (int32_t)(base + (a < b ? b : a));
    }
}

/* lods[i]: the ranges after the chain's first i merges, and the largest error made so far. */
static void write_lods(const order *o, const uint32_t *children, uint32_t n, uint32_t m,
                       const float *error, xyl_foliage_lod *lods)
{
    uint32_t a = n, dead = 0;
    float worst = 0.0f;
    lods[0] = (xyl_foliage_lod){n, n, 0, 0.0f};
    for (uint32_t k = 0; k < m; ++k) {
        uint32_t g = o->queue[m - 1 - k];
        uint32_t originals = (children[2 * g] < n) + (children[2 * g + 1] < n);
        a -= originals;
        dead += 2 - originals;
        if (error[n + g] > worst) worst = error[n + g];
        lods[k + 1] = (xyl_foliage_lod){a, n + dead, k + 1 - dead, worst};
    }
}

/* Moves every leaf x to dest[x], in place (dest ends as the identity). */
static void permute(xyl_leaf *leaves, uint32_t *dest, uint32_t count)
{
    for (uint32_t x = 0; x < count; ++x) {
        while (dest[x] != x) {
            uint32_t y = dest[x];
            xyl_leaf l = leaves[x];
            leaves[x] = leaves[y];
            leaves[y] = l;
            dest[x] = dest[y];
            dest[y] = y;
        }
    }
}

xyl_result xyl__linearize(xyl_leaf *leaves, const float *error, const uint32_t *children, uint32_t n,
                          uint32_t m, uint32_t base, const uint32_t *source,
                          xyl_leaf_link *links, xyl_foliage_lod *lods, const xyl_allocator *a,
                          xyl_diag *diag)
{
    size_t count = (size_t)n + m;
    order o;
    o.parent = xyl__alloc_array(a, count, sizeof *o.parent);
    o.queue = xyl__alloc_array(a, m, sizeof *o.queue);
    o.death = xyl__alloc_array(a, count, sizeof *o.death);
    o.dest = xyl__alloc_array(a, count, sizeof *o.dest);
    o.bucket = xyl__alloc_array(a, (size_t)m + 2, sizeof *o.bucket);
    xyl_result r = XYL_OK;
    if (!o.parent || !o.queue || !o.death || !o.dest || !o.bucket) {
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the LOD array");
    } else {
        breadth_first(&o, children, n, m);
        places(&o, n, m);
        write_links(&o, children, n, m, base, error, source, links);
        write_lods(&o, children, n, m, error, lods);
        permute(leaves, o.dest, (uint32_t)count);
    }
    xyl__free(a, o.parent);
    xyl__free(a, o.queue);
    xyl__free(a, o.death);
    xyl__free(a, o.dest);
    xyl__free(a, o.bucket);
    return r;
}

/* Twig pruning: a skeleton without the subtrees thinner than a width, for the stem LODs
 * (xyl_stems.h) and anyone who wants fewer nodes at a known world error. */
#include <string.h>

#include "skeleton_internal.h"
#include "xylem/xyl_skeleton.h"

/* widest[i]: the largest diameter 2 r of node i and its descendants. Children come after their
 * parent, so one backward pass carries each subtree's width up. 2 r is exact in float. */
static void subtree_widths(const xyl_skel_node *nodes, size_t n, float *widest)
{
    for (size_t i = 0; i < n; ++i) widest[i] = 2.0f * nodes[i].radius;
    for (size_t i = n; i-- > 0;) {
        int32_t p = nodes[i].parent;
        if (p >= 0 && widest[i] > widest[p]) widest[p] = widest[i];
    }
}

/* index[i] = the node's index in the pruned skeleton, or -1 where it goes. A node stays when it
 * is a root, the child that continues a root's branch (largest radius, first on ties, as
 * xyl_skeleton_create derives it; recomputed so that a caller-built view with stale branch ids
 * prunes the same), or when its subtree is at least min_width wide. The kept set is closed under
 * parents: a parent's subtree holds its child's. Removed nodes get widest[i] = -1 (their width
 * is no longer needed) so that the leaves can tell them; stats are counted on the way. */
static size_t mark_kept(const xyl_skel_node *nodes, size_t n, float *widest, float min_width,
                        int32_t *index, xyl_skeleton_prune_stats *st)
{
    for (size_t i = 0; i < n; ++i) index[i] = -1;
    /* first index[root] holds the root's continuing child */
    for (size_t i = 0; i < n; ++i) {
        int32_t p = nodes[i].parent;
        if (p < 0 || nodes[p].parent >= 0) continue;
        int32_t m = index[p];
        if (m < 0 || nodes[i].radius > nodes[m].radius) index[p] = (int32_t)i;
    }
    size_t kept = 0;
    for (size_t i = 0; i < n; ++i) {
        int32_t p = nodes[i].parent;
        if (p < 0) {
            int32_t m = index[i]; /* m > i, not visited yet: mark it for keeping */
            index[i] = (int32_t)kept++;
            if (m >= 0) index[m] = -2;
        } else if (index[i] == -2 || !(widest[i] < min_width)) {
            index[i] = (int32_t)kept++;
        } else {
            if (widest[p] >= 0.0f) { /* the parent stays: i heads a removed subtree */
                st->subtrees_removed++;
                if (widest[i] > st->max_removed_width) st->max_removed_width = widest[i];
            }
            st->nodes_removed++;
            widest[i] = -1.0f;
        }
    }
    return kept;
}

static xyl_result check(const xyl_skeleton *s, float min_width, xyl_diag *diag)
{
    if (!isfinite(min_width) || min_width < 0.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the prune width is %g; it must be finite and >= 0 (world units)",
                         (double)min_width);
    /* a caller-built view must hold what the walk relies on: parents before children */
    return xyl__skeleton_check_view(s, diag);
}

xyl_result xyl_skeleton_prune(const xyl_skeleton *s, float min_width,
                              const xyl_skeleton_prune_desc *desc, xyl_skeleton **out,
                              xyl_skeleton_prune_stats *stats, xyl_diag *diag)
{
    if (!s || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the skeleton and out must not be NULL");
    xyl_result r = check(s, min_width, diag);
    if (r != XYL_OK) return r;
    const xyl_allocator *a = desc ? &desc->alloc : NULL;
    size_t n = s->node_count;
    float *widest = xyl__alloc_array(a, n, sizeof *widest);
    int32_t *index = xyl__alloc_array(a, n, sizeof *index);
    xyl_skel_leaf *leaves = xyl__alloc_array(a, s->leaf_count, sizeof *leaves);
    xyl_skel_node *nodes = NULL;
    xyl_skeleton_prune_stats st = {0, 0, 0.0f, 0};
    size_t kept = 0;
    if (widest && index && leaves) {
        subtree_widths(s->nodes, n, widest);
        kept = mark_kept(s->nodes, n, widest, min_width, index, &st);
        nodes = xyl__alloc_array(a, kept, sizeof *nodes);
    }
    if (!nodes) {
        xyl__free(a, widest);
        xyl__free(a, index);
        xyl__free(a, leaves);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1,
                         "out of memory for the pruned skeleton");
    }
    for (size_t i = 0; i < n; ++i) {
        int32_t p = s->nodes[i].parent;
        if (index[i] >= 0) {
            xyl_skel_node *k = &nodes[index[i]];
            *k = s->nodes[i];
            k->parent = p < 0 ? -1 : index[p];
        } else {
            index[i] = index[p]; /* a removed node now names its nearest kept ancestor */
        }
    }
    /* a leaf of a removed node hangs from that ancestor, where it was */
    for (size_t j = 0; j < s->leaf_count; ++j) {
        leaves[j] = s->leaves[j];
        int32_t node = leaves[j].node;
        if (node < 0) continue;
        st.leaves_moved += widest[node] < 0.0f;
        leaves[j].node = index[node];
    }
    xyl__free(a, widest);
    xyl__free(a, index);
    xyl_skeleton *pruned = NULL;
    r = xyl__skeleton_adopt(nodes, kept, leaves, s->leaf_count, s->origin, a, &pruned, diag);
    if (r != XYL_OK) return r;
    ((xyl__skeleton *)pruned)->pub.clamped_forks = s->clamped_forks;
    *out = pruned;
    if (stats) *stats = st;
    return XYL_OK;
}

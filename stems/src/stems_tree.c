/* The tree as meshed: each node's children and main child, once laterals are placed and merged. */
#include "stems_internal.h"

/* Children of every node in one array (counting sort by parent) and each node's main child, in
 * two passes over the nodes. A child of the parent's branch is its main child; the last one in
 * node order wins, as child_list holds children in node order. */
static xyl_result index_children(stems *s, const int32_t *parent_of)
{
    size_t n = s->sk->node_count;
    const xyl_skel_node *nodes = s->sk->nodes;
    /* counts go to child_start[p + 2], so that after the prefix sum child_start[p + 1] is p's
     * first slot and filling moves it on to p's end, which is p + 1's start */
    xyl__free(&s->alloc, s->child_start); /* the second pass of index_tree */
    xyl__free(&s->alloc, s->child_list);
    xyl__free(&s->alloc, s->main);
    uint32_t *start = xyl__calloc(&s->alloc, n + 2, sizeof *start);
    s->child_start = start;
    s->child_list = xyl__alloc_array(&s->alloc, n, sizeof *s->child_list);
    s->main = xyl__alloc_array(&s->alloc, n, sizeof *s->main);
    if (!start || !s->child_list || !s->main) return xyl__stems_oom(s);
    for (size_t i = 0; i < n; ++i) {
        int32_t p = parent_of ? parent_of[i] : nodes[i].parent;
        if (p >= 0) ++start[p + 2];
        s->main[i] = UINT32_MAX;
    }
    for (size_t i = 2; i < n + 2; ++i) start[i] += start[i - 1];
    for (size_t i = 0; i < n; ++i) {
        int32_t p = parent_of ? parent_of[i] : nodes[i].parent;
        if (p < 0) continue;
        s->child_list[start[p + 1]++] = (uint32_t)i;
        if (nodes[i].branch != nodes[p].branch) continue;
        /* a lateral child of its parent's branch would add bridge faces to the parent's
         * vertex sums after the parent is built (xyl_skeleton_create never makes one) */
        if (s->main[p] != UINT32_MAX) s->unit_per_branch = false;
        s->main[p] = (uint32_t)i;
    }
    return XYL_OK;
}

/* Whether some node has two or more lateral children, the only place siblings can merge. */
static bool has_sibling_laterals(const stems *s)
{
    for (size_t n = 0; n < s->sk->node_count; ++n)
        if (s->child_start[n + 1] - s->child_start[n] > 1u + (s->main[n] != UINT32_MAX)) return true;
    return false;
}

/* Children of every node, indexed again after laterals inside their parent or a sibling were
 * moved, and again after laterals that came to hang from one node were merged (stems_merge.c),
 * so that the rest of the mesher sees the tree as meshed. One call site of index_children:
 * inlined twice, GCC doubts its sizes. */
xyl_result xyl__stems_index_tree(stems *s)
{
    size_t n = s->sk->node_count;
    int32_t *parent_of = NULL;
    xyl_result r = XYL_OK;
    bool moved = true;
    for (int step = 0; step < 3 && !r; ++step) {
        if (moved) r = index_children(s, parent_of);
        if (r) break;
        if (step == 0) { /* parent_of, then scratch */
            parent_of = xyl__alloc_array(&s->alloc, n ? 5 * n : 1, sizeof *parent_of);
            s->tails = xyl__alloc_array(&s->alloc, n ? 6 * n : 1, sizeof *s->tails);
            if (!parent_of || !s->tails) {
                r = xyl__stems_oom(s);
                break;
            }
            xyl__stems_tail_boxes(s, s->tails);
            moved = xyl__stems_place_laterals(s, parent_of, (uint32_t *)(parent_of + n));
        } else if (step == 1) {
            /* here moved says whether the placement moved laterals: one it moved may lie in
             * its new fork's tube, siblings or not */
            moved = (moved || has_sibling_laterals(s)) && xyl__stems_merge_siblings(s, parent_of);
        }
    }
    xyl__free(&s->alloc, parent_of);
    xyl__free(&s->alloc, s->tails);
    s->tails = NULL;
    return r;
}

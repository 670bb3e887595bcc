/* Skeleton construction: validation, copy, and derivation of branch ids and orders. */
#include <float.h>
#include <string.h>

#include "skeleton_internal.h"
#include "xylem/xyl_skeleton.h"


static xyl_result validate(const xyl_skeleton_desc *d, xyl_diag *diag)
{
    uint64_t max_nodes = d->limits.max_nodes ? d->limits.max_nodes : XYL__SKEL_DEFAULT_MAX_NODES;
    uint64_t max_leaves = d->limits.max_leaves ? d->limits.max_leaves : XYL__SKEL_DEFAULT_MAX_LEAVES;
    if ((d->node_count && !d->nodes) || (d->leaf_count && !d->leaves))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "array is NULL but count is not 0");
    if ((uint64_t)d->node_count > max_nodes || d->node_count > (size_t)INT32_MAX)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu nodes exceed the limit of %llu", d->node_count,
                         (unsigned long long)max_nodes);
    if ((uint64_t)d->leaf_count > max_leaves)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu leaves exceed the limit of %llu", d->leaf_count,
                         (unsigned long long)max_leaves);
    if (!isfinite(d->origin[0]) || !isfinite(d->origin[1]) || !isfinite(d->origin[2]))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "the origin is not finite");
    for (size_t i = 0; i < d->node_count; ++i) {
        const xyl_skel_node *n = &d->nodes[i];
        if (!isfinite(n->pos.x) || !isfinite(n->pos.y) || !isfinite(n->pos.z) ||
            !isfinite(n->radius))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)i,
                             "node %zu has a non-finite position or radius", i);
        if (!(n->radius > 0.0f))
            return xyl__fail(diag, XYL_ERR_INVALID_SKELETON, 0, 0, (int64_t)i,
                             "node %zu has radius %g; radii must be > 0", i, (double)n->radius);
        if (n->parent < -1 || (int64_t)n->parent >= (int64_t)i)
            return xyl__fail(diag, XYL_ERR_INVALID_SKELETON, 0, 0, (int64_t)i,
                             "node %zu has parent %d; a parent must come before its child "
                             "(or be -1 for a root)",
                             i, (int)n->parent);
    }
    for (size_t i = 0; i < d->leaf_count; ++i) {
        const xyl_skel_leaf *l = &d->leaves[i];
        xyl_vec3 v[4] = {l->pos, l->heading, l->left, l->up};
        for (int k = 0; k < 4; ++k) {
            if (!isfinite(v[k].x) || !isfinite(v[k].y) || !isfinite(v[k].z))
                return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)i,
                                 "leaf %zu has a non-finite vector", i);
        }
        if (!isfinite(l->size))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)i,
                             "leaf %zu has a non-finite size", i);
        if (!(l->size > 0.0f))
            return xyl__fail(diag, XYL_ERR_INVALID_SKELETON, 0, 0, (int64_t)i,
                             "leaf %zu has size %g; sizes must be > 0", i, (double)l->size);
        if (l->node < -1 || (int64_t)l->node >= (int64_t)d->node_count)
            return xyl__fail(diag, XYL_ERR_INVALID_SKELETON, 0, 0, (int64_t)i,
                             "leaf %zu hangs from node %d, which does not exist", i, (int)l->node);
    }
    return XYL_OK;
}

/* The child with the largest radius (first on ties) continues its parent's branch; every other
 * child opens a new branch one order higher. Parents precede children, so one pass finds each
 * node's heaviest child and a second pass numbers branches in node order. */
static uint32_t assign_branches(xyl_skel_node *nodes, size_t n, int32_t *main_child,
                                uint32_t *max_order)
{
    for (size_t i = 0; i < n; ++i) main_child[i] = -1;
    for (size_t i = 0; i < n; ++i) {
        int32_t p = nodes[i].parent;
        if (p < 0) continue;
        int32_t m = main_child[p];
        if (m < 0 || nodes[i].radius > nodes[m].radius) main_child[p] = (int32_t)i;
    }
    uint32_t branches = 0;
    *max_order = 0;
    for (size_t i = 0; i < n; ++i) {
        int32_t p = nodes[i].parent;
        if (p < 0) {
            nodes[i].branch = branches++;
            nodes[i].order = 0;
        } else if (main_child[p] == (int32_t)i) {
            nodes[i].branch = nodes[p].branch;
            nodes[i].order = nodes[p].order;
        } else {
            nodes[i].branch = branches++;
            nodes[i].order = nodes[p].order + 1;
        }
        if (nodes[i].order > *max_order) *max_order = nodes[i].order;
    }
    return branches;
}

xyl_result xyl__skeleton_adopt(xyl_skel_node *nodes, size_t node_count, xyl_skel_leaf *leaves,
                               size_t leaf_count, const double *origin,
                               const xyl_allocator *alloc, xyl_skeleton **out, xyl_diag *diag)
{
    xyl__skeleton *s = xyl__calloc(alloc, 1, sizeof *s);
    int32_t *main_child = xyl__calloc(alloc, node_count ? node_count : 1, sizeof *main_child);
    if (!s || !main_child) {
        xyl__free(alloc, s);
        xyl__free(alloc, main_child);
        xyl__free(alloc, nodes);
        xyl__free(alloc, leaves);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the skeleton");
    }
    if (alloc) s->alloc = *alloc;
    uint32_t max_order = 0;
    uint32_t branches = assign_branches(nodes, node_count, main_child, &max_order);
    uint32_t roots = 0;
    for (size_t i = 0; i < node_count; ++i) roots += nodes[i].parent < 0;
    xyl__free(alloc, main_child);
    s->nodes = nodes;
    s->leaves = leaves;
    s->pub.nodes = nodes;
    s->pub.node_count = node_count;
    s->pub.leaves = leaves;
    s->pub.leaf_count = leaf_count;
    s->pub.branch_count = branches;
    s->pub.root_count = roots;
    s->pub.max_order = max_order;
    if (origin) memcpy(s->pub.origin, origin, sizeof s->pub.origin);
    *out = &s->pub;
    xyl__diag_ok(diag);
    return XYL_OK;
}

double xyl__skel_float_spacing(xyl_vec3 p)
{
    double m = fabs((double)p.x);
    if (fabs((double)p.y) > m) m = fabs((double)p.y);
    if (fabs((double)p.z) > m) m = fabs((double)p.z);
    if (!(m >= (double)FLT_MIN)) return m > 0.0 ? ldexp(1.0, -149) : 0.0;
    return ldexp(1.0, ilogb(m) - 23);
}

void xyl__skeleton_warn_precision(const xyl_skel_node *nodes, size_t count, const char *what,
                                  xyl_diag *diag)
{
    double worst = 0.0;
    size_t at = 0;
    for (size_t i = 0; i < count; ++i) {
        double ratio = xyl__skel_float_spacing(nodes[i].pos) / (double)nodes[i].radius;
        if (ratio > worst) worst = ratio, at = i;
    }
    if (!(worst > XYL__SKEL_PRECISION_WARN)) return;
    const xyl_vec3 p = nodes[at].pos;
    xyl__warn(diag,
              "%s loses detail to float precision: node %zu lies at (%g, %g, %g) from the "
              "origin, where floats are spaced %g, %.3g %% of its radius %g; give the "
              "skeleton an origin near the tree",
              what, at, (double)p.x, (double)p.y, (double)p.z,
              xyl__skel_float_spacing(p), 100.0 * worst, (double)nodes[at].radius);
}

xyl_result xyl_skeleton_create(const xyl_skeleton_desc *desc, xyl_skeleton **out, xyl_diag *diag)
{
    if (!desc || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "desc and out must not be NULL");
    xyl_result r = validate(desc, diag);
    if (r != XYL_OK) return r;
    const xyl_allocator *a = &desc->alloc;
    xyl_skel_node *nodes = xyl__calloc(a, desc->node_count ? desc->node_count : 1, sizeof *nodes);
    xyl_skel_leaf *leaves = xyl__calloc(a, desc->leaf_count ? desc->leaf_count : 1, sizeof *leaves);
    if (!nodes || !leaves) {
        xyl__free(a, nodes);
        xyl__free(a, leaves);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the skeleton");
    }
    if (desc->node_count) memcpy(nodes, desc->nodes, desc->node_count * sizeof *nodes);
    if (desc->leaf_count) memcpy(leaves, desc->leaves, desc->leaf_count * sizeof *leaves);
    r = xyl__skeleton_adopt(nodes, desc->node_count, leaves, desc->leaf_count, desc->origin, a, out,
                            diag);
    if (r == XYL_OK) xyl__skeleton_warn_precision(desc->nodes, desc->node_count, "the skeleton", diag);
    return r;
}

xyl_result xyl__skeleton_validate(const xyl_skeleton_desc *desc, xyl_diag *diag)
{
    return validate(desc, diag);
}

xyl_result xyl__skeleton_check_view(const xyl_skeleton *sk, xyl_diag *diag)
{
    xyl_skeleton_desc d;
    memset(&d, 0, sizeof d);
    d.nodes = sk->nodes;
    d.node_count = sk->node_count;
    d.leaves = sk->leaves;
    d.leaf_count = sk->leaf_count;
    d.limits.max_nodes = UINT64_MAX;
    d.limits.max_leaves = UINT64_MAX;
    memcpy(d.origin, sk->origin, sizeof d.origin);
    return validate(&d, diag);
}

void xyl_skeleton_destroy(xyl_skeleton *skeleton)
{
    if (!skeleton) return;
    xyl__skeleton *s = (xyl__skeleton *)skeleton;
    xyl_allocator a = s->alloc;
    xyl__free(&a, s->nodes);
    xyl__free(&a, s->leaves);
    xyl__free(&a, s);
}

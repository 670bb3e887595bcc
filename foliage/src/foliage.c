/* The foliage object: options, the collapse chain of each sector laid out as one array, the
 * read-only view. */
#include <string.h>

#include "foliage_internal.h"

typedef struct xyl__foliage {
    xyl_foliage pub;
    xyl_allocator alloc;
    xyl_leaf *leaves;
    xyl_leaf_link *links;
    xyl_foliage_lod *lods;
    xyl_foliage_sector *sectors;
} xyl__foliage;

void xyl_foliage_destroy(xyl_foliage *foliage)
{
    if (!foliage) return;
    xyl__foliage *f = (xyl__foliage *)foliage;
    xyl_allocator a = f->alloc;
    xyl__free(&a, f->leaves);
    xyl__free(&a, f->links);
    xyl__free(&a, f->lods);
    xyl__free(&a, f->sectors);
    xyl__free(&a, f);
}

static bool finite_vec(xyl_vec3 v)
{
    return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

static xyl_result check_options(const xyl_foliage_desc *d, xyl_diag *diag)
{
    const float w[XYL__COLLAPSE_TERMS] = {d->weights.distance, d->weights.angle, d->weights.count,
                                          d->weights.area, d->weights.interiority};
    for (int k = 0; k < XYL__COLLAPSE_TERMS; ++k) {
        if (!isfinite(w[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "a collapse weight is NaN or infinite");
        if (w[k] < 0.0f)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "collapse weights must be >= 0");
    }
    if (!isfinite(d->max_distance) || !isfinite(d->max_angle) || !finite_vec(d->axis_origin) ||
        !finite_vec(d->axis_direction))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "a threshold or the axis is NaN or infinite");
    if (d->max_distance < 0.0f || d->max_angle < 0.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "thresholds must be >= 0 (0: none)");
    return XYL_OK;
}

/* The options as the collapse takes them, for the n checked and tidy leaves. */
static void resolve_options(const xyl_foliage_desc *d, const xyl_leaf *leaves, uint32_t n,
                            xyl__collapse_options *o)
{
    xyl__collapse_defaults(leaves, n, o);
    const float w[XYL__COLLAPSE_TERMS] = {d->weights.distance, d->weights.angle, d->weights.count,
                                          d->weights.area, d->weights.interiority};
    if (w[0] > 0.0f || w[1] > 0.0f || w[2] > 0.0f || w[3] > 0.0f || w[4] > 0.0f)
        for (int k = 0; k < XYL__COLLAPSE_TERMS; ++k) o->weights[k] = w[k];
    if (d->max_distance > 0.0f) o->max_distance = d->max_distance;
    if (d->max_angle > 0.0f) o->max_angle = d->max_angle;
    xyl__dvec3 dir = xyl__from_f3(d->axis_direction);
    if (dir.x != 0.0 || dir.y != 0.0 || dir.z != 0.0) {
        o->axis_direction = xyl__d3_normalize_or(dir, xyl__d3(0, 1, 0));
        o->axis_origin = xyl__from_f3(d->axis_origin);
        xyl__collapse_units(leaves, n, o);
    }
}

/* The arrays a build fills and hands over, and its scratch. */
typedef struct build {
    xyl__foliage *f;
    float *error;       /* per leaf in chain order */
    uint32_t *children; /* 2 per merge */
    uint32_t *source;   /* per original in chain order: its index in desc->leaves */
} build;

static void free_build(build *b, const xyl_allocator *a, bool keep_foliage)
{
    if (!keep_foliage && b->f) xyl_foliage_destroy(&b->f->pub);
    xyl__free(a, b->error);
    xyl__free(a, b->children);
    xyl__free(a, b->source);
}

static bool alloc_build(build *b, const xyl_allocator *a, size_t n, uint32_t sectors)
{
    size_t cap = n ? 2 * n - 1 : 1;
    memset(b, 0, sizeof *b);
    b->f = xyl__calloc(a, 1, sizeof *b->f);
    if (!b->f) return false;
    if (a) b->f->alloc = *a;
    b->f->leaves = xyl__alloc_array(a, cap, sizeof *b->f->leaves);
    b->f->links = xyl__alloc_array(a, cap, sizeof *b->f->links);
    b->f->lods = xyl__alloc_array(a, n + sectors, sizeof *b->f->lods);
    b->f->sectors = xyl__calloc(a, sectors, sizeof *b->f->sectors);
    b->error = xyl__alloc_array(a, cap, sizeof *b->error);
    b->children = xyl__alloc_array(a, cap, sizeof *b->children);
    b->source = xyl__alloc_array(a, n ? n : 1, sizeof *b->source);
    return b->f->leaves && b->f->links && b->f->lods && b->f->sectors && b->error &&
           b->children && b->source;
}

/* Collapses one sector whose originals are already at leaves[base ..] (their indices in the
 * desc in source[0 ..]) and lays it out there. */
static xyl_result build_sector(build *b, xyl_foliage_sector *s, xyl_foliage_lod *lods,
                               const xyl__collapse_options *o, const xyl_allocator *a,
                               xyl_diag *diag)
{
    xyl_leaf *leaves = b->f->leaves + s->base;
    uint32_t n = s->original_count, m = 0;
    xyl_result r = xyl__collapse(leaves, b->error, b->children, n, o, a, &m, NULL, diag);
    if (r == XYL_OK)
        r = xyl__linearize(leaves, b->error, b->children, n, m, s->base, b->source,
                           b->f->links + s->base, lods, a, diag);
    s->merged_count = m;
    s->lods = lods;
    return r;
}

xyl_result xyl_foliage_build(const xyl_foliage_desc *desc, xyl_foliage **out, xyl_diag *diag)
{
    if (!desc || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "desc and out must not be NULL");
    xyl_result r = xyl_foliage_check_leaves(desc->leaves, desc->leaf_count, &desc->limits, diag);
    if (r == XYL_OK) r = check_options(desc, diag);
    if (r != XYL_OK) return r;
    const xyl_allocator *a = &desc->alloc;
    size_t n = desc->leaf_count;
    build b;
    if (!alloc_build(&b, a, n, 1)) {
        free_build(&b, a, false);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the foliage of %zu leaves", n);
    }
    xyl__foliage *f = b.f;
    for (size_t i = 0; i < n; ++i) {
        f->leaves[i] = xyl__leaf_tidy(&desc->leaves[i]);
        b.source[i] = (uint32_t)i;
    }
    xyl__collapse_options o;
    resolve_options(desc, f->leaves, (uint32_t)n, &o);
    xyl_foliage_sector *s = &f->sectors[0];
    s->base = 0;
    s->original_count = (uint32_t)n;
    r = build_sector(&b, s, f->lods, &o, a, diag);
    if (r != XYL_OK) {
        free_build(&b, a, false);
        return r;
    }
    f->pub.leaves = f->leaves;
    f->pub.links = f->links;
    f->pub.leaf_count = n + s->merged_count;
    f->pub.original_count = n;
    f->pub.coarsest_count = n - s->merged_count;
    f->pub.sectors = f->sectors;
    f->pub.sector_count = 1;
    f->pub.axis_origin = xyl__to_f3(o.axis_origin);
    f->pub.axis_direction = xyl__to_f3(o.axis_direction);
    free_build(&b, a, true);
    *out = &f->pub;
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* The foliage object: options, the collapse chain of each sector laid out as one array, the
 * read-only view. */
#include <math.h>
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
    if (d->cost != XYL_FOLIAGE_COST_HIDALGO && d->cost != XYL_FOLIAGE_COST_VIEWPOINT)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "cost %d is not a xyl_foliage_cost", (int)d->cost);
    if (d->viewpoint.resolution > XYL_FOLIAGE_IMAGE_MAX_RESOLUTION || d->viewpoint.cell_leaves > XYL__GRID_K)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "viewpoint: resolution at most %u, cell_leaves at most %u",
                         XYL_FOLIAGE_IMAGE_MAX_RESOLUTION, XYL__GRID_K);
    if (d->sectors > XYL_FOLIAGE_MAX_SECTORS)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "%u sectors; at most %u",
                         d->sectors, XYL_FOLIAGE_MAX_SECTORS);
    return XYL_OK;
}

/* The options as the collapse takes them, for the n checked leaves. */
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

/* A sphere around the corners of the original leaves of sectors[0 .. count): the box's
 * centre, the farthest corner. The merged leaves of coarse LODs may reach out of it (their
 * error bounds say how far their originals lie from them): it bounds what they stand for,
 * tightly enough that sectors facing the eye are nearer to it than the others. */
static void originals_sphere(const xyl_leaf *leaves, const xyl_foliage_sector *sectors,
                             uint32_t count, xyl_vec3 *center, float *radius)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    xyl__dvec3 c[4];
    size_t total = 0;
    for (uint32_t s = 0; s < count; ++s)
        for (uint32_t i = 0; i < sectors[s].original_count; ++i, ++total) {
            xyl__leaf_corners(&leaves[sectors[s].base + i], c);
            for (int k = 0; k < 4; ++k) {
                const double v[3] = {c[k].x, c[k].y, c[k].z};
                for (int d = 0; d < 3; ++d) lo[d] = fmin(lo[d], v[d]), hi[d] = fmax(hi[d], v[d]);
            }
        }
    if (!total) {
        *center = (xyl_vec3){0, 0, 0};
        *radius = 0.0f;
        return;
    }
    *center = xyl__to_f3(xyl__d3(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])));
    xyl__dvec3 m = xyl__from_f3(*center);
    double r = 0.0;
    for (uint32_t s = 0; s < count; ++s)
        for (uint32_t i = 0; i < sectors[s].original_count; ++i) {
            xyl__leaf_corners(&leaves[sectors[s].base + i], c);
            for (int k = 0; k < 4; ++k) r = fmax(r, xyl__d3_len(xyl__d3_sub(c[k], m)));
        }
    *radius = xyl__round_up(r);
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
    b->children = xyl__alloc_array(a, cap > sectors ? cap : sectors, sizeof *b->children);
    b->source = xyl__alloc_array(a, n ? n : 1, sizeof *b->source);
    return b->f->leaves && b->f->links && b->f->lods && b->f->sectors && b->error &&
           b->children && b->source;
}

/* The viewpoint options as the chain takes them; NULL for the Hidalgo cost. */
static const xyl__viewpoint_options *resolve_viewpoint(const xyl_foliage_desc *d,
                                                       const xyl__collapse_options *o,
                                                       xyl__viewpoint_options *vo)
{
    if (d->cost != XYL_FOLIAGE_COST_VIEWPOINT) return NULL;
    vo->resolution = d->viewpoint.resolution ? d->viewpoint.resolution : XYL__VIEWPOINT_RESOLUTION;
    vo->cell_leaves = d->viewpoint.cell_leaves ? d->viewpoint.cell_leaves : XYL__GRID_K;
    vo->refresh = 0;
    vo->max_distance = o->max_distance;
    vo->max_angle = o->max_angle;
    return vo;
}

/* Collapses one sector whose originals are already at leaves[base ..] (their indices in the
 * desc in source[]) and lays it out there; by the viewpoint-driven chain when vo is given. */
static xyl_result build_sector(build *b, xyl_foliage_sector *s, const uint32_t *source,
                               xyl_foliage_lod *lods, const xyl__collapse_options *o,
                               const xyl__viewpoint_options *vo, const xyl_allocator *a,
                               xyl_diag *diag)
{
    xyl_leaf *leaves = b->f->leaves + s->base;
    uint32_t n = s->original_count, m = 0;
    xyl_result r = vo ? xyl__collapse_viewpoint(leaves, b->error, b->children, n, vo, a, &m, NULL, diag)
                      : xyl__collapse(leaves, b->error, b->children, n, o, a, &m, NULL, diag);
    /* the viewpoint chain's merges carry the sum bound: make them exact as the other chain's */
    if (r == XYL_OK && vo &&
        xyl__collapse_errors(leaves, b->error, b->children, n, m, xyl__collapse_error_budget(n), a) != XYL_OK)
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the errors of %u leaves", n);
    if (r == XYL_OK)
        r = xyl__linearize(leaves, b->error, b->children, n, m, s->base, source,
                           b->f->links + s->base, lods, a, diag);
    s->merged_count = m;
    s->lods = lods;
    if (r == XYL_OK) originals_sphere(b->f->leaves, s, 1, &s->center, &s->radius);
    return r;
}

/* Where the sectors' azimuths start: the world axis least aligned with the trunk axis (X
 * first on ties), made orthogonal to it. */
static xyl__dvec3 azimuth_zero(xyl__dvec3 axis)
{
    const double c[3] = {fabs(axis.x), fabs(axis.y), fabs(axis.z)};
    int k = c[0] <= c[1] && c[0] <= c[2] ? 0 : c[1] <= c[2] ? 1 : 2;
    xyl__dvec3 w = xyl__d3(k == 0, k == 1, k == 2);
    return xyl__d3_normalize_or(xyl__d3_sub(w, xyl__d3_scale(axis, xyl__d3_dot(w, axis))),
                                xyl__d3_any_orthogonal(axis));
}

typedef struct sectors {
    uint32_t count;
    xyl__dvec3 origin, axis, zero, quarter; /* quarter = axis x zero: azimuth pi / 2 */
} sectors;

/* The sector of a centre: its azimuth about the axis from zero towards quarter, in S equal
 * parts; a centre on the axis is in sector 0. */
static uint32_t sector_of(const sectors *sc, xyl_vec3 centre)
{
    if (sc->count == 1) return 0;
    xyl__dvec3 d = xyl__d3_sub(xyl__from_f3(centre), sc->origin);
    double azimuth = atan2(xyl__d3_dot(d, sc->quarter), xyl__d3_dot(d, sc->zero));
    if (azimuth < 0.0) azimuth += 2.0 * XYL__PI;
    uint32_t s = (uint32_t)(azimuth * sc->count / (2.0 * XYL__PI));
    return s < sc->count ? s : sc->count - 1;
}

static xyl_leaf *originals_end(xyl__foliage *f, size_t n)
{
    return f->leaves + (n ? n - 1 : 0);
}

/* Puts the tidy originals at the end of the leaf array, sector after sector, where each
 * sector's collapse finds them before it moves them to its base (the end is never reached
 * before: a sector's chain takes at most twice its leaves), and their desc indices in
 * b->source likewise. */
static void place_originals(build *b, const xyl_foliage_desc *d, const sectors *sc)
{
    xyl__foliage *f = b->f;
    uint32_t n = (uint32_t)d->leaf_count;
    for (uint32_t i = 0; i < n; ++i) f->sectors[sector_of(sc, d->leaves[i].center)].original_count++;
    uint32_t *next = b->children; /* borrowed (it has room for a count per sector): the next
                                     free place of each sector */
    for (uint32_t s = 0, at = 0; s < sc->count; ++s) {
        next[s] = at;
        at += f->sectors[s].original_count;
    }
    xyl_leaf *end = originals_end(f, n);
    for (uint32_t i = 0; i < n; ++i) {
        uint32_t at = next[sector_of(sc, d->leaves[i].center)]++;
        end[at] = xyl__leaf_tidy(&d->leaves[i]);
        b->source[at] = i;
    }
}

static void publish(xyl__foliage *f, size_t n, const sectors *sc)
{
    f->pub.leaves = f->leaves;
    f->pub.links = f->links;
    f->pub.original_count = n;
    f->pub.sectors = f->sectors;
    f->pub.sector_count = sc->count;
    for (uint32_t s = 0; s < sc->count; ++s) {
        f->pub.leaf_count += (size_t)f->sectors[s].original_count + f->sectors[s].merged_count;
        f->pub.coarsest_count += (size_t)f->sectors[s].original_count - f->sectors[s].merged_count;
    }
    f->pub.axis_origin = xyl__to_f3(sc->origin);
    f->pub.axis_direction = xyl__to_f3(sc->axis);
    f->pub.azimuth_zero = xyl__to_f3(sc->zero);
    originals_sphere(f->leaves, f->sectors, sc->count, &f->pub.center, &f->pub.radius);
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
    xyl__collapse_options o;
    resolve_options(desc, desc->leaves, (uint32_t)n, &o);
    xyl__viewpoint_options vo;
    const xyl__viewpoint_options *view = resolve_viewpoint(desc, &o, &vo);
    sectors sc = {desc->sectors ? desc->sectors : 1, o.axis_origin, o.axis_direction,
                  azimuth_zero(o.axis_direction), xyl__d3(0, 0, 0)};
    sc.quarter = xyl__d3_cross(sc.axis, sc.zero);
    build b;
    if (!alloc_build(&b, a, n, sc.count)) {
        free_build(&b, a, false);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the foliage of %zu leaves", n);
    }
    xyl__foliage *f = b.f;
    place_originals(&b, desc, &sc);
    uint32_t base = 0, first = 0, lods = 0;
    for (uint32_t s = 0; s < sc.count && r == XYL_OK; ++s) {
        xyl_foliage_sector *sector = &f->sectors[s];
        sector->base = base;
        memmove(f->leaves + base, originals_end(f, n) + first,
                sector->original_count * sizeof *f->leaves);
        r = build_sector(&b, sector, b.source + first, f->lods + lods, &o, view, a, diag);
        base += sector->original_count + sector->merged_count;
        first += sector->original_count;
        lods += sector->merged_count + 1;
    }
    if (r != XYL_OK) {
        free_build(&b, a, false);
        return r;
    }
    publish(f, n, &sc);
    free_build(&b, a, true);
    *out = &f->pub;
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- the LOD pick ---------------------------------------------------------------------------- */

/* The coarsest LOD of s whose error is at most allowed (the errors never decrease). */
static uint32_t coarsest_within(const xyl_foliage_sector *s, double allowed)
{
    uint32_t lo = 0, hi = s->merged_count; /* lods[lo] is within; find the last one that is */
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo + 1) / 2;
        if ((double)s->lods[mid].error <= allowed) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

xyl_result xyl__foliage_view_resolve(const xyl_foliage_view *view, double eye[3],
                                     double *per_distance, xyl_diag *diag)
{
    xyl_foliage_view zero = {{0, 0, 0}, 0, 0, 0};
    const xyl_foliage_view *v = view ? view : &zero;
    if (!isfinite(v->eye[0]) || !isfinite(v->eye[1]) || !isfinite(v->eye[2]) ||
        !isfinite(v->fovy) || !isfinite(v->error_px))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "the view has a NaN or infinity");
    if (v->fovy < 0.0f || v->fovy >= (float)XYL__PI || v->error_px < 0.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "view: fovy must be in [0, pi) (0: 0.8) and error_px >= 0 (0: 0.5)");
    double budget = v->error_px > 0.0f ? v->error_px : 0.5;
    /* world error per unit of distance that the budget allows */
    *per_distance = budget * xyl__world_per_px(v->fovy, v->viewport_height);
    for (int k = 0; k < 3; ++k) eye[k] = v->eye[k];
    return XYL_OK;
}

xyl_result xyl_foliage_pick(const xyl_foliage *foliage, const xyl_foliage_view *view,
                            uint32_t *lods, size_t capacity, xyl_diag *diag)
{
    if (!foliage || !lods || capacity < foliage->sector_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "foliage and lods must not be NULL, and lods must hold one LOD a sector");
    double e[3], per_distance = 0.0;
    xyl_result r = xyl__foliage_view_resolve(view, e, &per_distance, diag);
    if (r != XYL_OK) return r;
    xyl__dvec3 eye = xyl__d3(e[0], e[1], e[2]);
    for (uint32_t k = 0; k < foliage->sector_count; ++k) {
        const xyl_foliage_sector *s = &foliage->sectors[k];
        double d = xyl__d3_len(xyl__d3_sub(eye, xyl__from_f3(s->center))) - (double)s->radius;
        lods[k] = d > 0.0 ? coarsest_within(s, d * per_distance) : 0;
    }
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- the per-leaf cut ----------------------------------------------------------------------- */

double xyl__foliage_node_radius(const xyl_leaf *leaf, const xyl_leaf_link *link)
{
    double ax = leaf->axis.x, ay = leaf->axis.y, az = leaf->axis.z;
    double sx = leaf->side.x, sy = leaf->side.y, sz = leaf->side.z;
    return sqrt(ax * ax + ay * ay + az * az + sx * sx + sy * sy + sz * sz) + (double)link->error;
}

/* Leaf k within the budget: its error at most per_distance times the distance from the eye to
 * its sphere (0 inside it, where only an error of 0 passes). */
static bool cut_allowed(const xyl_foliage *f, uint32_t k, const double eye[3], double per_distance)
{
    const xyl_leaf *l = &f->leaves[k];
    double dx = eye[0] - l->center.x, dy = eye[1] - l->center.y, dz = eye[2] - l->center.z;
    double d = sqrt(dx * dx + dy * dy + dz * dz) - xyl__foliage_node_radius(l, &f->links[k]);
    return (double)f->links[k].error <= per_distance * (d > 0.0 ? d : 0.0);
}

xyl_result xyl_foliage_cut(const xyl_foliage *f, const xyl_foliage_view *view, uint32_t *out,
                           size_t capacity, size_t *count, xyl_diag *diag)
{
    if (!f || !count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "foliage and count must not be NULL");
    if (f->leaf_count && (!f->leaves || !f->links))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the foliage's leaves or links are missing");
    double eye[3], per_distance = 0.0;
    xyl_result r = xyl__foliage_view_resolve(view, eye, &per_distance, diag);
    if (r != XYL_OK) return r;
    size_t n = 0;
    for (int pass = 0; pass < 2; ++pass) {
        n = 0;
        for (size_t k = 0; k < f->leaf_count; ++k) {
            if (!cut_allowed(f, (uint32_t)k, eye, per_distance)) continue;
            int32_t p = f->links[k].parent;
            size_t steps = 0; /* a malformed forest with a cycle must not hang the walk */
            while (p >= 0 && (size_t)p < f->leaf_count && steps++ < f->leaf_count &&
                   !cut_allowed(f, (uint32_t)p, eye, per_distance))
                p = f->links[p].parent;
            if (p >= 0 && (size_t)p < f->leaf_count && steps <= f->leaf_count) continue;
            if (pass == 1) out[n] = (uint32_t)k;
            ++n;
        }
        if (pass == 0 && !out) break;
        if (pass == 0 && capacity < n)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                             "the cut has %zu leaves, out holds %zu", n, capacity);
    }
    *count = n;
    xyl__diag_ok(diag);
    return XYL_OK;
}

void xyl_foliage_bounds(const xyl_foliage *f, float lo[3], float hi[3])
{
    for (uint32_t s = 0; f && s < f->sector_count; ++s) {
        const xyl_foliage_sector *sec = &f->sectors[s];
        for (uint32_t i = 0; i < sec->original_count; ++i) {
            const xyl_leaf *l = &f->leaves[sec->base + i];
            const float c[3] = {l->center.x, l->center.y, l->center.z};
            const float e[3] = {fabsf(l->side.x) + fabsf(l->axis.x),
                                fabsf(l->side.y) + fabsf(l->axis.y),
                                fabsf(l->side.z) + fabsf(l->axis.z)};
            for (int k = 0; k < 3; ++k) {
                lo[k] = fminf(lo[k], c[k] - e[k]);
                hi[k] = fmaxf(hi[k], c[k] + e[k]);
            }
        }
    }
}

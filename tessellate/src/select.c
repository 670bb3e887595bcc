/* Per-frame level selection (screen-space error budget) and batching by (kind, level). */
#include <float.h>
#include <string.h>

#include "tess_debug.h"
#include "tess_internal.h"
#include "xyl_internal.h"

typedef struct view_params {
    float eye[3];
    float scale; /* pixels per world unit at distance 1 */
    float error_px;
    float near_distance;
    uint32_t max_level;
} view_params;

static float view_scale(const xyl_tess_view *view)
{
    return (float)(1.0 / xyl__world_per_px(view->fovy, view->viewport_height));
}

static uint32_t level_from(float coef, float distance, float scale, float error_px,
                           uint32_t max_level)
{
    double need = sqrt((double)coef * scale / ((double)distance * error_px));
    if (!(need > 1.0)) return 1;
    if (need >= (double)max_level) return max_level;
    return (uint32_t)ceil(need);
}

uint32_t xyl__tess_level_for(float coefficient, float distance, const xyl_tess_view *view,
                             uint32_t max_level)
{
    if (max_level == 0 || max_level > XYL_TESS_MAX_LEVEL) max_level = XYL_TESS_MAX_LEVEL;
    float budget = view && view->error_px > 0.0f ? view->error_px : 0.5f;
    xyl_tess_view zero = {0};
    if (!(distance > 0.0f)) return max_level;
    return level_from(coefficient, distance, view_scale(view ? view : &zero), budget, max_level);
}

xyl_result xyl_tess_view_world_error(const xyl_tess_view *view, const float center[3],
                                     float radius, float *world, xyl_diag *diag)
{
    if (!view || !center || !world)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "view, center and world are required");
    for (int k = 0; k < 3; ++k)
        if (!isfinite(view->eye[k]) || !isfinite(center[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "eye or center is not finite");
    if (!isfinite(radius))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "radius is not finite");
    if (!isfinite(view->fovy) || view->fovy < 0.0f || view->fovy >= 3.14159f ||
        !isfinite(view->error_px) || view->error_px < 0.0f || !isfinite(view->near_distance) ||
        view->near_distance < 0.0f || radius < 0.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "view: fovy must be in [0, pi), error_px, near_distance and radius >= 0");
    double dx = (double)center[0] - view->eye[0], dy = (double)center[1] - view->eye[1];
    double dz = (double)center[2] - view->eye[2];
    double d = sqrt(dx * dx + dy * dy + dz * dz) - radius;
    double near = view->near_distance > 0.0f ? view->near_distance
                                             : fmax(2e-3 * radius, (double)FLT_MIN);
    if (!(d > near)) d = near;
    double px = view->error_px > 0.0f ? view->error_px : 0.5;
    *world = (float)(px * d * xyl__world_per_px(view->fovy, view->viewport_height));
    xyl__diag_ok(diag);
    return XYL_OK;
}

static uint32_t level_of(const xyl__tess_bound *b, const view_params *vp)
{
    float dx = b->center[0] - vp->eye[0], dy = b->center[1] - vp->eye[1];
    float dz = b->center[2] - vp->eye[2];
    float d = sqrtf(dx * dx + dy * dy + dz * dz) - b->radius;
    if (!(d > vp->near_distance)) d = vp->near_distance;
    return level_from(b->coef, d, vp->scale, vp->error_px, vp->max_level);
}

static xyl_result check_view(const xyl_tess_patches *patches, const xyl_tess_patterns *patterns,
                             const xyl_tess_view *view, view_params *vp, xyl_diag *diag)
{
    for (int k = 0; k < 3; ++k)
        if (!isfinite(view->eye[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "eye is not finite");
    if (!isfinite(view->fovy) || view->fovy < 0.0f || view->fovy >= 3.14159f ||
        !isfinite(view->error_px) || view->error_px < 0.0f || !isfinite(view->near_distance) ||
        view->near_distance < 0.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "view: fovy must be in [0, pi), error_px and near_distance >= 0");
    uint32_t max_level = view->max_level ? view->max_level : patterns->max_level;
    if (max_level > patterns->max_level || view->fixed_level > patterns->max_level)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "level %u asked, patterns go up to %u",
                         view->fixed_level > max_level ? view->fixed_level : max_level,
                         patterns->max_level);
    memcpy(vp->eye, view->eye, sizeof vp->eye);
    vp->scale = view_scale(view);
    vp->error_px = view->error_px > 0.0f ? view->error_px : 0.5f;
    vp->near_distance = view->near_distance > 0.0f ? view->near_distance
                                                   : fmaxf(1e-3f * patches->size, FLT_MIN);
    vp->max_level = max_level;
    return XYL_OK;
}

/* What xyl_tess_batches_create hands out: the public view first, then the arrays it points at
 * (writable here) and their capacities. */
typedef struct owned_batches {
    xyl_tess_batches pub;
    xyl_tess_instance *instances;
    xyl_tess_draw_cmd *cmds;
    xyl_tess_batch *batches;
    uint8_t *edge_levels;
    uint8_t *patch_levels; /* scratch: each patch's level before bucketing */
    size_t instance_cap, edge_cap, patch_cap;
    size_t edge_count; /* edge levels the public view holds */
    xyl_allocator alloc;
} owned_batches;

xyl_result xyl_tess_batches_create(const xyl_allocator *alloc, xyl_tess_batches **out,
                                   xyl_diag *diag)
{
    if (!out) return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "out is required");
    owned_batches *b = xyl__calloc(alloc, 1, sizeof *b);
    if (b) {
        if (alloc) b->alloc = *alloc;
        /* one command per (kind, level) at most: allocated once */
        b->cmds = xyl__calloc(alloc, 2 * XYL_TESS_MAX_LEVEL, sizeof(xyl_tess_draw_cmd));
        b->batches = xyl__calloc(alloc, 2 * XYL_TESS_MAX_LEVEL, sizeof(xyl_tess_batch));
    }
    if (!b || !b->cmds || !b->batches) {
        xyl_tess_batches_destroy(b ? &b->pub : NULL);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    }
    b->pub.cmds = b->cmds;
    b->pub.batches = b->batches;
    *out = &b->pub;
    xyl__diag_ok(diag);
    return XYL_OK;
}

void xyl_tess_batches_destroy(xyl_tess_batches *batches)
{
    if (!batches) return;
    owned_batches *b = (owned_batches *)batches;
    xyl_allocator a = b->alloc;
    xyl__free(&a, b->instances);
    xyl__free(&a, b->cmds);
    xyl__free(&a, b->batches);
    xyl__free(&a, b->edge_levels);
    xyl__free(&a, b->patch_levels);
    xyl__free(&a, b);
}

/* Grows the arrays for a patch set, keeping what the public view shows: a failure leaves the
 * previous frame's batches intact. */
static bool reserve(owned_batches *b, size_t patches, size_t edges)
{
    void *p = b->instances;
    if (!xyl__grow(&b->alloc, &p, &b->instance_cap, b->pub.instance_count, patches,
                   sizeof(xyl_tess_instance)))
        return false;
    b->instances = p;
    b->pub.instances = b->instances;
    void *l = b->patch_levels;
    if (!xyl__grow(&b->alloc, &l, &b->patch_cap, 0, patches, 1)) return false;
    b->patch_levels = l;
    void *e = b->edge_levels;
    if (!xyl__grow(&b->alloc, &e, &b->edge_cap, b->edge_count, edges, 1)) return false;
    b->edge_levels = e;
    b->pub.edge_levels = b->edge_levels;
    return true;
}

static void choose_levels(const xyl__tess_patches *t, const xyl_tess_view *view,
                          const view_params *vp, owned_batches *b)
{
    const xyl_tess_patches *p = &t->pub;
    if (view->fixed_level) {
        memset(b->edge_levels, (int)view->fixed_level, p->edge_count);
        memset(b->patch_levels, (int)view->fixed_level, p->count);
        return;
    }
    for (size_t e = 0; e < p->edge_count; ++e)
        b->edge_levels[e] = (uint8_t)level_of(&t->edge_bounds[e], vp);
    /* A patch is drawn at least as finely as any of its edges: snapping only removes points. */
    for (size_t f = 0; f < p->count; ++f) {
        uint32_t l = level_of(&t->patch_bounds[f], vp);
        uint32_t kind = f < p->quad_count ? 4u : 3u;
        for (uint32_t e = 0; e < kind; ++e) {
            uint32_t le = b->edge_levels[p->patch_edges[4 * f + e]];
            if (le > l) l = le;
        }
        b->patch_levels[f] = (uint8_t)l;
    }
}

static void bucket(const xyl_tess_patches *p, const xyl_tess_patterns *patterns,
                   owned_batches *b)
{
    size_t count[2][XYL_TESS_MAX_LEVEL + 1] = {{0}};
    for (size_t f = 0; f < p->count; ++f) ++count[f < p->quad_count ? 0 : 1][b->patch_levels[f]];
    size_t start[2][XYL_TESS_MAX_LEVEL + 1];
    size_t at = 0;
    b->pub.cmd_count = 0;
    b->pub.triangles = 0;
    b->pub.vertices = 0;
    for (int k = 0; k < 2; ++k)
        for (uint32_t l = 1; l <= XYL_TESS_MAX_LEVEL; ++l) {
            start[k][l] = at;
            if (!count[k][l]) continue;
            const xyl_tess_pattern_range *r = &patterns->ranges[k][l];
            xyl_tess_draw_cmd *c = &b->cmds[b->pub.cmd_count];
            c->index_count = r->index_count;
            c->instance_count = (uint32_t)count[k][l];
            c->first_index = r->first_index;
            c->base_vertex = (int32_t)r->first_vertex;
            c->base_instance = (uint32_t)at;
            b->batches[b->pub.cmd_count].kind = k ? XYL_TESS_KIND_TRIANGLE : XYL_TESS_KIND_QUAD;
            b->batches[b->pub.cmd_count].level = l;
            ++b->pub.cmd_count;
            b->pub.triangles += (uint64_t)count[k][l] * (r->index_count / 3);
            b->pub.vertices += (uint64_t)count[k][l] * r->vertex_count;
            at += count[k][l];
        }
    for (size_t f = 0; f < p->count; ++f) {
        uint32_t kind = f < p->quad_count ? 4u : 3u;
        uint32_t l = b->patch_levels[f];
        xyl_tess_instance *in = &b->instances[start[kind == 4u ? 0 : 1][l]++];
        in->patch = (uint32_t)f;
        in->level = l;
        in->kind = kind;
        in->edge_levels = 0;
        for (uint32_t e = 0; e < kind; ++e)
            in->edge_levels |= (uint32_t)b->edge_levels[p->patch_edges[4 * f + e]]
                               << (XYL_TESS_EDGE_LEVEL_BITS * e);
    }
    b->pub.instance_count = p->count;
}

xyl_result xyl_tess_select(const xyl_tess_patches *patches, const xyl_tess_patterns *patterns,
                           const xyl_tess_view *view, xyl_tess_batches *batches, xyl_diag *diag)
{
    if (!patches || !patterns || !view || !batches)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "patches, patterns, view and batches are required");
    view_params vp;
    xyl_result r = check_view(patches, patterns, view, &vp, diag);
    if (r != XYL_OK) return r;
    owned_batches *b = (owned_batches *)batches;
    if (!reserve(b, patches->count, patches->edge_count))
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for %zu patches",
                         patches->count);
    choose_levels((const xyl__tess_patches *)patches, view, &vp, b);
    b->edge_count = patches->edge_count;
    bucket(patches, patterns, b);
    xyl__diag_ok(diag);
    return XYL_OK;
}

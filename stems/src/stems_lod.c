/* Stem LODs: a chain of closed stem meshes from one skeleton, each pruned of the twigs thinner
 * than a world-space budget that grows along the chain (docs/stems.md, "Stem LODs"), their
 * pick from the size of a pixel, and their glTF file (MSFT_lod). */
#include <float.h>
#include <string.h>

#include "glb_write.h"
#include "xyl_internal.h"
#include "xylem/xyl_stems.h"

#define DEFAULT_MAX_LODS 8u
#define DEFAULT_FACTOR 2.0f
#define DEFAULT_ERROR_PX 0.5f /* xyl_foliage_view's default budget */
#define DEFAULT_FOVY 0.8      /* xyl_foliage_view's defaults */
#define DEFAULT_HEIGHT 1080u

typedef struct chain {
    xyl_stems_lods pub;
    xyl_stems_lod lods[XYL_STEMS_LOD_MAX];
    xyl_allocator alloc;
} chain;

static xyl_result check_desc(const xyl_stems_lod_desc *d, xyl_diag *diag)
{
    if (d->max_lods > XYL_STEMS_LOD_MAX)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "max_lods is %u; a chain holds at most %d LODs (0: 8)", d->max_lods,
                         XYL_STEMS_LOD_MAX);
    if (!isfinite(d->first_budget) || d->first_budget < 0.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the first budget is %g; it must be finite and >= 0 (world units)",
                         (double)d->first_budget);
    if (!isfinite(d->factor) || d->factor < 0.0f || (d->factor > 0.0f && d->factor <= 1.0f))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the budget factor is %g; it must be finite and > 1 (0: 2)",
                         (double)d->factor);
    return XYL_OK;
}

/* The one place where a LOD's mesher options are made from the caller's: as the caller asked,
 * but for the ring sides, which follow the budget unless fixed_sides (a branch whose rings
 * are within the budget is no worse than a twig pruned at it). */
static xyl_stems_desc lod_stems_desc(const xyl_stems_lod_desc *d, float budget)
{
    xyl_stems_desc md = d->stems;
    if (!d->fixed_sides && budget > md.error_world) md.error_world = budget;
    return md;
}

float xyl_stems_lod_error(const xyl_stems_lod *lod)
{
    return lod ? fmaxf(lod->error, lod->ring_error) : 0.0f;
}

static void chain_free(chain *c)
{
    for (uint32_t i = 0; i < c->pub.lod_count; ++i) xyl_mesh_destroy(c->lods[i].mesh);
    xyl_allocator a = c->alloc;
    xyl__free(&a, c);
}

/* The thinnest and the widest node's diameter. */
static void width_range(const xyl_skeleton *s, float *thinnest, float *widest)
{
    *thinnest = FLT_MAX;
    *widest = 0.0f;
    for (size_t i = 0; i < s->node_count; ++i) {
        float w = 2.0f * s->nodes[i].radius;
        if (w < *thinnest) *thinnest = w;
        if (w > *widest) *widest = w;
    }
}

/* A sphere around every LOD's vertices: the box's centre and the farthest vertex from it. */
static void bounding_sphere(chain *c)
{
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    size_t seen = 0;
    for (uint32_t i = 0; i < c->pub.lod_count; ++i) {
        const xyl_mesh *m = c->lods[i].mesh;
        for (size_t v = 0; v < m->vertex_count; ++v, ++seen) {
            const double p[3] = {m->positions[v].x, m->positions[v].y, m->positions[v].z};
            for (int k = 0; k < 3; ++k) {
                if (p[k] < lo[k]) lo[k] = p[k];
                if (p[k] > hi[k]) hi[k] = p[k];
            }
        }
    }
    if (!seen) return; /* an empty tree: a point at 0 */
    double ctr[3], r2 = 0.0;
    for (int k = 0; k < 3; ++k) ctr[k] = 0.5 * (lo[k] + hi[k]);
    for (uint32_t i = 0; i < c->pub.lod_count; ++i) {
        const xyl_mesh *m = c->lods[i].mesh;
        for (size_t v = 0; v < m->vertex_count; ++v) {
            double dx = m->positions[v].x - ctr[0], dy = m->positions[v].y - ctr[1],
                   dz = m->positions[v].z - ctr[2];
            double d2 = dx * dx + dy * dy + dz * dz;
            if (d2 > r2) r2 = d2;
        }
    }
    for (int k = 0; k < 3; ++k) c->pub.center[k] = (float)ctr[k];
    /* rounded up, so the float sphere still holds every vertex */
    c->pub.radius = nextafterf((float)sqrt(r2), FLT_MAX);
}

/* Prunes s at budget and meshes it as LOD lods[count] when it removes more than the LOD before
 * and has fewer faces; *added says whether it did, *trunk whether that LOD has no lateral. */
static xyl_result try_lod(chain *c, const xyl_skeleton *s, const xyl_stems_lod_desc *d,
                          float budget, bool *added, bool *trunk, xyl_diag *diag)
{
    uint32_t n = c->pub.lod_count;
    const xyl_stems_lod *prev = n ? &c->lods[n - 1] : NULL;
    xyl_skeleton_prune_desc pd = {c->alloc};
    xyl_skeleton_prune_stats st;
    xyl_skeleton *pruned = NULL;
    *added = false;
    xyl_result r = xyl_skeleton_prune(s, budget, &pd, &pruned, &st, diag);
    if (r != XYL_OK) return r;
    if (prev && st.nodes_removed <= prev->nodes_removed) { /* nothing more pruned */
        xyl_skeleton_destroy(pruned);
        return XYL_OK;
    }
    xyl_stems_desc md = lod_stems_desc(d, budget);
    xyl_mesh *mesh = NULL;
    xyl_stems_stats ms;
    r = xyl_stems_build(pruned, &md, &mesh, &ms, diag);
    if (r != XYL_OK) {
        xyl_diag inner = diag ? *diag : (xyl_diag){0};
        xyl_skeleton_destroy(pruned);
        return xyl__fail(diag, r, inner.line, inner.column, inner.index,
                         "stem LOD %u (budget %g): %s", n, (double)budget, inner.message);
    }
    size_t faces = mesh->quad_count + mesh->triangle_count;
    if (prev && faces >= prev->face_count) { /* no cheaper to draw: no LOD */
        xyl_mesh_destroy(mesh);
        xyl_skeleton_destroy(pruned);
        return XYL_OK;
    }
    xyl_stems_lod *l = &c->lods[n];
    l->mesh = mesh;
    l->budget = budget;
    l->error = st.max_removed_width;
    l->ring_error = (float)ms.ring_error_max;
    l->node_count = pruned->node_count;
    l->branch_count = pruned->branch_count;
    l->face_count = faces;
    l->nodes_removed = st.nodes_removed;
    l->subtrees_removed = st.subtrees_removed;
    l->stats = ms;
    c->pub.lod_count = n + 1;
    *added = true;
    *trunk = pruned->branch_count <= pruned->root_count;
    xyl_skeleton_destroy(pruned);
    return XYL_OK;
}

xyl_result xyl_stems_lods_build(const xyl_skeleton *skeleton, const xyl_stems_lod_desc *desc,
                                xyl_stems_lods **out, xyl_diag *diag)
{
    if (!skeleton || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the skeleton and out must not be NULL");
    xyl_stems_lod_desc d;
    if (desc) d = *desc;
    else memset(&d, 0, sizeof d);
    xyl_result r = check_desc(&d, diag);
    if (r != XYL_OK) return r;
    uint32_t max_lods = d.max_lods ? d.max_lods : DEFAULT_MAX_LODS;
    float factor = d.factor > 0.0f ? d.factor : DEFAULT_FACTOR;
    chain *c = xyl__calloc(&d.stems.alloc, 1, sizeof *c);
    if (!c) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the LODs");
    c->alloc = d.stems.alloc;
    c->pub.lods = c->lods;
    float thinnest, widest;
    width_range(skeleton, &thinnest, &widest);
    float budget = d.first_budget;
    bool trunk = false;
    while (c->pub.lod_count < max_lods) {
        bool added = false;
        r = try_lod(c, skeleton, &d, budget, &added, &trunk, diag);
        if (r != XYL_OK) {
            chain_free(c);
            return r;
        }
        if ((added && trunk) || !(budget <= widest)) break; /* nothing more can go */
        float next = (budget > 0.0f ? budget : thinnest) * factor;
        if (!isfinite(next)) {
            if (budget == FLT_MAX) break;
            next = FLT_MAX;
        }
        budget = next;
    }
    c->pub.trunk_only = trunk;
    bounding_sphere(c);
    *out = &c->pub;
    xyl__diag_ok(diag);
    return XYL_OK;
}

void xyl_stems_lods_destroy(xyl_stems_lods *lods)
{
    if (lods) chain_free((chain *)lods);
}

/* ---- the pick ------------------------------------------------------------------------------ */

double xyl_stems_pixel_world(double d, float fovy, uint32_t viewport_height)
{
    double f = fovy > 0.0f ? (double)fovy : DEFAULT_FOVY;
    double h = viewport_height ? (double)viewport_height : (double)DEFAULT_HEIGHT;
    return 2.0 * (d > 0.0 ? d : 0.0) * tan(0.5 * f) / h;
}

xyl_result xyl_stems_lods_pick(const xyl_stems_lods *lods, double pixel_world, float error_px,
                               uint32_t *lod, xyl_diag *diag)
{
    if (!lods || !lod || !lods->lods || lods->lod_count == 0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the chain must hold a LOD and lod must not be NULL");
    if (isnan(pixel_world) || !isfinite(error_px))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1,
                         "the pixel size or the pixel budget is NaN or infinite");
    if (pixel_world < 0.0 || error_px < 0.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the pixel size (%g) and the pixel budget (%g) must be >= 0",
                         pixel_world, (double)error_px);
    double allowed = (double)(error_px > 0.0f ? error_px : DEFAULT_ERROR_PX) * pixel_world;
    uint32_t i = 0; /* the errors grow along the chain: the last one within */
    while (i + 1 < lods->lod_count && (double)xyl_stems_lod_error(&lods->lods[i + 1]) <= allowed)
        ++i;
    *lod = i;
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- glTF ---------------------------------------------------------------------------------- */

/* Five views a mesh (POSITION, NORMAL, TEXCOORD_0, _BRANCH_ID, indices): the document must
 * hold a full chain's. */
_Static_assert(5 * XYL_STEMS_LOD_MAX <= XYL__GLB_MAX_VIEWS, "a GLB of the longest chain");

typedef struct lod_doc {
    const xyl_stems_lods *chain;
    xyl__glb_mesh parts[XYL_STEMS_LOD_MAX];
    uint32_t mesh_of[XYL_STEMS_LOD_MAX]; /* glTF mesh index of LOD i's part (non-empty ones) */
} lod_doc;

static void put_node(xyl__sink *s, const lod_doc *d, uint32_t i)
{
    const xyl__glb_mesh *p = &d->parts[i];
    xyl__put_str(s, i ? ",{\"name\":\"stems-lod" : "{\"name\":\"stems-lod");
    xyl__put_uint(s, i);
    xyl__put_str(s, "\"");
    if (!p->empty) {
        xyl__put_str(s, ",\"mesh\":");
        xyl__put_uint(s, d->mesh_of[i]);
    }
    xyl__put_json_translation(s, d->chain->lods[i].mesh->origin);
    if (i == 0 && d->chain->lod_count > 1) {
        /* MSFT_lod: the coarser LODs' nodes, finest first; they are in no scene */
        xyl__put_str(s, ",\"extensions\":{\"MSFT_lod\":{\"ids\":[");
        for (uint32_t k = 1; k < d->chain->lod_count; ++k) {
            if (k > 1) xyl__put_str(s, ",");
            xyl__put_uint(s, k);
        }
        xyl__put_str(s, "]}}");
    }
    xyl__put_str(s, "}");
}

static void lod_body(const void *ctx, xyl__sink *s)
{
    const lod_doc *d = ctx;
    uint32_t n = d->chain->lod_count;
    if (n > 1) xyl__put_str(s, "\"extensionsUsed\":[\"MSFT_lod\"],");
    xyl__put_str(s, "\"scenes\":[{\"nodes\":[0]}],\"nodes\":[");
    for (uint32_t i = 0; i < n; ++i) put_node(s, d, i);
    xyl__put_str(s, "]");
    bool any = false;
    for (uint32_t i = 0; i < n; ++i) {
        if (d->parts[i].empty) continue;
        xyl__put_str(s, any ? "," : ",\"meshes\":[");
        any = true;
        xyl__glb_mesh_json_open(&d->parts[i], s);
        xyl__put_str(s, ",\"extras\":{\"lod\":");
        xyl__put_uint(s, i);
        xyl__put_str(s, ",\"error_world\":");
        xyl__put_float(s, xyl_stems_lod_error(&d->chain->lods[i]));
        xyl__put_str(s, "}}");
    }
    if (any) xyl__put_str(s, "]");
}

static void doc_free(lod_doc *d, uint32_t parts)
{
    for (uint32_t i = 0; i < parts; ++i) xyl__glb_mesh_free(&d->parts[i]);
}

/* The finished document; on success d holds the parts (doc_free). */
static xyl_result lod_glb(const xyl_stems_lods *c, const xyl_allocator *alloc, xyl__glb *g,
                          lod_doc *d, xyl_diag *diag)
{
    if (!c || !c->lods || c->lod_count == 0 || c->lod_count > XYL_STEMS_LOD_MAX)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the chain must hold 1 to %d LODs", XYL_STEMS_LOD_MAX);
    memset(g, 0, sizeof *g);
    memset(d, 0, sizeof *d);
    d->chain = c;
    uint32_t meshes = 0;
    for (uint32_t i = 0; i < c->lod_count; ++i) {
        xyl_result r = c->lods[i].mesh
                           ? xyl__glb_mesh_add(c->lods[i].mesh, alloc, g, &d->parts[i], diag)
                           : xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)i,
                                       "stem LOD %u has no mesh", i);
        if (r != XYL_OK) {
            doc_free(d, i);
            return r;
        }
        d->mesh_of[i] = meshes;
        meshes += !d->parts[i].empty;
    }
    g->body = lod_body;
    g->body_ctx = d;
    xyl_result r = xyl__glb_finish(g, diag);
    if (r != XYL_OK) doc_free(d, c->lod_count);
    return r;
}

xyl_result xyl_stems_lods_write_glb_memory(const xyl_stems_lods *lods, const xyl_allocator *alloc,
                                           void *buffer, size_t capacity, size_t *needed,
                                           xyl_diag *diag)
{
    if (!buffer && !needed)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "give a buffer or needed (or both)");
    xyl__glb g;
    lod_doc d;
    xyl_result r = lod_glb(lods, alloc, &g, &d, diag);
    if (r != XYL_OK) return r;
    r = xyl__glb_write_memory(&g, buffer, capacity, needed, diag);
    doc_free(&d, lods->lod_count);
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

xyl_result xyl_stems_lods_write_glb_file(const xyl_stems_lods *lods, const char *path,
                                         const xyl_allocator *alloc, xyl_diag *diag)
{
    if (!path || !*path)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "path must be given");
    xyl__glb g;
    lod_doc d;
    xyl_result r = lod_glb(lods, alloc, &g, &d, diag);
    if (r != XYL_OK) return r;
    r = xyl__glb_write_file(&g, path, alloc, diag);
    doc_free(&d, lods->lod_count);
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

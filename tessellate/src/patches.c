/* Patch records from an xyl_mesh, the mesh's unique edges, and the error bound of every patch and
 * edge (docs/tessellation.md, "Error bounds"). */
#include <float.h>
#include <string.h>

#include "mesh_internal.h"
#include "tess_internal.h"
#include "xyl_internal.h"

/* ---- records ------------------------------------------------------------------------------ */

static bool fill_record(const xyl_mesh *mesh, const uint32_t *face, uint32_t kind,
                        xyl_tess_patch *rec)
{
    memset(rec, 0, sizeof *rec);
    for (uint32_t c = 0; c < kind; ++c) {
        xyl_vec3 p = mesh->positions[face[c]];
        xyl_vec3 n = mesh->normals[face[c]];
        double l2 = (double)n.x * n.x + (double)n.y * n.y + (double)n.z * n.z;
        if (!(l2 > 1e-12)) return false; /* no direction: the PN rules need one */
        double inv = 1.0 / sqrt(l2);
        rec->p[c][0] = p.x; rec->p[c][1] = p.y; rec->p[c][2] = p.z;
        rec->n[c][0] = (float)(n.x * inv);
        rec->n[c][1] = (float)(n.y * inv);
        rec->n[c][2] = (float)(n.z * inv);
    }
    rec->p[0][3] = (float)kind;
    return true;
}

/* ---- unique edges: open addressing on (min, max) vertex index ------------------------------ */

typedef struct edge_map {
    uint64_t *keys; /* UINT64_MAX = empty */
    uint32_t *ids;
    size_t mask;
    size_t count;
} edge_map;

static uint64_t mix64(uint64_t x)
{
    x ^= x >> 33; x *= 0xff51afd7ed558ccdull;
    x ^= x >> 33; x *= 0xc4ceb9fe1a85ec53ull;
    return x ^ (x >> 33);
}

static uint32_t edge_id(edge_map *m, uint32_t a, uint32_t b, bool *fresh)
{
    uint64_t key = a < b ? ((uint64_t)a << 32 | b) : ((uint64_t)b << 32 | a);
    size_t slot = (size_t)mix64(key) & m->mask;
    while (m->keys[slot] != UINT64_MAX && m->keys[slot] != key) slot = (slot + 1) & m->mask;
    *fresh = m->keys[slot] == UINT64_MAX;
    if (*fresh) {
        m->keys[slot] = key;
        m->ids[slot] = (uint32_t)m->count++;
    }
    return m->ids[slot];
}

/* ---- error bounds ------------------------------------------------------------------------- */

static float dist3(tv3 a, tv3 b) { return tv3_len(tv3_sub(a, b)); }

/* Bounding sphere of control points (they bound the patch: convex hull property). */
static void sphere_of(const tv3 *pts, int count, xyl__tess_bound *b)
{
    tv3 lo = pts[0], hi = pts[0];
    for (int i = 1; i < count; ++i) {
        lo = tv3_make(fminf(lo.x, pts[i].x), fminf(lo.y, pts[i].y), fminf(lo.z, pts[i].z));
        hi = tv3_make(fmaxf(hi.x, pts[i].x), fmaxf(hi.y, pts[i].y), fmaxf(hi.z, pts[i].z));
    }
    tv3 c = tv3_mul(tv3_add(lo, hi), 0.5f);
    float r = 0.0f;
    for (int i = 0; i < count; ++i) r = fmaxf(r, dist3(pts[i], c));
    b->center[0] = c.x; b->center[1] = c.y; b->center[2] = c.z;
    b->radius = r * (1.0f + 4.0f * FLT_EPSILON);
}

static float second_diff(tv3 a, tv3 b, tv3 c)
{
    return tv3_len(tv3_add(tv3_sub(a, tv3_mul(b, 2.0f)), c));
}

/* Cubic edge: |B''| <= 6 max |second difference|, and a chord over 1/L of the parameter strays
 * at most |B''| / (8 L^2) from the curve. */
static float edge_coef(const tv3 b[4])
{
    return 0.75f * fmaxf(second_diff(b[0], b[1], b[2]), second_diff(b[1], b[2], b[3]));
}

/* Bicubic: |S_uu|, |S_vv| <= 6 D2, |S_uv| <= 9 D11; linear interpolation over a lattice triangle
 * of legs 1/L strays at most (|S_uu| + 2|S_uv| + |S_vv|) / (8 L^2). */
static float quad_coef(const tv3 b[16])
{
    float du = 0.0f, dv = 0.0f, twist = 0.0f;
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 2; ++i) {
            du = fmaxf(du, second_diff(b[i + 4 * j], b[i + 1 + 4 * j], b[i + 2 + 4 * j]));
            dv = fmaxf(dv, second_diff(b[j + 4 * i], b[j + 4 * (i + 1)], b[j + 4 * (i + 2)]));
        }
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
            tv3 t = tv3_sub(tv3_add(b[i + 4 * j], b[i + 1 + 4 * (j + 1)]),
                            tv3_add(b[i + 1 + 4 * j], b[i + 4 * (j + 1)]));
            twist = fmaxf(twist, tv3_len(t));
        }
    return 0.75f * (du + dv) + 2.25f * twist;
}

/* Cubic triangle: along each of the three lattice directions the second derivative is bounded
 * by 6 times the largest second difference in that direction; a lattice triangle's edges follow
 * those directions, so the sum of the three is a safe bound. */
static float tri_coef(const tv3 b[10])
{
    /* lattice of the net: index by (i, j, k), i + j + k = 3 */
    static const int at[4][4] = {
        /* at[j][k] for i = 3 - j - k */
        {0, 8, 7, 2}, {3, 9, 6, -1}, {4, 5, -1, -1}, {1, -1, -1, -1}};
    float d[3] = {0.0f, 0.0f, 0.0f};
    for (int j = 0; j <= 1; ++j)
        for (int k = 0; k + j <= 1; ++k) {
            /* three directions through the sub-net of points (i,j,k) .. two steps */
            d[0] = fmaxf(d[0], second_diff(b[at[j][k]], b[at[j + 1][k]], b[at[j + 2][k]]));
            d[1] = fmaxf(d[1], second_diff(b[at[j][k]], b[at[j][k + 1]], b[at[j][k + 2]]));
            d[2] = fmaxf(d[2], second_diff(b[at[j + 2][k]], b[at[j + 1][k + 1]], b[at[j][k + 2]]));
        }
    return 0.75f * (d[0] + d[1] + d[2]);
}

/* ---- create ------------------------------------------------------------------------------- */

static void patches_free(xyl__tess_patches *t)
{
    xyl_allocator a = t->alloc;
    xyl__free(&a, (void *)t->pub.records);
    xyl__free(&a, (void *)t->pub.patch_edges);
    xyl__free(&a, t->patch_bounds);
    xyl__free(&a, t->edge_bounds);
    xyl__free(&a, t);
}

void xyl_tess_patches_destroy(xyl_tess_patches *patches)
{
    if (patches) patches_free((xyl__tess_patches *)patches);
}

static xyl_result fill_all(const xyl_mesh *mesh, xyl__tess_patches *t, edge_map *map,
                           xyl_tess_patch *recs, uint32_t *pedges, xyl_diag *diag)
{
    xyl_tess_variant variant = t->pub.variant;
    size_t nq = mesh->quad_count;
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (size_t f = 0; f < t->pub.count; ++f) {
        uint32_t kind = f < nq ? XYL_TESS_KIND_QUAD : XYL_TESS_KIND_TRIANGLE;
        const uint32_t *face = f < nq ? mesh->quads + 4 * f : mesh->triangles + 3 * (f - nq);
        if (!fill_record(mesh, face, kind, &recs[f]))
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)f,
                             "face %zu has a vertex with a zero normal", f);
        tv3 net[16];
        int np = xyl__tess_control_net(&recs[f], variant, net);
        for (int i = 0; i < np; ++i)
            if (!isfinite(net[i].x) || !isfinite(net[i].y) || !isfinite(net[i].z))
                return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)f,
                                 "face %zu: control points overflow float", f);
        sphere_of(net, np, &t->patch_bounds[f]);
        t->patch_bounds[f].coef = kind == XYL_TESS_KIND_QUAD ? quad_coef(net) : tri_coef(net);
        pedges[4 * f + 3] = UINT32_MAX;
        for (uint32_t e = 0; e < kind; ++e) {
            bool fresh;
            uint32_t id = edge_id(map, face[e], face[(e + 1) % kind], &fresh);
            pedges[4 * f + e] = id;
            if (fresh) {
                tv3 eb[4];
                xyl__tess_edge_net(&recs[f], variant, e, eb);
                sphere_of(eb, 4, &t->edge_bounds[id]);
                t->edge_bounds[id].coef = edge_coef(eb);
            }
        }
        for (uint32_t c = 0; c < kind; ++c)
            for (int k = 0; k < 3; ++k) {
                lo[k] = fminf(lo[k], recs[f].p[c][k]);
                hi[k] = fmaxf(hi[k], recs[f].p[c][k]);
            }
    }
    t->pub.size = 0.0f;
    for (int k = 0; k < 3 && t->pub.count > 0; ++k) t->pub.size = fmaxf(t->pub.size, hi[k] - lo[k]);
    return XYL_OK;
}

xyl_result xyl_tess_patches_create(const xyl_mesh *mesh, const xyl_tess_patches_desc *desc,
                                   xyl_tess_patches **out, xyl_diag *diag)
{
    if (!mesh || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "mesh and out are required");
    xyl_tess_patches_desc d = desc ? *desc : (xyl_tess_patches_desc){0};
    if ((unsigned)d.variant >= XYL_TESS_VARIANT_COUNT)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "unknown variant %d",
                         (int)d.variant);
    size_t count = mesh->quad_count + mesh->triangle_count;
    if (count > UINT32_MAX / 4)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1, "%zu faces: more than 2^30", count);
    xyl_result r = xyl__mesh_validate(mesh, XYL__MESH_NORMALS | XYL__MESH_FACES, diag);
    if (r != XYL_OK) return r;
    size_t slots = 16;
    while (slots < 2 * (4 * count)) slots *= 2;

    const xyl_allocator *a = &d.alloc;
    xyl__tess_patches *t = xyl__calloc(a, 1, sizeof *t);
    edge_map map = {0};
    if (t) {
        t->alloc = d.alloc;
        t->pub.variant = d.variant;
        t->pub.count = count;
        t->pub.quad_count = mesh->quad_count;
        t->pub.records = xyl__calloc(a, count ? count : 1, sizeof(xyl_tess_patch));
        t->pub.patch_edges = xyl__calloc(a, count ? 4 * count : 1, sizeof(uint32_t));
        t->patch_bounds = xyl__calloc(a, count ? count : 1, sizeof(xyl__tess_bound));
        t->edge_bounds = xyl__calloc(a, count ? 4 * count : 1, sizeof(xyl__tess_bound));
        map.keys = xyl__calloc(a, slots, sizeof(uint64_t));
        map.ids = xyl__calloc(a, slots, sizeof(uint32_t));
        map.mask = slots - 1;
    }
    if (!t || !t->pub.records || !t->pub.patch_edges || !t->patch_bounds || !t->edge_bounds ||
        !map.keys || !map.ids) {
        if (t) patches_free(t);
        xyl__free(a, map.keys);
        xyl__free(a, map.ids);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for %zu patches",
                         count);
    }
    memset(map.keys, 0xff, slots * sizeof(uint64_t));
    r = fill_all(mesh, t, &map, (xyl_tess_patch *)t->pub.records,
                            (uint32_t *)t->pub.patch_edges, diag);
    t->pub.edge_count = map.count;
    xyl__free(a, map.keys);
    xyl__free(a, map.ids);
    if (r != XYL_OK) {
        patches_free(t);
        return r;
    }
    xyl__diag_ok(diag);
    *out = &t->pub;
    return XYL_OK;
}

float xyl_tess_patch_error_coefficient(const xyl_tess_patches *patches, size_t patch)
{
    const xyl__tess_patches *t = (const xyl__tess_patches *)patches;
    return patch < patches->count ? t->patch_bounds[patch].coef : 0.0f;
}

float xyl_tess_edge_error_coefficient(const xyl_tess_patches *patches, size_t edge)
{
    const xyl__tess_patches *t = (const xyl__tess_patches *)patches;
    return edge < patches->edge_count ? t->edge_bounds[edge].coef : 0.0f;
}

/* Patch records from an xyl_mesh, the mesh's unique edges, and the error bound of every patch and
 * edge (docs/tessellation.md, "Error bounds"). */
#include <float.h>
#include <string.h>

#include "mesh_internal.h"
#include "tess_internal.h"
#include "xyl_internal.h"

/* ---- records ------------------------------------------------------------------------------ */

static bool unit_normal(const xyl_mesh *mesh, uint32_t v, float out[3]);

/* axes: the arc variant's per-vertex axes, else NULL (the records' n[c].w stay 0). */
static bool fill_record(const xyl_mesh *mesh, const uint32_t *face, uint32_t kind,
                        const float *axes, xyl_tess_patch *rec)
{
    memset(rec, 0, sizeof *rec);
    for (uint32_t c = 0; c < kind; ++c) {
        xyl_vec3 p = mesh->positions[face[c]];
        if (!unit_normal(mesh, face[c], rec->n[c])) return false; /* the PN rules need one */
        rec->p[c][0] = p.x; rec->p[c][1] = p.y; rec->p[c][2] = p.z;
        if (axes) rec->n[c][3] = axes[face[c]];
    }
    rec->p[0][3] = (float)kind;
    return true;
}

/* ---- the arc variant's vertex axes (docs/tessellation.md, "The arc rule") ------------------- */

#define AXIS_MAX_VALENCE 8

/* The unit normal a record stores for vertex v (fill_record's arithmetic). */
static bool unit_normal(const xyl_mesh *mesh, uint32_t v, float out[3])
{
    xyl_vec3 n = mesh->normals[v];
    double l2 = (double)n.x * n.x + (double)n.y * n.y + (double)n.z * n.z;
    if (!(l2 > 1e-12)) return false;
    double inv = 1.0 / sqrt(l2);
    out[0] = (float)(n.x * inv);
    out[1] = (float)(n.y * inv);
    out[2] = (float)(n.z * inv);
    return true;
}

typedef struct fan {
    uint32_t nb[AXIS_MAX_VALENCE]; /* distinct neighbours */
    uint8_t adj[AXIS_MAX_VALENCE]; /* bit b: neighbours k and b follow each other in a face */
    uint8_t count, faces, bad; /* bad: more neighbours than fit, or a triangle among its faces */
} fan;

static int fan_slot(fan *f, uint32_t w)
{
    for (int k = 0; k < f->count; ++k)
        if (f->nb[k] == w) return k;
    if (f->count == AXIS_MAX_VALENCE) return -1;
    f->nb[f->count] = w;
    return f->count++;
}

/* How straight the curve a -> v -> b runs through v: the cosine of its turn. */
static double straightness(const xyl_mesh *mesh, uint32_t v, uint32_t a, uint32_t b)
{
    xyl_vec3 pa = mesh->positions[a], pv = mesh->positions[v], pb = mesh->positions[b];
    double u[3] = {(double)pv.x - pa.x, (double)pv.y - pa.y, (double)pv.z - pa.z};
    double w[3] = {(double)pb.x - pv.x, (double)pb.y - pv.y, (double)pb.z - pv.z};
    double lu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    double lw = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (!(lu > 0.0) || !(lw > 0.0)) return -2.0;
    return (u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) / (lu * lw);
}

/* The axis of a vertex whose faces, all quads, close a fan of even valence: of the pairs of
 * opposite neighbours, the one along the branch (the larger step in v where the mesh has UVs, else the
 * straighter), if it turns by less than 60 degrees; its tangent is that of the circle through
 * the three points (exact for unequal steps to first order), encoded in the tangent plane. */
/* Only quads: around a vertex of a triangulated tube a diagonal edge can leave within the
 * handle rule's 30 degrees of the axis, and would be bent onto it. */
static float vertex_axis(const xyl_mesh *mesh, uint32_t v, const fan *f)
{
    int m = f->count;
    if (f->bad || m < 4 || (m & 1) || f->faces != m) return 0.0f;
    for (int k = 0; k < m; ++k) { /* a closed fan: every neighbour follows exactly two others */
        int bits = 0;
        for (int b = 0; b < m; ++b) bits += f->adj[k] >> b & 1u;
        if (bits != 2) return 0.0f;
    }
    int order[AXIS_MAX_VALENCE];
    uint32_t seen = 1u;
    order[0] = 0;
    int prev = -1, cur = 0;
    for (int s = 1; s < m; ++s) {
        int next = -1;
        for (int b = 0; b < m && next < 0; ++b)
            if ((f->adj[cur] >> b & 1u) && b != prev) next = b;
        if (next < 0 || (seen >> next & 1u)) return 0.0f; /* two cycles: not one fan */
        seen |= 1u << next;
        order[s] = next;
        prev = cur;
        cur = next;
    }
    int best = -1;
    double best_cos = -2.0;
    bool by_uv = false;
    if (mesh->uvs) {
        double dv[AXIS_MAX_VALENCE / 2], hi = -1.0, lo = INFINITY;
        for (int k = 0; k < m / 2; ++k) {
            dv[k] = fabs((double)mesh->uvs[2 * f->nb[order[k]] + 1] -
                         (double)mesh->uvs[2 * f->nb[order[k + m / 2]] + 1]);
            if (dv[k] > hi) hi = dv[k], best = k;
        }
        for (int k = 0; k < m / 2; ++k)
            if (k != best) lo = fmin(lo, dv[k]);
        by_uv = hi > 0.0 && hi > 4.0 * lo;
    }
    if (!by_uv) {
        best = -1;
        for (int k = 0; k < m / 2; ++k) {
            double c = straightness(mesh, v, f->nb[order[k]], f->nb[order[k + m / 2]]);
            if (c > best_cos) best_cos = c, best = k;
        }
    }
    if (best < 0) return 0.0f;
    uint32_t a = f->nb[order[best]], b = f->nb[order[best + m / 2]];
    if (straightness(mesh, v, a, b) < 0.5) return 0.0f;
    float n[3];
    if (!unit_normal(mesh, v, n)) return 0.0f;
    xyl_vec3 pa = mesh->positions[a], pv = mesh->positions[v], pb = mesh->positions[b];
    double u[3] = {(double)pv.x - pa.x, (double)pv.y - pa.y, (double)pv.z - pa.z};
    double w[3] = {(double)pb.x - pv.x, (double)pb.y - pv.y, (double)pb.z - pv.z};
    double lu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    double lw = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    double t[3];
    for (int k = 0; k < 3; ++k) t[k] = u[k] * (lw / lu) + w[k] * (lu / lw);
    double tn = t[0] * n[0] + t[1] * n[1] + t[2] * n[2];
    for (int k = 0; k < 3; ++k) t[k] -= tn * n[k];
    double tl = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    if (!(tl > 0.0) || !isfinite(tl)) return 0.0f;
    for (int k = 0; k < 3; ++k) t[k] /= tl;
    return xyl__tess_encode_axis(n, t);
}

/* Every vertex's stored axis (0: none); NULL when out of memory. */
static float *vertex_axes(const xyl_mesh *mesh, const xyl_allocator *a)
{
    size_t nv = mesh->vertex_count;
    fan *fans = xyl__calloc(a, nv ? nv : 1, sizeof *fans);
    float *axes = xyl__calloc(a, nv ? nv : 1, sizeof *axes);
    if (!fans || !axes) {
        xyl__free(a, fans);
        xyl__free(a, axes);
        return NULL;
    }
    size_t nf = mesh->quad_count + mesh->triangle_count;
    for (size_t f = 0; f < nf; ++f) {
        bool quad = f < mesh->quad_count;
        uint32_t kind = quad ? 4u : 3u;
        const uint32_t *face = quad ? mesh->quads + 4 * f : mesh->triangles + 3 * (f - mesh->quad_count);
        for (uint32_t c = 0; c < kind; ++c) {
            fan *fv = &fans[face[c]];
            if (!quad) fv->bad = 1; /* see vertex_axis */
            int p = fan_slot(fv, face[(c + kind - 1) % kind]);
            int q = fan_slot(fv, face[(c + 1) % kind]);
            if (p < 0 || q < 0) {
                fv->bad = 1;
                continue;
            }
            fv->adj[p] |= (uint8_t)(1u << q);
            fv->adj[q] |= (uint8_t)(1u << p);
            if (fv->faces < 255) fv->faces++;
        }
    }
    for (size_t v = 0; v < nv; ++v) axes[v] = vertex_axis(mesh, (uint32_t)v, &fans[v]);
    xyl__free(a, fans);
    return axes;
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
                           const float *axes, xyl_tess_patch *recs, uint32_t *pedges,
                           xyl_diag *diag)
{
    xyl_tess_variant variant = t->pub.variant;
    size_t nq = mesh->quad_count;
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (size_t f = 0; f < t->pub.count; ++f) {
        uint32_t kind = f < nq ? XYL_TESS_KIND_QUAD : XYL_TESS_KIND_TRIANGLE;
        const uint32_t *face = f < nq ? mesh->quads + 4 * f : mesh->triangles + 3 * (f - nq);
        if (!fill_record(mesh, face, kind, axes, &recs[f]))
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
    float *axes = NULL;
    if (d.variant == XYL_TESS_ARC && !(axes = vertex_axes(mesh, a))) {
        patches_free(t);
        xyl__free(a, map.keys);
        xyl__free(a, map.ids);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1,
                         "out of memory for the axes of %zu vertices", mesh->vertex_count);
    }
    r = fill_all(mesh, t, &map, axes, (xyl_tess_patch *)t->pub.records,
                 (uint32_t *)t->pub.patch_edges, diag);
    xyl__free(a, axes);
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

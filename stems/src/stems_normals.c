/* Stem mesh normals: unit sums per branch, the joints' normals, branch normals on the limit. */
#include <float.h>
#include <string.h>

#include "mesh_internal.h"
#include "stems_internal.h"

/* With even k (no triangles) a vertex's own-branch faces are the bands, caps and bridge of its
 * branch, all made once the branch is built: its normals are normalised then, while they are
 * still in cache, instead of in one more pass over the whole mesh. A vertex without any keeps
 * its sum for xyl__mesh_normals_lonely. The branch's vertices are those of its rings and the
 * apexes of its domed caps. */
static void unit_normal(stems *s, xyl_vec3 *n)
{
    if (xyl__has_direction(*n)) *n = xyl__unit_or_up(*n);
    else s->lonely = true;
}

#ifdef XYL__SSE2
/* unit_normal on n[0] and n[1] at once: the same double operations in the same order, so the
 * same bits, two lanes per instruction (the square root and the division dominate this pass). */
static void unit_normal_pair(stems *s, xyl_vec3 *n)
{
    __m128d v[3];
    xyl__load_pair(n, 0, 1, v);
    __m128d l2 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(v[0], v[0]), _mm_mul_pd(v[1], v[1])),
                            _mm_mul_pd(v[2], v[2]));
    /* both with a direction and finite: else each on its own */
    __m128d ok = _mm_and_pd(_mm_cmpgt_pd(l2, _mm_set1_pd(XYL__EPS_NORMALIZE)),
                            _mm_cmple_pd(l2, _mm_set1_pd(DBL_MAX)));
    if (_mm_movemask_pd(ok) != 3) {
        unit_normal(s, &n[0]);
        unit_normal(s, &n[1]);
        return;
    }
    __m128d inv = _mm_div_pd(_mm_set1_pd(1.0), _mm_sqrt_pd(l2));
    xyl__store_pair(_mm_cvtpd_ps(_mm_mul_pd(v[0], inv)), _mm_cvtpd_ps(_mm_mul_pd(v[1], inv)),
               _mm_cvtpd_ps(_mm_mul_pd(v[2], inv)), n);
}
#endif

void xyl__stems_unit_branch_normals(stems *s)
{
    for (size_t i = 0; i < s->nrings; ++i) {
        xyl_vec3 *n = s->nrm + s->rings[i].first;
        uint32_t j = 0;
#ifdef XYL__SSE2
        for (; j + 2 <= s->k; j += 2) unit_normal_pair(s, n + j);
#endif
        for (; j < s->k; ++j) unit_normal(s, n + j);
    }
    for (int e = 0; e < 2; ++e) {
        if (s->apex[e] == UINT32_MAX) continue;
        unit_normal(s, s->nrm + s->apex[e]);
    }
}

/* A tube's true normal at a ring vertex has no component around the ring: it lies in the plane
 * of the radial direction and the branch's tangent (the taper tilts it along the tangent). The
 * face sums of a ring vertex on a bend have one: the faces on the outer side of the bend are
 * wider, and area weights lean the sum towards them (0.5 degrees on a k = 4 tube bent 4 degrees
 * per segment, which the tessellation's handles then follow: docs/tessellation.md, "The arc
 * rule"). Each ring's sums lose that component before they are normalised; a lateral's bridge
 * ring (its first), which is no tube's, keeps its sums. */
void xyl__stems_flatten_ring_normals(stems *s, bool lateral)
{
    for (size_t i = lateral ? 1 : 0; i < s->nrings; ++i) {
        const stems_ring *rg = &s->rings[i];
        for (uint32_t j = 0; j < s->k; ++j) {
            xyl_vec3 *n = s->nrm + rg->first + j;
            xyl__dvec3 around = xyl__d3_cross(
                rg->tangent, xyl__d3_sub(xyl__from_f3(s->pos[rg->first + j]), rg->centre));
            double aa = xyl__d3_dot(around, around);
            if (!(aa > 0.0) || !(aa <= DBL_MAX)) continue;
            xyl__dvec3 v = xyl__from_f3(*n);
            *n = xyl__to_f3(xyl__d3_sub(v, xyl__d3_scale(around, xyl__d3_dot(v, around) / aa)));
        }
    }
}

/* Normals of the mesh before the patches were dropped: a parent vertex on a joint still sees its
 * branch's full tube, so its normal is the parent's own (Skjermo 2008). The quads' share is in
 * s->nrm already; triangles come after all quads, as in xyl__mesh_normals. */
xyl_result xyl__stems_normals_with_patches(stems *s, xyl_vec3 **out)
{
    for (size_t t = 0; t < s->nt; ++t) {
        const uint32_t *f = s->tris + 3 * t;
        xyl_vec3 fn = xyl__tri_normal(s->pos, f);
        for (int k = 0; k < 3; ++k)
            if (s->vbranch[f[k]] == s->tbranch[t]) xyl__add_f3(&s->nrm[f[k]], fn);
    }
    xyl__mesh_arrays view; /* all faces, taken ones too: for vertices without own-branch faces */
    memset(&view, 0, sizeof view);
    view.positions = s->pos;
    view.vertex_count = s->nv;
    view.quads = s->quads;
    view.quad_count = s->nq;
    view.triangles = s->tris;
    view.triangle_count = s->nt;
    xyl_result r = XYL_OK;
    if (!s->unit_per_branch) r = xyl__mesh_normals_finish(&view, true, &s->alloc, s->nrm);
    else if (s->lonely) r = xyl__mesh_normals_lonely(&view, &s->alloc, s->nrm);
    if (r) return xyl__stems_oom(s);
    *out = s->nrm;
    s->nrm = NULL;
    return XYL_OK;
}

/* The faces of a that touch a vertex marked in seam (near: scratch, one per face), quads then
 * triangles in mesh order, with their branches, into view's face arrays (from alloc). */
static xyl_result near_faces(const xyl__mesh_arrays *a, const uint8_t *seam, uint8_t *near,
                             const xyl_allocator *alloc, xyl__mesh_arrays *view)
{
    size_t nq = 0, nt = 0;
    for (size_t f = 0; f < a->quad_count + a->triangle_count; ++f) {
        bool quad = f < a->quad_count;
        const uint32_t *idx = quad ? a->quads + 4 * f : a->triangles + 3 * (f - a->quad_count);
        for (int c = 0; c < (quad ? 4 : 3); ++c) near[f] = (uint8_t)(near[f] | seam[idx[c]]);
        if (near[f]) quad ? ++nq : ++nt;
    }
    view->quads = xyl__alloc_array(alloc, nq ? nq : 1, 4 * sizeof *view->quads);
    view->triangles = xyl__alloc_array(alloc, nt ? nt : 1, 3 * sizeof *view->triangles);
    view->face_branches =
        xyl__alloc_array(alloc, nq + nt ? nq + nt : 1, sizeof *view->face_branches);
    if (!view->quads || !view->triangles || !view->face_branches) return XYL_ERR_OUT_OF_MEMORY;
    view->quad_count = nq;
    view->triangle_count = nt;
    size_t q = 0, t = 0;
    for (size_t f = 0; f < a->quad_count + a->triangle_count; ++f) {
        if (!near[f]) continue;
        bool quad = f < a->quad_count;
        if (quad) memcpy(view->quads + 4 * q, a->quads + 4 * f, 4 * sizeof *view->quads);
        else memcpy(view->triangles + 3 * t, a->triangles + 3 * (f - a->quad_count),
                    3 * sizeof *view->triangles);
        view->face_branches[quad ? q : nq + t] = a->face_branches[f];
        quad ? ++q : ++t;
    }
    return XYL_OK;
}

/* Per-branch normals on a mesh whose vertices sit on the limit surface: the limit normal
 * (exact) wherever all of a vertex's faces are of its own branch, the own-branch face average
 * at the seams between branches, where the limit normal would lean towards the other branch.
 * The averages are taken over the faces that touch a seam vertex only, in mesh order: a seam
 * vertex sees all its faces in the same order, so its sums are those of the whole mesh, and
 * the rest (most of a subdivided mesh) is not summed only to be thrown away. */
xyl_result xyl__stems_branch_normals_on_limit(stems *s, xyl__mesh_arrays *a)
{
    xyl_vec3 *limit = a->normals;
    const size_t faces = a->quad_count + a->triangle_count;
    uint8_t *seam = xyl__calloc(&s->alloc, a->vertex_count ? a->vertex_count : 1, 1);
    uint8_t *near = xyl__calloc(&s->alloc, faces ? faces : 1, 1); /* touches a seam vertex */
    /* zeroed by xyl__mesh_normals */
    a->normals = xyl__alloc_array(&s->alloc, a->vertex_count, sizeof *a->normals);
    xyl__mesh_arrays view = *a; /* positions and branches; its faces are set below */
    view.normals = NULL;
    view.uv_wraps = NULL;
    view.quads = view.triangles = view.face_branches = NULL;
    xyl_result r = seam && near && a->normals ? XYL_OK : XYL_ERR_OUT_OF_MEMORY;
    if (!r) {
        for (size_t f = 0; f < faces; ++f) {
            bool quad = f < a->quad_count;
            const uint32_t *idx = quad ? a->quads + 4 * f : a->triangles + 3 * (f - a->quad_count);
            for (int c = 0; c < (quad ? 4 : 3); ++c)
                if (a->branch_ids[idx[c]] != a->face_branches[f]) seam[idx[c]] = 1;
        }
        r = near_faces(a, seam, near, &s->alloc, &view);
    }
    if (!r) r = xyl__mesh_normals(&view, view.face_branches, &s->alloc, a->normals);
    if (!r)
        for (size_t v = 0; v < a->vertex_count; ++v)
            if (!seam[v]) a->normals[v] = limit[v];
    xyl__free(&s->alloc, view.quads);
    xyl__free(&s->alloc, view.triangles);
    xyl__free(&s->alloc, view.face_branches);
    xyl__free(&s->alloc, near);
    xyl__free(&s->alloc, seam);
    xyl__free(&s->alloc, limit);
    return r ? xyl__stems_oom(s) : XYL_OK;
}

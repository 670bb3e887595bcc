/* tessellate: PN refinement levels chosen for a camera, evaluated on the CPU.
 * A short forked stem is meshed, each face becomes a PN patch, the levels for a 0.5 px budget
 * are chosen for a near and a far camera, and the near view is refined into triangles with the
 * reference evaluator (the same formulas the GPU backends run). */
#include <stdio.h>

#include <xylem/xyl_stems.h>
#include <xylem/xyl_tessellate.h>

static uint64_t triangles_at(const xyl_tess_patches *tp, const xyl_tess_patterns *pat,
                             xyl_tess_batches *b, float distance)
{
    xyl_tess_view view = {.eye = {0, 1, distance}};   /* 0.5 px, 1080 px, fovy 0.8 */
    return xyl_tess_select(tp, pat, &view, b, NULL) == XYL_OK ? b->triangles : 0;
}

int main(void)
{
    xyl_skel_node nodes[] = {{{0, 0, 0}, 0.10f, -1, 0, 0}, {{0, 1, 0}, 0.08f, 0, 0, 0},
                             {{0, 2, 0}, 0.06f, 1, 0, 0},  {{0.5f, 1.6f, 0}, 0.04f, 1, 0, 0}};
    xyl_skeleton_desc sd = {.nodes = nodes, .node_count = 4};
    xyl_tess_patches_desc pd = {.variant = XYL_TESS_CIRCLE};  /* exact on round sections */
    xyl_skeleton *sk = NULL;
    xyl_mesh *m = NULL, *refined = NULL;
    xyl_tess_patches *tp = NULL;
    xyl_tess_patterns *pat = NULL;
    xyl_tess_batches *b = NULL;
    xyl_diag diag = {0};
    xyl_result r = xyl_skeleton_create(&sd, &sk, &diag);
    if (!r) r = xyl_stems_build(sk, NULL, &m, NULL, &diag);
    if (!r) r = xyl_tess_patches_create(m, &pd, &tp, &diag);
    if (!r) r = xyl_tess_patterns_create(0, NULL, &pat, &diag);   /* levels 1..64, once */
    if (!r) r = xyl_tess_batches_create(NULL, &b, &diag);
    uint64_t far = r ? 0 : triangles_at(tp, pat, b, 40.0f);
    uint64_t near = r ? 0 : triangles_at(tp, pat, b, 2.0f);
    if (!r) r = xyl_tess_refine(tp, pat, b, NULL, NULL, &refined, &diag);
    int ok = !r && far > 0 && near > far && refined->triangle_count == near;
    if (r) fprintf(stderr, "%s: %s\n", xyl_result_string(r), diag.message);
    else
        printf("%zu patches; %llu triangles seen from 40 units, %llu from 2 units; "
               "refined on the CPU: %zu vertices, %zu triangles\n", tp->count,
               (unsigned long long)far, (unsigned long long)near, refined->vertex_count,
               refined->triangle_count);
    xyl_mesh_destroy(refined);
    xyl_tess_batches_destroy(b);
    xyl_tess_patterns_destroy(pat);
    xyl_tess_patches_destroy(tp);
    xyl_mesh_destroy(m);
    xyl_skeleton_destroy(sk);
    return ok ? 0 : 1;
}

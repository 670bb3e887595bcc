/* stems: one closed quad mesh around a whole skeleton.
 * A trunk with two laterals at different heights goes through the stem mesher with six ring
 * sides; the result is checked as a closed 2-manifold of quads and written as OBJ text. */
#include <stdio.h>

#include <xylem/xyl_stems.h>

int main(void)
{
    xyl_skel_node nodes[] = {
        {{0, 0, 0}, 0.12f, -1, 0, 0},  {{0, 1, 0}, 0.10f, 0, 0, 0},   {{0, 2, 0}, 0.08f, 1, 0, 0},
        {{0, 3, 0}, 0.06f, 2, 0, 0},   {{0.6f, 1.5f, 0}, 0.05f, 1, 0, 0},
        {{1.1f, 1.9f, 0}, 0.04f, 4, 0, 0}, {{-0.5f, 2.6f, 0.2f}, 0.04f, 2, 0, 0},
    };
    xyl_diag diag = {0};
    xyl_skeleton_desc sd = {0};
    sd.nodes = nodes;
    sd.node_count = sizeof nodes / sizeof nodes[0];
    xyl_skeleton *sk = NULL;
    xyl_mesh *m = NULL;
    xyl_stems_desc md = {0};   /* zero: k = 4, branch normals, joints checked */
    md.sides = 6;
    xyl_stems_stats stats;
    xyl_result r = xyl_skeleton_create(&sd, &sk, &diag);
    if (!r) r = xyl_stems_build(sk, &md, &m, &stats, &diag);
    if (r) {
        fprintf(stderr, "%s: %s\n", xyl_result_string(r), diag.message);
        xyl_skeleton_destroy(sk);
        return 1;
    }
    xyl_mesh_report rep;
    size_t obj_bytes = 0;
    int ok = !xyl_mesh_check(m, NULL, &rep, &diag) &&
             !xyl_mesh_write_memory(m, XYL_MESH_FORMAT_OBJ, NULL, NULL, 0, &obj_bytes);
    printf("%u branches -> %zu vertices, %zu quads, %zu triangles; closed manifold: %s; "
           "%zu joint pairs found, %u laterals moved; OBJ %zu bytes\n", sk->branch_count,
           m->vertex_count, m->quad_count, m->triangle_count, rep.closed_manifold ? "yes" : "no",
           stats.joint_pairs_first, stats.laterals_started_later, obj_bytes);
    ok = ok && rep.closed_manifold && rep.components == 1 && m->triangle_count == 0;
    xyl_mesh_destroy(m);
    xyl_skeleton_destroy(sk);
    return ok ? 0 : 1;
}

/* mesh: your own quad mesh, checked and written as glTF.
 * A cube of 6 quads: xyl_mesh_check says whether it is a closed 2-manifold, the
 * self-intersection test finds no crossing triangles, and the GLB bytes are counted, then
 * filled into the caller's buffer. */
#include <stdio.h>
#include <stdlib.h>

#include <xylem/xyl_mesh.h>

int main(void)
{
    xyl_vec3 pos[8];
    for (int i = 0; i < 8; ++i) /* corner i: x = bit 0, y = bit 1, z = bit 2 */
        pos[i] = (xyl_vec3){(float)(i & 1), (float)(i >> 1 & 1), (float)(i >> 2)};
    const uint32_t quads[] = {0, 2, 3, 1, 4, 5, 7, 6, 0, 1, 5, 4,   /* counter-clockwise */
                              2, 6, 7, 3, 0, 4, 6, 2, 1, 3, 7, 5};  /* seen from outside */
    xyl_diag diag = {0};
    xyl_mesh_desc d = {0};   /* no normals given: smooth ones are computed */
    d.positions = pos;
    d.vertex_count = 8;
    d.quads = quads;
    d.quad_count = 6;
    xyl_mesh *m = NULL;
    if (xyl_mesh_create(&d, &m, &diag)) {
        fprintf(stderr, "create: %s\n", diag.message);
        return 1;
    }
    xyl_mesh_report rep;
    size_t pairs = 0, bytes = 0;
    int ok = !xyl_mesh_check(m, NULL, &rep, &diag) &&
             !xyl_mesh_self_intersections(m, NULL, NULL, 0, &pairs, &diag) &&
             !xyl_mesh_write_memory(m, XYL_MESH_FORMAT_GLB, NULL, NULL, 0, &bytes);
    void *glb = ok ? malloc(bytes) : NULL;
    ok = ok && glb && !xyl_mesh_write_memory(m, XYL_MESH_FORMAT_GLB, NULL, glb, bytes, &bytes);
    printf("V %zu, E %zu, F %zu, Euler %lld, closed manifold: %s, intersecting pairs: %zu, "
           "GLB %zu bytes\n", rep.vertices, rep.edges, rep.faces, (long long)rep.euler,
           rep.closed_manifold ? "yes" : "no", pairs, bytes);
    ok = ok && rep.closed_manifold && rep.euler == 2 && pairs == 0;
    free(glb);
    xyl_mesh_destroy(m);
    return ok ? 0 : 1;
}

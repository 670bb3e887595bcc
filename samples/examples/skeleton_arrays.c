/* skeleton: a skeleton from your own arrays, and its .skel text.
 * A trunk with one fork: parents come before children, radii are yours. The skeleton derives
 * branch ids and orders; its text form reads back to the same nodes. */
#include <stdio.h>
#include <stdlib.h>

#include <xylem/xyl_skeleton.h>

int main(void)
{
    /* pos, radius, parent (-1: a root); branch and order are derived */
    xyl_skel_node nodes[] = {
        {{0, 0, 0}, 0.10f, -1, 0, 0},   {{0, 1, 0}, 0.08f, 0, 0, 0},
        {{0, 2, 0}, 0.06f, 1, 0, 0},    {{0.5f, 1.6f, 0}, 0.04f, 1, 0, 0},
        {{0.9f, 2.0f, 0.1f}, 0.03f, 3, 0, 0},
    };
    xyl_diag diag = {0};
    xyl_skeleton_desc d = {0};
    d.nodes = nodes;
    d.node_count = sizeof nodes / sizeof nodes[0];
    xyl_skeleton *sk = NULL, *back = NULL;
    if (xyl_skeleton_create(&d, &sk, &diag)) {
        fprintf(stderr, "create: %s\n", diag.message);
        return 1;
    }
    size_t size = 0;   /* count, then fill */
    xyl_skeleton_write_text(sk, XYL_SKEL_FORMAT_SKEL, NULL, 0, &size);
    char *text = malloc(size + 1);
    int ok = text && !xyl_skeleton_write_text(sk, XYL_SKEL_FORMAT_SKEL, text, size + 1, &size) &&
             !xyl_skeleton_read_text(text, size, NULL, &back, &diag);
    for (size_t i = 0; ok && i < sk->node_count; ++i)
        ok = back->nodes[i].pos.x == sk->nodes[i].pos.x &&
             back->nodes[i].radius == sk->nodes[i].radius &&
             back->nodes[i].branch == sk->nodes[i].branch;
    printf("%zu nodes, %u branches (node 3 starts branch %u of order %u); %zu bytes of .skel, "
           "read back %s\n", sk->node_count, sk->branch_count, sk->nodes[3].branch,
           sk->nodes[3].order, size, ok ? "equal" : "DIFFERENT");
    free(text);
    xyl_skeleton_destroy(back);
    xyl_skeleton_destroy(sk);
    return ok ? 0 : 1;
}

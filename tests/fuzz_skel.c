/* libFuzzer target for the .skel reader.
 *
 * Any bytes go to xyl_skeleton_read_text (with small limits so big inputs stay fast). A
 * rejected input must come back with a filled diag and *out untouched; an accepted one must
 * write back in both formats and re-read from .skel text to the very same bits. Anything else
 * abort()s, which libFuzzer reports as a crash.
 *
 *   ./fuzz_skel -max_total_time=60 new_corpus/ tests/data/skel
 */
#include <float.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_internal.h"
#include "xylem/xyl_stems.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check(int ok)
{
    if (!ok) abort();
}

static char *render(const xyl_skeleton *sk, xyl_skel_format format, size_t *len)
{
    size_t needed = 0;
    check(xyl_skeleton_write_text(sk, format, NULL, 0, &needed) == XYL_OK);
    char *text = malloc(needed + 1);
    check(text != NULL);
    check(xyl_skeleton_write_text(sk, format, text, needed + 1, len) == XYL_OK);
    check(*len == needed && strlen(text) == needed);
    return text;
}

static void check_same(const xyl_skeleton *a, const xyl_skeleton *b)
{
    check(a->node_count == b->node_count && a->leaf_count == b->leaf_count);
    check(a->branch_count == b->branch_count && a->root_count == b->root_count);
    check(a->max_order == b->max_order);
    check(a->node_count == 0 || memcmp(a->nodes, b->nodes, a->node_count * sizeof *a->nodes) == 0);
    check(a->leaf_count == 0 ||
          memcmp(a->leaves, b->leaves, a->leaf_count * sizeof *a->leaves) == 0);
}

/* A rejection must explain itself in printable text and point at the input, except when
 * memory ran out. */
static void check_rejection(xyl_result r, const xyl_skeleton *out, const xyl_diag *d)
{
    check(out == NULL && d->code == r && d->message[0] != '\0');
    for (const char *c = d->message; *c; ++c) check((unsigned char)*c >= 0x20);
    check(r == XYL_ERR_OUT_OF_MEMORY || d->line >= 1);
}

static size_t count_lines(const char *text, char first)
{
    size_t n = 0;
    for (const char *p = text; *p; ++p)
        if ((p == text || p[-1] == '\n') && *p == first) ++n;
    return n;
}

static void check_obj(const xyl_skeleton *sk)
{
    size_t len, segments = 0;
    char *obj = render(sk, XYL_SKEL_FORMAT_OBJ, &len);
    for (size_t i = 0; i < sk->node_count; ++i) segments += sk->nodes[i].parent >= 0;
    check(count_lines(obj, 'v') == sk->node_count);
    check(count_lines(obj, 'l') == segments);
    free(obj);
}

/* The mesh's UV wraps name only each face's own corners, and its seam-split mesh puts every
 * corner where the mesh has it, with the corner's UV (u + 1 where wrapped). */
static void check_seams(const xyl_mesh *m)
{
    xyl_mesh *split = NULL;
    check(xyl_mesh_split_seams(m, NULL, &split, NULL) == XYL_OK);
    check(split->vertex_count >= m->vertex_count && split->quad_count == m->quad_count &&
          split->triangle_count == m->triangle_count);
    for (size_t f = 0; f < m->quad_count + m->triangle_count; ++f) {
        int n, ns;
        const uint32_t *a = xyl__mesh_face(m, f, &n), *b = xyl__mesh_face(split, f, &ns);
        check((m->uv_wraps[f] >> n) == 0 && split->uv_wraps[f] == 0);
        for (int c = 0; c < n; ++c) {
            float u = m->uvs[2 * a[c]] + ((m->uv_wraps[f] >> c & 1u) ? 1.0f : 0.0f);
            check(memcmp(&split->positions[b[c]], &m->positions[a[c]], sizeof(xyl_vec3)) == 0);
            check(split->uvs[2 * b[c]] == u && split->uvs[2 * b[c] + 1] == m->uvs[2 * a[c] + 1]);
        }
    }
    xyl_mesh_destroy(split);
}

/* Every skeleton the reader accepts must mesh into a closed oriented manifold with one sphere
 * per root: the mesher's guarantee holds by construction, whatever the geometry. (Degenerate
 * faces are allowed here: random radii and coincident nodes can make faces below the tolerance.) */
static void check_mesh(const xyl_skeleton *sk, uint32_t sides, float error_world)
{
    if (sk->node_count > 512) return;
    xyl_stems_desc d;
    memset(&d, 0, sizeof d);
    d.sides = sides;
    d.error_world = error_world;
    xyl_mesh *m = NULL;
    xyl_result r = xyl_stems_build(sk, &d, &m, NULL, NULL);
    if (r == XYL_ERR_LIMIT_EXCEEDED) return;
    check(r == XYL_OK);
    xyl_mesh_report rep;
    check(xyl_mesh_check(m, NULL, &rep, NULL) == XYL_OK);
    check(rep.boundary_edges == 0 && rep.nonmanifold_edges == 0 && rep.misoriented_edges == 0);
    check(rep.nonmanifold_vertices == 0 && rep.duplicate_faces == 0);
    check(rep.euler == 2 * (int64_t)sk->root_count && rep.components == sk->root_count);
    check_seams(m);
    xyl_mesh_destroy(m);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    xyl_skeleton_read_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.limits.max_nodes = 4096;
    desc.limits.max_leaves = 4096;
    xyl_diag diag;
    memset(&diag, 0, sizeof diag);
    xyl_skeleton *sk = NULL;
    xyl_result r = xyl_skeleton_read_text((const char *)data, size, &desc, &sk, &diag);
    if (r != XYL_OK) {
        check_rejection(r, sk, &diag);
        return 0;
    }
    size_t len;
    char *text = render(sk, XYL_SKEL_FORMAT_SKEL, &len);
    xyl_skeleton *back = NULL;
    check(xyl_skeleton_read_text(text, len, &desc, &back, &diag) == XYL_OK);
    check_same(sk, back);
    check_obj(sk);
    check_mesh(sk, 3 + (uint32_t)(size % 6), 0.0f);
    /* ring sides per branch: a budget that gives the widest branch 8 sides and thinner ones
     * fewer, down to 3 (docs/stems.md, "Ring sides per branch") */
    float widest = 0.0f;
    for (size_t i = 0; i < sk->node_count; ++i)
        widest = sk->nodes[i].radius > widest ? sk->nodes[i].radius : widest;
    float budget = widest * (0.02f + 0.07f * (float)(size % 5));
    if (budget > 0.0f && budget <= FLT_MAX) check_mesh(sk, 8, budget);
    free(text);
    xyl_skeleton_destroy(back);
    xyl_skeleton_destroy(sk);
    return 0;
}

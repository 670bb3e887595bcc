/* The foliage .glb read back by a glTF library (tinygltf, through the samples' reader): the
 * leaves, their LOD tables in the extras, the material and texture, and the stems beside them.
 *
 * With XYL_GLB_SAMPLES=FOLDER in the environment this program also writes its files there
 * (leaves without a texture, stems and leaves with and without one, a tree without leaves), for
 * the gltf_validator test. */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "xylem/xyl_foliage.h"
#include "foliage_internal.h"
#include "glb_read.h"
#include "leaf_texture.h"
#include "png_write.h"
#include "test_util.h"

typedef struct tree {
    xyl_mesh *stems;
    xyl_foliage *foliage;
} tree;

/* A preset's stems and its leaves' LODs in `sectors` sectors. */
static tree grow_tree(const char *preset, uint32_t sectors)
{
    tree t = {0};
    xyl_skeleton *sk = tu_grow(xyl_lsystem_preset_source(preset), NULL);
    assert_int_equal(xyl_stems_build(sk, NULL, &t.stems, NULL, NULL), XYL_OK);
    size_t n = 0;
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, NULL, NULL, 0, &n, NULL), XYL_OK);
    xyl_leaf *leaves = malloc((n ? n : 1) * sizeof *leaves);
    assert_non_null(leaves);
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, NULL, leaves, n, &n, NULL), XYL_OK);
    xyl_foliage_desc d = {0};
    d.leaves = leaves;
    d.leaf_count = n;
    d.sectors = sectors;
    assert_int_equal(xyl_foliage_build(&d, &t.foliage, NULL), XYL_OK);
    free(leaves);
    xyl_skeleton_destroy(sk);
    return t;
}

static void tree_free(tree *t)
{
    xyl_mesh_destroy(t->stems);
    xyl_foliage_destroy(t->foliage);
}

/* The procedural leaf texture as PNG bytes (malloc). */
static unsigned char *leaf_png(size_t *size)
{
    uint32_t w = XYL_LEAF_TEXTURE_WIDTH, h = XYL_LEAF_TEXTURE_HEIGHT;
    uint8_t *rgba = malloc((size_t)w * h * 4);
    assert_non_null(rgba);
    xyl_leaf_texture(rgba, w, h);
    unsigned char *png = NULL;
    char msg[256];
    if (xyl_png_encode(rgba, w, h, &png, size, msg, sizeof msg) != 0) fail_msg("%s", msg);
    free(rgba);
    return png;
}

/* Writes the file (memory variant), saves it as a sample when asked, and returns its bytes. */
static unsigned char *write_glb(const tree *t, const xyl_foliage_glb_desc *d, const char *sample,
                                size_t *n)
{
    xyl_diag diag = {0};
    xyl_result r = xyl_foliage_write_glb_memory(t->foliage, d, NULL, 0, n, &diag);
    if (r != XYL_OK) fail_msg("%s: %s", xyl_result_string(r), diag.message);
    unsigned char *b = malloc(*n);
    assert_non_null(b);
    assert_int_equal(xyl_foliage_write_glb_memory(t->foliage, d, b, *n, NULL, &diag), XYL_OK);
    const char *dir = getenv("XYL_GLB_SAMPLES");
    if (dir && *dir) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, sample);
        char msg[512];
        if (xyl_write_file_atomic(path, b, *n, msg, sizeof msg) != 0) fail_msg("%s", msg);
    }
    return b;
}

static xyl_sample_glb_leaves read_back(const unsigned char *b, size_t n)
{
    xyl_sample_glb_leaves l;
    xyl_diag diag = {0};
    xyl_result r = xyl_sample_read_glb_leaves(b, n, &l, &diag);
    if (r != XYL_OK) fail_msg("read back: %s (%s)", xyl_result_string(r), diag.message);
    return l;
}

/* Leaf count, every corner, normal and texture coordinate, the triangles, and the extras' table
 * against the foliage. */
static void assert_leaves_match(const xyl_sample_glb_leaves *l, const xyl_foliage *f)
{
    assert_int_equal(l->leaf_count, f->leaf_count);
    assert_int_equal(l->extras_leaf_count, f->leaf_count);
    assert_int_equal(l->extras_original_count, f->original_count);
    for (size_t i = 0; i < f->leaf_count; ++i) {
        const xyl_leaf *leaf = &f->leaves[i];
        xyl__dvec3 c[4];
        xyl__leaf_corners(leaf, c);
        for (int k = 0; k < 4; ++k) {
            xyl_vec3 p = l->positions[4 * i + k], nrm = l->normals[4 * i + k];
            if (p.x != (float)c[k].x || p.y != (float)c[k].y || p.z != (float)c[k].z)
                fail_msg("leaf %zu corner %d: (%g, %g, %g), want (%g, %g, %g)", i, k, p.x, p.y,
                         p.z, c[k].x, c[k].y, c[k].z);
            assert_true(nrm.x == leaf->normal.x && nrm.y == leaf->normal.y &&
                        nrm.z == leaf->normal.z);
            assert_true(l->uvs[8 * i + 2 * k] == (k & 1 ? leaf->uv[2] : leaf->uv[0]));
            assert_true(l->uvs[8 * i + 2 * k + 1] == 1.0f - (k & 2 ? leaf->uv[3] : leaf->uv[1]));
        }
        static const uint32_t tri[6] = {0, 1, 3, 0, 3, 2};
        for (int k = 0; k < 6; ++k) assert_int_equal(l->indices[6 * i + k], 4 * i + tri[k]);
    }
    assert_int_equal(l->sector_count, f->sector_count);
    for (uint32_t s = 0; s < f->sector_count; ++s) {
        const xyl_foliage_sector *want = &f->sectors[s];
        const xyl_sample_leaf_sector *got = &l->sectors[s];
        assert_int_equal(got->base, want->base);
        assert_int_equal(got->original_count, want->original_count);
        assert_int_equal(got->merged_count, want->merged_count);
        assert_int_equal(got->lod_count, want->merged_count + 1);
        for (size_t i = 0; i < got->lod_count; ++i) {
            assert_int_equal(got->lods[i].a, want->lods[i].a);
            assert_int_equal(got->lods[i].b, want->lods[i].b);
            assert_int_equal(got->lods[i].c, want->lods[i].c);
            /* the shortest text that reads back as the same float */
            if (got->lods[i].error != want->lods[i].error)
                fail_msg("sector %u LOD %zu: error %.9g, want %.9g", s, i,
                         (double)got->lods[i].error, (double)want->lods[i].error);
        }
    }
}

static void leaves_alone_read_back_as_written(void **state)
{
    (void)state;
    tree t = grow_tree("faycal-leaves", 3);
    size_t n = 0;
    unsigned char *b = write_glb(&t, NULL, "leaves-faycal-untextured.glb", &n);
    xyl_sample_glb_leaves l = read_back(b, n);
    assert_true(l.leaf_count > 255); /* originals and merged leaves */
    assert_leaves_match(&l, t.foliage);
    assert_true(l.masked && l.double_sided);
    assert_true(l.alpha_cutoff == 0.5);
    assert_int_equal(l.texture_bytes, 0);
    assert_int_equal(l.stem_vertex_count, 0);
    xyl_sample_glb_leaves_free(&l);
    free(b);
    tree_free(&t);
}

static void stems_and_textured_leaves_read_back_as_written(void **state)
{
    (void)state;
    tree t = grow_tree(xyl_lsystem_default_preset(), 4);
    size_t png_size = 0, n = 0;
    unsigned char *png = leaf_png(&png_size);
    xyl_foliage_glb_desc d = {0};
    d.stems = t.stems;
    d.texture_png = png;
    d.texture_png_size = png_size;
    d.alpha_cutoff = 0.4f;
    unsigned char *b = write_glb(&t, &d, "tree-default-textured.glb", &n);
    xyl_sample_glb_leaves l = read_back(b, n);
    assert_leaves_match(&l, t.foliage);
    assert_int_equal(l.texture_bytes, png_size);
    assert_true(fabs(l.alpha_cutoff - 0.4) < 1e-7);
    /* the stems: what the stem writer's file holds; the stem reader leaves the leaves out */
    size_t ns = 0;
    assert_int_equal(xyl_mesh_write_memory(t.stems, XYL_MESH_FORMAT_GLB, NULL, NULL, 0, &ns), XYL_OK);
    unsigned char *bs = malloc(ns);
    assert_non_null(bs);
    assert_int_equal(xyl_mesh_write_memory(t.stems, XYL_MESH_FORMAT_GLB, NULL, bs, ns, NULL), XYL_OK);
    xyl_mesh *alone = NULL, *both = NULL;
    assert_int_equal(xyl_sample_read_glb(bs, ns, &alone, NULL), XYL_OK);
    assert_int_equal(xyl_sample_read_glb(b, n, &both, NULL), XYL_OK);
    assert_int_equal(l.stem_vertex_count, alone->vertex_count);
    assert_int_equal(both->vertex_count, alone->vertex_count);
    assert_int_equal(both->quad_count, alone->quad_count);
    assert_int_equal(both->triangle_count, alone->triangle_count);
    assert_memory_equal(both->positions, alone->positions, alone->vertex_count * sizeof(xyl_vec3));
    xyl_mesh_destroy(both);
    xyl_mesh_destroy(alone);
    free(bs);
    xyl_sample_glb_leaves_free(&l);
    /* and once more without the texture, for the validator */
    d.texture_png = NULL;
    d.texture_png_size = 0;
    free(b);
    b = write_glb(&t, &d, "tree-default-untextured.glb", &n);
    l = read_back(b, n);
    assert_int_equal(l.texture_bytes, 0);
    assert_leaves_match(&l, t.foliage);
    xyl_sample_glb_leaves_free(&l);
    free(b);
    free(png);
    tree_free(&t);
}

static void a_tree_without_leaves_reads_back_with_its_empty_tables(void **state)
{
    (void)state;
    tree t = grow_tree("abop-1.24a", 2);
    assert_int_equal(t.foliage->leaf_count, 0);
    xyl_foliage_glb_desc d = {0};
    d.stems = t.stems;
    size_t n = 0;
    unsigned char *b = write_glb(&t, &d, "tree-abop-1.24a-no-leaves.glb", &n);
    xyl_sample_glb_leaves l = read_back(b, n);
    assert_int_equal(l.leaf_count, 0);
    assert_null(l.positions);
    assert_int_equal(l.sector_count, 2);
    for (uint32_t s = 0; s < 2; ++s) {
        assert_int_equal(l.sectors[s].lod_count, 1);
        assert_int_equal(l.sectors[s].lods[0].a + l.sectors[s].lods[0].c, 0);
    }
    assert_int_equal(l.stem_vertex_count > 0, 1);
    xyl_sample_glb_leaves_free(&l);
    free(b);
    tree_free(&t);
}

static void the_leaf_reader_refuses_a_file_without_leaves_node(void **state)
{
    (void)state;
    tree t = grow_tree("abop-1.24a", 1);
    size_t ns = 0;
    assert_int_equal(xyl_mesh_write_memory(t.stems, XYL_MESH_FORMAT_GLB, NULL, NULL, 0, &ns), XYL_OK);
    unsigned char *bs = malloc(ns);
    assert_non_null(bs);
    assert_int_equal(xyl_mesh_write_memory(t.stems, XYL_MESH_FORMAT_GLB, NULL, bs, ns, NULL), XYL_OK);
    xyl_sample_glb_leaves l;
    xyl_diag diag = {0};
    assert_int_equal(xyl_sample_read_glb_leaves(bs, ns, &l, &diag), XYL_ERR_PARSE);
    assert_non_null(strstr(diag.message, "leaves"));
    assert_int_equal(l.leaf_count, 0);
    free(bs);
    tree_free(&t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(leaves_alone_read_back_as_written),
        cmocka_unit_test(stems_and_textured_leaves_read_back_as_written),
        cmocka_unit_test(a_tree_without_leaves_reads_back_with_its_empty_tables),
        cmocka_unit_test(the_leaf_reader_refuses_a_file_without_leaves_node),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

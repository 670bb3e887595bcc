/* World coordinates: skeletons, meshes and their files far from (0, 0, 0) behave like the same
 * tree at it, up to the translation their origin holds; float precision that would still be
 * lost is reported; texture coordinates stay finite and a failing stage names itself. */
#include "test_util.h"

#include <float.h>

#include <xylem/xyl_foliage.h>
#include <xylem/xyl_mesh.h>
#include <xylem/xyl_skeleton.h>

#include "float_text.h"

/* The places a tree is planted at: the origin, 1e5 and 1e7 units away (all three axes moved,
 * by values that are no float's). */
static const double PLACES[][3] = {
    {0.0, 0.0, 0.0},
    {100000.0123, -54321.0987, 76543.21},
    {10000000.5, 3000000.25, -9999999.75},
};
#define PLACE_COUNT (sizeof PLACES / sizeof PLACES[0])

/* A stochastic ternary tree: its shape comes from the seed. */
static const char *RANDOM_TREE = "#angle 30\n#depth 5\n#seed 20261203\n#width 0.3\n"
                                 "axiom: F(2) A\n"
                                 "A -> (1) F(1) [ + & A ] [ - ^ A ] \\ A\n"
                                 "A -> (1) F(0.8) [ + A ] / [ & A ]\n"
                                 "A -> (1) F(1.2) [ ^ ^ A ] [ - A ]\n";

static uint32_t fbits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static bool same_origin(const double a[3], const double b[3])
{
    return memcmp(a, b, 3 * sizeof *a) == 0;
}

static xyl_skeleton *grow_at(const char *grammar, const double origin[3])
{
    xyl_turtle_desc td = {0};
    memcpy(td.origin, origin, sizeof td.origin);
    return tu_grow(grammar, &td);
}

static char *skel_text(const xyl_skeleton *sk, xyl_skel_format format, size_t *len)
{
    assert_int_equal(xyl_skeleton_write_text(sk, format, NULL, 0, len), XYL_OK);
    char *text = malloc(*len + 1);
    assert_non_null(text);
    assert_int_equal(xyl_skeleton_write_text(sk, format, text, *len + 1, len), XYL_OK);
    return text;
}

static xyl_skeleton *read_skel(const char *text, size_t len, xyl_diag *diag)
{
    xyl_skeleton *sk = NULL;
    xyl_diag local = {0};
    xyl_diag *d = diag ? diag : &local;
    xyl_result r = xyl_skeleton_read_text(text, len, NULL, &sk, d);
    if (r != XYL_OK) fail_msg("read: %s at %u:%u", d->message, d->line, d->column);
    return sk;
}

static xyl_mesh *mesh_of(const xyl_skeleton *sk, xyl_diag *diag)
{
    xyl_mesh *m = NULL;
    xyl_diag local = {0};
    xyl_diag *d = diag ? diag : &local;
    xyl_result r = xyl_stems_build(sk, NULL, &m, NULL, d);
    if (r != XYL_OK) fail_msg("stems: %s", d->message);
    return m;
}

static void *mesh_bytes(const xyl_mesh *m, xyl_mesh_format format, size_t *len)
{
    assert_int_equal(xyl_mesh_write_memory(m, format, NULL, NULL, 0, len), XYL_OK);
    char *buf = malloc(*len + 1);
    assert_non_null(buf);
    assert_int_equal(xyl_mesh_write_memory(m, format, NULL, buf, *len + 1, len), XYL_OK);
    return buf;
}

/* ---- the double text the writers print world positions with ------------------------------- */

static void double_text_reads_back_as_the_same_double(void **state)
{
    (void)state;
    uint64_t seed = UINT64_C(0x2545F4914F6CDD1D);
    const double specials[] = {0.0, -0.0, 1.0, 0.1, 1e-5, 123456.789, 1e16, 1e17, 1e-300,
                               4.9e-324, DBL_MAX, -DBL_MIN, 100000.0123, 10000000.5};
    for (size_t i = 0; i < 200000 + sizeof specials / sizeof specials[0]; ++i) {
        double v;
        if (i < sizeof specials / sizeof specials[0]) {
            v = specials[i];
        } else {
            seed ^= seed << 13, seed ^= seed >> 7, seed ^= seed << 17;
            memcpy(&v, &seed, sizeof v);
            if (!isfinite(v)) continue;
        }
        char out[XYL__DOUBLE_TEXT_MAX + 1];
        size_t n = xyl__double_text(v, out);
        assert_true(n < XYL__DOUBLE_TEXT_MAX);
        out[n] = '\0';
        double back = strtod(out, NULL);
        if (memcmp(&back, &v, sizeof v) != 0) fail_msg("%.17g printed as %s", v, out);
        /* one digit fewer would not do: %.*g with fewer digits reads back differently or is
         * no shorter */
        size_t digits = 0;
        for (size_t k = 0; k < n && out[k] != 'e'; ++k) digits += out[k] >= '0' && out[k] <= '9';
        assert_true(digits <= 17 + 5); /* 17 significant digits and up to 5 leading zeros */
    }
    char out[XYL__DOUBLE_TEXT_MAX];
    assert_int_equal(xyl__double_text(100000.0123, out), 11);
    assert_memory_equal(out, "100000.0123", 11);
}

/* ---- skeletons ----------------------------------------------------------------------------- */

/* The turtle plants the same nodes at any origin: the place is only the origin. */
static void turtle_origin_moves_the_tree_not_its_nodes(void **state)
{
    (void)state;
    const char *trees[] = {xyl_lsystem_preset_source(xyl_lsystem_default_preset()), RANDOM_TREE};
    for (size_t t = 0; t < 2; ++t) {
        xyl_skeleton *at0 = grow_at(trees[t], PLACES[0]);
        for (size_t p = 1; p < PLACE_COUNT; ++p) {
            xyl_skeleton *far = grow_at(trees[t], PLACES[p]);
            assert_true(same_origin(far->origin, PLACES[p]));
            assert_int_equal(far->node_count, at0->node_count);
            assert_memory_equal(far->nodes, at0->nodes, at0->node_count * sizeof *at0->nodes);
            if (at0->leaf_count)
                assert_memory_equal(far->leaves, at0->leaves, at0->leaf_count * sizeof *at0->leaves);
            xyl_skeleton_destroy(far);
        }
        xyl_skeleton_destroy(at0);
    }
    xyl_turtle_desc td = {0};
    td.origin[1] = NAN;
    xyl_grammar *g = tu_parse(RANDOM_TREE);
    xyl_lstring *s = NULL;
    assert_int_equal(xyl_lsystem_derive(g, NULL, &s, NULL), XYL_OK);
    xyl_skeleton *sk = NULL;
    xyl_diag d = {0};
    assert_int_equal(xyl_lsystem_interpret(g, s, &td, &sk, &d), XYL_ERR_NON_FINITE);
    assert_null(sk);
    assert_non_null(strstr(d.message, "origin"));
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
}

/* A grammar that walks 1e5 units before it grows a twig warns; planting it there does not. */
static void turtle_warns_when_a_grammar_walks_far(void **state)
{
    (void)state;
    xyl_grammar *g = tu_parse("#width 0.02\naxiom: f(100000) F(1) F(1)\n");
    xyl_lstring *s = NULL;
    assert_int_equal(xyl_lsystem_derive(g, NULL, &s, NULL), XYL_OK);
    xyl_skeleton *sk = NULL;
    xyl_diag d = {0};
    assert_int_equal(xyl_lsystem_interpret(g, s, NULL, &sk, &d), XYL_OK);
    assert_int_equal(d.warning_count, 1);
    assert_non_null(strstr(d.warning, "float precision"));
    xyl_skeleton_destroy(sk);
    xyl_grammar_destroy(g);
    xyl_lstring_destroy(s);
    g = tu_parse("#width 0.02\naxiom: F(1) F(1)\n");
    assert_int_equal(xyl_lsystem_derive(g, NULL, &s, NULL), XYL_OK);
    xyl_turtle_desc td = {0};
    td.origin[1] = 100000.0;
    memset(&d, 0, sizeof d);
    assert_int_equal(xyl_lsystem_interpret(g, s, &td, &sk, &d), XYL_OK);
    assert_int_equal(d.warning_count, 0);
    xyl_skeleton_destroy(sk);
    xyl_grammar_destroy(g);
    xyl_lstring_destroy(s);
}

/* A .skel written at 1e5 or 1e7 holds world positions; read back, the first root is the origin
 * again, every node has the bits of the tree at the origin, and writing it again gives the same
 * text. The tree at the origin writes and reads as it always did. */
static void far_skel_files_read_like_the_tree_at_the_origin(void **state)
{
    (void)state;
    const char *trees[] = {xyl_lsystem_preset_source(xyl_lsystem_default_preset()), RANDOM_TREE};
    for (size_t t = 0; t < 2; ++t) {
        xyl_skeleton *at0 = grow_at(trees[t], PLACES[0]);
        for (size_t p = 0; p < PLACE_COUNT; ++p) {
            xyl_skeleton *planted = grow_at(trees[t], PLACES[p]);
            size_t len = 0, len2 = 0;
            char *text = skel_text(planted, XYL_SKEL_FORMAT_SKEL, &len);
            xyl_diag d = {0};
            xyl_skeleton *back = read_skel(text, len, &d);
            assert_int_equal(d.warning_count, 0);
            assert_true(same_origin(back->origin, PLACES[p]));
            assert_int_equal(back->node_count, at0->node_count);
            assert_int_equal(back->leaf_count, at0->leaf_count);
            for (size_t i = 0; i < at0->node_count; ++i) {
                const xyl_skel_node *a = &at0->nodes[i], *b = &back->nodes[i];
                if (fbits(a->pos.x) != fbits(b->pos.x) || fbits(a->pos.y) != fbits(b->pos.y) ||
                    fbits(a->pos.z) != fbits(b->pos.z) || fbits(a->radius) != fbits(b->radius))
                    fail_msg("tree %zu at place %zu: node %zu reads back as (%.9g %.9g %.9g), "
                             "not (%.9g %.9g %.9g)", t, p, i, (double)b->pos.x,
                             (double)b->pos.y, (double)b->pos.z, (double)a->pos.x,
                             (double)a->pos.y, (double)a->pos.z);
            }
            for (size_t i = 0; i < at0->leaf_count; ++i)
                assert_memory_equal(&back->leaves[i], &at0->leaves[i], sizeof *at0->leaves);
            char *again = skel_text(back, XYL_SKEL_FORMAT_SKEL, &len2);
            assert_int_equal(len2, len);
            assert_memory_equal(again, text, len);
            free(again);
            free(text);
            xyl_skeleton_destroy(back);
            xyl_skeleton_destroy(planted);
        }
        xyl_skeleton_destroy(at0);
    }
}

/* World positions in a far file are kept in double: a twig of 1e-3 at 1e5 units keeps its
 * shape, where a float would round it to 0.0078. */
static void skel_reader_takes_a_far_first_root_as_origin(void **state)
{
    (void)state;
    const char *text = "xylem-skeleton 1\nnodes 3\nleaves 1\n"
                       "n 0 -1 100000.0123 5 -7 0.01\n"
                       "n 1 0 100000.0123 6 -7 0.001\n"
                       "n 2 1 100000.0133 6.001 -7 0.001\n"
                       "l 2 100000.0138 6.001 -7 0 1 0 1 0 0 0 0 -1 0.002\n"
                       "end\n";
    xyl_diag d = {0};
    xyl_skeleton *sk = read_skel(text, strlen(text), &d);
    assert_int_equal(d.warning_count, 0);
    assert_true(sk->origin[0] == 100000.0123 && sk->origin[1] == 5.0 && sk->origin[2] == -7.0);
    assert_true(sk->nodes[0].pos.x == 0.0f && sk->nodes[0].pos.y == 0.0f);
    assert_true(sk->nodes[1].pos.x == 0.0f && sk->nodes[1].pos.y == 1.0f);
    assert_true(sk->nodes[2].pos.x == (float)(100000.0133 - 100000.0123));
    assert_true(sk->leaves[0].pos.x == (float)(100000.0138 - 100000.0123));
    assert_true(fabsf(sk->nodes[2].pos.x - 0.001f) < 1e-9f);
    /* the world text comes back */
    size_t len = 0;
    char *out = skel_text(sk, XYL_SKEL_FORMAT_SKEL, &len);
    assert_non_null(strstr(out, "n 0 -1 100000.0123 5 -7 0.01\n"));
    char *obj = skel_text(sk, XYL_SKEL_FORMAT_OBJ, &len);
    assert_non_null(strstr(obj, "v 100000.0123 5 -7\n"));
    free(obj);
    free(out);
    xyl_skeleton_destroy(sk);
}

/* A forest around the world's origin keeps origin 0 (the first root's would coarsen the others),
 * and the twig far from it is reported with its figures. */
static void skel_reader_keeps_origin_zero_and_warns_where_floats_lose_detail(void **state)
{
    (void)state;
    const char *text = "xylem-skeleton 1\nnodes 4\nleaves 0\n"
                       "n 0 -1 0 0 0 0.5\nn 1 0 0 1 0 0.4\n"
                       "n 2 -1 100000 0 0 0.01\nn 3 2 100000 1 0 0.01\nend\n";
    xyl_diag d = {0};
    xyl_skeleton *sk = read_skel(text, strlen(text), &d);
    assert_true(sk->origin[0] == 0.0 && sk->origin[1] == 0.0 && sk->origin[2] == 0.0);
    assert_true(sk->nodes[2].pos.x == 100000.0f);
    assert_int_equal(d.warning_count, 1);
    assert_non_null(strstr(d.warning, "float precision"));
    assert_non_null(strstr(d.warning, "node 2"));
    assert_non_null(strstr(d.warning, "spaced 0.0078125"));
    /* the mesh of it says so too */
    xyl_diag md = {0};
    xyl_mesh *m = mesh_of(sk, &md);
    assert_int_equal(md.warning_count, 1);
    assert_non_null(strstr(md.warning, "the stem mesh loses detail"));
    xyl_mesh_destroy(m);
    xyl_skeleton_destroy(sk);
}

/* A caller's floats at 1e5 warn on create; the same tree given its origin does not. */
static void create_warns_of_far_float_positions_and_takes_an_origin(void **state)
{
    (void)state;
    xyl_skel_node far[2], local[2];
    memset(far, 0, sizeof far);
    memset(local, 0, sizeof local);
    far[0] = (xyl_skel_node){{100000.0f, 0, 0}, 0.01f, -1, 0, 0};
    far[1] = (xyl_skel_node){{100000.0f, 1, 0}, 0.01f, 0, 0, 0};
    local[0] = (xyl_skel_node){{0, 0, 0}, 0.01f, -1, 0, 0};
    local[1] = (xyl_skel_node){{0, 1, 0}, 0.01f, 0, 0, 0};
    xyl_skeleton_desc sd = {0};
    sd.nodes = far;
    sd.node_count = 2;
    xyl_skeleton *sk = NULL;
    xyl_diag d = {0};
    assert_int_equal(xyl_skeleton_create(&sd, &sk, &d), XYL_OK);
    assert_int_equal(d.warning_count, 1);
    assert_non_null(strstr(d.warning, "78.1 %")); /* 0.0078125 of 0.01 */
    xyl_skeleton_destroy(sk);
    sd.nodes = local;
    sd.origin[0] = 100000.0;
    memset(&d, 0, sizeof d);
    assert_int_equal(xyl_skeleton_create(&sd, &sk, &d), XYL_OK);
    assert_int_equal(d.warning_count, 0);
    assert_true(sk->origin[0] == 100000.0);
    xyl_skeleton_destroy(sk);
    sd.origin[2] = INFINITY;
    sk = NULL;
    assert_int_equal(xyl_skeleton_create(&sd, &sk, &d), XYL_ERR_NON_FINITE);
    assert_null(sk);
}

/* ---- meshes and their files ---------------------------------------------------------------- */

/* The stems of a far tree read from its file have the bits of the tree at the origin, and carry
 * the origin; subdivision and the seam split keep it. */
static void far_meshes_equal_the_mesh_at_the_origin(void **state)
{
    (void)state;
    const char *trees[] = {xyl_lsystem_preset_source(xyl_lsystem_default_preset()), RANDOM_TREE};
    for (size_t t = 0; t < 2; ++t) {
        xyl_skeleton *at0 = grow_at(trees[t], PLACES[0]);
        xyl_mesh *m0 = mesh_of(at0, NULL);
        for (size_t p = 1; p < PLACE_COUNT; ++p) {
            xyl_skeleton *planted = grow_at(trees[t], PLACES[p]);
            size_t len = 0;
            char *text = skel_text(planted, XYL_SKEL_FORMAT_SKEL, &len);
            xyl_skeleton *back = read_skel(text, len, NULL);
            xyl_diag d = {0};
            xyl_mesh *m = mesh_of(back, &d);
            assert_int_equal(d.warning_count, 0);
            assert_true(same_origin(m->origin, PLACES[p]));
            assert_int_equal(m->vertex_count, m0->vertex_count);
            assert_int_equal(m->quad_count, m0->quad_count);
            assert_memory_equal(m->positions, m0->positions, m0->vertex_count * sizeof *m0->positions);
            assert_memory_equal(m->normals, m0->normals, m0->vertex_count * sizeof *m0->normals);
            assert_memory_equal(m->uvs, m0->uvs, 2 * m0->vertex_count * sizeof *m0->uvs);
            assert_memory_equal(m->quads, m0->quads, 4 * m0->quad_count * sizeof *m0->quads);
            xyl_mesh *split = NULL;
            assert_int_equal(xyl_mesh_split_seams(m, NULL, &split, NULL), XYL_OK);
            assert_true(same_origin(split->origin, PLACES[p]));
            xyl_mesh_destroy(split);
#ifdef XYL_HAVE_OPENSUBDIV
            xyl_subdivide_desc sub = {0};
            sub.scheme = XYL_SUBDIVIDE_CATMARK;
            xyl_mesh *fine = NULL;
            assert_int_equal(xyl_mesh_subdivide(m, &sub, &fine, NULL), XYL_OK);
            assert_true(same_origin(fine->origin, PLACES[p]));
            xyl_mesh_destroy(fine);
            xyl_stems_desc sdesc = {0};
            sdesc.subdivision = XYL_SUBDIVIDE_LOOP;
            assert_int_equal(xyl_stems_build(back, &sdesc, &fine, NULL, NULL), XYL_OK);
            assert_true(same_origin(fine->origin, PLACES[p]));
            xyl_mesh_destroy(fine);
#endif
            xyl_mesh_destroy(m);
            xyl_skeleton_destroy(back);
            xyl_skeleton_destroy(planted);
            free(text);
        }
        xyl_mesh_destroy(m0);
        xyl_skeleton_destroy(at0);
    }
}

/* OBJ "v" lines are origin + position, summed in double and printed so that they read back as
 * that double; at origin 0 they are the floats as before. */
static void obj_writes_world_positions_that_read_back_exactly(void **state)
{
    (void)state;
    for (size_t p = 0; p < PLACE_COUNT; ++p) {
        xyl_skeleton *sk = grow_at(RANDOM_TREE, PLACES[p]);
        xyl_mesh *m = mesh_of(sk, NULL);
        size_t len = 0;
        char *text = mesh_bytes(m, XYL_MESH_FORMAT_OBJ, &len);
        text[len] = '\0';
        size_t v = 0;
        for (const char *line = text; line && *line; line = strchr(line, '\n'), line += line != NULL) {
            if (strncmp(line, "v ", 2) != 0) continue;
            char *end = NULL;
            double x = strtod(line + 2, &end), y = strtod(end, &end), z = strtod(end, &end);
            assert_true(v < m->vertex_count);
            const xyl_vec3 q = m->positions[v];
            const double want[3] = {PLACES[p][0] + (double)q.x, PLACES[p][1] + (double)q.y,
                                    PLACES[p][2] + (double)q.z};
            if (p == 0) {
                /* the floats themselves, as before origins existed */
                assert_true((float)x == q.x && (float)y == q.y && (float)z == q.z);
            } else if (x != want[0] || y != want[1] || z != want[2]) {
                fail_msg("place %zu: vertex %zu written as (%.17g %.17g %.17g), not "
                         "(%.17g %.17g %.17g)", p, v, x, y, z, want[0], want[1], want[2]);
            }
            ++v;
        }
        assert_int_equal(v, m->vertex_count);
        free(text);
        xyl_mesh_destroy(m);
        xyl_skeleton_destroy(sk);
    }
}

/* The glTF node's translation is the origin, as the shortest doubles; the mesh's POSITION bytes
 * are the same at every place. No translation at origin 0. */
static void glb_node_translation_is_the_origin(void **state)
{
    (void)state;
    xyl_skeleton *sk0 = grow_at(RANDOM_TREE, PLACES[0]);
    xyl_mesh *m0 = mesh_of(sk0, NULL);
    size_t len0 = 0;
    char *glb0 = mesh_bytes(m0, XYL_MESH_FORMAT_GLB, &len0);
    uint32_t json0 = 0;
    memcpy(&json0, glb0 + 12, 4);
    char *doc0 = calloc(1, json0 + 1);
    assert_non_null(doc0);
    memcpy(doc0, glb0 + 20, json0);
    assert_null(strstr(doc0, "translation"));
    free(doc0);
    for (size_t p = 1; p < PLACE_COUNT; ++p) {
        xyl_skeleton *sk = grow_at(RANDOM_TREE, PLACES[p]);
        xyl_mesh *m = mesh_of(sk, NULL);
        size_t len = 0;
        char *glb = mesh_bytes(m, XYL_MESH_FORMAT_GLB, &len);
        uint32_t json = 0;
        memcpy(&json, glb + 12, 4);
        char *doc = calloc(1, json + 1);
        assert_non_null(doc);
        memcpy(doc, glb + 20, json);
        const char *t = strstr(doc, "\"translation\":[");
        assert_non_null(t);
        char *end = NULL;
        double x = strtod(t + 15, &end);
        double y = strtod(end + 1, &end);
        double z = strtod(end + 1, &end);
        assert_true(x == PLACES[p][0] && y == PLACES[p][1] && z == PLACES[p][2]);
        /* the binary chunk (positions and all) is the mesh at the origin's */
        assert_int_equal(len - 20 - json, len0 - 20 - json0);
        assert_memory_equal(glb + 20 + json, glb0 + 20 + json0, len - 20 - json);
        free(doc);
        free(glb);
        xyl_mesh_destroy(m);
        xyl_skeleton_destroy(sk);
    }
    free(glb0);
    xyl_mesh_destroy(m0);
    xyl_skeleton_destroy(sk0);
}

/* The foliage GLB puts the leaves where the stems are: both nodes carry the origin. */
static void foliage_glb_places_leaves_and_stems_at_the_origin(void **state)
{
    (void)state;
    xyl_skeleton *sk = grow_at(xyl_lsystem_preset_source("abop-2.8-ternary"), PLACES[1]);
    assert_true(sk->leaf_count > 0);
    xyl_mesh *m = mesh_of(sk, NULL);
    xyl_foliage_leaves_desc ld = {0};
    size_t n = 0;
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, &ld, NULL, 0, &n, NULL), XYL_OK);
    xyl_leaf *leaves = malloc(n * sizeof *leaves);
    assert_non_null(leaves);
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, &ld, leaves, n, &n, NULL), XYL_OK);
    xyl_foliage_desc fd = {0};
    fd.leaves = leaves;
    fd.leaf_count = n;
    xyl_foliage *f = NULL;
    assert_int_equal(xyl_foliage_build(&fd, &f, NULL), XYL_OK);
    xyl_foliage_glb_desc gd = {0};
    gd.stems = m;
    memcpy(gd.origin, sk->origin, sizeof gd.origin);
    size_t size = 0;
    assert_int_equal(xyl_foliage_write_glb_memory(f, &gd, NULL, 0, &size, NULL), XYL_OK);
    char *glb = malloc(size);
    assert_non_null(glb);
    assert_int_equal(xyl_foliage_write_glb_memory(f, &gd, glb, size, &size, NULL), XYL_OK);
    uint32_t json = 0;
    memcpy(&json, glb + 12, 4);
    char *doc = calloc(1, json + 1);
    assert_non_null(doc);
    memcpy(doc, glb + 20, json);
    const char *want = "\"translation\":[100000.0123,-54321.0987,76543.21]";
    const char *stems = strstr(doc, "{\"name\":\"stems\"");
    const char *leaf_node = strstr(doc, "{\"name\":\"leaves\"");
    assert_non_null(stems);
    assert_non_null(leaf_node);
    assert_true(strstr(stems, want) && strstr(stems, want) < leaf_node);
    assert_non_null(strstr(leaf_node, want));
    gd.origin[0] = NAN;
    xyl_diag d = {0};
    assert_int_equal(xyl_foliage_write_glb_memory(f, &gd, NULL, 0, &size, &d), XYL_ERR_NON_FINITE);
    free(doc);
    free(glb);
    xyl_foliage_destroy(f);
    free(leaves);
    xyl_mesh_destroy(m);
    xyl_skeleton_destroy(sk);
}

static void mesh_create_takes_a_finite_origin(void **state)
{
    (void)state;
    const xyl_vec3 pos[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const uint32_t tri[3] = {0, 1, 2};
    xyl_mesh_desc md = {0};
    md.positions = pos;
    md.vertex_count = 3;
    md.triangles = tri;
    md.triangle_count = 1;
    md.origin[0] = -2.5e6;
    xyl_mesh *m = NULL;
    assert_int_equal(xyl_mesh_create(&md, &m, NULL), XYL_OK);
    assert_true(m->origin[0] == -2.5e6 && m->origin[1] == 0.0);
    xyl_mesh_destroy(m);
    md.origin[1] = NAN;
    m = NULL;
    xyl_diag d = {0};
    assert_int_equal(xyl_mesh_create(&md, &m, &d), XYL_ERR_NON_FINITE);
    assert_null(m);
    assert_non_null(strstr(d.message, "origin"));
}

/* ---- finite numbers, and the stage that fails ---------------------------------------------- */

static xyl_skeleton *two_nodes(float length, float radius)
{
    xyl_skel_node n[2];
    memset(n, 0, sizeof n);
    n[0] = (xyl_skel_node){{0, 0, 0}, radius, -1, 0, 0};
    n[1] = (xyl_skel_node){{0, length, 0}, radius, 0, 0, 0};
    xyl_skeleton_desc sd = {0};
    sd.nodes = n;
    sd.node_count = 2;
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_skeleton_create(&sd, &sk, NULL), XYL_OK);
    return sk;
}

/* Segment length / radius of 1e39 and more (a radius of 1e-40, a length of 3e38) still give
 * finite texture coordinates, and the mesh writes. */
static void absurd_length_to_radius_ratios_give_finite_uvs(void **state)
{
    (void)state;
    const float cases[][2] = {{1.0f, 1e-40f}, {3e38f, 1.0f}, {1e30f, 1e-30f}};
    for (size_t c = 0; c < 3; ++c) {
        xyl_skeleton *sk = two_nodes(cases[c][0], cases[c][1]);
        xyl_mesh *m = mesh_of(sk, NULL);
        for (size_t v = 0; v < m->vertex_count; ++v)
            assert_true(isfinite(m->uvs[2 * v]) && isfinite(m->uvs[2 * v + 1]));
        size_t len = 0;
        free(mesh_bytes(m, XYL_MESH_FORMAT_OBJ, &len));
        free(mesh_bytes(m, XYL_MESH_FORMAT_GLB, &len));
        xyl_mesh_destroy(m);
        xyl_skeleton_destroy(sk);
    }
}

/* A valid skeleton whose rings would leave the float range fails in the mesher, which says so,
 * not in a later stage or in the writer. */
static void a_mesh_beyond_the_float_range_fails_in_the_mesher(void **state)
{
    (void)state;
    xyl_skeleton *sk = two_nodes(3e38f, 3e38f);
    xyl_stems_desc sd = {0};
    sd.subdivision = XYL_SUBDIVIDE_CATMARK;
    xyl_mesh *m = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_stems_build(sk, &sd, &m, NULL, &d);
#ifdef XYL_HAVE_OPENSUBDIV
    assert_int_equal(r, XYL_ERR_NON_FINITE);
    assert_null(m);
    assert_non_null(strstr(d.message, "the stem mesher"));
    assert_non_null(strstr(d.message, "inflated for subdivision"));
#else
    (void)r;
#endif
    xyl_skeleton_destroy(sk);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(double_text_reads_back_as_the_same_double),
        cmocka_unit_test(turtle_origin_moves_the_tree_not_its_nodes),
        cmocka_unit_test(turtle_warns_when_a_grammar_walks_far),
        cmocka_unit_test(far_skel_files_read_like_the_tree_at_the_origin),
        cmocka_unit_test(skel_reader_takes_a_far_first_root_as_origin),
        cmocka_unit_test(skel_reader_keeps_origin_zero_and_warns_where_floats_lose_detail),
        cmocka_unit_test(create_warns_of_far_float_positions_and_takes_an_origin),
        cmocka_unit_test(far_meshes_equal_the_mesh_at_the_origin),
        cmocka_unit_test(obj_writes_world_positions_that_read_back_exactly),
        cmocka_unit_test(glb_node_translation_is_the_origin),
        cmocka_unit_test(foliage_glb_places_leaves_and_stems_at_the_origin),
        cmocka_unit_test(mesh_create_takes_a_finite_origin),
        cmocka_unit_test(absurd_length_to_radius_ratios_give_finite_uvs),
        cmocka_unit_test(a_mesh_beyond_the_float_range_fails_in_the_mesher),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

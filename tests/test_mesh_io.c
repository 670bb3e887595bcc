/* Mesh export: xyl_mesh_write_memory / xyl_mesh_write_file, OBJ and GLB.
 *
 * With XYL_GLB_SAMPLES=FOLDER in the environment this program writes its sample meshes as .glb
 * files into FOLDER instead of running the suite; the gltf_validator test then runs the Khronos
 * glTF-Validator over that folder (tests/CMakeLists.txt). */
#define _POSIX_C_SOURCE 200809L

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <locale.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "xylem/xyl_stems.h"
#include "float_text.h"

#define GLB_MAGIC 0x46546C67u
#define GLB_JSON 0x4E4F534Au
#define GLB_BIN 0x004E4942u

/* ---- sample meshes -------------------------------------------------------------------------- */

typedef struct mesh_spec {
    const xyl_vec3 *positions;
    const xyl_vec3 *normals;
    const float *uvs;
    const uint32_t *branch_ids;
    size_t vertex_count;
    const uint32_t *quads;
    size_t quad_count;
    const uint32_t *triangles;
    size_t triangle_count;
    const uint32_t *face_branches;
} mesh_spec;

static xyl_mesh *build(const mesh_spec *s)
{
    xyl_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.positions = s->positions;
    d.normals = s->normals;
    d.uvs = s->uvs;
    d.branch_ids = s->branch_ids;
    d.vertex_count = s->vertex_count;
    d.quads = s->quads;
    d.quad_count = s->quad_count;
    d.triangles = s->triangles;
    d.triangle_count = s->triangle_count;
    d.face_branches = s->face_branches;
    xyl_mesh *m = NULL;
    xyl_diag diag;
    memset(&diag, 0, sizeof diag);
    xyl_result r = xyl_mesh_create(&d, &m, &diag);
    if (r != XYL_OK) fail_msg("xyl_mesh_create: %s: %s", xyl_result_string(r), diag.message);
    return m;
}

static const xyl_vec3 CUBE_POS[8] = {
    {-0.5f, -0.5f, -0.5f}, {0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, -0.5f}, {-0.5f, 0.5f, -0.5f},
    {-0.5f, -0.5f, 0.5f},  {0.5f, -0.5f, 0.5f},  {0.5f, 0.5f, 0.5f},  {-0.5f, 0.5f, 0.5f},
};
/* Counter-clockwise seen from outside. */
static const uint32_t CUBE_QUADS[24] = {
    0, 3, 2, 1, /* -z */ 4, 5, 6, 7, /* +z */ 0, 1, 5, 4, /* -y */
    3, 7, 6, 2, /* +y */ 0, 4, 7, 3, /* -x */ 1, 2, 6, 5, /* +x */
};

static xyl_mesh *cube(void)
{
    float uvs[16];
    for (int i = 0; i < 8; ++i) {
        uvs[2 * i] = (float)(i % 4) * 0.25f;
        uvs[2 * i + 1] = (float)(i / 4);
    }
    mesh_spec s = {CUBE_POS, NULL, uvs, NULL, 8, CUBE_QUADS, 6, NULL, 0, NULL};
    return build(&s);
}

static xyl_mesh *tetra(void)
{
    static const xyl_vec3 p[4] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
    static const uint32_t t[12] = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
    mesh_spec s = {p, NULL, NULL, NULL, 4, NULL, 0, t, 4, NULL};
    return build(&s);
}

/* A square pyramid: one quad (the base) and four triangles. */
static xyl_mesh *mixed(void)
{
    static const xyl_vec3 p[5] = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}, {0, 1.5f, 0}};
    static const uint32_t q[4] = {0, 1, 2, 3};
    static const uint32_t t[12] = {4, 1, 0, 4, 2, 1, 4, 3, 2, 4, 0, 3};
    static const uint32_t fb[5] = {3, 3, 3, 7, 7};
    mesh_spec s = {p, NULL, NULL, NULL, 5, q, 1, t, 4, fb};
    return build(&s);
}

/* Two cubes, the second one a branch (id 1) beside the first; a third block of faces goes back
 * to branch 0, so a group name repeats. */
static xyl_mesh *branches(void)
{
    xyl_vec3 p[16];
    uint32_t q[48], vb[16], fb[12];
    for (int i = 0; i < 8; ++i) {
        p[i] = CUBE_POS[i];
        p[8 + i] = CUBE_POS[i];
        p[8 + i].x += 2.0f;
        vb[i] = 0;
        vb[8 + i] = 1;
    }
    for (int i = 0; i < 24; ++i) {
        q[i] = CUBE_QUADS[i];
        q[24 + i] = CUBE_QUADS[i] + 8;
    }
    /* faces: 3 of cube 0, all 6 of cube 1, the other 3 of cube 0 */
    uint32_t order[48];
    memcpy(order, q, 12 * sizeof *q);
    memcpy(order + 12, q + 24, 24 * sizeof *q);
    memcpy(order + 36, q + 12, 12 * sizeof *q);
    for (int f = 0; f < 12; ++f) fb[f] = f >= 3 && f < 9 ? 1u : 0u;
    mesh_spec s = {p, NULL, NULL, vb, 16, order, 12, NULL, 0, fb};
    return build(&s);
}

static xyl_mesh *empty_mesh(void)
{
    mesh_spec s = {NULL, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, NULL};
    return build(&s);
}

/* A seeded xorshift generator: the tests must not depend on rand(). */
static uint64_t next_random(uint64_t *state)
{
    uint64_t x = *state;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    *state = x;
    return x;
}

static float random_float(uint64_t *state, float lo, float hi)
{
    double t = (double)(next_random(state) >> 11) / 9007199254740992.0;
    return (float)(lo + (hi - lo) * t);
}

/* n distinct random indices below vertex_count. */
static void random_face(uint64_t *state, uint32_t vertex_count, uint32_t *f, int n)
{
    for (int k = 0; k < n; ++k) {
        bool again;
        do {
            f[k] = (uint32_t)(next_random(state) % vertex_count);
            again = false;
            for (int j = 0; j < k; ++j) again |= f[j] == f[k];
        } while (again);
    }
}

/* Random soup of quads and triangles with random UVs and branch ids; some vertices unused. */
static xyl_mesh *random_mesh(uint64_t seed, uint32_t nv, uint32_t nq, uint32_t nt)
{
    uint64_t st = seed;
    xyl_vec3 *p = malloc(nv * sizeof *p);
    float *uv = malloc(2 * (size_t)nv * sizeof *uv);
    uint32_t *vb = malloc(nv * sizeof *vb), *q = malloc(4 * (size_t)nq * sizeof *q);
    uint32_t *t = malloc(3 * (size_t)nt * sizeof *t), *fb = malloc((nq + nt) * sizeof *fb);
    assert_true(p && uv && vb && q && t && fb);
    for (uint32_t v = 0; v < nv; ++v) {
        p[v].x = random_float(&st, -10.0f, 10.0f);
        p[v].y = random_float(&st, 0.0f, 30.0f);
        p[v].z = random_float(&st, -10.0f, 10.0f);
        uv[2 * v] = random_float(&st, 0.0f, 1.0f);
        uv[2 * v + 1] = random_float(&st, 0.0f, 20.0f);
        vb[v] = (uint32_t)(next_random(&st) % 500);
    }
    for (uint32_t f = 0; f < nq; ++f) random_face(&st, nv - 7, q + 4 * f, 4);
    for (uint32_t f = 0; f < nt; ++f) random_face(&st, nv - 7, t + 3 * f, 3);
    for (uint32_t f = 0; f < nq + nt; ++f) fb[f] = f / 64;
    mesh_spec s = {p, NULL, uv, vb, nv, q, nq, t, nt, fb};
    xyl_mesh *m = build(&s);
    free(p);
    free(uv);
    free(vb);
    free(q);
    free(t);
    free(fb);
    return m;
}

/* Numbers that stress the JSON min/max: denormals, huge values, negative zero, 0.1. */
static xyl_mesh *extreme(void)
{
    static const xyl_vec3 p[4] = {{0.1f, -0.0f, 1e-40f},
                                  {-3.0e38f, 1.17549435e-38f, 0.3f},
                                  {3.0e38f, 16777217.0f, -1e-7f},
                                  {1.0f / 3.0f, -2.5e-45f, 123456.789f}};
    static const uint32_t t[12] = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
    mesh_spec s = {p, NULL, NULL, NULL, 4, NULL, 0, t, 4, NULL};
    return build(&s);
}

/* Caller normals that are not unit (and one zero): GLB renormalises them. */
static xyl_mesh *sloppy_normals(void)
{
    static const xyl_vec3 n[8] = {{0, 0, 2},   {0, 0, 0}, {3, 4, 0},     {0, -0.5f, 0},
                                  {1, 1, 1},   {0, 1, 0}, {0.6f, 0.8f, 0}, {1e-30f, 0, 0}};
    mesh_spec s = {CUBE_POS, n, NULL, NULL, 8, CUBE_QUADS, 6, NULL, 0, NULL};
    return build(&s);
}

/* ---- helpers -------------------------------------------------------------------------------- */

static unsigned char *write_alloc(const xyl_mesh *m, xyl_mesh_format f, size_t *len)
{
    size_t need = 0;
    xyl_result r = xyl_mesh_write_memory(m, f, NULL, NULL, 0, &need);
    if (r != XYL_OK) fail_msg("count pass: %s", xyl_result_string(r));
    unsigned char *buf = malloc(need + 1);
    assert_non_null(buf);
    size_t again = 0;
    assert_int_equal(xyl_mesh_write_memory(m, f, NULL, buf, need + 1, &again), XYL_OK);
    assert_int_equal(again, need);
    *len = need;
    return buf;
}

static uint32_t le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static void store_le32(unsigned char *b, uint32_t v)
{
    for (int i = 0; i < 4; ++i) b[i] = (unsigned char)(v >> (8 * i));
}

static void store_f32(unsigned char *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    store_le32(b, u);
}

/* A GLB taken apart: the JSON text (NUL-terminated copy) and the BIN chunk. */
typedef struct glb {
    char *json;
    size_t json_len; /* with padding */
    const unsigned char *bin;
    size_t bin_len;
} glb;

/* Checks the container: header, chunk types and lengths, alignment and padding. */
static glb parse_glb(const unsigned char *b, size_t len)
{
    glb g = {NULL, 0, NULL, 0};
    assert_true(len >= 20 && len % 4 == 0);
    assert_int_equal(le32(b), GLB_MAGIC);
    assert_int_equal(le32(b + 4), 2);
    assert_int_equal(le32(b + 8), len);
    g.json_len = le32(b + 12);
    assert_int_equal(le32(b + 16), GLB_JSON);
    assert_int_equal(g.json_len % 4, 0);
    assert_true(20 + g.json_len <= len);
    g.json = malloc(g.json_len + 1);
    assert_non_null(g.json);
    memcpy(g.json, b + 20, g.json_len);
    g.json[g.json_len] = '\0';
    size_t at = 20 + g.json_len;
    if (at == len) return g;
    assert_true(at + 8 <= len);
    g.bin_len = le32(b + at);
    assert_int_equal(le32(b + at + 4), GLB_BIN);
    assert_int_equal(g.bin_len % 4, 0);
    assert_int_equal(at + 8 + g.bin_len, len);
    g.bin = b + at + 8;
    return g;
}

static size_t count_substr(const char *hay, const char *needle)
{
    size_t n = 0;
    for (const char *p = strstr(hay, needle); p; p = strstr(p + 1, needle)) ++n;
    return n;
}

static void assert_contains(const char *hay, const char *needle)
{
    if (!strstr(hay, needle)) fail_msg("'%s' not found in:\n%s", needle, hay);
}

static size_t count_lines(const char *text, const char *prefix)
{
    size_t n = 0, k = strlen(prefix);
    for (const char *line = text; *line;) {
        n += strncmp(line, prefix, k) == 0;
        const char *lf = strchr(line, '\n');
        if (!lf) break;
        line = lf + 1;
    }
    return n;
}

/* ---- OBJ ------------------------------------------------------------------------------------ */

static void obj_of_a_tiny_mesh_is_exact(void **state)
{
    (void)state;
    static const xyl_vec3 p[5] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.1f, -2.5f, 1e-7f}};
    static const xyl_vec3 n[5] = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 1, 0}};
    static const float uv[10] = {0, 0, 0.25f, 0, 0.25f, 1, 0, 1, 0.5f, 3};
    static const uint32_t q[4] = {0, 1, 2, 3};
    static const uint32_t t[3] = {1, 0, 4};
    static const uint32_t fb[2] = {0, 12};
    mesh_spec s = {p, n, uv, NULL, 5, q, 1, t, 1, fb};
    xyl_mesh *m = build(&s);
    size_t len;
    char *text = (char *)write_alloc(m, XYL_MESH_FORMAT_OBJ, &len);
    const char *expect = "# xylem mesh: 5 vertices, 1 quads, 1 triangles\n"
                         "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.1 -2.5 1e-7\n"
                         "vt 0 0\nvt 0.25 0\nvt 0.25 1\nvt 0 1\nvt 0.5 3\n"
                         "vn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 1 0\n"
                         "g branch_0\nf 1/1/1 2/2/2 3/3/3 4/4/4\n"
                         "g branch_12\nf 2/2/2 1/1/1 5/5/5\n";
    assert_string_equal(text, expect);
    assert_int_equal(len, strlen(expect));
    free(text);
    xyl_mesh_destroy(m);
}

static void obj_cube_has_eight_vertices_and_six_quads(void **state)
{
    (void)state;
    xyl_mesh *m = cube();
    size_t len;
    char *text = (char *)write_alloc(m, XYL_MESH_FORMAT_OBJ, &len);
    assert_int_equal(count_lines(text, "v "), 8);
    assert_int_equal(count_lines(text, "vt "), 8);
    assert_int_equal(count_lines(text, "vn "), 8);
    assert_int_equal(count_lines(text, "f "), 6);
    assert_int_equal(count_lines(text, "g "), 1);
    assert_contains(text, "# xylem mesh: 8 vertices, 6 quads, 0 triangles\n");
    assert_contains(text, "\nf 1/1/1 4/4/4 3/3/3 2/2/2\n");
    assert_contains(text, "\nf 2/2/2 3/3/3 7/7/7 6/6/6\n");
    /* smooth normals of a cube corner point along the diagonal */
    assert_contains(text, "\nvn -0.57735026 -0.57735026 -0.57735026\n");
    free(text);
    xyl_mesh_destroy(m);
}

static void obj_writes_triangles_as_triangles_and_quads_as_quads(void **state)
{
    (void)state;
    xyl_mesh *m = mixed();
    size_t len;
    char *text = (char *)write_alloc(m, XYL_MESH_FORMAT_OBJ, &len);
    assert_int_equal(count_lines(text, "f "), 5);
    assert_contains(text, "g branch_3\nf 1/1/1 2/2/2 3/3/3 4/4/4\nf 5/5/5 2/2/2 1/1/1\n");
    assert_contains(text, "g branch_7\nf 5/5/5 4/4/4 3/3/3\nf 5/5/5 1/1/1 4/4/4\n");
    free(text);
    xyl_mesh_destroy(m);
}

static void obj_groups_follow_face_branches(void **state)
{
    (void)state;
    xyl_mesh *m = branches();
    size_t len;
    char *text = (char *)write_alloc(m, XYL_MESH_FORMAT_OBJ, &len);
    assert_int_equal(count_lines(text, "g "), 3);
    const char *g0 = strstr(text, "g branch_0\n"), *g1 = strstr(text, "g branch_1\n");
    assert_non_null(g0);
    assert_non_null(g1);
    assert_non_null(strstr(g1, "g branch_0\n")); /* branch 0 again after branch 1 */
    assert_int_equal(count_lines(g0, "f "), 12);
    assert_int_equal(count_lines(g1, "f "), 9);
    free(text);
    xyl_mesh_destroy(m);
}

static void obj_of_an_empty_mesh_is_the_header(void **state)
{
    (void)state;
    xyl_mesh *m = empty_mesh();
    size_t len;
    char *text = (char *)write_alloc(m, XYL_MESH_FORMAT_OBJ, &len);
    assert_string_equal(text, "# xylem mesh: 0 vertices, 0 quads, 0 triangles\n");
    free(text);
    xyl_mesh_destroy(m);
}

static void obj_does_not_depend_on_the_locale(void **state)
{
    (void)state;
    const char *names[] = {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "ru_RU.UTF-8"};
    const char *found = NULL;
    for (size_t i = 0; i < 4 && !found; ++i)
        if (setlocale(LC_NUMERIC, names[i])) found = names[i];
    if (!found) skip(); /* no locale with a decimal comma installed */
    xyl_mesh *m = extreme();
    size_t len_obj, len_glb;
    char *text = (char *)write_alloc(m, XYL_MESH_FORMAT_OBJ, &len_obj);
    unsigned char *bytes = write_alloc(m, XYL_MESH_FORMAT_GLB, &len_glb);
    setlocale(LC_NUMERIC, "C");
    assert_contains(text, "v 0.1 ");
    glb g = parse_glb(bytes, len_glb);
    assert_contains(g.json, "\"min\":[-3e38,");
    free(g.json);
    free(text);
    free(bytes);
    xyl_mesh_destroy(m);
}

/* ---- GLB ------------------------------------------------------------------------------------ */

static void glb_container_is_well_formed_and_aligned(void **state)
{
    (void)state;
    xyl_mesh *meshes[] = {cube(), tetra(), mixed(), branches(), extreme()};
    for (size_t i = 0; i < sizeof meshes / sizeof *meshes; ++i) {
        size_t len;
        unsigned char *b = write_alloc(meshes[i], XYL_MESH_FORMAT_GLB, &len);
        glb g = parse_glb(b, len);
        size_t n = meshes[i]->vertex_count, t = meshes[i]->tri_view_count;
        assert_int_equal(g.bin_len, n * (12 + 12 + 8 + 4) + t * 12);
        /* the JSON is padded with spaces only, after its closing brace */
        size_t end = strlen(g.json);
        while (end > 0 && g.json[end - 1] == ' ') --end;
        assert_int_equal(g.json[end - 1], '}');
        assert_true(g.json_len - end < 4);
        assert_int_equal(strlen(g.json), g.json_len); /* no NUL inside */
        free(g.json);
        free(b);
        xyl_mesh_destroy(meshes[i]);
    }
}

static void glb_json_declares_the_attributes_and_accessors(void **state)
{
    (void)state;
    xyl_mesh *m = cube();
    size_t len;
    unsigned char *b = write_alloc(m, XYL_MESH_FORMAT_GLB, &len);
    glb g = parse_glb(b, len);
    assert_contains(g.json, "\"asset\":{\"version\":\"2.0\",\"generator\":\"xylem\"}");
    assert_contains(g.json, "\"scene\":0,\"scenes\":[{\"nodes\":[0]}]");
    assert_contains(g.json, "\"attributes\":{\"POSITION\":0,\"NORMAL\":1,\"TEXCOORD_0\":2,"
                            "\"_BRANCH_ID\":3},\"indices\":4,\"mode\":4");
    assert_int_equal(count_substr(g.json, "\"count\":8,"), 4);
    assert_int_equal(count_substr(g.json, "\"count\":36,"), 1);
    assert_int_equal(count_substr(g.json, "\"componentType\":5126"), 4);
    assert_int_equal(count_substr(g.json, "\"componentType\":5125"), 1);
    assert_int_equal(count_substr(g.json, "\"target\":34962"), 4);
    assert_int_equal(count_substr(g.json, "\"target\":34963"), 1);
    assert_contains(g.json, "\"type\":\"VEC3\",\"min\":[-0.5,-0.5,-0.5],\"max\":[0.5,0.5,0.5]}");
    assert_contains(g.json, "\"type\":\"VEC2\"");
    assert_int_equal(count_substr(g.json, "\"type\":\"SCALAR\""), 2);
    assert_contains(g.json, "\"buffers\":[{\"byteLength\":432}]"); /* 8 * 36 + 36 * 4 */
    free(g.json);
    free(b);
    xyl_mesh_destroy(m);
}

/* Expected BIN chunk: positions, normals, UVs, branch ids (float), tri_view indices. */
static unsigned char *expected_bin(const xyl_mesh *m, size_t *len)
{
    size_t n = m->vertex_count, t = m->tri_view_count;
    *len = n * 36 + t * 12;
    unsigned char *e = malloc(*len), *w = e;
    assert_non_null(e);
    for (size_t v = 0; v < n; ++v, w += 12) {
        store_f32(w, m->positions[v].x);
        store_f32(w + 4, m->positions[v].y);
        store_f32(w + 8, m->positions[v].z);
    }
    for (size_t v = 0; v < n; ++v, w += 12) {
        store_f32(w, m->normals[v].x);
        store_f32(w + 4, m->normals[v].y);
        store_f32(w + 8, m->normals[v].z);
    }
    for (size_t i = 0; i < 2 * n; ++i, w += 4) store_f32(w, m->uvs[i]);
    for (size_t v = 0; v < n; ++v, w += 4) store_f32(w, (float)m->branch_ids[v]);
    for (size_t i = 0; i < 3 * t; ++i, w += 4) store_le32(w, m->tri_view[i]);
    return e;
}

static void glb_bin_holds_the_exact_vertex_and_index_bytes(void **state)
{
    (void)state;
    xyl_mesh *meshes[] = {cube(), tetra(), mixed(), branches(), extreme(),
                          random_mesh(7, 300, 200, 100)};
    for (size_t i = 0; i < sizeof meshes / sizeof *meshes; ++i) {
        size_t len, elen;
        unsigned char *b = write_alloc(meshes[i], XYL_MESH_FORMAT_GLB, &len);
        glb g = parse_glb(b, len);
        unsigned char *e = expected_bin(meshes[i], &elen);
        assert_int_equal(g.bin_len, elen);
        assert_memory_equal(g.bin, e, elen);
        free(e);
        free(g.json);
        free(b);
        xyl_mesh_destroy(meshes[i]);
    }
}

static void glb_indices_come_from_the_triangulated_view(void **state)
{
    (void)state;
    xyl_mesh *m = mixed();
    size_t len;
    unsigned char *b = write_alloc(m, XYL_MESH_FORMAT_GLB, &len);
    glb g = parse_glb(b, len);
    assert_int_equal(m->tri_view_count, 6);
    assert_int_equal(count_substr(g.json, "\"count\":18,"), 1);
    const unsigned char *idx = g.bin + 5 * 36;
    const uint32_t expect[6] = {0, 1, 2, 0, 2, 3}; /* the base quad, split (a,b,c),(a,c,d) */
    for (int k = 0; k < 6; ++k) assert_int_equal(le32(idx + 4 * k), expect[k]);
    assert_int_equal(le32(idx + 4 * 6), 4); /* then the triangles */
    free(g.json);
    free(b);
    xyl_mesh_destroy(m);
}

static void glb_branch_ids_are_floats(void **state)
{
    (void)state;
    xyl_mesh *m = branches();
    size_t len;
    unsigned char *b = write_alloc(m, XYL_MESH_FORMAT_GLB, &len);
    glb g = parse_glb(b, len);
    const unsigned char *ids = g.bin + 16 * 32;
    for (size_t v = 0; v < 16; ++v) {
        float f;
        uint32_t u = le32(ids + 4 * v);
        memcpy(&f, &u, sizeof f);
        assert_true(f == (v < 8 ? 0.0f : 1.0f));
    }
    free(g.json);
    free(b);
    xyl_mesh_destroy(m);
}

static void glb_of_an_empty_mesh_is_a_scene_with_one_empty_node(void **state)
{
    (void)state;
    xyl_mesh *m = empty_mesh();
    size_t len;
    unsigned char *b = write_alloc(m, XYL_MESH_FORMAT_GLB, &len);
    glb g = parse_glb(b, len);
    assert_null(g.bin);
    assert_int_equal(len, 20 + g.json_len);
    assert_contains(g.json, "\"nodes\":[{\"name\":\"xylem\"}]}");
    assert_null(strstr(g.json, "meshes"));
    assert_null(strstr(g.json, "buffers"));
    free(g.json);
    free(b);
    xyl_mesh_destroy(m);
}

static void glb_rejects_vertices_without_faces(void **state)
{
    (void)state;
    mesh_spec s = {CUBE_POS, NULL, NULL, NULL, 8, NULL, 0, NULL, 0, NULL};
    xyl_mesh *m = build(&s);
    size_t need = 0;
    assert_int_equal(xyl_mesh_write_memory(m, XYL_MESH_FORMAT_GLB, NULL, NULL, 0, &need),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_mesh_write_memory(m, XYL_MESH_FORMAT_OBJ, NULL, NULL, 0, &need), XYL_OK);
    xyl_mesh_destroy(m);
}

static void glb_renormalises_normals_that_are_not_unit(void **state)
{
    (void)state;
    xyl_mesh *m = sloppy_normals();
    size_t len;
    unsigned char *b = write_alloc(m, XYL_MESH_FORMAT_GLB, &len);
    glb g = parse_glb(b, len);
    const float expect[8][3] = {{0, 0, 1}, {0, 1, 0}, {0.6f, 0.8f, 0}, {0, -1, 0},
                                {0.577350259f, 0.577350259f, 0.577350259f},
                                {0, 1, 0}, {0.6f, 0.8f, 0}, {1, 0, 0}};
    for (int v = 0; v < 8; ++v) {
        for (int k = 0; k < 3; ++k) {
            uint32_t u = le32(g.bin + 8 * 12 + 12 * v + 4 * k);
            float f;
            memcpy(&f, &u, sizeof f);
            if (fabsf(f - expect[v][k]) > 1e-7f)
                fail_msg("normal %d[%d] = %.9g, expected %.9g", v, k, (double)f,
                         (double)expect[v][k]);
        }
    }
    /* The already unit ones pass bit for bit. */
    static const unsigned char plus_y[12] = {0, 0, 0, 0, 0, 0, 0x80, 0x3f, 0, 0, 0, 0};
    assert_memory_equal(g.bin + 8 * 12 + 12 * 5, plus_y, 12);
    free(g.json);
    free(b);
    xyl_mesh_destroy(m);
}

static void writers_are_deterministic(void **state)
{
    (void)state;
    xyl_mesh *a = random_mesh(99, 500, 300, 300), *b = random_mesh(99, 500, 300, 300);
    for (int f = 0; f < 2; ++f) {
        size_t la, lb;
        unsigned char *ba = write_alloc(a, (xyl_mesh_format)f, &la);
        unsigned char *bb = write_alloc(b, (xyl_mesh_format)f, &lb);
        assert_int_equal(la, lb);
        assert_memory_equal(ba, bb, la);
        free(ba);
        free(bb);
    }
    xyl_mesh_destroy(a);
    xyl_mesh_destroy(b);
}

/* ---- count-then-fill ------------------------------------------------------------------------ */

static void count_then_fill_refuses_a_small_buffer_untouched(void **state)
{
    (void)state;
    xyl_mesh *m = cube();
    for (int f = 0; f < 2; ++f) {
        xyl_mesh_format fmt = (xyl_mesh_format)f;
        size_t need = 0, again = 0;
        assert_int_equal(xyl_mesh_write_memory(m, fmt, NULL, NULL, 0, &need), XYL_OK);
        assert_true(need > 0);
        /* OBJ is text and needs room for its NUL; GLB is exactly need bytes. */
        size_t exact = fmt == XYL_MESH_FORMAT_OBJ ? need + 1 : need;
        unsigned char *buf = malloc(exact + 8);
        assert_non_null(buf);
        memset(buf, 0xAB, exact + 8);
        assert_int_equal(xyl_mesh_write_memory(m, fmt, NULL, buf, exact - 1, &again),
                         XYL_ERR_INVALID_ARGUMENT);
        assert_int_equal(again, need);
        for (size_t i = 0; i < exact + 8; ++i) assert_int_equal(buf[i], 0xAB);
        assert_int_equal(xyl_mesh_write_memory(m, fmt, NULL, buf, exact, NULL), XYL_OK);
        for (size_t i = exact; i < exact + 8; ++i) assert_int_equal(buf[i], 0xAB);
        if (fmt == XYL_MESH_FORMAT_OBJ) assert_int_equal(buf[need], '\0');
        else assert_int_equal(le32(buf + 8), need);
        free(buf);
    }
    xyl_mesh_destroy(m);
}

static void write_memory_rejects_bad_arguments(void **state)
{
    (void)state;
    xyl_mesh *m = cube();
    size_t need = 7;
    char buf[16];
    assert_int_equal(xyl_mesh_write_memory(NULL, XYL_MESH_FORMAT_OBJ, NULL, NULL, 0, &need),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_mesh_write_memory(m, XYL_MESH_FORMAT_OBJ, NULL, NULL, 0, NULL),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_mesh_write_memory(m, (xyl_mesh_format)2, NULL, NULL, 0, &need),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_mesh_write_memory(m, (xyl_mesh_format)-1, NULL, buf, sizeof buf, &need),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(need, 7);
    xyl_mesh_destroy(m);
}

typedef struct tmpdir {
    char path[64];
} tmpdir;

static void make_tmpdir(tmpdir *t)
{
    snprintf(t->path, sizeof t->path, "/tmp/xyl_mesh_io_XXXXXX");
    assert_non_null(mkdtemp(t->path));
}

static size_t dir_entries(const char *path)
{
    DIR *dir = opendir(path);
    assert_non_null(dir);
    size_t n = 0;
    for (struct dirent *e; (e = readdir(dir)) != NULL;)
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(dir);
    return n;
}

/* ---- caller-built views --------------------------------------------------------------------- */

/* A view of the cube that a caller could have built by hand (arrays in *store). */
typedef struct view_store {
    xyl_vec3 pos[8], nrm[8];
    float uv[16];
    uint32_t ids[8], quads[24], fb[6], tri[36];
    uint8_t wraps[6];
} view_store;

static xyl_mesh cube_view(view_store *st)
{
    xyl_mesh *c = cube();
    memcpy(st->pos, c->positions, sizeof st->pos);
    memcpy(st->nrm, c->normals, sizeof st->nrm);
    memcpy(st->uv, c->uvs, sizeof st->uv);
    memcpy(st->ids, c->branch_ids, sizeof st->ids);
    memcpy(st->quads, c->quads, sizeof st->quads);
    memcpy(st->fb, c->face_branches, sizeof st->fb);
    memcpy(st->tri, c->tri_view, sizeof st->tri);
    memcpy(st->wraps, c->uv_wraps, sizeof st->wraps);
    xyl_mesh v = *c;
    xyl_mesh_destroy(c);
    v.positions = st->pos;
    v.normals = st->nrm;
    v.uvs = st->uv;
    v.branch_ids = st->ids;
    v.quads = st->quads;
    v.face_branches = st->fb;
    v.tri_view = st->tri;
    v.uv_wraps = st->wraps;
    return v;
}

static void expect_both(const xyl_mesh *v, xyl_result obj, xyl_result glb_result)
{
    size_t need = 0;
    assert_int_equal(xyl_mesh_write_memory(v, XYL_MESH_FORMAT_OBJ, NULL, NULL, 0, &need), obj);
    assert_int_equal(xyl_mesh_write_memory(v, XYL_MESH_FORMAT_GLB, NULL, NULL, 0, &need),
                     glb_result);
}

static void views_with_non_finite_numbers_are_refused(void **state)
{
    (void)state;
    view_store st;
    xyl_mesh v = cube_view(&st);
    expect_both(&v, XYL_OK, XYL_OK);
    st.pos[3].y = NAN;
    expect_both(&v, XYL_ERR_NON_FINITE, XYL_ERR_NON_FINITE);
    v = cube_view(&st);
    st.nrm[7].z = INFINITY;
    expect_both(&v, XYL_ERR_NON_FINITE, XYL_ERR_NON_FINITE);
    v = cube_view(&st);
    st.uv[5] = -INFINITY;
    tmpdir t;
    make_tmpdir(&t);
    char path[128];
    snprintf(path, sizeof path, "%s/never.glb", t.path);
    xyl_diag d;
    memset(&d, 0, sizeof d);
    assert_int_equal(xyl_mesh_write_file(&v, path, XYL_MESH_FORMAT_GLB, NULL, &d),
                     XYL_ERR_NON_FINITE);
    assert_int_equal(d.index, 2);
    assert_int_equal(dir_entries(t.path), 0);
    rmdir(t.path);
}

static void views_with_bad_indices_or_arrays_are_refused(void **state)
{
    (void)state;
    view_store st;
    xyl_mesh v = cube_view(&st);
    st.quads[9] = 8;
    expect_both(&v, XYL_ERR_INVALID_ARGUMENT, XYL_ERR_INVALID_ARGUMENT);
    v = cube_view(&st);
    st.tri[35] = 100;
    expect_both(&v, XYL_ERR_INVALID_ARGUMENT, XYL_ERR_INVALID_ARGUMENT);
    v = cube_view(&st);
    v.tri_view_count = 11;
    expect_both(&v, XYL_ERR_INVALID_ARGUMENT, XYL_ERR_INVALID_ARGUMENT);
    v = cube_view(&st);
    v.normals = NULL;
    expect_both(&v, XYL_ERR_INVALID_ARGUMENT, XYL_ERR_INVALID_ARGUMENT);
    v = cube_view(&st);
    v.face_branches = NULL;
    expect_both(&v, XYL_ERR_INVALID_ARGUMENT, XYL_ERR_INVALID_ARGUMENT);
    v = cube_view(&st);
    v.quad_count = SIZE_MAX / 2;
    expect_both(&v, XYL_ERR_INVALID_ARGUMENT, XYL_ERR_INVALID_ARGUMENT);
}

/* A face that uses one vertex twice is refused by both writers, as by xyl_mesh_create, and
 * named in the diagnostic; nothing is written. */
static void views_with_a_face_repeating_a_vertex_are_refused(void **state)
{
    (void)state;
    view_store st;
    xyl_mesh v = cube_view(&st);
    st.quads[4 * 2 + 2] = st.quads[4 * 2 + 0];
    expect_both(&v, XYL_ERR_INVALID_ARGUMENT, XYL_ERR_INVALID_ARGUMENT);
    tmpdir t;
    make_tmpdir(&t);
    char path[128];
    snprintf(path, sizeof path, "%s/never.obj", t.path);
    for (int f = 0; f < 2; ++f) {
        xyl_diag d;
        memset(&d, 0, sizeof d);
        assert_int_equal(xyl_mesh_write_file(&v, path, (xyl_mesh_format)f, NULL, &d),
                         XYL_ERR_INVALID_ARGUMENT);
        assert_int_equal(d.index, 2);
        assert_int_equal(dir_entries(t.path), 0);
    }
    rmdir(t.path);
}

static void glb_refuses_branch_ids_a_float_cannot_hold(void **state)
{
    (void)state;
    view_store st;
    xyl_mesh v = cube_view(&st);
    st.ids[4] = (1u << 24);
    expect_both(&v, XYL_OK, XYL_OK);
    st.ids[4] = (1u << 24) + 1;
    expect_both(&v, XYL_OK, XYL_ERR_LIMIT_EXCEEDED);
}

/* A view announcing more than a GLB's uint32 lengths can hold is refused before its arrays are
 * read (they are far too short here). */
static void glb_larger_than_4_gib_is_refused(void **state)
{
    (void)state;
    view_store st;
    xyl_mesh v = cube_view(&st);
    v.vertex_count = 120000000; /* 36 bytes each: 4.32e9 */
    size_t need = 5;
    assert_int_equal(xyl_mesh_write_memory(&v, XYL_MESH_FORMAT_GLB, NULL, NULL, 0, &need),
                     XYL_ERR_LIMIT_EXCEEDED);
    assert_int_equal(need, 5);
    v = cube_view(&st);
    v.vertex_count = (size_t)UINT32_MAX + 1;
    assert_int_equal(xyl_mesh_write_memory(&v, XYL_MESH_FORMAT_GLB, NULL, NULL, 0, &need),
                     XYL_ERR_LIMIT_EXCEEDED);
    v = cube_view(&st);
    v.triangle_count = 400000000;
    v.tri_view_count = 400000012;
    v.triangles = st.tri;
    tmpdir t;
    make_tmpdir(&t);
    char path[128];
    snprintf(path, sizeof path, "%s/never.glb", t.path);
    xyl_diag d;
    memset(&d, 0, sizeof d);
    assert_int_equal(xyl_mesh_write_file(&v, path, XYL_MESH_FORMAT_GLB, NULL, &d),
                     XYL_ERR_LIMIT_EXCEEDED);
    assert_int_equal(d.code, XYL_ERR_LIMIT_EXCEEDED);
    assert_true(strlen(d.message) > 0);
    assert_int_equal(dir_entries(t.path), 0);
    rmdir(t.path);
}

/* ---- write_file ----------------------------------------------------------------------------- */

static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc((size_t)n + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *len = (size_t)n;
    return b;
}

/* A stem of 400 segments (k = 5): its OBJ text is far above the 64 KiB that write_file's buffer
 * starts with, and its faces wrap UVs at every ring. */
static xyl_mesh *long_stem(void)
{
    enum { NODES = 401 };
    xyl_skel_node nodes[NODES];
    memset(nodes, 0, sizeof nodes);
    for (int i = 0; i < NODES; ++i) {
        nodes[i].pos = (xyl_vec3){0.1f * (float)sin(0.05 * i), 0.25f * (float)i, 0.0f};
        nodes[i].radius = 0.1f;
        nodes[i].parent = i - 1;
    }
    xyl_skeleton_desc sd = {0};
    sd.nodes = nodes;
    sd.node_count = NODES;
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_skeleton_create(&sd, &sk, NULL), XYL_OK);
    xyl_stems_desc d = {0};
    d.sides = 5;
    xyl_mesh *m = NULL;
    assert_int_equal(xyl_stems_build(sk, &d, &m, NULL, NULL), XYL_OK);
    xyl_skeleton_destroy(sk);
    return m;
}

static void write_file_writes_what_write_memory_renders(void **state)
{
    (void)state;
    tmpdir t;
    make_tmpdir(&t);
    const char *names[2] = {"mesh.obj", "mesh.glb"};
    for (int which = 0; which < 2; ++which) {
        xyl_mesh *m = which ? long_stem() : mixed();
        for (int f = 0; f < 2; ++f) {
            char path[128];
            snprintf(path, sizeof path, "%s/%s", t.path, names[f]);
            xyl_diag d;
            memset(&d, 0, sizeof d);
            d.code = XYL_ERR_IO;
            assert_int_equal(xyl_mesh_write_file(m, path, (xyl_mesh_format)f, NULL, &d), XYL_OK);
            assert_int_equal(d.code, XYL_OK);
            size_t len, elen;
            unsigned char *got = slurp(path, &len);
            unsigned char *expect = write_alloc(m, (xyl_mesh_format)f, &elen);
            assert_int_equal(len, elen);
            assert_memory_equal(got, expect, len);
            if (which) assert_true(len > (1u << 16));
            free(got);
            free(expect);
        }
        assert_int_equal(dir_entries(t.path), 2);
        for (int f = 0; f < 2; ++f) {
            char path[128];
            snprintf(path, sizeof path, "%s/%s", t.path, names[f]);
            unlink(path);
        }
        xyl_mesh_destroy(m);
    }
    rmdir(t.path);
}

static void write_file_replaces_an_existing_file_atomically(void **state)
{
    (void)state;
    tmpdir t;
    make_tmpdir(&t);
    char path[128];
    snprintf(path, sizeof path, "%s/tree.glb", t.path);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs("old contents\n", f);
    fclose(f);
    /* A reader holding the old file keeps seeing it whole: the new one arrives by rename. */
    int old_fd = open(path, O_RDONLY);
    assert_true(old_fd >= 0);
    xyl_mesh *m = cube();
    assert_int_equal(xyl_mesh_write_file(m, path, XYL_MESH_FORMAT_GLB, NULL, NULL), XYL_OK);
    char old[32] = {0};
    assert_int_equal(read(old_fd, old, sizeof old - 1), 13);
    assert_string_equal(old, "old contents\n");
    close(old_fd);
    size_t len;
    unsigned char *b = slurp(path, &len);
    glb g = parse_glb(b, len);
    free(g.json);
    free(b);
    assert_int_equal(dir_entries(t.path), 1); /* no temporary file left behind */
    unlink(path);
    rmdir(t.path);
    xyl_mesh_destroy(m);
}

static void write_file_into_a_missing_folder_fails_with_io_and_leaves_nothing(void **state)
{
    (void)state;
    tmpdir t;
    make_tmpdir(&t);
    char path[128];
    snprintf(path, sizeof path, "%s/missing/tree.obj", t.path);
    xyl_mesh *m = cube();
    for (int f = 0; f < 2; ++f) {
        xyl_diag d;
        memset(&d, 0, sizeof d);
        assert_int_equal(xyl_mesh_write_file(m, path, (xyl_mesh_format)f, NULL, &d), XYL_ERR_IO);
        assert_int_equal(d.code, XYL_ERR_IO);
        assert_true(strlen(d.message) > 0);
        assert_int_equal(dir_entries(t.path), 0);
    }
    rmdir(t.path);
    xyl_mesh_destroy(m);
}

static void write_file_rejects_bad_arguments(void **state)
{
    (void)state;
    xyl_mesh *m = cube();
    xyl_diag d;
    memset(&d, 0, sizeof d);
    assert_int_equal(xyl_mesh_write_file(NULL, "/tmp/x.obj", XYL_MESH_FORMAT_OBJ, NULL, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(d.code, XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_mesh_write_file(m, NULL, XYL_MESH_FORMAT_OBJ, NULL, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_mesh_write_file(m, "", XYL_MESH_FORMAT_GLB, NULL, NULL),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_mesh_write_file(m, "/tmp/x.obj", (xyl_mesh_format)5, NULL, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    xyl_mesh_destroy(m);
}

/* ---- samples for the glTF-Validator --------------------------------------------------------- */

typedef struct sample {
    const char *name;
    xyl_mesh *(*make)(void);
} sample;

static xyl_mesh *large_random(void)
{
    return random_mesh(20240601, 40000, 30000, 20000);
}

static const sample SAMPLES[] = {
    {"cube", cube},           {"tetra", tetra},   {"mixed", mixed},
    {"branches", branches},   {"empty", empty_mesh}, {"extreme", extreme},
    {"sloppy_normals", sloppy_normals}, {"large_random", large_random},
};

/* Writes every sample as FOLDER/mesh_io_<name>.glb; returns the process exit status. */
static int write_samples(const char *folder)
{
    if (mkdir(folder, 0777) != 0 && errno != EEXIST) {
        fprintf(stderr, "cannot create %s: %s\n", folder, strerror(errno));
        return 1;
    }
    for (size_t i = 0; i < sizeof SAMPLES / sizeof *SAMPLES; ++i) {
        char path[4096];
        snprintf(path, sizeof path, "%s/mesh_io_%s.glb", folder, SAMPLES[i].name);
        xyl_mesh *m = SAMPLES[i].make();
        xyl_diag d;
        memset(&d, 0, sizeof d);
        xyl_result r = xyl_mesh_write_file(m, path, XYL_MESH_FORMAT_GLB, NULL, &d);
        xyl_mesh_destroy(m);
        if (r != XYL_OK) {
            fprintf(stderr, "%s: %s: %s\n", path, xyl_result_string(r), d.message);
            return 1;
        }
        printf("wrote %s\n", path);
    }
    return 0;
}

/* ---- float text (float_text.h): every text writer's numbers ---------------------------------- */

static uint32_t float_bits(float f)
{
    uint32_t b;
    memcpy(&b, &f, sizeof b);
    return b;
}

static float float_of_bits(uint32_t b)
{
    float f;
    memcpy(&f, &b, sizeof f);
    return f;
}

/* Significant digits of a number's text: those of its mantissa without leading zeros, or
 * trailing ones (an integer's padding). */
static int significant_digits(const char *t)
{
    int first = -1, last = -1, i = 0;
    for (; t[i] && t[i] != 'e'; ++i)
        if (t[i] >= '1' && t[i] <= '9') {
            if (first < 0) first = i;
            last = i;
        }
    int n = 0;
    for (int j = first; j >= 0 && j <= last; ++j) n += t[j] >= '0' && t[j] <= '9';
    return n;
}

/* v's text reads back as exactly v, in the documented alphabet, and no text with one
 * significant digit fewer does: the nearest such decimal (printf's %.*e) reads back as
 * another float. */
static void check_float_text(float v)
{
    char out[XYL__FLOAT_TEXT_MAX + 1];
    size_t n = xyl__float_text(v, out);
    assert_true(n > 0 && n <= 16);
    out[n] = '\0';
    for (size_t i = 0; i < n; ++i)
        if (!strchr("0123456789.-e", out[i])) fail_msg("'%s' for %a has '%c'", out, (double)v, out[i]);
    char *end = NULL;
    float back = strtof(out, &end);
    if (*end != '\0' || float_bits(back) != float_bits(v))
        fail_msg("'%s' reads back as %a, not %a", out, (double)back, (double)v);
    int d = significant_digits(out);
    if (d > 1) {
        char shorter[48];
        snprintf(shorter, sizeof shorter, "%.*e", d - 2, (double)v);
        if (float_bits(strtof(shorter, NULL)) == float_bits(v))
            fail_msg("'%s' for %a, but '%s' reads back too", out, (double)v, shorter);
    }
}

static void float_text_is_the_shortest_that_reads_back(void **state)
{
    (void)state;
    static const struct {
        float v;
        const char *text;
    } cases[] = {
        {0.0f, "0"}, {-0.0f, "-0"}, {0.1f, "0.1"}, {-2.5f, "-2.5"}, {1.0f / 3.0f, "0.33333334"},
        {123456.789f, "123456.79"}, {16777216.0f, "16777216"}, {16777218.0f, "16777218"},
        {1e8f, "100000000"}, {1e9f, "1e9"}, {0.00001f, "0.00001"}, {0.000001f, "1e-6"},
        {1e-7f, "1e-7"}, {-2.5e-7f, "-2.5e-7"}, {FLT_MAX, "3.4028235e38"},
        {-3.0e38f, "-3e38"}, {FLT_MIN, "1.1754944e-38"}, {1e-45f, "1e-45"},
        {-0.57735026f, "-0.57735026"}, {1.5e10f, "1.5e10"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char out[XYL__FLOAT_TEXT_MAX + 1];
        size_t n = xyl__float_text(cases[i].v, out);
        out[n] = '\0';
        if (strcmp(out, cases[i].text) != 0)
            fail_msg("%a: '%s', expected '%s'", (double)cases[i].v, out, cases[i].text);
        check_float_text(cases[i].v);
    }
    /* every binade's ends and their neighbours, then random bits, denormals included */
    for (uint32_t e = 0; e < 255; ++e)
        for (uint32_t m = 0; m < 4; ++m) {
            uint32_t b = e << 23;
            check_float_text(float_of_bits(b + m));
            check_float_text(float_of_bits((b | 0x7fffffu) - m));
            check_float_text(float_of_bits(0x80000000u | (b + m)));
        }
    uint64_t x = 0x9e3779b97f4a7c15u;
    for (int i = 0; i < 300000; ++i) {
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        float v = float_of_bits((uint32_t)(x >> 32));
        if (isfinite(v)) check_float_text(v);
    }
    char out[XYL__FLOAT_TEXT_MAX];
    assert_int_equal(xyl__float_text(NAN, out), 3);
    assert_memory_equal(out, "nan", 3);
    assert_int_equal(xyl__float_text(-INFINITY, out), 4);
    assert_memory_equal(out, "-inf", 4);
}

int main(void)
{
    const char *samples = getenv("XYL_GLB_SAMPLES");
    if (samples && *samples) return write_samples(samples);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(obj_of_a_tiny_mesh_is_exact),
        cmocka_unit_test(obj_cube_has_eight_vertices_and_six_quads),
        cmocka_unit_test(obj_writes_triangles_as_triangles_and_quads_as_quads),
        cmocka_unit_test(obj_groups_follow_face_branches),
        cmocka_unit_test(obj_of_an_empty_mesh_is_the_header),
        cmocka_unit_test(obj_does_not_depend_on_the_locale),
        cmocka_unit_test(glb_container_is_well_formed_and_aligned),
        cmocka_unit_test(glb_json_declares_the_attributes_and_accessors),
        cmocka_unit_test(glb_bin_holds_the_exact_vertex_and_index_bytes),
        cmocka_unit_test(glb_indices_come_from_the_triangulated_view),
        cmocka_unit_test(glb_branch_ids_are_floats),
        cmocka_unit_test(glb_of_an_empty_mesh_is_a_scene_with_one_empty_node),
        cmocka_unit_test(glb_rejects_vertices_without_faces),
        cmocka_unit_test(glb_renormalises_normals_that_are_not_unit),
        cmocka_unit_test(writers_are_deterministic),
        cmocka_unit_test(count_then_fill_refuses_a_small_buffer_untouched),
        cmocka_unit_test(write_memory_rejects_bad_arguments),
        cmocka_unit_test(views_with_non_finite_numbers_are_refused),
        cmocka_unit_test(views_with_bad_indices_or_arrays_are_refused),
        cmocka_unit_test(views_with_a_face_repeating_a_vertex_are_refused),
        cmocka_unit_test(glb_refuses_branch_ids_a_float_cannot_hold),
        cmocka_unit_test(glb_larger_than_4_gib_is_refused),
        cmocka_unit_test(write_file_writes_what_write_memory_renders),
        cmocka_unit_test(write_file_replaces_an_existing_file_atomically),
        cmocka_unit_test(write_file_into_a_missing_folder_fails_with_io_and_leaves_nothing),
        cmocka_unit_test(write_file_rejects_bad_arguments),
        cmocka_unit_test(float_text_is_the_shortest_that_reads_back),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

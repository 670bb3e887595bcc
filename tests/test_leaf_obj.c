/* foliage/: leaves from an OBJ leaf mesh (xyl_foliage_leaves_from_obj). */
#include <float.h>
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
#include "test_util.h"

#define PI 3.14159265358979323846

/* ---- helpers ------------------------------------------------------------------------------- */

static void assert_near(double got, double want, double tol)
{
    if (!(fabs(got - want) <= tol)) fail_msg("got %.9g, want %.9g (tolerance %g)", got, want, tol);
}

static void assert_vec_near(xyl_vec3 got, double x, double y, double z, double tol)
{
    assert_near(got.x, x, tol);
    assert_near(got.y, y, tol);
    assert_near(got.z, z, tol);
}

static double len3(xyl_vec3 v)
{
    return sqrt((double)v.x * v.x + (double)v.y * v.y + (double)v.z * v.z);
}

static double dot3(xyl_vec3 a, xyl_vec3 b)
{
    return (double)a.x * b.x + (double)a.y * b.y + (double)a.z * b.z;
}

/* Reads text with desc (NULL: defaults) into at most 16 leaves; fails the test on an error. */
static size_t read_leaves(const char *text, const xyl_leaf_mesh_desc *desc, xyl_leaf out[16])
{
    size_t n = 99;
    xyl_diag d = {0};
    xyl_result r = xyl_foliage_leaves_from_obj(text, strlen(text), desc, NULL, 0, &n, &d);
    if (r != XYL_OK) fail_msg("count: %s at line %u: %s", xyl_result_string(r), d.line, d.message);
    assert_true(n <= 16);
    size_t m = 99;
    r = xyl_foliage_leaves_from_obj(text, strlen(text), desc, out, 16, &m, &d);
    if (r != XYL_OK) fail_msg("fill: %s at line %u: %s", xyl_result_string(r), d.line, d.message);
    assert_int_equal(m, n);
    assert_int_equal(xyl_foliage_check_leaves(out, n, NULL, &d), XYL_OK);
    return n;
}

/* Expects text to fail with code at line (index: the component, -1 for none); the outputs stay
 * untouched in both calls. */
static void expect_failure(const char *text, size_t size, const xyl_leaf_mesh_desc *desc,
                           xyl_result code, uint32_t line, int64_t index)
{
    xyl_leaf leaves[4];
    memset(leaves, 0xab, sizeof leaves);
    unsigned char before[sizeof leaves];
    memcpy(before, leaves, sizeof leaves);
    for (int fill = 0; fill < 2; ++fill) {
        size_t n = 77;
        xyl_diag d = {0};
        xyl_result r = xyl_foliage_leaves_from_obj(text, size, desc, fill ? leaves : NULL,
                                                   fill ? 4 : 0, &n, &d);
        if (r != code || d.line != line || d.index != index)
            fail_msg("'%.40s': got %s at line %u index %lld (%s), want %s at line %u index %lld",
                     text ? text : "(null)", xyl_result_string(r), d.line, (long long)d.index,
                     d.message, xyl_result_string(code), line, (long long)index);
        assert_int_equal(d.code, code);
        assert_true(d.message[0] != '\0');
        assert_int_equal(n, 77);
        assert_memory_equal(leaves, before, sizeof leaves);
    }
}

static void expect_text_failure(const char *text, xyl_result code, uint32_t line)
{
    expect_failure(text, strlen(text), NULL, code, line, -1);
}

static char *read_data(const char *name, size_t *size)
{
    char path[512];
    snprintf(path, sizeof path, "%s/leaves/%s", XYL_TEST_DATA, name);
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("cannot open %s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)n + 1);
    assert_non_null(text);
    assert_int_equal(fread(text, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    text[n] = '\0';
    *size = (size_t)n;
    return text;
}

/* The quad's four corners are the four given points, in any order. */
static void assert_corners(const xyl_leaf *l, const double want[4][3], double tol)
{
    bool used[4] = {false, false, false, false};
    for (int k = 0; k < 4; ++k) {
        double s = k & 1 ? 1 : -1, t = k & 2 ? 1 : -1;
        double c[3] = {l->center.x + s * l->side.x + t * l->axis.x,
                       l->center.y + s * l->side.y + t * l->axis.y,
                       l->center.z + s * l->side.z + t * l->axis.z};
        int found = -1;
        for (int w = 0; w < 4 && found < 0; ++w)
            if (!used[w] && fabs(c[0] - want[w][0]) <= tol && fabs(c[1] - want[w][1]) <= tol &&
                fabs(c[2] - want[w][2]) <= tol)
                found = w;
        if (found < 0) fail_msg("corner (%g, %g, %g) is none of the expected", c[0], c[1], c[2]);
        used[found] = true;
    }
}

/* ---- known polygons ------------------------------------------------------------------------ */

static void unit_square_is_its_own_quad(void **state)
{
    (void)state;
    xyl_leaf l[16];
    assert_int_equal(read_leaves("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", NULL, l), 1);
    const double corners[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    assert_corners(&l[0], corners, 1e-6);
    assert_vec_near(l[0].center, 0.5, 0.5, 0, 1e-6);
    assert_vec_near(l[0].normal, 0, 0, 1, 1e-6); /* counter-clockwise seen from +z */
    assert_near(len3(l[0].axis), 0.5, 1e-6);
    assert_near(len3(l[0].side), 0.5, 1e-6);
    assert_int_equal(l[0].count, 1);
    assert_int_equal(l[0].node, -1);
    assert_true(l[0].uv[0] == 0 && l[0].uv[1] == 0 && l[0].uv[2] == 1 && l[0].uv[3] == 1);
    /* the other winding faces the other way */
    assert_int_equal(read_leaves("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 4 3 2 1\n", NULL, l), 1);
    assert_vec_near(l[0].normal, 0, 0, -1, 1e-6);
}

/* A 2 x 1 rectangle turned and moved in space, as two triangles. */
static void write_rectangle(char *buf, size_t size, const double c[3], const double a[3],
                            const double s[3])
{
    int n = 0;
    for (int k = 0; k < 4; ++k) {
        double sa = (k == 1 || k == 2) ? 1 : -1, ss = k >= 2 ? 1 : -1; /* ccw about a x s... */
        n += snprintf(buf + n, size - (size_t)n, "v %.9g %.9g %.9g\n", c[0] + sa * a[0] + ss * s[0],
                      c[1] + sa * a[1] + ss * s[1], c[2] + sa * a[2] + ss * s[2]);
    }
    snprintf(buf + n, size - (size_t)n, "f 1 2 3\nf 1 3 4\n");
}

static void rotated_rectangle_is_its_own_quad_along_its_length(void **state)
{
    (void)state;
    /* an orthonormal frame: long direction a, across s, normal a x s */
    double a[3] = {2.0 / 3, 2.0 / 3, 1.0 / 3}, s[3] = {-2.0 / 3, 1.0 / 3, 2.0 / 3};
    double c[3] = {10, -4, 7};
    double ha[3], hs[3];
    for (int k = 0; k < 3; ++k) ha[k] = 1.0 * a[k], hs[k] = 0.5 * s[k];
    char text[512];
    write_rectangle(text, sizeof text, c, ha, hs);
    xyl_leaf_mesh_desc d = {0};
    d.has_stalk_point = true; /* near the -a end */
    d.stalk_point = (xyl_vec3){(float)(c[0] - 3 * a[0]), (float)(c[1] - 3 * a[1]),
                               (float)(c[2] - 3 * a[2])};
    xyl_leaf l[16];
    assert_int_equal(read_leaves(text, &d, l), 1);
    assert_vec_near(l[0].center, c[0], c[1], c[2], 1e-5);
    assert_vec_near(l[0].axis, a[0], a[1], a[2], 1e-5);
    assert_near(len3(l[0].side), 0.5, 1e-5);
    assert_near(fabs(dot3(l[0].side, (xyl_vec3){(float)s[0], (float)s[1], (float)s[2]})), 0.5, 1e-5);
    /* corners (-a, -s), (a, -s), (a, s): counter-clockwise about a x s */
    double n[3] = {a[1] * s[2] - a[2] * s[1], a[2] * s[0] - a[0] * s[2], a[0] * s[1] - a[1] * s[0]};
    assert_vec_near(l[0].normal, n[0], n[1], n[2], 1e-5);
    /* the stalk point at the other end turns the axis round */
    d.stalk_point = (xyl_vec3){(float)(c[0] + 3 * a[0]), (float)(c[1] + 3 * a[1]),
                               (float)(c[2] + 3 * a[2])};
    assert_int_equal(read_leaves(text, &d, l), 1);
    assert_vec_near(l[0].axis, -a[0], -a[1], -a[2], 1e-5);
    assert_vec_near(l[0].normal, n[0], n[1], n[2], 1e-5);
    /* without one, the single component's stalk is its lower end in y: a has y > 0 */
    assert_int_equal(read_leaves(text, NULL, l), 1);
    assert_vec_near(l[0].axis, a[0], a[1], a[2], 1e-5);
}

static void triangle_reduces_to_its_bounding_rectangle_from_the_base(void **state)
{
    (void)state;
    xyl_leaf l[16];
    /* isosceles: base 2 on y = 0, apex at height 3; its long axis is its height */
    assert_int_equal(read_leaves("v -1 0 0\nv 1 0 0\nv 0 3 0\nf 1 2 3\n", NULL, l), 1);
    assert_vec_near(l[0].center, 0, 1.5, 0, 1e-6);
    assert_vec_near(l[0].axis, 0, 1.5, 0, 1e-6);
    assert_vec_near(l[0].side, 1, 0, 0, 1e-6);
    assert_vec_near(l[0].normal, 0, 0, 1, 1e-6);
}

/* A blade with a petiole: stalk at (0, -0.2), tip at (0, 1.3), widest 0.6 at y = 0.5. */
static const char *const stalked_leaf = "# a stalked leaf\n"
                                        "v 0 -0.2 0\nv 0.02 0 0\nv -0.02 0 0\n"
                                        "v 0.3 0.5 0\nv 0 1.3 0\nv -0.3 0.5 0\n"
                                        "f 1 2 3\n"
                                        "f 3 2 4 5 6\n";

static void stalked_leaf_runs_from_its_stalk_to_its_tip(void **state)
{
    (void)state;
    xyl_leaf l[16];
    assert_int_equal(read_leaves(stalked_leaf, NULL, l), 1);
    assert_vec_near(l[0].center, 0, 0.55, 0, 1e-6);
    assert_vec_near(l[0].axis, 0, 0.75, 0, 1e-6);
    assert_vec_near(l[0].side, 0.3, 0, 0, 1e-6);
    assert_vec_near(l[0].normal, 0, 0, 1, 1e-6);
    /* hanging down (y negated, x negated to keep the winding): the stalk is the upper end
     * now, and only a stalk point says so */
    const char *hanging = "v 0 0.2 0\nv -0.02 0 0\nv 0.02 0 0\n"
                          "v -0.3 -0.5 0\nv 0 -1.3 0\nv 0.3 -0.5 0\n"
                          "f 1 2 3\nf 3 2 4 5 6\n";
    assert_int_equal(read_leaves(hanging, NULL, l), 1);
    assert_vec_near(l[0].axis, 0, 0.75, 0, 1e-6); /* lower end first: the wrong way round */
    xyl_leaf_mesh_desc d = {0};
    d.has_stalk_point = true;
    d.stalk_point = (xyl_vec3){0, 0.25f, 0};
    assert_int_equal(read_leaves(hanging, &d, l), 1);
    assert_vec_near(l[0].center, 0, -0.55, 0, 1e-6);
    assert_vec_near(l[0].axis, 0, -0.75, 0, 1e-6);
    assert_vec_near(l[0].side, -0.3, 0, 0, 1e-6);
    assert_vec_near(l[0].normal, 0, 0, 1, 1e-6);
}

static void slightly_bent_quad_passes_and_a_curved_leaf_does_not(void **state)
{
    (void)state;
    xyl_leaf l[16];
    /* one corner 0.05 up: 0.0125 of the length from the fitted plane */
    assert_int_equal(read_leaves("v 0 0 0\nv 1 0 0\nv 1 2 0.05\nv 0 2 0\nf 1 2 3\nf 1 3 4\n",
                                 NULL, l), 1);
    assert_true(l[0].normal.z > 0.999f);
    assert_near(len3(l[0].axis), 1.0, 1e-3);
    /* half a cylinder of radius 1, 8 strips of length 2 */
    char text[2048];
    int n = 0;
    for (int i = 0; i <= 8; ++i) {
        double a = PI * i / 8;
        n += snprintf(text + n, sizeof text - (size_t)n, "v %.9f %.9f 0\nv %.9f %.9f 2\n", cos(a),
                      sin(a), cos(a), sin(a));
    }
    n += snprintf(text + n, sizeof text - (size_t)n, "# the strips\n");
    for (int i = 0; i < 8; ++i)
        n += snprintf(text + n, sizeof text - (size_t)n, "f %d %d %d %d\n", 2 * i + 1, 2 * i + 3,
                      2 * i + 4, 2 * i + 2);
    expect_failure(text, strlen(text), NULL, XYL_ERR_INVALID_ARGUMENT, 20, 0);
    xyl_leaf_mesh_desc d = {0};
    d.planarity = 0.5f; /* now it is flat enough */
    assert_int_equal(read_leaves(text, &d, l), 1);
    assert_near(len3(l[0].axis), 1.0, 1e-5); /* 2 along z, 2 across: a square */
}

static void several_components_come_in_the_order_of_their_first_faces(void **state)
{
    (void)state;
    /* two triangles of one leaf sharing vertex 2, interleaved with a leaf of its own; a fourth
     * face touches the first leaf's vertices only by position, not by index */
    const char *text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                       "v 5 0 0\nv 7 0 0\nv 6 3 0\n"
                       "v 0 0 0\nv 1 0 0\nv 0 -1 0\n"
                       "f 5 6 7\n"
                       "f 1 2 3\n"
                       "f 2 4 3\n"
                       "f 8 10 9\n";
    xyl_leaf l[16];
    assert_int_equal(read_leaves(text, NULL, l), 3);
    assert_vec_near(l[0].center, 6, 1.5, 0, 1e-5);
    assert_vec_near(l[1].center, 0.5, 0.5, 0, 1e-5);
    assert_near(len3(l[1].axis), 0.5, 1e-5);
    /* a right triangle's long axis is along its hypotenuse */
    assert_vec_near(l[2].center, 0.25, -0.25, 0, 1e-5);
    /* with several leaves, each stalk is the end nearer the vertical line through the mesh's
     * centroid: tied here, so the lower end */
    assert_true(dot3(l[0].axis, (xyl_vec3){0, 1, 0}) > 0.0);
}

static void every_corner_form_comment_and_line_break_reads_alike(void **state)
{
    (void)state;
    const char *plain = "v -1 0 0\nv 1 0 0\nv 0 3 0\nf 1 2 3\n";
    const char *mixed = "# header\r\n\r\nmtllib a.mtl\r\no leaf\r\ng g1 g2\r\ns off\r\n"
                        "v -1 0 0 1\r\n  v\t1 0 0 0.5 0.5 0.5 # coloured\r\n"
                        "v 0 3e0 0 1 1 1 1\r\nvt 0 0\r\nvt 1 1\r\nvn 0 0 1\r\nvp 0.5\r\n"
                        "usemtl leaf\r\nl 1 2\r\np 3\r\n"
                        "f -3/1/1 2//1 3/2\r\n"
                        "v 9 9 9"; /* unused, and no final line break */
    xyl_leaf a[16], b[16];
    assert_int_equal(read_leaves(plain, NULL, a), 1);
    assert_int_equal(read_leaves(mixed, NULL, b), 1);
    assert_memory_equal(a, b, sizeof a[0]);
}

static void text_without_faces_gives_no_leaves(void **state)
{
    (void)state;
    const char *texts[] = {"", "\n\n", "# nothing\n", "v 1 2 3\nv 4 5 6\nv 7 8 9\n"};
    for (size_t i = 0; i < sizeof texts / sizeof texts[0]; ++i) {
        size_t n = 5;
        xyl_diag d = {0};
        assert_int_equal(xyl_foliage_leaves_from_obj(texts[i], strlen(texts[i]), NULL, NULL, 0,
                                                     &n, &d), XYL_OK);
        assert_int_equal(n, 0);
    }
    size_t n = 5;
    assert_int_equal(xyl_foliage_leaves_from_obj(NULL, 0, NULL, NULL, 0, &n, NULL), XYL_OK);
    assert_int_equal(n, 0);
}

static void texture_rectangle_comes_from_the_desc(void **state)
{
    (void)state;
    xyl_leaf_mesh_desc d = {0};
    d.uv[0] = 0.25f, d.uv[1] = 0.5f, d.uv[2] = 0.75f, d.uv[3] = 1.0f;
    xyl_leaf l[16];
    assert_int_equal(read_leaves(stalked_leaf, &d, l), 1);
    assert_memory_equal(l[0].uv, d.uv, sizeof d.uv);
}

/* ---- bad input ----------------------------------------------------------------------------- */

static void malformed_records_fail_with_their_line(void **state)
{
    (void)state;
    const char *tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    char buf[256];
    struct {
        const char *tail;
        xyl_result code;
        uint32_t line; /* of the whole text, tri's three lines first */
    } cases[] = {
        {"v 0 0\n", XYL_ERR_PARSE, 4},
        {"v 0 0", XYL_ERR_TRUNCATED, 4},
        {"v 0 x 0\n", XYL_ERR_PARSE, 4},
        {"v 0 0 0 0 0\n", XYL_ERR_PARSE, 4},
        {"v 0 0 0 1 1 1 1 1\n", XYL_ERR_PARSE, 4},
        {"v 1e 0 0\n", XYL_ERR_PARSE, 4},
        {"v 1.2.3 0 0\n", XYL_ERR_PARSE, 4},
        {"v nan 0 0\n", XYL_ERR_NON_FINITE, 4},
        {"v 0 -Inf 0\n", XYL_ERR_NON_FINITE, 4},
        {"v 0 0 2e6\n", XYL_ERR_LIMIT_EXCEEDED, 4},
        {"v 0 0 1e400\n", XYL_ERR_LIMIT_EXCEEDED, 4},
        {"f 1 2\n", XYL_ERR_PARSE, 4},
        {"f 1 2", XYL_ERR_TRUNCATED, 4},
        {"f 1 2 4\n", XYL_ERR_PARSE, 4},
        {"f 0 1 2\n", XYL_ERR_PARSE, 4},
        {"f -4 1 2\n", XYL_ERR_PARSE, 4},
        {"f 1/ 2 3\n", XYL_ERR_PARSE, 4},
        {"f 1/a 2 3\n", XYL_ERR_PARSE, 4},
        {"f 1/1/1/1 2 3\n", XYL_ERR_PARSE, 4},
        {"f 1//0 2 3\n", XYL_ERR_PARSE, 4},
        {"f 1/0 2 3\n", XYL_ERR_PARSE, 4},
        {"f 1// 2 3\n", XYL_ERR_PARSE, 4},
        {"f +1 2 3\n", XYL_ERR_PARSE, 4},
        {"f 1 2 3 \\\n", XYL_ERR_PARSE, 4},
        {"\n\nvx 1 2 3\n", XYL_ERR_PARSE, 6},
        {"F 1 2 3\n", XYL_ERR_PARSE, 4},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        snprintf(buf, sizeof buf, "%s%s", tri, cases[i].tail);
        expect_text_failure(buf, cases[i].code, cases[i].line);
    }
    /* a face before its vertices */
    expect_text_failure("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", XYL_ERR_PARSE, 1);
    /* a NUL byte */
    expect_failure("v 0 0 0\nv 1\0 0 0\n", 17, NULL, XYL_ERR_PARSE, 2, -1);
    /* the column points at the bad field */
    xyl_diag d = {0};
    size_t n;
    assert_int_equal(xyl_foliage_leaves_from_obj("v 0 x 0\n", 8, NULL, NULL, 0, &n, &d),
                     XYL_ERR_PARSE);
    assert_int_equal(d.column, 5);
}

static void degenerate_components_fail_with_their_index_and_line(void **state)
{
    (void)state;
    const char *good = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    char buf[256];
    /* collinear, then coincident, as the second component (line 8) */
    snprintf(buf, sizeof buf, "%sv 0 0 1\nv 1 1 1\nv 2 2 1\nf 4 5 6\n", good);
    expect_failure(buf, strlen(buf), NULL, XYL_ERR_INVALID_ARGUMENT, 8, 1);
    snprintf(buf, sizeof buf, "%sv 3 3 3\nv 3 3 3\nv 3 3 3\nf 4 5 6\n", good);
    expect_failure(buf, strlen(buf), NULL, XYL_ERR_INVALID_ARGUMENT, 8, 1);
    snprintf(buf, sizeof buf, "%sf 1 1 1\n", "v 0 0 0\n");
    expect_failure(buf, strlen(buf), NULL, XYL_ERR_INVALID_ARGUMENT, 2, 0);
}

static void limits_and_options_are_enforced(void **state)
{
    (void)state;
    const char *two = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nv 6 5 5\nv 5 6 5\nf 1 2 3\nf 4 5 6\n";
    xyl_leaf_mesh_desc d = {0};
    d.limits.max_leaves = 1;
    expect_failure(two, strlen(two), &d, XYL_ERR_LIMIT_EXCEEDED, 8, 1);
    d.limits.max_leaves = 2;
    xyl_leaf l[16];
    assert_int_equal(read_leaves(two, &d, l), 2);
    memset(&d, 0, sizeof d);
    d.limits.max_coordinate = 5.5f;
    expect_failure(two, strlen(two), &d, XYL_ERR_LIMIT_EXCEEDED, 5, -1);
    memset(&d, 0, sizeof d);
    d.limits.max_leaves = ((uint64_t)1 << 30) + 1;
    expect_failure(two, strlen(two), &d, XYL_ERR_INVALID_ARGUMENT, 0, -1);
    memset(&d, 0, sizeof d);
    d.planarity = -0.5f;
    expect_failure(two, strlen(two), &d, XYL_ERR_INVALID_ARGUMENT, 0, -1);
    d.planarity = NAN;
    expect_failure(two, strlen(two), &d, XYL_ERR_NON_FINITE, 0, -1);
    memset(&d, 0, sizeof d);
    d.has_stalk_point = true;
    d.stalk_point.y = INFINITY;
    expect_failure(two, strlen(two), &d, XYL_ERR_NON_FINITE, 0, -1);
    memset(&d, 0, sizeof d);
    d.uv[2] = 1.5f;
    expect_failure(two, strlen(two), &d, XYL_ERR_INVALID_ARGUMENT, 0, -1);
    /* vertices within the limit whose quad's half-axis is not */
    memset(&d, 0, sizeof d);
    d.limits.max_coordinate = 10.0f;
    const char *long_leaf = "v -10 -10 0\nv 10 10 0\nv -10 -9 0\nf 1 2 3\n";
    expect_failure(long_leaf, strlen(long_leaf), &d, XYL_ERR_LIMIT_EXCEEDED, 4, 0);
    /* too thin to have a plane */
    const char *thin = "v 0 0 0\nv 1 1e-30 0\nv 0 3e-30 0\nf 1 2 3\n";
    expect_failure(thin, strlen(thin), NULL, XYL_ERR_INVALID_ARGUMENT, 4, 0);
}

static void bad_arguments_and_small_capacity_write_nothing(void **state)
{
    (void)state;
    size_t n = 3;
    xyl_diag d = {0};
    assert_int_equal(xyl_foliage_leaves_from_obj(stalked_leaf, strlen(stalked_leaf), NULL, NULL,
                                                 0, NULL, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_leaves_from_obj(NULL, 4, NULL, NULL, 0, &n, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(n, 3);
    const char *two = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nv 6 5 5\nv 5 6 5\nf 1 2 3\nf 4 5 6\n";
    xyl_leaf l[2];
    memset(l, 0xcd, sizeof l);
    xyl_leaf before[2];
    memcpy(before, l, sizeof l);
    assert_int_equal(xyl_foliage_leaves_from_obj(two, strlen(two), NULL, l, 1, &n, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(n, 3);
    assert_memory_equal(l, before, sizeof l);
    assert_int_equal(xyl_foliage_leaves_from_obj(two, strlen(two), NULL, l, 2, &n, &d), XYL_OK);
    assert_int_equal(n, 2);
}

/* ---- the data files ------------------------------------------------------------------------ */

static void broadleaf_twig_gives_six_outward_leaves_that_build_a_foliage(void **state)
{
    (void)state;
    size_t size, n = 0;
    char *text = read_data("broadleaf.obj", &size);
    xyl_diag d = {0};
    assert_int_equal(xyl_foliage_leaves_from_obj(text, size, NULL, NULL, 0, &n, &d), XYL_OK);
    assert_int_equal(n, 6);
    xyl_leaf l[6], again[6];
    assert_int_equal(xyl_foliage_leaves_from_obj(text, size, NULL, l, 6, &n, &d), XYL_OK);
    assert_int_equal(xyl_foliage_leaves_from_obj(text, size, NULL, again, 6, &n, &d), XYL_OK);
    assert_memory_equal(l, again, sizeof l); /* the same bits */
    assert_int_equal(xyl_foliage_check_leaves(l, n, NULL, &d), XYL_OK);
    for (size_t i = 0; i < n; ++i) {
        /* leaf i (scripts/make_leaf_meshes.py): stalk near (0, 0.3 i, 0), tip out and up at
         * 30 degrees, length 1.15, blade width 0.45, facing away from the twig's top */
        double turn = 137.5 * (double)i * PI / 180.0;
        xyl_vec3 tip = {(float)(cos(turn) * cos(PI / 6)), 0.5f,
                        (float)(sin(turn) * cos(PI / 6))};
        assert_true(dot3(l[i].axis, tip) / len3(l[i].axis) > 0.999);
        assert_near(2 * len3(l[i].axis), 1.15, 0.01);
        assert_near(2 * len3(l[i].side), 0.45, 0.01);
        xyl_vec3 stalk = {l[i].center.x - l[i].axis.x, l[i].center.y - l[i].axis.y,
                          l[i].center.z - l[i].axis.z};
        assert_near(stalk.x * stalk.x + stalk.z * stalk.z, 0.0, 0.03 * 0.03);
        assert_near(stalk.y, 0.3 * (double)i, 0.03);
        xyl_vec3 up = {(float)(-sin(PI / 6) * cos(turn)), (float)cos(PI / 6),
                       (float)(-sin(PI / 6) * sin(turn))};
        assert_true(dot3(l[i].normal, up) > 0.99);
    }
    xyl_foliage_desc fd = {0};
    fd.leaves = l;
    fd.leaf_count = n;
    xyl_foliage *f = NULL;
    assert_int_equal(xyl_foliage_build(&fd, &f, &d), XYL_OK);
    assert_int_equal(f->original_count, 6);
    xyl_foliage_destroy(f);
    free(text);
}

static void template_leaf_and_card_reduce_to_their_own_quads(void **state)
{
    (void)state;
    size_t size, n = 0;
    char *text = read_data("template_leaf.obj", &size); /* CRLF line breaks */
    xyl_leaf l[1];
    xyl_diag d = {0};
    assert_int_equal(xyl_foliage_leaves_from_obj(text, size, NULL, l, 1, &n, &d), XYL_OK);
    assert_int_equal(n, 1);
    assert_vec_near(l[0].axis, 0, 0.575, 0, 2e-3);
    assert_vec_near(l[0].center, 0, 0.575, -0.01, 0.01);
    assert_near(2 * len3(l[0].side), 0.45, 1e-4);
    assert_true(l[0].normal.z > 0.99f);
    free(text);
    text = read_data("card.obj", &size);
    assert_int_equal(xyl_foliage_leaves_from_obj(text, size, NULL, l, 1, &n, &d), XYL_OK);
    assert_vec_near(l[0].center, 0, 1, 0, 1e-6);
    assert_vec_near(l[0].axis, 0, 1, 0, 1e-6);
    assert_vec_near(l[0].side, 0.5, 0, 0, 1e-6);
    assert_vec_near(l[0].normal, 0, 0, 1, 1e-6);
    free(text);
}

static void every_allocation_failure_is_reported_and_freed(void **state)
{
    (void)state;
    size_t size;
    char *text = read_data("broadleaf.obj", &size);
    xyl_leaf l[6];
    for (size_t k = 1;; ++k) {
        tu_counter c = {0, 0, 0, k};
        xyl_leaf_mesh_desc d = {0};
        d.alloc = tu_counting(&c);
        size_t n = 0;
        xyl_result r = xyl_foliage_leaves_from_obj(text, size, &d, l, 6, &n, NULL);
        assert_int_equal(c.allocs, c.frees);
        if (r == XYL_OK) {
            assert_true(c.attempts < k);
            assert_int_equal(n, 6);
            break;
        }
        assert_int_equal(r, XYL_ERR_OUT_OF_MEMORY);
        assert_int_equal(n, 0);
    }
    free(text);
}

/* ---- a template leaf ------------------------------------------------------------------------ */

static void template_leaf_gives_the_shape_of_every_attachment(void **state)
{
    (void)state;
    size_t size, n = 0;
    char *text = read_data("template_leaf.obj", &size);
    xyl_leaf tmpl;
    xyl_diag d = {0};
    assert_int_equal(xyl_foliage_leaves_from_obj(text, size, NULL, &tmpl, 1, &n, &d), XYL_OK);
    free(text);
    xyl_foliage_leaves_desc ld = {0};
    ld.shape.seed = 7;
    assert_int_equal(xyl_leaf_shape_from_template(&tmpl, NULL, &ld.shape, &d), XYL_OK);
    assert_near(ld.shape.aspect, 0.45 / 1.15, 1e-4);
    assert_near(ld.shape.stalk, 0.0, 1e-6); /* the petiole is part of the mesh */
    assert_true(ld.shape.uv[2] == 1.0f && ld.shape.uv[3] == 1.0f);
    assert_true(ld.shape.seed == 7);
    /* placed at an attachment of size 2 heading +y, facing +z: the template, scaled by 2 / 1.15 */
    xyl_skel_node nodes[1] = {{{0, 0, 0}, 0.1f, -1, 0, 0}};
    xyl_skel_leaf at[1] = {{{1, 2, 3}, {0, 1, 0}, {-1, 0, 0}, {0, 0, 1}, 2.0f, 0}};
    xyl_skeleton sk;
    memset(&sk, 0, sizeof sk);
    sk.nodes = nodes;
    sk.node_count = 1;
    sk.leaves = at;
    sk.leaf_count = 1;
    xyl_leaf l;
    assert_int_equal(xyl_foliage_leaves_from_skeleton(&sk, &ld, &l, 1, &n, &d), XYL_OK);
    assert_vec_near(l.center, 1, 3, 3, 1e-4);
    assert_vec_near(l.axis, 0, 1, 0, 1e-4);
    assert_near(len3(l.side), 0.45 / 1.15, 1e-4);
    /* a stalk point below the stalked leaf's stalk end: 1 of its 1.5 long */
    xyl_leaf s[16];
    assert_int_equal(read_leaves(stalked_leaf, NULL, s), 1);
    xyl_vec3 below = {0, -1.2f, 0};
    assert_int_equal(xyl_leaf_shape_from_template(&s[0], &below, &ld.shape, &d), XYL_OK);
    assert_near(ld.shape.stalk, 1.0 / 1.5, 1e-6);
    assert_near(ld.shape.aspect, 0.3 / 0.75, 1e-6);
}

static void template_shape_rejects_bad_templates_and_leaves_the_shape_alone(void **state)
{
    (void)state;
    xyl_leaf s[16];
    assert_int_equal(read_leaves(stalked_leaf, NULL, s), 1);
    xyl_leaf_shape shape, before;
    memset(&shape, 0x33, sizeof shape);
    memcpy(&before, &shape, sizeof shape);
    xyl_diag d = {0};
    assert_int_equal(xyl_leaf_shape_from_template(NULL, NULL, &shape, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_leaf_shape_from_template(&s[0], NULL, NULL, &d), XYL_ERR_INVALID_ARGUMENT);
    xyl_vec3 inside = {0, 0.5f, 0}, nan_point = {0, NAN, 0};
    assert_int_equal(xyl_leaf_shape_from_template(&s[0], &inside, &shape, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_leaf_shape_from_template(&s[0], &nan_point, &shape, &d),
                     XYL_ERR_NON_FINITE);
    xyl_leaf flat = s[0];
    flat.side = (xyl_vec3){0, 0, 0};
    assert_int_equal(xyl_leaf_shape_from_template(&flat, NULL, &shape, &d), XYL_ERR_INVALID_ARGUMENT);
    xyl_leaf bad = s[0];
    bad.center.x = INFINITY;
    assert_int_equal(xyl_leaf_shape_from_template(&bad, NULL, &shape, &d), XYL_ERR_NON_FINITE);
    assert_memory_equal(&shape, &before, sizeof shape);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(unit_square_is_its_own_quad),
        cmocka_unit_test(rotated_rectangle_is_its_own_quad_along_its_length),
        cmocka_unit_test(triangle_reduces_to_its_bounding_rectangle_from_the_base),
        cmocka_unit_test(stalked_leaf_runs_from_its_stalk_to_its_tip),
        cmocka_unit_test(slightly_bent_quad_passes_and_a_curved_leaf_does_not),
        cmocka_unit_test(several_components_come_in_the_order_of_their_first_faces),
        cmocka_unit_test(every_corner_form_comment_and_line_break_reads_alike),
        cmocka_unit_test(text_without_faces_gives_no_leaves),
        cmocka_unit_test(texture_rectangle_comes_from_the_desc),
        cmocka_unit_test(malformed_records_fail_with_their_line),
        cmocka_unit_test(degenerate_components_fail_with_their_index_and_line),
        cmocka_unit_test(limits_and_options_are_enforced),
        cmocka_unit_test(bad_arguments_and_small_capacity_write_nothing),
        cmocka_unit_test(broadleaf_twig_gives_six_outward_leaves_that_build_a_foliage),
        cmocka_unit_test(template_leaf_and_card_reduce_to_their_own_quads),
        cmocka_unit_test(every_allocation_failure_is_reported_and_freed),
        cmocka_unit_test(template_leaf_gives_the_shape_of_every_attachment),
        cmocka_unit_test(template_shape_rejects_bad_templates_and_leaves_the_shape_alone),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

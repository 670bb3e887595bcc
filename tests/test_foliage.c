/* foliage/: leaves from skeletons and from the caller, and their GPU record. */
#define _POSIX_C_SOURCE 200809L

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
#include "foliage_internal.h"
#include "test_util.h"
#include <sys/stat.h>
#include <unistd.h>

/* ---- helpers ------------------------------------------------------------------------------- */

static double len3(xyl_vec3 v)
{
    return sqrt((double)v.x * v.x + (double)v.y * v.y + (double)v.z * v.z);
}

static double dot3(xyl_vec3 a, xyl_vec3 b)
{
    return (double)a.x * b.x + (double)a.y * b.y + (double)a.z * b.z;
}

static xyl_vec3 cross3(xyl_vec3 a, xyl_vec3 b)
{
    xyl_vec3 r = {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
    return r;
}

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

/* A leaf in the plane z = cz facing +z: axis along +y, side along +x. */
static xyl_leaf flat_leaf(float x, float y, float cz, float half_length, float half_width)
{
    xyl_leaf l = {0};
    l.center = (xyl_vec3){x, y, cz};
    l.normal = (xyl_vec3){0, 0, 1};
    l.axis = (xyl_vec3){0, half_length, 0};
    l.side = (xyl_vec3){half_width, 0, 0};
    l.node = -1;
    return l;
}

static xyl_skel_leaf attachment(float x, float y, float z, float size, int32_t node)
{
    /* heading +y, left -x, up = heading x left = +z */
    xyl_skel_leaf a = {{x, y, z}, {0, 1, 0}, {-1, 0, 0}, {0, 0, 1}, size, node};
    return a;
}

/* A skeleton view built by hand: two nodes, the given attachments. */
typedef struct view_skeleton {
    xyl_skel_node nodes[2];
    xyl_skeleton view;
} view_skeleton;

static void make_view(view_skeleton *v, const xyl_skel_leaf *leaves, size_t count)
{
    memset(v, 0, sizeof *v);
    v->nodes[0] = (xyl_skel_node){{0, 0, 0}, 0.1f, -1, 0, 0};
    v->nodes[1] = (xyl_skel_node){{0, 1, 0}, 0.1f, 0, 0, 0};
    v->view.nodes = v->nodes;
    v->view.node_count = 2;
    v->view.leaves = leaves;
    v->view.leaf_count = count;
}

static xyl_result from_view(const xyl_skel_leaf *att, size_t count, const xyl_foliage_leaves_desc *d,
                            xyl_leaf *out, size_t *n, xyl_diag *diag)
{
    view_skeleton v;
    make_view(&v, att, count);
    return xyl_foliage_leaves_from_skeleton(&v.view, d, out, count, n, diag);
}

/* ---- leaves from a skeleton ------------------------------------------------------------------ */

static void leaves_from_skeleton_put_the_blade_along_heading_facing_up(void **state)
{
    (void)state;
    xyl_skel_leaf att[2] = {attachment(1, 2, 3, 0.4f, 1), attachment(0, 0, 0, 1.0f, -1)};
    xyl_foliage_leaves_desc d = {0};
    d.shape.aspect = 0.25f;
    d.shape.stalk = 0.5f;
    xyl_leaf out[2];
    size_t n = 0;
    xyl_diag diag = {0};
    assert_int_equal(from_view(att, 2, &d, out, &n, &diag), XYL_OK);
    assert_int_equal(n, 2);
    /* base 0.5 * 0.4 past the attachment, centre half a length further */
    assert_vec_near(out[0].center, 1, 2 + 0.2 + 0.2, 3, 1e-6);
    assert_vec_near(out[0].axis, 0, 0.2, 0, 1e-7);
    assert_vec_near(out[0].normal, 0, 0, 1, 1e-7);
    assert_vec_near(out[0].side, 0.05, 0, 0, 1e-7); /* -left, a quarter of the length wide */
    assert_int_equal(out[0].count, 1);
    assert_int_equal(out[0].node, 1);
    assert_int_equal(out[1].node, -1);
    const float unit_rect[4] = {0, 0, 1, 1};
    assert_memory_equal(out[0].uv, unit_rect, sizeof unit_rect);
    xyl_vec3 c = cross3(out[0].side, out[0].axis);
    assert_true(dot3(c, out[0].normal) > 0.0);
    assert_int_equal(xyl_foliage_check_leaves(out, 2, NULL, &diag), XYL_OK);
}

static void leaves_from_skeleton_count_then_fill(void **state)
{
    (void)state;
    xyl_skel_leaf att[3] = {attachment(0, 0, 0, 1, 0), attachment(1, 0, 0, 1, 0),
                            attachment(2, 0, 0, 1, 1)};
    view_skeleton v;
    make_view(&v, att, 3);
    size_t n = 0;
    assert_int_equal(xyl_foliage_leaves_from_skeleton(&v.view, NULL, NULL, 0, &n, NULL), XYL_OK);
    assert_int_equal(n, 3);
    xyl_leaf out[3];
    memset(out, 0xab, sizeof out);
    xyl_leaf before[3];
    memcpy(before, out, sizeof out);
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_leaves_from_skeleton(&v.view, NULL, out, 2, &n, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_memory_equal(out, before, sizeof out);
    assert_int_equal(xyl_foliage_leaves_from_skeleton(&v.view, NULL, out, 3, &n, &diag), XYL_OK);
    assert_near(out[2].center.x, 2.0, 0.0);
}

static void leaves_from_a_skeleton_without_attachments_are_none(void **state)
{
    (void)state;
    view_skeleton v; /* a real skeleton this time, made from the view's nodes */
    make_view(&v, NULL, 0);
    xyl_skeleton_desc sd = {0};
    sd.nodes = v.nodes;
    sd.node_count = v.view.node_count;
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_skeleton_create(&sd, &sk, NULL), XYL_OK);
    size_t n = 99;
    xyl_leaf out[1];
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, NULL, NULL, 0, &n, &diag), XYL_OK);
    assert_int_equal(n, 0);
    n = 99;
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, NULL, out, 1, &n, &diag), XYL_OK);
    assert_int_equal(n, 0);
    xyl_skeleton_destroy(sk);
}

static void leaves_from_skeleton_jitter_depends_on_seed_and_index_only(void **state)
{
    (void)state;
    enum { N = 64 };
    xyl_skel_leaf att[N];
    for (int i = 0; i < N; ++i) att[i] = attachment((float)i, 0, 0, 1.0f, 0);
    xyl_foliage_leaves_desc d = {0};
    d.shape.size_jitter = 0.3f;
    d.shape.roll_jitter = 1.0f;
    d.shape.seed = 42;
    xyl_leaf a[N], b[N], c[N], tail[N];
    size_t n;
    assert_int_equal(from_view(att, N, &d, a, &n, NULL), XYL_OK);
    assert_int_equal(from_view(att, N, &d, b, &n, NULL), XYL_OK);
    assert_memory_equal(a, b, sizeof a);
    d.shape.seed = 43;
    assert_int_equal(from_view(att, N, &d, c, &n, NULL), XYL_OK);
    assert_true(memcmp(a, c, sizeof a) != 0);
    d.shape.seed = 42; /* another first leaf changes nothing of the others' */
    att[0] = attachment(-5, 1, 2, 3.0f, 1);
    assert_int_equal(from_view(att, N, &d, tail, &n, NULL), XYL_OK);
    assert_memory_equal(a + 1, tail + 1, (N - 1) * sizeof *a);
    int rolled = 0, resized = 0;
    for (int i = 0; i < N; ++i) {
        double half = len3(a[i].axis);
        assert_true(half >= 0.5 * 0.7 - 1e-6 && half <= 0.5 * 1.3 + 1e-6);
        resized += fabs(half - 0.5) > 1e-3;
        /* roll turns the normal about the axis, by at most 1 radian */
        double cosine = dot3(a[i].normal, (xyl_vec3){0, 0, 1});
        assert_true(cosine >= cos(1.0) - 1e-6);
        rolled += cosine < 1.0 - 1e-6;
        assert_near(dot3(a[i].normal, a[i].axis), 0.0, 1e-6);
        assert_near(len3(a[i].side), 0.5 * half, 1e-6);
    }
    assert_true(rolled > N / 2 && resized > N / 2);
    assert_int_equal(xyl_foliage_check_leaves(a, N, NULL, NULL), XYL_OK);
}

static void leaves_from_skeleton_reject_bad_shape_options(void **state)
{
    (void)state;
    xyl_skel_leaf att[1] = {attachment(0, 0, 0, 1, 0)};
    struct {
        int field;
        float value;
        xyl_result code;
    } cases[] = {
        {0, -1.0f, XYL_ERR_INVALID_ARGUMENT}, {0, NAN, XYL_ERR_NON_FINITE},
        {1, -0.1f, XYL_ERR_INVALID_ARGUMENT}, {1, INFINITY, XYL_ERR_NON_FINITE},
        {2, 1.0f, XYL_ERR_INVALID_ARGUMENT},  {2, -0.5f, XYL_ERR_INVALID_ARGUMENT},
        {3, 4.0f, XYL_ERR_INVALID_ARGUMENT},  {3, -1.0f, XYL_ERR_INVALID_ARGUMENT},
        {4, 1.5f, XYL_ERR_INVALID_ARGUMENT},  {4, NAN, XYL_ERR_NON_FINITE},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        xyl_foliage_leaves_desc d = {0};
        float *fields[5] = {&d.shape.aspect, &d.shape.stalk, &d.shape.size_jitter,
                            &d.shape.roll_jitter, &d.shape.uv[2]};
        *fields[cases[k].field] = cases[k].value;
        xyl_leaf out[1];
        size_t n = 7;
        xyl_diag diag = {0};
        xyl_result r = from_view(att, 1, &d, out, &n, &diag);
        if (r != cases[k].code)
            fail_msg("case %zu: got %s, want %s", k, xyl_result_string(r),
                     xyl_result_string(cases[k].code));
        assert_int_equal(n, 7);
        assert_true(strlen(diag.message) > 0);
    }
}

static void leaves_from_skeleton_reject_each_bad_attachment_with_its_code(void **state)
{
    (void)state;
    xyl_skel_leaf good = attachment(0, 0, 0, 1, 0);
    struct {
        xyl_skel_leaf leaf;
        xyl_result code;
    } cases[] = {
        {good, XYL_OK},
        {good, XYL_ERR_NON_FINITE},
        {good, XYL_ERR_NON_FINITE},
        {good, XYL_ERR_INVALID_ARGUMENT},
        {good, XYL_ERR_INVALID_ARGUMENT},
        {good, XYL_ERR_INVALID_ARGUMENT},
        {good, XYL_ERR_INVALID_ARGUMENT},
        {good, XYL_ERR_LIMIT_EXCEEDED},
        {good, XYL_ERR_LIMIT_EXCEEDED},
    };
    cases[1].leaf.pos.y = NAN;
    cases[2].leaf.size = INFINITY;
    cases[3].leaf.size = 0.0f;
    cases[4].leaf.up = cases[4].leaf.heading; /* parallel: no plane */
    cases[5].leaf.heading = (xyl_vec3){0, 0, 0};
    cases[6].leaf.node = 2; /* the view has 2 nodes */
    cases[7].leaf.pos.x = 2e6f;
    cases[8].leaf.size = 3e6f;
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        xyl_skel_leaf att[3] = {good, cases[k].leaf, good};
        xyl_leaf out[3];
        memset(out, 0x5a, sizeof out);
        xyl_leaf before[3];
        memcpy(before, out, sizeof out);
        size_t n = 0;
        xyl_diag diag = {0};
        xyl_result r = from_view(att, 3, NULL, out, &n, &diag);
        if (r != cases[k].code)
            fail_msg("case %zu: got %s (%s), want %s", k, xyl_result_string(r), diag.message,
                     xyl_result_string(cases[k].code));
        if (r == XYL_OK) continue;
        assert_int_equal(diag.index, 1);
        assert_memory_equal(out, before, sizeof out); /* nothing written */
    }
}

static void leaves_from_skeleton_respect_the_leaf_limit(void **state)
{
    (void)state;
    xyl_skel_leaf att[3] = {attachment(0, 0, 0, 1, 0), attachment(0, 0, 0, 1, 0),
                            attachment(0, 0, 0, 1, 0)};
    xyl_foliage_leaves_desc d = {0};
    d.limits.max_leaves = 2;
    size_t n = 0;
    xyl_diag diag = {0};
    view_skeleton v;
    make_view(&v, att, 3);
    assert_int_equal(xyl_foliage_leaves_from_skeleton(&v.view, &d, NULL, 0, &n, &diag),
                     XYL_ERR_LIMIT_EXCEEDED);
    d.limits.max_leaves = 3;
    assert_int_equal(xyl_foliage_leaves_from_skeleton(&v.view, &d, NULL, 0, &n, &diag), XYL_OK);
    d.limits.max_leaves = ((uint64_t)1 << 30) + 1;
    assert_int_equal(xyl_foliage_leaves_from_skeleton(&v.view, &d, NULL, 0, &n, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_leaves_from_skeleton(NULL, NULL, NULL, 0, &n, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_leaves_from_skeleton(&v.view, NULL, NULL, 0, NULL, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
}

static void leaves_from_the_default_tree_pass_the_leaf_rules(void **state)
{
    (void)state;
    xyl_grammar *g = tu_parse(xyl_lsystem_preset_source(xyl_lsystem_default_preset()));
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_lsystem_derive(g, NULL, &s, NULL), XYL_OK);
    assert_int_equal(xyl_lsystem_interpret(g, s, NULL, &sk, NULL), XYL_OK);
    size_t n = 0;
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, NULL, NULL, 0, &n, NULL), XYL_OK);
    assert_int_equal(n, sk->leaf_count);
    xyl_leaf *out = malloc((n ? n : 1) * sizeof *out);
    assert_non_null(out);
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, NULL, out, n, &n, NULL), XYL_OK);
    assert_int_equal(xyl_foliage_check_leaves(out, n, NULL, NULL), XYL_OK);
    free(out);
    xyl_skeleton_destroy(sk);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
}

/* ---- the caller's leaves ------------------------------------------------------------------- */

static void check_leaves_accepts_coincident_and_coplanar_leaves(void **state)
{
    (void)state;
    xyl_leaf l[4] = {flat_leaf(0, 0, 0, 1, 0.5f), flat_leaf(0, 0, 0, 1, 0.5f),
                     flat_leaf(3, 0, 0, 1, 0.5f), flat_leaf(0, 3, 0, 2, 0.1f)};
    assert_int_equal(xyl_foliage_check_leaves(l, 4, NULL, NULL), XYL_OK);
    assert_int_equal(xyl_foliage_check_leaves(NULL, 0, NULL, NULL), XYL_OK);
}

static void check_leaves_rejects_each_bad_leaf_with_its_code(void **state)
{
    (void)state;
    xyl_leaf good = flat_leaf(1, 2, 3, 1, 0.5f);
    enum { CASES = 15 };
    xyl_leaf bad[CASES];
    xyl_result code[CASES];
    for (int k = 0; k < CASES; ++k) bad[k] = good;
    int k = 0;
    bad[k].center.x = NAN, code[k++] = XYL_ERR_NON_FINITE;
    bad[k].axis.z = INFINITY, code[k++] = XYL_ERR_NON_FINITE;
    bad[k].uv[1] = NAN, code[k++] = XYL_ERR_NON_FINITE;
    bad[k].axis = (xyl_vec3){0, 0, 0}, code[k++] = XYL_ERR_INVALID_ARGUMENT;   /* size 0 */
    bad[k].side = (xyl_vec3){0, 0, 0}, code[k++] = XYL_ERR_INVALID_ARGUMENT;   /* size 0 */
    bad[k].normal = (xyl_vec3){0, 0, 0}, code[k++] = XYL_ERR_INVALID_ARGUMENT;
    bad[k].side = (xyl_vec3){0.5f, 0.01f, 0}, code[k++] = XYL_ERR_INVALID_ARGUMENT; /* skew */
    bad[k].normal = (xyl_vec3){0, 0.01f, 1}, code[k++] = XYL_ERR_INVALID_ARGUMENT;
    bad[k].side.x = -0.5f, code[k++] = XYL_ERR_INVALID_ARGUMENT;               /* mirrored */
    bad[k].uv[2] = 1.5f, code[k++] = XYL_ERR_INVALID_ARGUMENT;
    bad[k].node = -2, code[k++] = XYL_ERR_INVALID_ARGUMENT;
    bad[k].center.z = -1.5e6f, code[k++] = XYL_ERR_LIMIT_EXCEEDED;           /* huge */
    bad[k].axis.y = 2e6f, code[k++] = XYL_ERR_LIMIT_EXCEEDED;
    bad[k].center.y = 3e38f, code[k++] = XYL_ERR_LIMIT_EXCEEDED;
    bad[k].normal = (xyl_vec3){0, 0, 5}, code[k++] = XYL_OK; /* any length: normalised */
    assert_int_equal(k, CASES);
    for (k = 0; k < CASES; ++k) {
        xyl_leaf l[3] = {good, bad[k], good};
        xyl_diag diag = {0};
        xyl_result r = xyl_foliage_check_leaves(l, 3, NULL, &diag);
        if (r != code[k])
            fail_msg("case %d: got %s (%s), want %s", k, xyl_result_string(r), diag.message,
                     xyl_result_string(code[k]));
        if (r != XYL_OK) {
            assert_int_equal(diag.index, 1);
            assert_int_equal(diag.code, r);
        }
    }
}

static void check_leaves_tolerates_rounding_and_the_build_squares_it(void **state)
{
    (void)state;
    xyl_leaf l = flat_leaf(0, 0, 0, 1, 0.5f);
    l.side.y = 2e-4f; /* |cos| 4e-4: within 1e-3 */
    l.normal.x = 3e-4f;
    assert_int_equal(xyl_foliage_check_leaves(&l, 1, NULL, NULL), XYL_OK);
    xyl_leaf t = xyl__leaf_tidy(&l);
    assert_near(len3(t.normal), 1.0, 1e-7);
    assert_near(dot3(t.normal, t.axis), 0.0, 1e-7);
    assert_near(dot3(t.normal, t.side), 0.0, 1e-7);
    assert_near(dot3(t.axis, t.side), 0.0, 1e-7);
    assert_near(len3(t.axis), len3(l.axis), 1e-7);
    assert_near(len3(t.side), len3(l.side), 1e-7);
    assert_int_equal(t.count, 1);
    assert_true(t.uv[2] == 1.0f && t.uv[3] == 1.0f);
}

static void check_leaves_limits_counts_and_their_sum(void **state)
{
    (void)state;
    xyl_leaf l[3] = {flat_leaf(0, 0, 0, 1, 1), flat_leaf(0, 0, 0, 1, 1), flat_leaf(0, 0, 0, 1, 1)};
    xyl_foliage_limits lim = {0};
    lim.max_leaves = 2;
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_check_leaves(l, 3, &lim, &diag), XYL_ERR_LIMIT_EXCEEDED);
    lim.max_leaves = 0;
    lim.max_coordinate = 0.5f;
    assert_int_equal(xyl_foliage_check_leaves(l, 3, &lim, &diag), XYL_ERR_LIMIT_EXCEEDED);
    lim.max_coordinate = -1.0f;
    assert_int_equal(xyl_foliage_check_leaves(l, 3, &lim, &diag), XYL_ERR_INVALID_ARGUMENT);
    l[0].count = UINT32_MAX - 1;
    l[1].count = 1;
    assert_int_equal(xyl_foliage_check_leaves(l, 2, NULL, &diag), XYL_OK);
    assert_int_equal(xyl_foliage_check_leaves(l, 3, NULL, &diag), XYL_ERR_LIMIT_EXCEEDED);
    assert_int_equal(diag.index, 2);
    assert_int_equal(xyl_foliage_check_leaves(NULL, 1, NULL, &diag), XYL_ERR_INVALID_ARGUMENT);
}

/* ---- the GPU record ------------------------------------------------------------------------ */

static uint64_t next_random(uint64_t *state)
{
    /* xorshift64*: deterministic, seeded by the caller */
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    return *state * UINT64_C(2685821657736338717);
}

static double uniform(uint64_t *state, double lo, double hi)
{
    return lo + (hi - lo) * (double)(next_random(state) >> 11) * (1.0 / 9007199254740992.0);
}

static void half_floats_round_trip_every_finite_half_exactly(void **state)
{
    (void)state;
    for (uint32_t h = 0; h < 0x10000u; ++h) {
        if ((h & 0x7c00u) == 0x7c00u) continue; /* inf, NaN */
        float f = xyl__float_from_half((uint16_t)h);
        if (xyl__half_from_float(f) != h) fail_msg("half 0x%04x -> %g -> 0x%04x", h, (double)f,
                                                   xyl__half_from_float(f));
    }
    /* ties go to the even neighbour; past 65504 it overflows */
    assert_int_equal(xyl__half_from_float(1.0f + 1.0f / 2048.0f), 0x3c00); /* 1 + 2^-11: to 1 */
    assert_int_equal(xyl__half_from_float(1.0f + 3.0f / 2048.0f), 0x3c02);
    assert_int_equal(xyl__half_from_float(65519.0f), 0x7bff);
    assert_int_equal(xyl__half_from_float(65520.0f), 0x7c00);
    assert_int_equal(xyl__half_from_float(ldexpf(1.0f, -25)), 0x0000); /* tie to even 0 */
    assert_int_equal(xyl__half_from_float(ldexpf(1.5f, -25)), 0x0001);
    assert_int_equal(xyl__half_from_float(ldexpf(3.0f, -25)), 0x0002); /* 1.5 ulp: to even 2 */
    assert_int_equal(xyl__half_from_float(-0.0f), 0x8000);
}

#if defined(__FLT16_MAX__)
static void half_floats_match_the_compilers_conversion(void **state)
{
    (void)state;
    uint64_t rng = 7;
    for (int i = 0; i < (SANITIZED ? 200000 : 2000000); ++i) {
        uint32_t bits = (uint32_t)(next_random(&rng) >> 32);
        /* exponents around the half range, where the rounding happens */
        bits = (bits & 0x807fffffu) | ((uint32_t)(96 + (bits >> 23) % 50) << 23);
        float f;
        memcpy(&f, &bits, sizeof f);
        _Float16 h = (_Float16)f;
        uint16_t want;
        memcpy(&want, &h, sizeof want);
        if (xyl__half_from_float(f) != want)
            fail_msg("%a: 0x%04x, the compiler says 0x%04x", (double)f, xyl__half_from_float(f), want);
    }
}
#endif

/* A leaf at c facing n (unit), its axis turned by roll about n. */
static xyl_leaf oriented_leaf(xyl_vec3 c, xyl_vec3 n, double roll, double half_length, double half_width)
{
    xyl_vec3 t = fabsf(n.x) < 0.9f ? (xyl_vec3){1, 0, 0} : (xyl_vec3){0, 1, 0};
    xyl_vec3 u = cross3(n, t);
    double lu = len3(u);
    u = (xyl_vec3){(float)(u.x / lu), (float)(u.y / lu), (float)(u.z / lu)};
    xyl_vec3 v = cross3(n, u);
    xyl_vec3 a = {(float)(cos(roll) * u.x + sin(roll) * v.x), (float)(cos(roll) * u.y + sin(roll) * v.y),
                  (float)(cos(roll) * u.z + sin(roll) * v.z)};
    xyl_vec3 s = cross3(a, n);
    xyl_leaf l = {0};
    l.center = c;
    l.normal = n;
    l.axis = (xyl_vec3){(float)(a.x * half_length), (float)(a.y * half_length), (float)(a.z * half_length)};
    l.side = (xyl_vec3){(float)(s.x * half_width), (float)(s.y * half_width), (float)(s.z * half_width)};
    l.node = -1;
    return xyl__leaf_tidy(&l);
}

static xyl_leaf random_leaf(uint64_t *rng)
{
    /* a frame from a random rotation, half-axes from 1e-6 to 1e4 */
    double a = uniform(rng, 0, 6.283185307179586), b = uniform(rng, -1, 1);
    double roll = uniform(rng, 0, 6.283185307179586);
    double r = sqrt(1 - b * b);
    xyl_vec3 n = {(float)(r * cos(a)), (float)b, (float)(r * sin(a))};
    double la = pow(10.0, uniform(rng, -6, 4)), ls = la * uniform(rng, 0.05, 2);
    xyl_vec3 c = {(float)uniform(rng, -1e5, 1e5), (float)uniform(rng, -10, 10),
                  (float)uniform(rng, -1e-3, 1e-3)};
    xyl_leaf l = oriented_leaf(c, n, roll, la, ls);
    for (int k = 0; k < 4; ++k) l.uv[k] = (float)uniform(rng, 0, 1);
    return l;
}

/* The stated bounds: relative 2^-11 from 2^-14 up, absolute 2^-25 below. */
static void assert_half_close(float got, float want)
{
    double err = fabs((double)got - (double)want), a = fabs((double)want);
    double bound = a >= ldexp(1.0, -14) ? ldexp(a, -11) : ldexp(1.0, -25);
    if (!(err <= bound)) fail_msg("%.9g came back as %.9g (error %g > %g)", (double)want, (double)got, err, bound);
}

static void pack_gpu_round_trip_keeps_the_stated_precision(void **state)
{
    (void)state;
    enum { N = 4096 };
    xyl_leaf *in = malloc(N * sizeof *in);
    xyl_foliage_gpu_leaf *gpu = malloc(N * sizeof *gpu);
    assert_true(in && gpu);
    uint64_t rng = 99;
    for (int i = 0; i < N; ++i) in[i] = random_leaf(&rng);
    in[0].uv[0] = 0.0f, in[0].uv[3] = 1.0f;
    assert_int_equal(xyl_foliage_check_leaves(in, N, NULL, NULL), XYL_OK);
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_pack_gpu(in, N, gpu, &diag), XYL_OK);
    double worst_normal = 0.0;
    for (int i = 0; i < N; ++i) {
        xyl_leaf o = xyl__foliage_unpack_gpu(&gpu[i]);
        assert_memory_equal(&o.center, &in[i].center, sizeof o.center); /* exact */
        const float *g = &o.axis.x, *w = &in[i].axis.x;
        for (int k = 0; k < 3; ++k) assert_half_close(g[k], w[k]);
        g = &o.side.x, w = &in[i].side.x;
        for (int k = 0; k < 3; ++k) assert_half_close(g[k], w[k]);
        for (int k = 0; k < 4; ++k) assert_true(fabs((double)o.uv[k] - in[i].uv[k]) <= 0.5 / 65535.0 + 1e-9);
        double cosine = dot3(o.normal, in[i].normal);
        if (len3(in[i].side) >= ldexp(1.0, -14) && len3(in[i].axis) >= ldexp(1.0, -14))
            worst_normal = fmax(worst_normal, acos(fmin(1.0, cosine)));
    }
    assert_true(gpu[0].uv[0] == 0 && gpu[0].uv[3] == 65535);
    /* the normal the shader computes is the leaf's within a few half ulps, for half-axes of
       2^-14 and more */
    if (!(worst_normal < 4.0 * ldexp(1.0, -11))) fail_msg("normals turned by up to %g", worst_normal);
    free(in);
    free(gpu);
}

static void pack_gpu_rejects_what_the_record_cannot_hold(void **state)
{
    (void)state;
    xyl_leaf good = flat_leaf(1, 2, 3, 1, 0.5f);
    good.uv[2] = good.uv[3] = 1.0f;
    xyl_leaf l[2] = {good, good};
    xyl_foliage_gpu_leaf out[2];
    memset(out, 0x77, sizeof out);
    xyl_foliage_gpu_leaf before[2];
    memcpy(before, out, sizeof out);
    xyl_diag diag = {0};
    l[1].axis.y = 65505.0f;
    assert_int_equal(xyl_foliage_pack_gpu(l, 2, out, &diag), XYL_ERR_LIMIT_EXCEEDED);
    assert_int_equal(diag.index, 1);
    l[1] = good, l[1].side.x = -70000.0f;
    assert_int_equal(xyl_foliage_pack_gpu(l, 2, out, &diag), XYL_ERR_LIMIT_EXCEEDED);
    l[1] = good, l[1].center.z = NAN;
    assert_int_equal(xyl_foliage_pack_gpu(l, 2, out, &diag), XYL_ERR_NON_FINITE);
    l[1] = good, l[1].uv[1] = -0.01f;
    assert_int_equal(xyl_foliage_pack_gpu(l, 2, out, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_memory_equal(out, before, sizeof out);
    assert_int_equal(xyl_foliage_pack_gpu(NULL, 1, out, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_pack_gpu(l, 1, NULL, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_pack_gpu(NULL, 0, NULL, &diag), XYL_OK);
    l[1] = good, l[1].axis.y = 65504.0f; /* the largest half fits */
    assert_int_equal(xyl_foliage_pack_gpu(l, 2, out, &diag), XYL_OK);
    assert_int_equal(out[1].axis[1], 0x7bff);
}

/* ---- leaf collapse ----------------------------------------------------------------------- */

typedef enum leaf_set { SET_CROWN, SET_COINCIDENT, SET_COPLANAR, SET_CLUMPS } leaf_set;

/* Test leaf sets: a crown (uniform in an ellipsoid, normals biased up, sizes 0.05..0.15,
 * textures and nodes varied), n copies of one leaf, leaves all in the plane z = 0, and tight
 * clumps of coincident leaves. */
static void make_leaves(xyl_leaf *out, uint32_t n, leaf_set set, uint64_t seed)
{
    uint64_t rng = seed * 2654435761u + 1;
    for (uint32_t i = 0; i < n; ++i) {
        xyl_vec3 c, nrm = {0, 0, 1};
        double roll = uniform(&rng, 0, 6.283185307179586), hl = uniform(&rng, 0.025, 0.075);
        double hw = hl * uniform(&rng, 0.3, 0.8);
        if (set == SET_COINCIDENT) {
            c = (xyl_vec3){1, 2, 3};
            roll = 0.3, hl = 0.05, hw = 0.02;
        } else if (set == SET_COPLANAR) {
            c = (xyl_vec3){(float)uniform(&rng, -2, 2), (float)uniform(&rng, -1, 1), 0};
        } else if (set == SET_CLUMPS) {
            uint32_t clump = (uint32_t)(next_random(&rng) % 7);
            c = (xyl_vec3){(float)clump, (float)(clump % 3), 0.5f};
            nrm = (xyl_vec3){0, 1, 0};
        } else {
            double x, y, z;
            do {
                x = uniform(&rng, -1, 1), y = uniform(&rng, -1, 1), z = uniform(&rng, -1, 1);
            } while (x * x + y * y + z * z > 1.0);
            c = (xyl_vec3){(float)(3 * x), (float)(4 + 2 * y), (float)(3 * z)};
            double a = uniform(&rng, 0, 6.283185307179586), b = uniform(&rng, -0.3, 1);
            double r = sqrt(1 - b * b);
            nrm = (xyl_vec3){(float)(r * cos(a)), (float)b, (float)(r * sin(a))};
        }
        out[i] = oriented_leaf(c, nrm, roll, hl, hw);
        out[i].node = (int32_t)(i % 17) - 1;
        float u0 = (float)(i % 4) * 0.25f;
        out[i].uv[0] = u0, out[i].uv[1] = 0, out[i].uv[2] = u0 + 0.25f, out[i].uv[3] = 1;
    }
}

/* make_leaves into a new array (free it). */
static xyl_leaf *new_leaves(uint32_t n, leaf_set set, uint64_t seed)
{
    xyl_leaf *in = malloc((n ? n : 1) * sizeof *in);
    assert_non_null(in);
    make_leaves(in, n, set, seed);
    return in;
}

typedef struct chain {
    xyl_leaf *leaves;
    float *error;
    uint32_t *children;
    uint32_t n, m;
    xyl__collapse_stats stats;
} chain;

static chain run_collapse(const xyl_leaf *in, uint32_t n, const xyl__collapse_options *options)
{
    chain c = {0};
    size_t cap = n ? 2 * (size_t)n - 1 : 1;
    c.leaves = malloc(cap * sizeof *c.leaves);
    c.error = malloc(cap * sizeof *c.error);
    c.children = malloc((cap + 1) * sizeof *c.children);
    assert_true(c.leaves && c.error && c.children);
    if (n) memcpy(c.leaves, in, n * sizeof *in);
    xyl__collapse_options o;
    if (options) o = *options;
    else xyl__collapse_defaults(in, n, &o);
    c.n = n;
    xyl_diag diag = {0};
    assert_int_equal(xyl__collapse(c.leaves, c.error, c.children, n, &o, NULL, &c.m, &c.stats, &diag), XYL_OK);
    return c;
}

static void free_chain(chain *c)
{
    free(c->leaves);
    free(c->error);
    free(c->children);
}

/* Replays the greedy chain: every merge joins two live, distinct leaves and removes one leaf. */
static void assert_chain_replays(const chain *c)
{
    uint8_t *alive = calloc(c->n + c->m + 1, 1);
    assert_non_null(alive);
    memset(alive, 1, c->n);
    uint64_t live = c->n;
    for (uint32_t k = 0; k < c->m; ++k) {
        uint32_t p = c->children[2 * k], q = c->children[2 * k + 1];
        assert_true(p < q && q < c->n + k);
        assert_true(alive[p] && alive[q]);
        alive[p] = alive[q] = 0;
        alive[c->n + k] = 1;
        assert_int_equal(c->leaves[c->n + k].count, c->leaves[p].count + c->leaves[q].count);
        --live;
    }
    assert_int_equal(live, c->n - c->m);
    uint64_t originals = 0, left = 0; /* the leaves left stand for all the originals */
    for (uint32_t k = 0; k < c->n + c->m; ++k) {
        if (k < c->n) originals += c->leaves[k].count;
        if (alive[k]) left += c->leaves[k].count;
    }
    assert_int_equal(left, originals);
    free(alive);
}

static void collapse_runs_to_one_leaf_standing_for_all(void **state)
{
    (void)state;
    const leaf_set sets[4] = {SET_CROWN, SET_COINCIDENT, SET_COPLANAR, SET_CLUMPS};
    for (int s = 0; s < 4; ++s) {
        uint32_t n = SANITIZED ? 300 : 3000;
        xyl_leaf *in = new_leaves(n, sets[s], 5);
        chain c = run_collapse(in, n, NULL);
        assert_int_equal(c.m, n - 1);
        assert_int_equal(c.leaves[2 * n - 2].count, n);
        assert_chain_replays(&c);
        assert_int_equal(xyl_foliage_check_leaves(c.leaves, 2 * n - 1, NULL, NULL), XYL_OK);
        free_chain(&c);
        free(in);
    }
}

/* The error of merged leaf n + k by its definition, found by brute force: the farthest corner
 * of the originals under it from its quad (the distance to a convex quad is convex: an
 * original's farthest point is a corner), or a child's error where that is larger, rounded up
 * to float. */
static float exact_error(const xyl_leaf *leaves, uint32_t n, const uint32_t *children, uint32_t k,
                         const float *err)
{
    uint32_t *stack = malloc((2 * (size_t)n + 1) * sizeof *stack), top = 0;
    assert_non_null(stack);
    double worst = 0.0;
    stack[top++] = n + k;
    while (top) {
        uint32_t j = stack[--top];
        if (j >= n) {
            stack[top++] = children[2 * (j - n)];
            stack[top++] = children[2 * (j - n) + 1];
            continue;
        }
        xyl__dvec3 c[4];
        xyl__leaf_corners(&leaves[j], c);
        for (int i = 0; i < 4; ++i) worst = fmax(worst, xyl__leaf_quad_distance(c[i], &leaves[n + k]));
    }
    free(stack);
    worst = fmax(worst, fmax(err[children[2 * k]], err[children[2 * k + 1]]));
    return xyl__round_up(worst);
}

/* With at most K + 1 leaves every leaf sees every other, so the chain is the exact greedy one:
 * a brute-force search for the cheapest pair (ties: lower indices) at each step. */
static void collapse_of_few_leaves_is_the_exact_greedy_chain(void **state)
{
    (void)state;
    for (uint64_t seed = 1; seed <= 40; ++seed) {
        uint32_t n = 2 + (uint32_t)(seed % 8);
        xyl_leaf in[9], ref[17];
        float err[17] = {0};
        uint8_t alive[17] = {0};
        make_leaves(in, n, seed % 3 ? SET_CROWN : SET_COPLANAR, seed);
        chain c = run_collapse(in, n, NULL);
        xyl__collapse_options o;
        xyl__collapse_defaults(in, n, &o);
        memcpy(ref, in, n * sizeof *in);
        memset(alive, 1, n);
        assert_int_equal(c.m, n - 1);
        for (uint32_t k = 0; k + 1 < n; ++k) {
            float best = INFINITY;
            uint32_t bp = 0, bq = 0;
            for (uint32_t p = 0; p < n + k; ++p)
                for (uint32_t q = p + 1; q < n + k; ++q) {
                    if (!alive[p] || !alive[q]) continue;
                    float cost = xyl__collapse_cost(&ref[p], &ref[q], &o);
                    if (cost < best) best = cost, bp = p, bq = q;
                }
            if (c.children[2 * k] != bp || c.children[2 * k + 1] != bq)
                fail_msg("seed %llu, merge %u: chain joined %u and %u, greedy %u and %u",
                         (unsigned long long)seed, k, c.children[2 * k], c.children[2 * k + 1], bp, bq);
            ref[n + k] = xyl__leaf_merge(&ref[bp], &ref[bq], err[bp], err[bq], NULL);
            err[n + k] = exact_error(ref, n, c.children, k, err);
            alive[bp] = alive[bq] = 0;
            alive[n + k] = 1;
        }
        assert_memory_equal(ref, c.leaves, (2 * n - 1) * sizeof *ref);
        assert_memory_equal(err, c.error, (2 * n - 1) * sizeof *err);
        free_chain(&c);
    }
}

static void merged_leaf_is_the_weighted_bounding_rectangle(void **state)
{
    (void)state;
    /* two leaves in the plane z = 0 facing +z, side by side along x: the merged leaf's axis
       runs through both centres, so its length spans both and its width is scaled */
    xyl_leaf p = flat_leaf(0, 0, 0, 1.0f, 0.5f), q = flat_leaf(3, 0, 0, 1.0f, 0.25f);
    p.count = 3, q.count = 1; /* the centre is at x = 0.75, the rectangle's at 1.375 */
    p.uv[2] = p.uv[3] = 0.5f;
    q.uv[2] = q.uv[3] = 1.0f;
    p.node = 4, q.node = 9;
    float err = -1;
    xyl_leaf m = xyl__leaf_merge(&p, &q, 0.0f, 0.0f, &err);
    assert_int_equal(m.count, 4);
    assert_int_equal(m.node, 4); /* the larger leaf's node and texture */
    assert_memory_equal(m.uv, p.uv, sizeof m.uv);
    assert_vec_near(m.normal, 0, 0, 1, 1e-7);
    /* projected corners span x in [-0.5, 3.25] and y in [-1, 1]; the main axis is x */
    assert_near(fabs(m.axis.x), (3.25 + 0.5) / 2, 1e-6);
    assert_vec_near(m.center, (3.25 - 0.5) / 2, 0, 0, 1e-6);
    double areas = 4 * 1.0 * 0.5 + 4 * 1.0 * 0.25, box = 3.75 * 2.0;
    double area = 4.0 * len3(m.axis) * len3(m.side);
    assert_near(area, 0.5 * (areas + box), 1e-5);
    assert_true(m.axis.x > 0.0f); /* turned to agree with p's and q's axes? both are +y: dot 0 */
    assert_near(dot3(m.axis, m.side), 0.0, 1e-6);
    xyl_vec3 c = cross3(m.side, m.axis);
    assert_true(dot3(c, m.normal) > 0.0);
    /* the width shrank from 2 to area / 3.75: the corners at y = +-1 lie outside */
    assert_near(err, 1.0 - 0.5 * area / 3.75, 1e-5);
}

static void merged_leaf_of_coincident_leaves_covers_them_with_no_error(void **state)
{
    (void)state;
    xyl_leaf p = flat_leaf(1, 2, 3, 1.0f, 0.5f);
    p = xyl__leaf_tidy(&p);
    float err = -1;
    xyl_leaf m = xyl__leaf_merge(&p, &p, 0.0f, 0.0f, &err);
    assert_memory_equal(&m.center, &p.center, sizeof m.center);
    assert_near(len3(m.axis), 1.0, 1e-7);     /* the length stays; the mean of 2A and A */
    assert_near(len3(m.side), 0.75, 1e-7);    /* widens 1.5 times */
    assert_true(m.axis.y > 0.0f);             /* the fallback axis: the leaves' own */
    assert_true(err == 0.0f);
    /* opposite normals of equal weight: the plane of the larger (here the first) leaf */
    xyl_leaf back = p;
    back.normal.z = -1, back.side.x = -back.side.x;
    m = xyl__leaf_merge(&p, &back, 0.0f, 0.0f, &err);
    assert_vec_near(m.normal, 0, 0, 1, 0);
}

static void collapse_keeps_coplanar_leaves_in_their_plane(void **state)
{
    (void)state;
    uint32_t n = 500;
    xyl_leaf *in = new_leaves(n, SET_COPLANAR, 11);
    chain c = run_collapse(in, n, NULL);
    assert_int_equal(c.m, n - 1);
    for (uint32_t k = n; k < n + c.m; ++k) {
        assert_vec_near(c.leaves[k].normal, 0, 0, 1, 1e-6);
        assert_near(c.leaves[k].center.z, 0.0, 1e-6);
    }
    free_chain(&c);
    free(in);
}

/* The largest distance from a 5 x 5 lattice of points of leaf o (corners included) to quad q. */
static double sampled_distance(const xyl_leaf *o, const xyl_leaf *q)
{
    double worst = 0.0;
    for (int s = -2; s <= 2; ++s)
        for (int t = -2; t <= 2; ++t) {
            xyl__dvec3 x = {o->center.x + 0.5 * s * o->side.x + 0.5 * t * o->axis.x,
                            o->center.y + 0.5 * s * o->side.y + 0.5 * t * o->axis.y,
                            o->center.z + 0.5 * s * o->side.z + 0.5 * t * o->axis.z};
            worst = fmax(worst, xyl__leaf_quad_distance(x, q));
        }
    return worst;
}

/* Every point of the originals a merged leaf stands for lies within its error of its quad. */
static void assert_error_bounds_hold(const chain *c)
{
    uint32_t total = c->n + c->m;
    uint32_t *stack = malloc((total + 1) * sizeof *stack);
    assert_non_null(stack);
    double scale = 0.0;
    for (uint32_t k = 0; k < total; ++k) scale = fmax(scale, len3(c->leaves[k].center));
    for (uint32_t k = c->n; k < total; ++k) {
        const xyl_leaf *m = &c->leaves[k];
        double worst = 0.0;
        uint32_t top = 0;
        stack[top++] = k;
        while (top) {
            uint32_t j = stack[--top];
            if (j >= c->n) {
                stack[top++] = c->children[2 * (j - c->n)];
                stack[top++] = c->children[2 * (j - c->n) + 1];
                continue;
            }
            worst = fmax(worst, sampled_distance(&c->leaves[j], m));
        }
        if (!(worst <= c->error[k] + 1e-6 * (scale + 1.0)))
            fail_msg("leaf %u: an original point is %g from it, its bound is %g", k, worst, (double)c->error[k]);
    }
    free(stack);
}

static void collapse_error_bounds_every_original_point(void **state)
{
    (void)state;
    const leaf_set sets[3] = {SET_CROWN, SET_COPLANAR, SET_CLUMPS};
    for (int s = 0; s < 3; ++s) {
        uint32_t n = SANITIZED ? 200 : 1000;
        xyl_leaf *in = new_leaves(n, sets[s], 21);
        chain c = run_collapse(in, n, NULL);
        assert_error_bounds_hold(&c);
        /* each error is its definition's exact value, and never above the sum bound of the
           merges (a child's bound plus its corners' distance), which the chain used to give */
        float *sum = calloc(2 * (size_t)n, sizeof *sum);
        assert_non_null(sum);
        uint32_t looser = 0;
        for (uint32_t k = 0; k < c.m; ++k) {
            uint32_t p = c.children[2 * k], q = c.children[2 * k + 1];
            xyl__leaf_merge(&c.leaves[p], &c.leaves[q], sum[p], sum[q], &sum[c.n + k]);
            assert_true(c.error[c.n + k] == exact_error(c.leaves, c.n, c.children, k, c.error));
            assert_true(c.error[c.n + k] <= sum[c.n + k]);
            looser += c.error[c.n + k] < sum[c.n + k];
        }
        print_message("set %d: the sum bound is looser for %u of %u merged leaves\n", s, looser, c.m);
        assert_true(looser > 0);
        /* past the work budget the sum bound takes over: with none it is the sum bound
           throughout, with some it lies between the two and still bounds every point */
        float *exact = malloc(2 * (size_t)n * sizeof *exact);
        assert_non_null(exact);
        memcpy(exact, c.error, (2 * (size_t)n - 1) * sizeof *exact);
        assert_int_equal(xyl__collapse_errors(c.leaves, c.error, c.children, c.n, c.m, 0, NULL), XYL_OK);
        assert_memory_equal(c.error + c.n, sum + c.n, c.m * sizeof *sum);
        uint64_t budget = 2 * (uint64_t)n;
        assert_true(budget < xyl__collapse_error_budget(n));
        assert_int_equal(xyl__collapse_errors(c.leaves, c.error, c.children, c.n, c.m, budget, NULL), XYL_OK);
        uint32_t exact_kept = 0;
        for (uint32_t k = 0; k < c.n + c.m; ++k) {
            assert_true(exact[k] <= c.error[k] && c.error[k] <= sum[k]);
            exact_kept += k >= c.n && c.error[k] == exact[k];
        }
        for (uint32_t k = 0; k < c.m; ++k)
            for (int h = 0; h < 2; ++h) assert_true(c.error[c.children[2 * k + h]] <= c.error[c.n + k]);
        assert_true(exact_kept > 0 && exact_kept < c.m);
        assert_error_bounds_hold(&c);
        free(exact);
        free(sum);
        free_chain(&c);
        free(in);
    }
}

static void collapse_stops_at_the_thresholds(void **state)
{
    (void)state;
    enum { N = 200 };
    xyl_leaf in[N];
    make_leaves(in, N, SET_CROWN, 3);
    for (int i = N / 2; i < N; ++i) in[i].center.x += 100.0f; /* a second crown far away */
    xyl__collapse_options o;
    xyl__collapse_defaults(in, N, &o);
    o.max_distance = 20.0;
    chain c = run_collapse(in, N, &o);
    assert_int_equal(c.m, N - 2); /* one leaf per crown */
    assert_chain_replays(&c);
    free_chain(&c);
    /* leaves facing up and down never meet under a 90 degree threshold */
    for (int i = 0; i < N; ++i) in[i] = oriented_leaf((xyl_vec3){(float)(i % 20), (float)(i / 20), 0},
                                                       (xyl_vec3){0, 0, i % 2 ? 1.0f : -1.0f}, 0.2, 0.3, 0.1);
    xyl__collapse_defaults(in, N, &o);
    o.max_angle = 1.5;
    c = run_collapse(in, N, &o);
    assert_int_equal(c.m, N - 2);
    assert_chain_replays(&c);
    free_chain(&c);
}

static void collapse_is_deterministic_and_never_searches_all_pairs(void **state)
{
    (void)state;
    uint32_t n = SANITIZED ? 5000 : 50000;
    xyl_leaf *in = new_leaves(n, SET_CROWN, 8);
    chain a = run_collapse(in, n, NULL), b = run_collapse(in, n, NULL);
    assert_int_equal(a.m, n - 1);
    assert_memory_equal(a.leaves, b.leaves, (2 * (size_t)n - 1) * sizeof *a.leaves);
    assert_memory_equal(a.error, b.error, (2 * (size_t)n - 1) * sizeof *a.error);
    assert_memory_equal(a.children, b.children, 2 * (size_t)a.m * sizeof *a.children);
    /* a bounded number of candidates per merge, whatever n is */
    print_message("%u leaves: %.1f cost evaluations and %.1f cells a merge, %llu grids, %zu bytes a leaf\n", n,
                  (double)a.stats.cost_evaluations / n, (double)a.stats.cells_scanned / n,
                  (unsigned long long)a.stats.grid_builds, a.stats.bytes / n);
    assert_true(a.stats.cost_evaluations < 60ull * n);
    assert_true(a.stats.cells_scanned < 400ull * n);
    free_chain(&a);
    free_chain(&b);
    /* a million-fold stack of one leaf costs the same per merge */
    make_leaves(in, n, SET_COINCIDENT, 1);
    a = run_collapse(in, n, NULL);
    assert_int_equal(a.m, n - 1);
    print_message("coincident: %.1f cost evaluations and %.1f cells a merge, %llu grids\n",
                  (double)a.stats.cost_evaluations / n, (double)a.stats.cells_scanned / n,
                  (unsigned long long)a.stats.grid_builds);
    assert_true(a.stats.cost_evaluations < 60ull * n);
    free_chain(&a);
    free(in);
}

/* Counts and optionally fails allocations, so tests can prove nothing leaks. */
typedef struct counter {
    size_t attempts, allocs, frees, bytes, peak, live_bytes;
    size_t fail_at; /* 1-based attempt that returns NULL; 0 = never */
} counter;

static void *count_alloc(size_t size, void *user)
{
    counter *c = user;
    if (++c->attempts == c->fail_at) return NULL;
    size_t *p = malloc(size + sizeof(size_t) * 2);
    if (!p) return NULL;
    c->allocs++;
    p[0] = size;
    c->live_bytes += size;
    if (c->live_bytes > c->peak) c->peak = c->live_bytes;
    return p + 2;
}

static void count_free(void *ptr, void *user)
{
    counter *c = user;
    if (!ptr) return;
    size_t *p = (size_t *)ptr - 2;
    c->frees++;
    c->live_bytes -= p[0];
    free(p);
}

static void collapse_survives_every_allocation_failure(void **state)
{
    (void)state;
    enum { N = 300 };
    xyl_leaf in[N], work[2 * N];
    float err[2 * N];
    uint32_t children[2 * N];
    make_leaves(in, N, SET_CROWN, 4);
    xyl__collapse_options o;
    xyl__collapse_defaults(in, N, &o);
    for (size_t fail = 1;; ++fail) {
        counter c = {0};
        c.fail_at = fail;
        xyl_allocator a = {count_alloc, count_free, &c};
        memcpy(work, in, sizeof in);
        uint32_t m = 12345;
        xyl_diag diag = {0};
        xyl_result r = xyl__collapse(work, err, children, N, &o, &a, &m, NULL, &diag);
        assert_int_equal(c.allocs, c.frees);
        if (c.attempts < fail) { /* no failure left to inject */
            assert_int_equal(r, XYL_OK);
            assert_int_equal(m, N - 1);
            break;
        }
        assert_int_equal(r, XYL_ERR_OUT_OF_MEMORY);
        assert_int_equal(m, 12345);
    }
}

/* ---- the linear LOD array ---------------------------------------------------------------- */

static xyl_foliage *build_ok(const xyl_leaf *leaves, size_t n, const xyl_foliage_desc *options)
{
    xyl_foliage_desc d = {0};
    if (options) d = *options;
    d.leaves = leaves;
    d.leaf_count = n;
    xyl_foliage *f = NULL;
    xyl_diag diag = {0};
    xyl_result r = xyl_foliage_build(&d, &f, &diag);
    if (r != XYL_OK) fail_msg("build: %s (%s)", xyl_result_string(r), diag.message);
    assert_non_null(f);
    return f;
}

/* The property the layout exists for, checked against a direct simulation of the stored chain:
 * for EVERY i the leaves in the two ranges of LOD i are exactly those alive after the chain's
 * first i merges, a + c = n - i, and every merge joins two leaves alive when it happens. Also
 * the links agree with each other and the originals are the desc's leaves. */
static void assert_lods_draw_the_live_leaves(const xyl_foliage *f, const xyl_foliage_sector *s,
                                             bool every_step_in_full)
{
    uint32_t n = s->original_count, m = s->merged_count, base = s->base;
    uint8_t *alive = calloc(n + m + 1, 1), *drawn = calloc(n + m + 1, 1);
    assert_true(alive && drawn);
    memset(alive, 1, n);
    for (uint32_t i = 0; i <= m; ++i) {
        if (i > 0) { /* merge i - 1 makes leaf n + i - 1 */
            const xyl_leaf_link *l = &f->links[base + n + i - 1];
            uint32_t p = (uint32_t)l->children[0] - base, q = (uint32_t)l->children[1] - base;
            assert_true(p < n + i - 1 && q < n + i - 1 && p != q);
            assert_true(alive[p] && alive[q]);
            alive[p] = alive[q] = 0;
            alive[n + i - 1] = 1;
        }
        const xyl_foliage_lod *lod = &s->lods[i];
        assert_int_equal(lod->a + lod->c, n - i);
        assert_true(lod->a <= n && lod->b >= n && lod->b + lod->c <= n + m && lod->b + lod->c == n + i);
        if (i > 0) assert_true(lod->error >= s->lods[i - 1].error);
        if (!every_step_in_full && i % 97 != 0 && i != m) continue;
        memset(drawn, 0, n + m);
        for (uint32_t k = 0; k < lod->a; ++k) drawn[k] = 1;
        for (uint32_t k = lod->b; k < lod->b + lod->c; ++k) drawn[k] = 1;
        if (memcmp(drawn, alive, n + m) != 0) fail_msg("LOD %u draws other leaves than are alive", i);
    }
    assert_true(s->lods[0].error == 0.0f && s->lods[0].a == n && s->lods[0].c == 0);
    free(alive);
    free(drawn);
}

static void assert_links_agree(const xyl_foliage *f, const xyl_leaf *desc_leaves)
{
    uint8_t *seen = calloc(f->original_count + 1, 1);
    assert_non_null(seen);
    size_t roots = 0;
    for (size_t k = 0; k < f->leaf_count; ++k) {
        const xyl_leaf_link *l = &f->links[k];
        if (l->source != UINT32_MAX) {
            assert_true(l->source < f->original_count && !seen[l->source]);
            seen[l->source] = 1;
            assert_int_equal(l->children[0], -1);
            assert_true(l->error == 0.0f);
            xyl_leaf t = xyl__leaf_tidy(&desc_leaves[l->source]);
            assert_memory_equal(&f->leaves[k], &t, sizeof t);
        } else {
            for (int c = 0; c < 2; ++c) {
                int32_t ch = l->children[c];
                assert_true(ch >= 0 && (size_t)ch < k);
                assert_int_equal(f->links[ch].parent, (int32_t)k);
                assert_true(l->error >= f->links[ch].error);
            }
            assert_int_equal(f->leaves[k].count, f->leaves[l->children[0]].count + f->leaves[l->children[1]].count);
        }
        if (l->parent < 0) ++roots;
        else assert_true((size_t)l->parent > k);
    }
    assert_int_equal(roots, f->coarsest_count);
    free(seen);
}

/* For both costs: the layout takes any chain in xyl__collapse's format. */
static void lods_draw_the_live_leaves_of_random_sets_at_every_step(void **state)
{
    (void)state;
    const leaf_set sets[4] = {SET_CROWN, SET_COINCIDENT, SET_COPLANAR, SET_CLUMPS};
    const uint32_t sizes[4] = {1, 2, 37, SANITIZED ? 300 : 1200};
    for (int cost = 0; cost < 2; ++cost)
    for (int set = 0; set < 4; ++set)
        for (int size = 0; size < 4; ++size)
            for (uint64_t seed = 1; seed <= 3; ++seed) {
                if (cost && size == 3 && seed > 1) continue; /* its renders are the slow part */
                uint32_t n = sizes[size];
                xyl_leaf *in = new_leaves(n, sets[set], seed * 7 + (uint64_t)size);
                xyl_foliage_desc d = {0};
                d.cost = cost ? XYL_FOLIAGE_COST_VIEWPOINT : XYL_FOLIAGE_COST_HIDALGO;
                d.viewpoint.resolution = 64; /* small views: the layout, not the images, is tested */
                xyl_foliage *f = build_ok(in, n, &d);
                assert_int_equal(f->sector_count, 1);
                assert_int_equal(f->sectors[0].merged_count, n - 1);
                assert_int_equal(f->leaf_count, 2 * n - 1);
                assert_lods_draw_the_live_leaves(f, &f->sectors[0], true);
                assert_links_agree(f, in);
                xyl_foliage_destroy(f);
                free(in);
            }
}

static void lods_of_a_large_crown_and_a_stopped_chain_draw_the_live_leaves(void **state)
{
    (void)state;
    uint32_t n = SANITIZED ? 4000 : 40000;
    xyl_leaf *in = new_leaves(n, SET_CROWN, 77);
    xyl_foliage *f = build_ok(in, n, NULL);
    assert_lods_draw_the_live_leaves(f, &f->sectors[0], false);
    assert_links_agree(f, in);
    xyl_foliage_destroy(f);
    /* thresholds: the chain stops with several leaves, and says how many */
    xyl_foliage_desc d = {0};
    d.max_distance = 0.2f;
    d.max_angle = 0.5f;
    f = build_ok(in, n, &d);
    const xyl_foliage_sector *s = &f->sectors[0];
    assert_true(s->merged_count < n - 1);
    assert_int_equal(f->coarsest_count, n - s->merged_count);
    assert_int_equal(s->lods[s->merged_count].a + s->lods[s->merged_count].c, f->coarsest_count);
    assert_lods_draw_the_live_leaves(f, s, false);
    assert_links_agree(f, in);
    xyl_foliage_destroy(f);
    free(in);
}

static void build_of_no_leaves_is_an_empty_foliage(void **state)
{
    (void)state;
    xyl_foliage *f = build_ok(NULL, 0, NULL);
    assert_int_equal(f->leaf_count, 0);
    assert_int_equal(f->original_count, 0);
    assert_int_equal(f->coarsest_count, 0);
    assert_int_equal(f->sector_count, 1);
    assert_int_equal(f->sectors[0].merged_count, 0);
    const xyl_foliage_lod *l = &f->sectors[0].lods[0];
    assert_true(l->a == 0 && l->c == 0 && l->error == 0.0f);
    xyl_foliage_destroy(f);
    xyl_foliage_destroy(NULL);
}

static void build_is_deterministic(void **state)
{
    (void)state;
    uint32_t n = SANITIZED ? 2000 : 20000;
    xyl_leaf *in = new_leaves(n, SET_CROWN, 5);
    xyl_foliage *a = build_ok(in, n, NULL), *b = build_ok(in, n, NULL);
    assert_int_equal(a->leaf_count, b->leaf_count);
    assert_memory_equal(a->leaves, b->leaves, a->leaf_count * sizeof *a->leaves);
    assert_memory_equal(a->links, b->links, a->leaf_count * sizeof *a->links);
    assert_memory_equal(a->sectors[0].lods, b->sectors[0].lods,
                        (a->sectors[0].merged_count + 1) * sizeof *a->sectors[0].lods);
    xyl_foliage_destroy(a);
    xyl_foliage_destroy(b);
    free(in);
}

static void build_rejects_bad_leaves_and_options_with_their_codes(void **state)
{
    (void)state;
    xyl_leaf in[3];
    make_leaves(in, 3, SET_CROWN, 1);
    struct {
        int what;
        xyl_result code;
    } cases[] = {
        {0, XYL_ERR_NON_FINITE}, {1, XYL_ERR_INVALID_ARGUMENT}, {2, XYL_ERR_LIMIT_EXCEEDED},
        {3, XYL_ERR_INVALID_ARGUMENT}, {4, XYL_ERR_NON_FINITE}, {5, XYL_ERR_INVALID_ARGUMENT},
        {6, XYL_ERR_NON_FINITE}, {7, XYL_ERR_INVALID_ARGUMENT}, {8, XYL_ERR_LIMIT_EXCEEDED},
        {9, XYL_ERR_INVALID_ARGUMENT},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        xyl_leaf l[3];
        memcpy(l, in, sizeof l);
        xyl_foliage_desc d = {0};
        d.leaves = l;
        d.leaf_count = 3;
        switch (cases[k].what) {
        case 0: l[1].center.y = NAN; break;
        case 1: l[2].axis = (xyl_vec3){0, 0, 0}; break; /* size 0 */
        case 2: l[0].center.x = 1e7f; break;            /* huge */
        case 3: d.weights.angle = -1.0f; break;
        case 4: d.weights.area = INFINITY; break;
        case 5: d.max_distance = -2.0f; break;
        case 6: d.max_angle = NAN; break;
        case 7: d.limits.max_coordinate = -1.0f; break;
        case 8: d.limits.max_leaves = 2; break;
        case 9: d.leaves = NULL; break;
        }
        xyl_foliage *f = (xyl_foliage *)(uintptr_t)1;
        xyl_diag diag = {0};
        xyl_result r = xyl_foliage_build(&d, &f, &diag);
        if (r != cases[k].code)
            fail_msg("case %zu: got %s (%s), want %s", k, xyl_result_string(r), diag.message,
                     xyl_result_string(cases[k].code));
        assert_ptr_equal(f, (xyl_foliage *)(uintptr_t)1);
        assert_true(strlen(diag.message) > 0);
    }
    xyl_foliage *f = NULL;
    assert_int_equal(xyl_foliage_build(NULL, &f, NULL), XYL_ERR_INVALID_ARGUMENT);
    xyl_foliage_desc d = {0};
    assert_int_equal(xyl_foliage_build(&d, NULL, NULL), XYL_ERR_INVALID_ARGUMENT);
}

static void build_survives_every_allocation_failure(void **state)
{
    (void)state;
    enum { N = 200 };
    xyl_leaf in[N];
    make_leaves(in, N, SET_CROWN, 9);
    for (size_t fail = 1;; ++fail) {
        counter c = {0};
        c.fail_at = fail;
        xyl_foliage_desc d = {0};
        d.leaves = in;
        d.leaf_count = N;
        d.sectors = 3;
        d.alloc = (xyl_allocator){count_alloc, count_free, &c};
        xyl_foliage *f = (xyl_foliage *)(uintptr_t)1;
        xyl_result r = xyl_foliage_build(&d, &f, NULL);
        if (c.attempts < fail) {
            assert_int_equal(r, XYL_OK);
            assert_true(c.allocs > c.frees); /* the foliage's arrays */
            xyl_foliage_destroy(f);
            assert_int_equal(c.allocs, c.frees);
            break;
        }
        assert_int_equal(r, XYL_ERR_OUT_OF_MEMORY);
        assert_ptr_equal(f, (xyl_foliage *)(uintptr_t)1);
        assert_int_equal(c.allocs, c.frees);
    }
}

/* ---- LOD errors and the LOD pick ------------------------------------------------------------ */

/* Largest distance from sampled points of the originals under array leaf k to the quad q. */
static double worst_original_distance(const xyl_foliage *f, uint32_t k, const xyl_leaf *q, uint32_t *stack)
{
    double worst = 0.0;
    uint32_t top = 0;
    stack[top++] = k;
    while (top) {
        uint32_t j = stack[--top];
        const xyl_leaf_link *l = &f->links[j];
        if (l->children[0] >= 0) {
            stack[top++] = (uint32_t)l->children[0];
            stack[top++] = (uint32_t)l->children[1];
            continue;
        }
        worst = fmax(worst, sampled_distance(&f->leaves[j], q));
    }
    return worst;
}

static void lod_errors_bound_every_original_point(void **state)
{
    (void)state;
    const leaf_set sets[3] = {SET_CROWN, SET_COPLANAR, SET_CLUMPS};
    for (int set = 0; set < 3; ++set) {
        uint32_t n = SANITIZED ? 150 : 600;
        xyl_leaf *in = malloc(n * sizeof *in);
        uint32_t *stack = malloc(2 * n * sizeof *stack);
        assert_true(in && stack);
        make_leaves(in, n, sets[set], 31);
        xyl_foliage *f = build_ok(in, n, NULL);
        const xyl_foliage_sector *s = &f->sectors[0];
        for (uint32_t step = 0;; ++step) { /* every 40th LOD and the coarsest */
            uint32_t i = 40 * step < s->merged_count ? 40 * step : s->merged_count;
            const xyl_foliage_lod *lod = &s->lods[i];
            for (uint32_t k = 0; k < f->leaf_count; ++k) {
                bool drawn = k < lod->a || (k >= lod->b && k < lod->b + lod->c);
                if (!drawn) continue;
                double worst = worst_original_distance(f, k, &f->leaves[k], stack);
                double tol = 1e-6 * (1.0 + len3(f->leaves[k].center));
                if (!(worst <= f->links[k].error + tol && f->links[k].error <= lod->error))
                    fail_msg("LOD %u, leaf %u: originals %g away, its bound %g, the LOD's %g", i, k,
                             worst, (double)f->links[k].error, (double)lod->error);
            }
            if (i == s->merged_count) break;
        }
        xyl_foliage_destroy(f);
        free(in);
        free(stack);
    }
}

static void bounding_spheres_hold_every_original_leaf(void **state)
{
    (void)state;
    enum { N = 300 };
    xyl_leaf in[N];
    make_leaves(in, N, SET_CROWN, 12);
    xyl_foliage *f = build_ok(in, N, NULL);
    const xyl_foliage_sector *s = &f->sectors[0];
    for (size_t k = 0; k < f->original_count; ++k) {
        xyl__dvec3 c[4];
        xyl__leaf_corners(&f->leaves[k], c);
        for (int j = 0; j < 4; ++j) {
            assert_true(xyl__d3_len(xyl__d3_sub(c[j], xyl__from_f3(s->center))) <= s->radius);
            assert_true(xyl__d3_len(xyl__d3_sub(c[j], xyl__from_f3(f->center))) <= f->radius);
        }
    }
    xyl_foliage_destroy(f);
}

static void pick_is_finest_inside_coarsest_far_and_monotone_in_distance(void **state)
{
    (void)state;
    uint32_t n = SANITIZED ? 500 : 5000;
    xyl_leaf *in = new_leaves(n, SET_CROWN, 44);
    xyl_foliage *f = build_ok(in, n, NULL);
    const xyl_foliage_sector *s = &f->sectors[0];
    xyl_foliage_view v = {0};
    v.eye[0] = s->center.x, v.eye[1] = s->center.y, v.eye[2] = s->center.z;
    uint32_t lod = 99;
    assert_int_equal(xyl_foliage_pick(f, &v, &lod, 1, NULL), XYL_OK);
    assert_int_equal(lod, 0); /* inside */
    uint32_t last = 0;
    double per_distance = 0.5 * 2.0 * tan(0.4) / 1080.0; /* the defaults */
    for (double d = 0.25 * s->radius; d < 1e7; d *= 1.3) {
        v.eye[0] = (float)(s->center.x + s->radius + d);
        assert_int_equal(xyl_foliage_pick(f, &v, &lod, 1, NULL), XYL_OK);
        assert_true(lod >= last);
        last = lod;
        /* the coarsest within the budget */
        double dist = len3((xyl_vec3){v.eye[0] - s->center.x, 0, 0}) - s->radius;
        double allowed = dist * per_distance;
        assert_true(s->lods[lod].error <= allowed);
        if (lod < s->merged_count) assert_true(s->lods[lod + 1].error > allowed);
    }
    v.eye[0] = 1e30f;
    assert_int_equal(xyl_foliage_pick(f, &v, &lod, 1, NULL), XYL_OK);
    assert_int_equal(lod, s->merged_count); /* far enough: one leaf */
    assert_true(last > 0);
    /* a finer budget never gives a coarser LOD */
    v.eye[0] = (float)(s->center.x + 3.0 * s->radius);
    v.error_px = 4.0f;
    uint32_t coarse, fine;
    xyl_foliage_pick(f, &v, &coarse, 1, NULL);
    v.error_px = 0.1f;
    xyl_foliage_pick(f, &v, &fine, 1, NULL);
    assert_true(fine <= coarse);
    xyl_foliage_destroy(f);
    free(in);
}

/* The per-leaf cut on the CPU: every original stood for exactly once by a leaf within the
 * budget whose ancestors are not, all originals inside the crown, the roots far away, and
 * count-then-fill with the view's checks. */
static void cut_is_a_valid_cut_of_the_coarsest_leaves_within_the_budget(void **state)
{
    (void)state;
    uint32_t n = SANITIZED ? 500 : 3000;
    xyl_leaf *in = new_leaves(n, SET_CROWN, 45);
    xyl_foliage_desc fd = {0};
    fd.sectors = 3;
    xyl_foliage *f = build_ok(in, n, &fd);
    uint32_t *cut = malloc(f->leaf_count * sizeof *cut);
    uint8_t *drawn = malloc(f->leaf_count);
    assert_true(cut && drawn);
    double per_distance = 0.5 * 2.0 * tan(0.4) / 1080.0; /* the defaults */
    size_t previous = 0;
    for (double k = 0.0; k < 1e5; k = k ? k * 3.0 : 0.5) {
        xyl_foliage_view v = {{f->center.x + (float)(k * f->radius), f->center.y,
                               f->center.z + (float)(0.5 * k * f->radius)}, 0, 0, 0};
        size_t count = 0;
        assert_int_equal(xyl_foliage_cut(f, &v, NULL, 0, &count, NULL), XYL_OK);
        if (count > 1) {
            size_t got = 0;
            xyl_diag d = {0};
            assert_int_equal(xyl_foliage_cut(f, &v, cut, count - 1, &got, &d),
                             XYL_ERR_INVALID_ARGUMENT);
            assert_true(strlen(d.message) > 0);
        }
        assert_int_equal(xyl_foliage_cut(f, &v, cut, f->leaf_count, &count, NULL), XYL_OK);
        memset(drawn, 0, f->leaf_count);
        for (size_t i = 0; i < count; ++i) {
            if (i) assert_true(cut[i] > cut[i - 1]);
            drawn[cut[i]] = 1;
        }
        for (size_t i = 0; i < f->leaf_count; ++i) {
            /* within the budget, by the documented test */
            const xyl_leaf *l = &f->leaves[i];
            double dx = v.eye[0] - l->center.x, dy = v.eye[1] - l->center.y,
                   dz = v.eye[2] - l->center.z;
            double r = sqrt((double)l->axis.x * l->axis.x + (double)l->axis.y * l->axis.y +
                            (double)l->axis.z * l->axis.z + (double)l->side.x * l->side.x +
                            (double)l->side.y * l->side.y + (double)l->side.z * l->side.z) +
                       f->links[i].error;
            double dist = sqrt(dx * dx + dy * dy + dz * dz) - r;
            bool within = f->links[i].error <= per_distance * (dist > 0 ? dist : 0);
            if (drawn[i]) assert_true(within);
            if (f->links[i].source == UINT32_MAX) continue;
            int covered = 0;
            for (int32_t p = (int32_t)i; p >= 0; p = f->links[p].parent) covered += drawn[p];
            assert_int_equal(covered, 1);
        }
        if (k == 0.0) assert_int_equal(count, f->original_count); /* inside the crown */
        previous = count;
    }
    assert_int_equal(previous, f->coarsest_count); /* far away: the roots */
    xyl_diag d = {0};
    size_t count = 0;
    xyl_foliage_view bad = {{0, 0, 0}, 0, 0, -1.0f};
    assert_int_equal(xyl_foliage_cut(f, &bad, NULL, 0, &count, &d), XYL_ERR_INVALID_ARGUMENT);
    bad.error_px = 0.0f;
    bad.eye[2] = NAN;
    assert_int_equal(xyl_foliage_cut(f, &bad, NULL, 0, &count, &d), XYL_ERR_NON_FINITE);
    assert_int_equal(xyl_foliage_cut(NULL, NULL, NULL, 0, &count, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_cut(f, NULL, NULL, 0, NULL, &d), XYL_ERR_INVALID_ARGUMENT);
    xyl_foliage_destroy(f);
    free(cut);
    free(drawn);
    free(in);
}

static void pick_rejects_bad_views_and_leaves_lods_untouched(void **state)
{
    (void)state;
    xyl_leaf in[4];
    make_leaves(in, 4, SET_CROWN, 2);
    xyl_foliage *f = build_ok(in, 4, NULL);
    uint32_t lod = 77;
    xyl_diag diag = {0};
    xyl_foliage_view v = {0};
    v.eye[1] = NAN;
    assert_int_equal(xyl_foliage_pick(f, &v, &lod, 1, &diag), XYL_ERR_NON_FINITE);
    v.eye[1] = 0, v.fovy = 3.5f;
    assert_int_equal(xyl_foliage_pick(f, &v, &lod, 1, &diag), XYL_ERR_INVALID_ARGUMENT);
    v.fovy = 0, v.error_px = -1.0f;
    assert_int_equal(xyl_foliage_pick(f, &v, &lod, 1, &diag), XYL_ERR_INVALID_ARGUMENT);
    v.error_px = INFINITY;
    assert_int_equal(xyl_foliage_pick(f, &v, &lod, 1, &diag), XYL_ERR_NON_FINITE);
    v.error_px = 0;
    assert_int_equal(xyl_foliage_pick(f, &v, &lod, 0, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_pick(f, &v, NULL, 1, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_pick(NULL, &v, &lod, 1, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(lod, 77);
    assert_int_equal(xyl_foliage_pick(f, NULL, &lod, 1, &diag), XYL_OK);
    xyl_foliage_destroy(f);
    f = build_ok(NULL, 0, NULL); /* an empty foliage has LOD 0 only */
    lod = 5;
    v.eye[0] = 1e20f;
    assert_int_equal(xyl_foliage_pick(f, &v, &lod, 1, &diag), XYL_OK);
    assert_int_equal(lod, 0);
    xyl_foliage_destroy(f);
}

/* ---- sectors ------------------------------------------------------------------------------- */

static double azimuth_about(const xyl_foliage *f, xyl_vec3 c)
{
    xyl_vec3 d = {c.x - f->axis_origin.x, c.y - f->axis_origin.y, c.z - f->axis_origin.z};
    xyl_vec3 quarter = cross3(f->axis_direction, f->azimuth_zero);
    double a = atan2(dot3(d, quarter), dot3(d, f->azimuth_zero));
    return a < 0 ? a + 2 * 3.14159265358979323846 : a;
}

static void sectors_split_the_crown_by_azimuth_and_each_draws_its_live_leaves(void **state)
{
    (void)state;
    const leaf_set sets[3] = {SET_CROWN, SET_COPLANAR, SET_CLUMPS};
    const uint32_t counts[3] = {2, 4, 7};
    for (int set = 0; set < 3; ++set)
        for (int k = 0; k < 3; ++k) {
            uint32_t n = SANITIZED ? 300 : 1500, S = counts[k];
            xyl_leaf *in = new_leaves(n, sets[set], 100 + (uint64_t)k);
            xyl_foliage_desc d = {0};
            d.sectors = S;
            if (sets[set] == SET_COPLANAR) d.axis_direction = (xyl_vec3){0, 0, 1}; /* across the plane */
            xyl_foliage *f = build_ok(in, n, &d);
            assert_int_equal(f->sector_count, S);
            uint32_t base = 0, originals = 0;
            for (uint32_t si = 0; si < S; ++si) {
                const xyl_foliage_sector *sec = &f->sectors[si];
                assert_int_equal(sec->base, base);
                if (sec->original_count) assert_int_equal(sec->merged_count, sec->original_count - 1);
                for (uint32_t j = 0; j < sec->original_count; ++j) {
                    double a = azimuth_about(f, f->leaves[base + j].center) * S / (2 * 3.14159265358979323846);
                    assert_true(a >= si - 1e-6 && a <= si + 1 + 1e-6);
                }
                assert_lods_draw_the_live_leaves(f, sec, sec->original_count < 800);
                base += sec->original_count + sec->merged_count;
                originals += sec->original_count;
            }
            assert_int_equal(base, f->leaf_count);
            assert_int_equal(originals, n);
            uint32_t nonempty = 0;
            for (uint32_t si = 0; si < S; ++si) nonempty += f->sectors[si].original_count > 0;
            assert_int_equal(f->coarsest_count, nonempty);
            assert_links_agree(f, in);
            xyl_foliage_destroy(f);
            free(in);
        }
}

static void sectors_without_leaves_have_one_empty_lod(void **state)
{
    (void)state;
    enum { N = 50 };
    xyl_leaf in[N];
    for (int i = 0; i < N; ++i) /* all at x > 0, z <= 0: azimuths in [0, pi / 2] about +Y */
        in[i] = oriented_leaf((xyl_vec3){1.0f + (float)(i % 5), (float)(i / 5), -0.5f * (float)(i % 3)},
                              (xyl_vec3){0, 1, 0}, 0.1 * i, 0.2, 0.1);
    xyl_foliage_desc d = {0};
    d.sectors = 4;
    d.axis_direction = (xyl_vec3){0, 2, 0};
    xyl_foliage *f = build_ok(in, N, &d);
    assert_vec_near(f->azimuth_zero, 1, 0, 0, 0);
    assert_vec_near(f->axis_direction, 0, 1, 0, 0);
    assert_int_equal(f->sectors[0].original_count, N);
    assert_int_equal(f->coarsest_count, 1);
    for (int s = 1; s < 4; ++s) {
        const xyl_foliage_sector *sec = &f->sectors[s];
        assert_int_equal(sec->original_count, 0);
        assert_int_equal(sec->merged_count, 0);
        assert_int_equal(sec->base, 2 * N - 1);
        assert_true(sec->lods[0].a == 0 && sec->lods[0].c == 0 && sec->radius == 0.0f);
    }
    uint32_t lods[4] = {9, 9, 9, 9};
    xyl_foliage_view v = {0};
    v.eye[0] = 1e6f;
    assert_int_equal(xyl_foliage_pick(f, &v, lods, 4, NULL), XYL_OK);
    assert_int_equal(lods[0], N - 1);
    assert_int_equal(lods[1] + lods[2] + lods[3], 0);
    assert_int_equal(xyl_foliage_pick(f, &v, lods, 3, NULL), XYL_ERR_INVALID_ARGUMENT);
    xyl_foliage_destroy(f);
    /* more sectors than leaves */
    d.sectors = XYL_FOLIAGE_MAX_SECTORS;
    f = build_ok(in, 1, &d);
    assert_int_equal(f->leaf_count, 1);
    xyl_foliage_destroy(f);
    d.sectors = XYL_FOLIAGE_MAX_SECTORS + 1;
    d.leaves = in, d.leaf_count = 1;
    assert_int_equal(xyl_foliage_build(&d, &f, NULL), XYL_ERR_INVALID_ARGUMENT);
}

static void one_sector_is_the_default(void **state)
{
    (void)state;
    uint32_t n = 2000;
    xyl_leaf *in = new_leaves(n, SET_CROWN, 3);
    xyl_foliage_desc d = {0};
    d.sectors = 1;
    xyl_foliage *a = build_ok(in, n, NULL), *b = build_ok(in, n, &d);
    assert_memory_equal(a->leaves, b->leaves, a->leaf_count * sizeof *a->leaves);
    assert_memory_equal(a->links, b->links, a->leaf_count * sizeof *a->links);
    xyl_foliage_destroy(a);
    xyl_foliage_destroy(b);
    free(in);
}

static void pick_gives_each_sector_its_own_lod(void **state)
{
    (void)state;
    uint32_t n = SANITIZED ? 800 : 4000;
    xyl_leaf *in = new_leaves(n, SET_CROWN, 8);
    xyl_foliage_desc d = {0};
    d.sectors = 4;
    xyl_foliage *f = build_ok(in, n, &d);
    /* eyes out along the middle of sector 0 and of sector 2, at the same distances: each
       sector is drawn finer from its own side, and each LOD is the coarsest its own budget
       allows */
    xyl_vec3 z = f->azimuth_zero, q = cross3(f->axis_direction, z);
    double c = cos(3.14159265358979323846 / 4), s = sin(3.14159265358979323846 / 4);
    xyl_vec3 dir = {(float)(c * z.x + s * q.x), (float)(c * z.y + s * q.y), (float)(c * z.z + s * q.z)};
    int finer = 0;
    for (double dist = 1; dist < 3000; dist *= 1.02) {
        uint32_t lods[2][4];
        for (int side = 0; side < 2; ++side) {
            double t = side ? -dist : dist;
            xyl_foliage_view v = {0};
            v.eye[0] = f->axis_origin.x + (float)t * dir.x;
            v.eye[1] = f->axis_origin.y + (float)t * dir.y;
            v.eye[2] = f->axis_origin.z + (float)t * dir.z;
            assert_int_equal(xyl_foliage_pick(f, &v, lods[side], 4, NULL), XYL_OK);
            for (int k = 0; k < 4; ++k) {
                const xyl_foliage_sector *sec = &f->sectors[k];
                double e = len3((xyl_vec3){v.eye[0] - sec->center.x, v.eye[1] - sec->center.y,
                                           v.eye[2] - sec->center.z}) - sec->radius;
                double allowed = e * 0.5 * 2.0 * tan(0.4) / 1080.0;
                uint32_t l = lods[side][k];
                if (e <= 0) assert_int_equal(l, 0);
                else assert_true(sec->lods[l].error <= allowed &&
                                 (l == sec->merged_count || sec->lods[l + 1].error > allowed));
            }
        }
        assert_true(lods[0][0] <= lods[1][0] && lods[1][2] <= lods[0][2]);
        finer += lods[0][0] < lods[1][0];
    }
    assert_true(finer > 0);
    xyl_foliage_destroy(f);
    free(in);
}
static void build_returns_every_block_of_the_default_allocator(void **state)
{
    (void)state;
    uint32_t n = SANITIZED ? 3000 : 30000;
    xyl_leaf *in = new_leaves(n, SET_CROWN, 6);
    size_t before = xyl__alloc_blocks_in_use();
    xyl_foliage_desc d = {0};
    d.sectors = 2;
    xyl_foliage *f = build_ok(in, n, &d);
    xyl_foliage_destroy(f);
    assert_int_equal(xyl__alloc_blocks_in_use(), before);
    free(in);
}

static void build_refuses_a_million_leaves_over_the_limit_before_allocating(void **state)
{
    (void)state;
    uint32_t n = 1000000;
    xyl_leaf *in = calloc(n, sizeof *in); /* not even checked: the count comes first */
    assert_non_null(in);
    counter c = {0};
    xyl_foliage_desc d = {0};
    d.leaves = in;
    d.leaf_count = n;
    d.limits.max_leaves = n - 1;
    d.alloc = (xyl_allocator){count_alloc, count_free, &c};
    xyl_foliage *f = NULL;
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_build(&d, &f, &diag), XYL_ERR_LIMIT_EXCEEDED);
    assert_null(f);
    assert_int_equal(c.attempts, 0);
    assert_non_null(strstr(diag.message, "1000000"));
    free(in);
}


/* ---- glTF export --------------------------------------------------------------------------- */

/* The two chunks of a GLB, checked against the container's rules. */
typedef struct glb_parts {
    char *json;               /* NUL-terminated copy (malloc) */
    size_t json_len;
    const unsigned char *bin; /* NULL without a BIN chunk */
    size_t bin_len;
} glb_parts;

static uint32_t u32le(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static float f32le(const unsigned char *b)
{
    uint32_t u = u32le(b);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static glb_parts glb_split(const unsigned char *b, size_t n)
{
    glb_parts p = {0};
    assert_true(n >= 20 && n % 4 == 0);
    assert_int_equal(u32le(b), 0x46546C67u);
    assert_int_equal(u32le(b + 4), 2);
    assert_int_equal(u32le(b + 8), n);
    p.json_len = u32le(b + 12);
    assert_int_equal(u32le(b + 16), 0x4E4F534Au);
    assert_true(20 + p.json_len <= n && p.json_len % 4 == 0);
    p.json = malloc(p.json_len + 1);
    assert_non_null(p.json);
    memcpy(p.json, b + 20, p.json_len);
    p.json[p.json_len] = '\0';
    size_t at = 20 + p.json_len;
    if (at < n) {
        p.bin_len = u32le(b + at);
        assert_int_equal(u32le(b + at + 4), 0x004E4942u);
        assert_int_equal(at + 8 + p.bin_len, n);
        p.bin = b + at + 8;
    }
    return p;
}

static void assert_has(const char *json, const char *part)
{
    if (!strstr(json, part)) fail_msg("the JSON lacks %s:\n%.2000s", part, json);
}

static void assert_lacks(const char *json, const char *part)
{
    if (strstr(json, part)) fail_msg("the JSON has %s:\n%.2000s", part, json);
}

/* Count, then fill; fails the test unless both succeed. */
static unsigned char *glb_memory(const xyl_foliage *f, const xyl_foliage_glb_desc *d, size_t *n)
{
    xyl_diag diag = {0};
    xyl_result r = xyl_foliage_write_glb_memory(f, d, NULL, 0, n, &diag);
    if (r != XYL_OK) fail_msg("count: %s (%s)", xyl_result_string(r), diag.message);
    unsigned char *b = malloc(*n);
    assert_non_null(b);
    size_t again = 0;
    r = xyl_foliage_write_glb_memory(f, d, b, *n, &again, &diag);
    if (r != XYL_OK) fail_msg("fill: %s (%s)", xyl_result_string(r), diag.message);
    assert_int_equal(again, *n);
    return b;
}

/* Leaves of three sizes with their own texture rectangles, in two sectors. */
static xyl_foliage *small_foliage(void)
{
    xyl_leaf l[7];
    for (int i = 0; i < 7; ++i) {
        float a = 6.2831853f * (float)i / 7.0f;
        l[i] = flat_leaf(2.0f * cosf(a), 3.0f + 0.25f * (float)i, 2.0f * sinf(a),
                         0.2f + 0.05f * (float)(i % 3), 0.1f);
        l[i].uv[0] = 0.5f * (float)(i % 2);
        l[i].uv[1] = 0.0f;
        l[i].uv[2] = l[i].uv[0] + 0.5f;
        l[i].uv[3] = 1.0f;
    }
    xyl_foliage_desc d = {0};
    d.sectors = 2;
    return build_ok(l, 7, &d);
}

static void glb_holds_the_leaves_corners_normals_uvs_and_triangles_in_array_order(void **state)
{
    (void)state;
    xyl_foliage *f = small_foliage();
    size_t n = 0;
    unsigned char *b = glb_memory(f, NULL, &n);
    glb_parts p = glb_split(b, n);
    size_t L = f->leaf_count;
    assert_non_null(p.bin);
    assert_int_equal(p.bin_len, 152 * L); /* 4 x (12 + 12 + 8) + 6 x 4 bytes a leaf */
    for (size_t i = 0; i < L; ++i) {
        const xyl_leaf *l = &f->leaves[i];
        xyl__dvec3 c[4];
        xyl__leaf_corners(l, c);
        const float *r = l->uv;
        for (int k = 0; k < 4; ++k) {
            const unsigned char *pos = p.bin + 48 * i + 12 * k, *nrm = pos + 48 * L;
            const unsigned char *uv = p.bin + 96 * L + 32 * i + 8 * k;
            assert_true(f32le(pos) == (float)c[k].x && f32le(pos + 4) == (float)c[k].y &&
                        f32le(pos + 8) == (float)c[k].z);
            assert_true(f32le(nrm) == l->normal.x && f32le(nrm + 4) == l->normal.y &&
                        f32le(nrm + 8) == l->normal.z);
            assert_true(f32le(uv) == (k & 1 ? r[2] : r[0]));
            assert_true(f32le(uv + 4) == 1.0f - (k & 2 ? r[3] : r[1]));
        }
        static const uint32_t tri[6] = {0, 1, 3, 0, 3, 2};
        for (int k = 0; k < 6; ++k)
            assert_int_equal(u32le(p.bin + 128 * L + 24 * i + 4 * k), 4 * i + tri[k]);
    }
    assert_has(p.json, "\"nodes\":[{\"name\":\"leaves\",\"mesh\":0,\"extras\":{\"xylem_foliage\":"
                       "{\"version\":1,");
    assert_has(p.json, "\"attributes\":{\"POSITION\":0,\"NORMAL\":1,\"TEXCOORD_0\":2},"
                       "\"indices\":3,\"material\":0,\"mode\":4");
    assert_has(p.json, "\"alphaMode\":\"MASK\",\"alphaCutoff\":0.5,\"doubleSided\":true");
    assert_has(p.json, "\"baseColorFactor\":");
    assert_lacks(p.json, "\"images\"");
    assert_lacks(p.json, "stems");
    free(p.json);
    free(b);
    xyl_foliage_destroy(f);
}

static void glb_extras_hold_every_sectors_lod_table(void **state)
{
    (void)state;
    xyl_foliage *f = small_foliage();
    size_t n = 0;
    unsigned char *b = glb_memory(f, NULL, &n);
    glb_parts p = glb_split(b, n);
    char want[256];
    snprintf(want, sizeof want, "\"leaf_count\":%zu,\"original_count\":7,\"vertices_per_leaf\":4,"
             "\"indices_per_leaf\":6,", f->leaf_count);
    assert_has(p.json, want);
    for (uint32_t s = 0; s < f->sector_count; ++s) {
        const xyl_foliage_sector *sec = &f->sectors[s];
        snprintf(want, sizeof want, "{\"base\":%u,\"original_count\":%u,\"merged_count\":%u,",
                 sec->base, sec->original_count, sec->merged_count);
        assert_has(p.json, want);
        /* every row, in order: the table is one run of [a,b,c,error] */
        char *rows = strstr(strstr(p.json, want), "\"lods\":[");
        assert_non_null(rows);
        rows += strlen("\"lods\":[");
        for (uint32_t i = 0; i <= sec->merged_count; ++i) {
            const xyl_foliage_lod *l = &sec->lods[i];
            unsigned a, bb, c;
            float e;
            int used = 0;
            assert_int_equal(sscanf(rows, "[%u,%u,%u,%g]%n", &a, &bb, &c, &e, &used), 4);
            assert_true(used > 0);
            assert_int_equal(a, l->a);
            assert_int_equal(bb, l->b);
            assert_int_equal(c, l->c);
            assert_true(e == l->error);
            rows += used;
            assert_int_equal(*rows, i < sec->merged_count ? ',' : ']');
            rows++;
        }
    }
    free(p.json);
    free(b);
    xyl_foliage_destroy(f);
}

/* The signature, an IHDR chunk of a 1 x 1 RGBA image and a few more bytes: the header is all the
 * writer looks at. */
static const unsigned char FAKE_PNG[37] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A, 0, 0, 0,
                                           13, 'I', 'H', 'D', 'R', 0, 0, 0, 1, 0, 0, 0, 1, 8, 6,
                                           0, 0, 0, 1, 2, 3, 4, 'I', 'E', 'N', 'D'};

static void glb_embeds_the_texture_and_its_cutoff(void **state)
{
    (void)state;
    xyl_foliage *f = small_foliage();
    xyl_foliage_glb_desc d = {0};
    d.texture_png = FAKE_PNG;
    d.texture_png_size = sizeof FAKE_PNG;
    d.alpha_cutoff = 0.25f;
    size_t n = 0;
    unsigned char *b = glb_memory(f, &d, &n);
    glb_parts p = glb_split(b, n);
    size_t L = f->leaf_count;
    assert_int_equal(p.bin_len, 152 * L + sizeof FAKE_PNG + 3); /* padded to 4 */
    assert_memory_equal(p.bin + 152 * L, FAKE_PNG, sizeof FAKE_PNG);
    char want[128];
    snprintf(want, sizeof want, "\"images\":[{\"bufferView\":4,\"mimeType\":\"image/png\"}]");
    assert_has(p.json, want);
    snprintf(want, sizeof want, "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu}", 152 * L,
             sizeof FAKE_PNG);
    assert_has(p.json, want);
    assert_has(p.json, "\"baseColorTexture\":{\"index\":0}");
    assert_has(p.json, "\"textures\":[{\"sampler\":0,\"source\":0}]");
    assert_has(p.json, "\"alphaMode\":\"MASK\",\"alphaCutoff\":0.25,\"doubleSided\":true");
    assert_lacks(p.json, "baseColorFactor");
    free(p.json);
    free(b);
    xyl_foliage_destroy(f);
}

static xyl_mesh *stems_and_leaves(xyl_foliage **f)
{
    xyl_skeleton *sk = tu_grow(xyl_lsystem_preset_source("faycal-leaves"), NULL);
    xyl_mesh *m = NULL;
    assert_int_equal(xyl_stems_build(sk, NULL, &m, NULL, NULL), XYL_OK);
    size_t n = 0;
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, NULL, NULL, 0, &n, NULL), XYL_OK);
    assert_true(n > 0);
    xyl_leaf *leaves = malloc(n * sizeof *leaves);
    assert_non_null(leaves);
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, NULL, leaves, n, &n, NULL), XYL_OK);
    xyl_foliage_desc d = {0};
    d.sectors = 3;
    *f = build_ok(leaves, n, &d);
    free(leaves);
    xyl_skeleton_destroy(sk);
    return m;
}

static void glb_with_stems_holds_the_stem_writers_part_first(void **state)
{
    (void)state;
    xyl_foliage *f = NULL;
    xyl_mesh *m = stems_and_leaves(&f);
    xyl_foliage_glb_desc d = {0};
    d.stems = m;
    size_t n = 0, ns = 0;
    unsigned char *b = glb_memory(f, &d, &n);
    assert_int_equal(xyl_mesh_write_memory(m, XYL_MESH_FORMAT_GLB, NULL, NULL, 0, &ns), XYL_OK);
    unsigned char *bs = malloc(ns);
    assert_non_null(bs);
    assert_int_equal(xyl_mesh_write_memory(m, XYL_MESH_FORMAT_GLB, NULL, bs, ns, NULL), XYL_OK);
    glb_parts p = glb_split(b, n), ps = glb_split(bs, ns);
    /* the stems' bytes, then the leaves' */
    assert_int_equal(p.bin_len, ps.bin_len + 152 * f->leaf_count);
    assert_memory_equal(p.bin, ps.bin, ps.bin_len);
    assert_has(p.json, "\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"name\":\"stems\",\"mesh\":0},"
                       "{\"name\":\"leaves\",\"mesh\":1,\"extras\":");
    /* the same glTF mesh and accessors as the stem writer's, then the leaves' */
    char *acc = strstr(ps.json, "\"accessors\":[");
    assert_non_null(acc);
    *strchr(acc, ']') = '\0';
    assert_has(p.json, acc);
    char *stems = strstr(ps.json, "{\"name\":\"stems\",\"primitives\"");
    assert_non_null(stems);
    char *end = strstr(stems, "}]}");
    assert_non_null(end);
    end[3] = '\0';
    assert_has(p.json, stems);
    assert_has(p.json, "{\"name\":\"leaves\",\"primitives\":[{\"attributes\":{\"POSITION\":5,"
                       "\"NORMAL\":6,\"TEXCOORD_0\":7},\"indices\":8,\"material\":0");
    free(p.json);
    free(ps.json);
    free(bs);
    free(b);
    xyl_mesh_destroy(m);
    xyl_foliage_destroy(f);
}

static void glb_of_no_leaves_has_a_leaves_node_without_a_mesh(void **state)
{
    (void)state;
    xyl_foliage_desc fd = {0};
    fd.sectors = 3;
    xyl_foliage *f = build_ok(NULL, 0, &fd);
    xyl_foliage_glb_desc d = {0};
    d.texture_png = FAKE_PNG; /* no material uses it, so it stays out */
    d.texture_png_size = sizeof FAKE_PNG;
    size_t n = 0;
    unsigned char *b = glb_memory(f, &d, &n);
    glb_parts p = glb_split(b, n);
    assert_null(p.bin);
    assert_has(p.json, "\"nodes\":[{\"name\":\"leaves\",\"extras\":{\"xylem_foliage\":{\"version\":1,"
                       "\"leaf_count\":0,\"original_count\":0,");
    assert_has(p.json, "{\"base\":0,\"original_count\":0,\"merged_count\":0,\"center\":");
    const char *row = p.json;
    for (int s = 0; s < 3; ++s) assert_non_null(row = strstr(row + 1, "\"lods\":[[0,0,0,0]]}"));
    assert_null(strstr(row + 1, "\"lods\""));
    assert_lacks(p.json, "\"meshes\"");
    assert_lacks(p.json, "\"materials\"");
    assert_lacks(p.json, "\"images\"");
    assert_lacks(p.json, "\"buffers\"");
    free(p.json);
    free(b);
    /* with stems: the stems' mesh, and the leaves node still without one */
    xyl_foliage *g = NULL;
    xyl_mesh *m = stems_and_leaves(&g);
    d.stems = m;
    b = glb_memory(f, &d, &n);
    p = glb_split(b, n);
    assert_has(p.json, "\"nodes\":[{\"name\":\"stems\",\"mesh\":0},{\"name\":\"leaves\",\"extras\":");
    assert_lacks(p.json, "\"materials\"");
    free(p.json);
    free(b);
    xyl_mesh_destroy(m);
    xyl_foliage_destroy(g);
    xyl_foliage_destroy(f);
}

static bool glb_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

static void glb_file_holds_the_memory_bytes_and_a_failed_write_leaves_no_file(void **state)
{
    (void)state;
    xyl_foliage *f = small_foliage();
    size_t n = 0;
    unsigned char *b = glb_memory(f, NULL, &n);
    char dir[64], path[96], missing[128];
    snprintf(dir, sizeof dir, "xyl-foliage-glb-XXXXXX"); /* in the test's working folder */
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/leaves.glb", dir);
    snprintf(missing, sizeof missing, "%s/no/such/folder/leaves.glb", dir);
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_write_glb_file(f, NULL, path, &diag), XYL_OK);
    assert_int_equal(diag.code, XYL_OK);
    FILE *fp = fopen(path, "rb");
    assert_non_null(fp);
    unsigned char *back = malloc(n + 1);
    assert_non_null(back);
    assert_int_equal(fread(back, 1, n + 1, fp), n);
    fclose(fp);
    assert_memory_equal(back, b, n);
    assert_int_equal(xyl_foliage_write_glb_file(f, NULL, missing, &diag), XYL_ERR_IO);
    assert_int_equal(diag.code, XYL_ERR_IO);
    assert_false(glb_exists(missing));
    /* a bad desc writes nothing: the old file stays as it was */
    xyl_foliage_glb_desc d = {0};
    d.alpha_cutoff = 2.0f;
    assert_int_equal(xyl_foliage_write_glb_file(f, &d, path, &diag), XYL_ERR_INVALID_ARGUMENT);
    fp = fopen(path, "rb");
    assert_non_null(fp);
    assert_int_equal(fread(back, 1, n + 1, fp), n);
    fclose(fp);
    assert_memory_equal(back, b, n);
    assert_int_equal(unlink(path), 0);
    assert_int_equal(rmdir(dir), 0);
    free(back);
    free(b);
    xyl_foliage_destroy(f);
}

static void glb_writers_reject_bad_arguments_with_their_codes(void **state)
{
    (void)state;
    xyl_foliage *f = small_foliage();
    size_t n = 0;
    unsigned char *b = glb_memory(f, NULL, &n);
    unsigned char *out = malloc(n);
    assert_non_null(out);
    xyl_diag diag = {0};
    size_t size = 7;
    /* too small: refused before a byte is written, the size still told */
    memset(out, 0xA5, n);
    assert_int_equal(xyl_foliage_write_glb_memory(f, NULL, out, n - 1, &size, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(size, n);
    for (size_t i = 0; i < n; ++i) assert_int_equal(out[i], 0xA5);
    assert_int_equal(xyl_foliage_write_glb_memory(NULL, NULL, NULL, 0, &size, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_write_glb_memory(f, NULL, NULL, 0, NULL, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_write_glb_file(NULL, NULL, "x.glb", &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_write_glb_file(f, NULL, NULL, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_write_glb_file(f, NULL, "", &diag), XYL_ERR_INVALID_ARGUMENT);
    static const unsigned char not_png[40] = "GIF89a, not a PNG at all, but 40 bytes";
    unsigned char no_ihdr[sizeof FAKE_PNG], empty_image[sizeof FAKE_PNG];
    memcpy(no_ihdr, FAKE_PNG, sizeof FAKE_PNG);
    no_ihdr[12] = 'X';
    memcpy(empty_image, FAKE_PNG, sizeof FAKE_PNG);
    empty_image[19] = 0; /* width 0 */
    struct {
        float cutoff;
        const unsigned char *png;
        size_t png_size;
        xyl_result want;
    } bad[] = {
        {NAN, NULL, 0, XYL_ERR_NON_FINITE},
        {INFINITY, NULL, 0, XYL_ERR_NON_FINITE},
        {-0.1f, NULL, 0, XYL_ERR_INVALID_ARGUMENT},
        {1.5f, NULL, 0, XYL_ERR_INVALID_ARGUMENT},
        {0.5f, NULL, 10, XYL_ERR_INVALID_ARGUMENT},
        {0.5f, FAKE_PNG, 0, XYL_ERR_INVALID_ARGUMENT},
        {0.5f, not_png, sizeof not_png, XYL_ERR_INVALID_ARGUMENT},
        {0.5f, FAKE_PNG, 20, XYL_ERR_INVALID_ARGUMENT},
        {0.5f, no_ihdr, sizeof no_ihdr, XYL_ERR_INVALID_ARGUMENT},
        {0.5f, empty_image, sizeof empty_image, XYL_ERR_INVALID_ARGUMENT},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        xyl_foliage_glb_desc d = {0};
        d.alpha_cutoff = bad[i].cutoff;
        d.texture_png = bad[i].png;
        d.texture_png_size = bad[i].png_size;
        size = 7;
        diag.code = XYL_OK;
        memset(out, 0xA5, n);
        xyl_result r = xyl_foliage_write_glb_memory(f, &d, out, n + 64, &size, &diag);
        if (r != bad[i].want) fail_msg("case %zu: %s (%s)", i, xyl_result_string(r), diag.message);
        assert_int_equal(diag.code, bad[i].want);
        assert_true(strlen(diag.message) > 0);
        assert_int_equal(size, 7);
        for (size_t k = 0; k < n; ++k) assert_int_equal(out[k], 0xA5);
    }
    /* the ends of the cutoff's range are fine */
    xyl_foliage_glb_desc ends = {0};
    ends.alpha_cutoff = 1.0f;
    assert_int_equal(xyl_foliage_write_glb_memory(f, &ends, NULL, 0, &size, &diag), XYL_OK);
    /* a bad stem mesh gives its own code */
    xyl_foliage *g = NULL;
    xyl_mesh *m = stems_and_leaves(&g);
    xyl_vec3 *pos = malloc(m->vertex_count * sizeof *pos);
    assert_non_null(pos);
    memcpy(pos, m->positions, m->vertex_count * sizeof *pos);
    pos[3].y = NAN;
    xyl_mesh view = *m;
    view.positions = pos;
    xyl_foliage_glb_desc d = {0};
    d.stems = &view;
    assert_int_equal(xyl_foliage_write_glb_memory(f, &d, NULL, 0, &size, &diag),
                     XYL_ERR_NON_FINITE);
    assert_int_equal(diag.index, 3);
    view.positions = m->positions;
    view.tri_view_count = 0; /* faces without their triangulated view */
    assert_int_equal(xyl_foliage_write_glb_memory(f, &d, NULL, 0, &size, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    free(pos);
    xyl_mesh_destroy(m);
    xyl_foliage_destroy(g);
    free(out);
    free(b);
    xyl_foliage_destroy(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(leaves_from_skeleton_put_the_blade_along_heading_facing_up),
        cmocka_unit_test(leaves_from_skeleton_count_then_fill),
        cmocka_unit_test(leaves_from_a_skeleton_without_attachments_are_none),
        cmocka_unit_test(leaves_from_skeleton_jitter_depends_on_seed_and_index_only),
        cmocka_unit_test(leaves_from_skeleton_reject_bad_shape_options),
        cmocka_unit_test(leaves_from_skeleton_reject_each_bad_attachment_with_its_code),
        cmocka_unit_test(leaves_from_skeleton_respect_the_leaf_limit),
        cmocka_unit_test(leaves_from_the_default_tree_pass_the_leaf_rules),
        cmocka_unit_test(check_leaves_accepts_coincident_and_coplanar_leaves),
        cmocka_unit_test(check_leaves_rejects_each_bad_leaf_with_its_code),
        cmocka_unit_test(check_leaves_tolerates_rounding_and_the_build_squares_it),
        cmocka_unit_test(check_leaves_limits_counts_and_their_sum),
        cmocka_unit_test(half_floats_round_trip_every_finite_half_exactly),
#if defined(__FLT16_MAX__)
        cmocka_unit_test(half_floats_match_the_compilers_conversion),
#endif
        cmocka_unit_test(pack_gpu_round_trip_keeps_the_stated_precision),
        cmocka_unit_test(pack_gpu_rejects_what_the_record_cannot_hold),
        cmocka_unit_test(collapse_runs_to_one_leaf_standing_for_all),
        cmocka_unit_test(collapse_of_few_leaves_is_the_exact_greedy_chain),
        cmocka_unit_test(merged_leaf_is_the_weighted_bounding_rectangle),
        cmocka_unit_test(merged_leaf_of_coincident_leaves_covers_them_with_no_error),
        cmocka_unit_test(collapse_keeps_coplanar_leaves_in_their_plane),
        cmocka_unit_test(collapse_error_bounds_every_original_point),
        cmocka_unit_test(collapse_stops_at_the_thresholds),
        cmocka_unit_test(collapse_is_deterministic_and_never_searches_all_pairs),
        cmocka_unit_test(collapse_survives_every_allocation_failure),
        cmocka_unit_test(lods_draw_the_live_leaves_of_random_sets_at_every_step),
        cmocka_unit_test(lods_of_a_large_crown_and_a_stopped_chain_draw_the_live_leaves),
        cmocka_unit_test(build_of_no_leaves_is_an_empty_foliage),
        cmocka_unit_test(build_is_deterministic),
        cmocka_unit_test(build_rejects_bad_leaves_and_options_with_their_codes),
        cmocka_unit_test(build_survives_every_allocation_failure),
        cmocka_unit_test(build_returns_every_block_of_the_default_allocator),
        cmocka_unit_test(build_refuses_a_million_leaves_over_the_limit_before_allocating),
        cmocka_unit_test(lod_errors_bound_every_original_point),
        cmocka_unit_test(bounding_spheres_hold_every_original_leaf),
        cmocka_unit_test(pick_is_finest_inside_coarsest_far_and_monotone_in_distance),
        cmocka_unit_test(pick_rejects_bad_views_and_leaves_lods_untouched),
        cmocka_unit_test(cut_is_a_valid_cut_of_the_coarsest_leaves_within_the_budget),
        cmocka_unit_test(sectors_split_the_crown_by_azimuth_and_each_draws_its_live_leaves),
        cmocka_unit_test(sectors_without_leaves_have_one_empty_lod),
        cmocka_unit_test(one_sector_is_the_default),
        cmocka_unit_test(pick_gives_each_sector_its_own_lod),
        cmocka_unit_test(glb_holds_the_leaves_corners_normals_uvs_and_triangles_in_array_order),
        cmocka_unit_test(glb_extras_hold_every_sectors_lod_table),
        cmocka_unit_test(glb_embeds_the_texture_and_its_cutoff),
        cmocka_unit_test(glb_with_stems_holds_the_stem_writers_part_first),
        cmocka_unit_test(glb_of_no_leaves_has_a_leaves_node_without_a_mesh),
        cmocka_unit_test(glb_file_holds_the_memory_bytes_and_a_failed_write_leaves_no_file),
        cmocka_unit_test(glb_writers_reject_bad_arguments_with_their_codes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* foliage/: the CPU rasteriser of leaves, the image error of a leaf set, the leaves of a LOD,
 * and the viewpoint-driven collapse. */
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

/* ---- helpers ------------------------------------------------------------------------------- */

static void assert_near(double got, double want, double tol)
{
    if (!(fabs(got - want) <= tol)) fail_msg("got %.9g, want %.9g (tolerance %g)", got, want, tol);
}

/* A leaf in the plane z = cz facing +z, axis along +y, side along +x. */
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

static uint64_t next_random(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double uniform(uint64_t *s, double lo, double hi)
{
    return lo + (hi - lo) * (double)(next_random(s) >> 11) * (1.0 / 9007199254740992.0);
}

/* n leaves in an ellipsoid crown about (0, 4, 0), random orientation, sizes 0.05 .. 0.15. */
static xyl_leaf *crown(uint32_t n, uint64_t seed)
{
    xyl_leaf *l = malloc((n ? n : 1) * sizeof *l);
    assert_non_null(l);
    uint64_t rng = seed;
    for (uint32_t i = 0; i < n; ++i) {
        double x, y, z;
        do {
            x = uniform(&rng, -1, 1), y = uniform(&rng, -1, 1), z = uniform(&rng, -1, 1);
        } while (x * x + y * y + z * z > 1.0);
        xyl__dvec3 nrm = xyl__d3_normalize_or(xyl__d3(uniform(&rng, -1, 1), uniform(&rng, -0.3, 1),
                                                      uniform(&rng, -1, 1)), xyl__d3(0, 1, 0));
        xyl__dvec3 a = xyl__d3_any_orthogonal(nrm);
        a = xyl__d3_rotate(a, nrm, uniform(&rng, 0, 6.283185307179586));
        double hl = uniform(&rng, 0.025, 0.075), hw = hl * uniform(&rng, 0.3, 0.8);
        xyl__dvec3 s = xyl__d3_cross(a, nrm);
        xyl_leaf t = {0};
        t.center = xyl__to_f3(xyl__d3(3 * x, 4 + 2 * y, 3 * z));
        t.normal = xyl__to_f3(nrm);
        t.axis = xyl__to_f3(xyl__d3_scale(a, hl));
        t.side = xyl__to_f3(xyl__d3_scale(s, hw));
        t.node = -1;
        l[i] = xyl__leaf_tidy(&t);
    }
    return l;
}

/* Looking down -z at the plane z = 0: one world unit a pixel for an image of 2 half pixels. */
static xyl__ortho_view top_view(double half)
{
    xyl__ortho_view v;
    v.center = xyl__d3(0, 0, 0);
    v.right = xyl__d3(1, 0, 0);
    v.up = xyl__d3(0, 1, 0);
    v.toward = xyl__d3(0, 0, 1);
    v.half = half;
    return v;
}

static size_t covered(const xyl__raster *r, uint32_t id)
{
    size_t k = 0;
    for (size_t i = 0; i < (size_t)r->width * r->height; ++i) k += r->id[i] == id;
    return k;
}

/* ---- the rasteriser ------------------------------------------------------------------------ */

static void raster_covers_the_pixel_centres_inside_and_those_on_top_left_edges(void **state)
{
    (void)state;
    xyl__raster r;
    assert_int_equal(xyl__raster_init(&r, 8, 8, NULL), XYL_OK);
    xyl__ortho_view v = top_view(4.0);
    /* x in [-2, 1], y in [-1, 2]: centres x = -1.5, -0.5, 0.5 and y = 1.5, 0.5, -0.5 */
    xyl_leaf a = flat_leaf(-0.5f, 0.5f, 0.0f, 1.5f, 1.5f);
    xyl__raster_leaf(&r, &v, &a, 7, 0.5f);
    assert_int_equal(covered(&r, 7), 9);
    /* column x = -1.5 .. -0.5, rows from y = 1.5 down: pixel (2, 2) is x -1.5, y 1.5 */
    assert_int_equal(r.id[2 * 8 + 2], 7);
    assert_int_equal(r.id[1 * 8 + 2], XYL__RASTER_NONE);
    assert_true(r.shade[2 * 8 + 2] == 0.5f);
    /* edges through pixel centres: x in [-1.5, 0.5], y in [-0.5, 1.5]: the left and top edges'
       centres are in, the right and bottom ones' out */
    xyl__raster_clear(&r);
    xyl_leaf b = flat_leaf(-0.5f, 0.5f, 0.0f, 1.0f, 1.0f);
    xyl__raster_leaf(&r, &v, &b, 3, 1.0f);
    assert_int_equal(covered(&r, 3), 4);
    assert_int_equal(r.id[2 * 8 + 2], 3); /* x -1.5 (left edge), y 1.5 (top edge) */
    assert_int_equal(r.id[2 * 8 + 4], XYL__RASTER_NONE); /* x 0.5: right edge */
    assert_int_equal(r.id[4 * 8 + 2], XYL__RASTER_NONE); /* y -0.5: bottom edge */
    xyl__raster_free(&r, NULL);
}

/* Two quads that share an edge, on a slant, cover disjoint pixel sets whose union is exactly
 * the quad they make together (every coordinate dyadic, so the three are exact). */
static void raster_is_watertight_along_a_shared_edge(void **state)
{
    (void)state;
    xyl__raster r;
    assert_int_equal(xyl__raster_init(&r, 64, 64, NULL), XYL_OK);
    xyl__ortho_view v = top_view(32.0);
    for (int turn = 0; turn < 4; ++turn) {
        float sx = 1.5f + (float)turn * 0.75f, sy = 0.5f + (float)turn * 0.25f;
        xyl_leaf a = {0};
        a.center = (xyl_vec3){-3.25f, 0.75f, 0};
        a.normal = (xyl_vec3){0, 0, 1};
        a.side = (xyl_vec3){sx, sy, 0};
        a.axis = (xyl_vec3){-sy * 3.0f, sx * 3.0f, 0};
        a.node = -1;
        xyl_leaf b = a, ab = a;
        b.center.x += 2 * sx, b.center.y += 2 * sy;
        ab.center.x += sx, ab.center.y += sy;
        ab.side.x *= 2, ab.side.y *= 2;
        uint8_t in_a[64 * 64], in_b[64 * 64];
        xyl__raster_clear(&r);
        xyl__raster_leaf(&r, &v, &a, 1, 1.0f);
        for (int k = 0; k < 64 * 64; ++k) in_a[k] = r.id[k] == 1;
        xyl__raster_clear(&r);
        xyl__raster_leaf(&r, &v, &b, 2, 1.0f);
        for (int k = 0; k < 64 * 64; ++k) in_b[k] = r.id[k] == 2;
        xyl__raster_clear(&r);
        xyl__raster_leaf(&r, &v, &ab, 3, 1.0f);
        size_t na = 0, nb = 0;
        for (int k = 0; k < 64 * 64; ++k) {
            assert_false(in_a[k] && in_b[k]);
            assert_int_equal(in_a[k] || in_b[k], r.id[k] == 3);
            na += in_a[k], nb += in_b[k];
        }
        assert_true(na > 20 && nb > 20);
    }
    xyl__raster_free(&r, NULL);
}

static void raster_keeps_the_nearest_leaf_and_skips_edge_on_ones(void **state)
{
    (void)state;
    xyl__raster r;
    assert_int_equal(xyl__raster_init(&r, 16, 16, NULL), XYL_OK);
    xyl__ortho_view v = top_view(8.0);
    xyl_leaf back = flat_leaf(0, 0, -1.0f, 4, 4), front = flat_leaf(0, 0, 1.0f, 2, 2);
    xyl__raster_leaf(&r, &v, &front, 1, 1.0f);
    xyl__raster_leaf(&r, &v, &back, 0, 0.25f);
    assert_int_equal(covered(&r, 1), 16);
    assert_int_equal(covered(&r, 0), 64 - 16);
    /* a tilted leaf through both: nearer than the back one where it is above it */
    xyl__raster_clear(&r);
    xyl__raster_leaf(&r, &v, &back, 0, 0.25f);
    xyl_leaf tilt = flat_leaf(0, 0, 0, 4, 4);
    tilt.normal = (xyl_vec3){0.6f, 0, 0.8f};
    tilt.side = (xyl_vec3){4 * 0.8f, 0, -4 * 0.6f};
    xyl__raster_leaf(&r, &v, &tilt, 5, 1.0f);
    /* its depth is -0.75 x: above z = -1 for x < 4/3, and it spans |x| <= 3.2 */
    for (uint32_t y = 0; y < 16; ++y)
        for (uint32_t x = 0; x < 16; ++x) {
            double wx = x + 0.5 - 8.0, wy = 8.0 - (y + 0.5);
            uint32_t id = r.id[y * 16 + x];
            if (fabs(wy) < 4 && fabs(wx) < 3.2 && wx < 4.0 / 3.0) assert_int_equal(id, 5);
            else if (fabs(wy) < 4 && fabs(wx) < 4) assert_int_equal(id, 0);
        }
    /* edge-on: nothing */
    xyl__raster_clear(&r);
    xyl_leaf edge = flat_leaf(0, 0, 0, 3, 3);
    edge.normal = (xyl_vec3){1, 0, 0};
    edge.side = (xyl_vec3){0, 0, -3};
    xyl__raster_leaf(&r, &v, &edge, 9, 1.0f);
    assert_int_equal(covered(&r, 9), 0);
    xyl__raster_free(&r, NULL);
}

/* Set up relative to the view's centre in double: a leaf 1e5 from the origin covers the
 * pixels it covers at the origin; a leaf far outside the image (clipped to the guard band)
 * still covers the image where it reaches into it. */
static void raster_is_exact_far_from_the_origin_and_for_huge_leaves(void **state)
{
    (void)state;
    xyl__raster r, s;
    assert_int_equal(xyl__raster_init(&r, 32, 24, NULL), XYL_OK);
    assert_int_equal(xyl__raster_init(&s, 32, 24, NULL), XYL_OK);
    xyl__ortho_view v = top_view(16.0);
    xyl_leaf l = flat_leaf(1.25f, -2.5f, 0.0f, 5.5f, 3.75f);
    l.normal = (xyl_vec3){0, 0.6f, 0.8f};
    l.axis = (xyl_vec3){0, 5.5f * 0.8f, -5.5f * 0.6f};
    xyl__raster_leaf(&r, &v, &l, 1, 1.0f);
    xyl__ortho_view far = v;
    far.center = xyl__d3(1e5, -2e5, 3e5);
    xyl_leaf lf = l;
    lf.center.x += 1e5f, lf.center.y -= 2e5f, lf.center.z += 3e5f;
    xyl__raster_leaf(&s, &far, &lf, 1, 1.0f);
    assert_memory_equal(r.id, s.id, 32 * 24 * sizeof *r.id);
    assert_true(covered(&r, 1) > 50);
    /* a leaf a million pixels wide: everything but the column x < 2 */
    xyl__raster_clear(&r);
    xyl_leaf huge = flat_leaf(1e6f + 2.0f - 16.0f, 0, 0, 1e6f, 1e6f);
    xyl__raster_leaf(&r, &v, &huge, 4, 1.0f);
    assert_int_equal(covered(&r, 4), 30 * 24);
    xyl__raster_free(&r, NULL);
    xyl__raster_free(&s, NULL);
}

static void dodecahedron_views_are_twenty_unit_frames_framing_the_sphere(void **state)
{
    (void)state;
    xyl__ortho_view v[XYL__VIEWS];
    xyl__dodecahedron_views(xyl__d3(1, 2, 3), 5.0, v);
    for (int i = 0; i < XYL__VIEWS; ++i) {
        assert_near(xyl__d3_len(v[i].toward), 1, 1e-12);
        assert_near(xyl__d3_len(v[i].up), 1, 1e-12);
        assert_near(xyl__d3_dot(v[i].up, v[i].toward), 0, 1e-12);
        xyl__dvec3 t = xyl__d3_cross(v[i].right, v[i].up);
        assert_near(xyl__d3_len(xyl__d3_sub(t, v[i].toward)), 0, 1e-12);
        assert_true(v[i].half == 5.0 && v[i].center.x == 1 && v[i].center.z == 3);
        /* a dodecahedron's vertex has three nearest at the edge's angle, cos = sqrt(5) / 3 */
        int near = 0;
        for (int j = 0; j < XYL__VIEWS; ++j) {
            double c = xyl__d3_dot(v[i].toward, v[j].toward);
            if (j != i) assert_true(c < 0.75);
            near += fabs(c - sqrt(5.0) / 3.0) < 1e-12;
        }
        assert_int_equal(near, 3);
    }
}

/* ---- the image error ----------------------------------------------------------------------- */

static void image_error_of_a_set_against_itself_is_zero(void **state)
{
    (void)state;
    xyl_leaf *l = crown(500, 3);
    xyl_foliage_image_error e;
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_image_error_of(l, 500, l, 500, NULL, &e, &diag), XYL_OK);
    assert_true(e.rmse_mean == 0.0 && e.rmse_worst == 0.0 && e.coverage_mean == 0.0 &&
                e.coverage_worst == 0.0);
    assert_near(e.hausdorff, 0.0, 1e-7); /* the samples' rounding off their float quads */
    assert_int_equal(e.resolution, 256);
    assert_true(e.radius > 3.0f && e.radius < 4.5f);
    free(l);
}

/* One square facing +z against nothing: every view sees it but the four that lie in its plane
 * (views 9, 12, 15, 18: (+-1/phi, +-phi, 0)), so the coverage error is 1 in 16 views, 0 in 4. */
static void image_error_of_a_removed_square_is_its_coverage(void **state)
{
    (void)state;
    xyl_leaf sq = flat_leaf(0, 0, 0, 1, 1);
    xyl_foliage_image_error e;
    xyl_diag diag = {0};
    xyl_foliage_image_desc d = {0};
    d.resolution = 64;
    assert_int_equal(xyl_foliage_image_error_of(&sq, 1, NULL, 0, &d, &e, &diag), XYL_OK);
    for (int v = 0; v < XYL_FOLIAGE_IMAGE_VIEWS; ++v) {
        bool edge_on = v == 9 || v == 12 || v == 15 || v == 18;
        assert_true(e.coverage[v] == (edge_on ? 0.0 : 1.0));
        if (edge_on) assert_true(e.rmse[v] == 0.0);
        else assert_true(e.rmse[v] > 0.1);
    }
    assert_near(e.coverage_mean, 0.8, 1e-12);
    assert_true(e.coverage_worst == 1.0);
    assert_true(isinf(e.hausdorff));
    /* seen straight on in its own view (toward (1, 1, 1) / sqrt 3), the square covers the
       fraction 4 cos / (pi r^2 ... ) of the frame: its shade |n . l| = 3 / sqrt(14) over area
       4 / sqrt(3) of a (2 sqrt 2)^2 frame gives rmse = shade sqrt(fraction) */
    double fraction = (4.0 / sqrt(3.0)) / 8.0, shade = 3.0 / sqrt(14.0);
    assert_near(e.rmse[7], shade * sqrt(fraction), 0.02);
    /* two squares side by side, one removed: half the covered pixels in every view that sees
       them, up to the pixels' quantisation */
    xyl_leaf two[2] = {flat_leaf(-1, 0, 0, 1, 1), flat_leaf(1, 0, 0, 1, 1)};
    d.resolution = 512;
    assert_int_equal(xyl_foliage_image_error_of(two, 2, two, 1, &d, &e, &diag), XYL_OK);
    for (int v = 0; v < XYL_FOLIAGE_IMAGE_VIEWS; ++v) {
        bool edge_on = v == 9 || v == 12 || v == 15 || v == 18;
        if (edge_on) assert_true(e.coverage[v] == 0.0);
        else assert_near(e.coverage[v], 0.5, 0.01);
    }
    assert_near(e.coverage_mean, 0.4, 0.01);
    assert_near(e.hausdorff, 2.0, 1e-6); /* the far edge of the removed square */
}

static void hausdorff_of_parallel_squares_is_their_offset(void **state)
{
    (void)state;
    const double offsets[4] = {0.0, 0.001, 0.3, 7.0};
    for (int i = 0; i < 4; ++i) {
        xyl_leaf a = flat_leaf(0.5f, 0.5f, 0, 0.5f, 0.5f), b = flat_leaf(0.5f, 0.5f, (float)offsets[i], 0.5f, 0.5f);
        xyl_foliage_image_error e;
        xyl_diag diag = {0};
        assert_int_equal(xyl_foliage_image_error_of(&a, 1, &b, 1, NULL, &e, &diag), XYL_OK);
        assert_near(e.hausdorff, (double)(float)offsets[i], 1e-7);
    }
    /* shifted in its plane by 0.25: the far edges are 0.25 from the other square */
    xyl_leaf a = flat_leaf(0, 0, 0, 0.5f, 0.5f), b = flat_leaf(0.25f, 0, 0, 0.5f, 0.5f);
    xyl_foliage_image_error e;
    assert_int_equal(xyl_foliage_image_error_of(&a, 1, &b, 1, NULL, &e, NULL), XYL_OK);
    assert_near(e.hausdorff, 0.25, 1e-7);
}

/* Against a brute force over every sample and every quad: the grid search loses nothing. */
static void hausdorff_matches_a_brute_force(void **state)
{
    (void)state;
    xyl_leaf *a = crown(150, 5), *b = crown(90, 6);
    for (uint32_t i = 0; i < 90; ++i) b[i].center.x += 0.5f;
    xyl_foliage_image_desc d = {0};
    d.hausdorff_step = 0.02f;
    xyl_foliage_image_error e;
    assert_int_equal(xyl_foliage_image_error_of(a, 150, b, 90, &d, &e, NULL), XYL_OK);
    double h = 0.0;
    for (int dir = 0; dir < 2; ++dir) {
        const xyl_leaf *p = dir ? b : a, *q = dir ? a : b;
        uint32_t np = dir ? 90 : 150, nq = dir ? 150 : 90;
        for (uint32_t i = 0; i < np; ++i) {
            xyl__dvec3 c = xyl__from_f3(p[i].center), s = xyl__from_f3(p[i].side), t = xyl__from_f3(p[i].axis);
            double ks = fmax(2, ceil(2 * xyl__d3_len(s) / 0.02f) + 1), kt = fmax(2, ceil(2 * xyl__d3_len(t) / 0.02f) + 1);
            for (double u = 0; u < ks; ++u)
                for (double w = 0; w < kt; ++w) {
                    xyl__dvec3 x = xyl__d3_add(c, xyl__d3_add(xyl__d3_scale(s, -1 + 2 * u / (ks - 1)),
                                                              xyl__d3_scale(t, -1 + 2 * w / (kt - 1))));
                    double m = INFINITY;
                    for (uint32_t j = 0; j < nq; ++j) m = fmin(m, xyl__leaf_quad_distance(x, &q[j]));
                    h = fmax(h, m);
                }
        }
    }
    assert_near(e.hausdorff, h, 1e-8); /* the call measures tidied copies */
    assert_true(h > 0.3);
    free(a);
    free(b);
}

static void image_error_is_deterministic(void **state)
{
    (void)state;
    xyl_leaf *a = crown(800, 8), *b = crown(300, 9);
    xyl_foliage_image_error e1, e2;
    memset(&e1, 0x5A, sizeof e1);
    memset(&e2, 0xA5, sizeof e2);
    xyl_foliage_image_desc d = {0};
    d.resolution = 128;
    assert_int_equal(xyl_foliage_image_error_of(a, 800, b, 300, &d, &e1, NULL), XYL_OK);
    assert_int_equal(xyl_foliage_image_error_of(a, 800, b, 300, &d, &e2, NULL), XYL_OK);
    assert_memory_equal(&e1.rmse, &e2.rmse, sizeof e1.rmse);
    assert_memory_equal(&e1.coverage, &e2.coverage, sizeof e1.coverage);
    assert_true(e1.hausdorff == e2.hausdorff && e1.rmse_mean == e2.rmse_mean);
    assert_true(e1.coverage_mean > 0.1 && e1.coverage_worst >= e1.coverage_mean);
    free(a);
    free(b);
}

static void image_error_rejects_bad_input_with_its_code(void **state)
{
    (void)state;
    xyl_leaf good[2] = {flat_leaf(0, 0, 0, 1, 1), flat_leaf(3, 0, 0, 1, 1)};
    xyl_leaf bad[2] = {good[0], good[1]};
    xyl_foliage_image_error e, before;
    memset(&e, 0x3C, sizeof e);
    before = e;
    xyl_diag diag = {0};
    xyl_foliage_image_desc d = {0};
#define EXPECT(call, want)                                                                         \
    do {                                                                                           \
        assert_int_equal((call), (want));                                                          \
        assert_int_equal(diag.code, (want));                                                       \
        assert_memory_equal(&e, &before, sizeof e);                                                \
    } while (0)
    EXPECT(xyl_foliage_image_error_of(NULL, 0, good, 2, &d, &e, &diag), XYL_ERR_INVALID_ARGUMENT);
    EXPECT(xyl_foliage_image_error_of(good, 0, good, 2, &d, &e, &diag), XYL_ERR_INVALID_ARGUMENT);
    EXPECT(xyl_foliage_image_error_of(good, 2, NULL, 2, &d, &e, &diag), XYL_ERR_INVALID_ARGUMENT);
    EXPECT(xyl_foliage_image_error_of(good, 2, good, 2, &d, NULL, &diag), XYL_ERR_INVALID_ARGUMENT);
    bad[1].center.y = NAN;
    EXPECT(xyl_foliage_image_error_of(good, 2, bad, 2, &d, &e, &diag), XYL_ERR_NON_FINITE);
    assert_int_equal(diag.index, 1);
    assert_non_null(strstr(diag.message, "approx"));
    EXPECT(xyl_foliage_image_error_of(bad, 2, good, 2, &d, &e, &diag), XYL_ERR_NON_FINITE);
    assert_non_null(strstr(diag.message, "reference"));
    bad[1].center.y = 2e6f;
    EXPECT(xyl_foliage_image_error_of(bad, 2, good, 2, &d, &e, &diag), XYL_ERR_LIMIT_EXCEEDED);
    bad[1] = good[1];
    bad[1].axis.y = 0;
    EXPECT(xyl_foliage_image_error_of(good, 2, bad, 2, &d, &e, &diag), XYL_ERR_INVALID_ARGUMENT);
    d.resolution = XYL_FOLIAGE_IMAGE_MAX_RESOLUTION + 1;
    EXPECT(xyl_foliage_image_error_of(good, 2, good, 2, &d, &e, &diag), XYL_ERR_INVALID_ARGUMENT);
    d.resolution = 0;
    d.hausdorff_step = -1.0f;
    EXPECT(xyl_foliage_image_error_of(good, 2, good, 2, &d, &e, &diag), XYL_ERR_INVALID_ARGUMENT);
    d.hausdorff_step = NAN;
    EXPECT(xyl_foliage_image_error_of(good, 2, good, 2, &d, &e, &diag), XYL_ERR_NON_FINITE);
    d.hausdorff_step = 1e-4f; /* (2e4 + 1)^2 samples a square */
    EXPECT(xyl_foliage_image_error_of(good, 2, good, 2, &d, &e, &diag), XYL_ERR_LIMIT_EXCEEDED);
    d.hausdorff_step = 0.0f;
    d.limits.max_leaves = 1;
    EXPECT(xyl_foliage_image_error_of(good, 2, good, 1, &d, &e, &diag), XYL_ERR_LIMIT_EXCEEDED);
#undef EXPECT
    /* a huge approximation far from the reference is measured, not refused */
    xyl_leaf far = flat_leaf(9e5f, 0, 0, 9e4f, 9e4f);
    d.limits.max_leaves = 0;
    d.hausdorff_step = 1e4f;
    assert_int_equal(xyl_foliage_image_error_of(good, 2, &far, 1, &d, &e, &diag), XYL_OK);
    assert_near(e.coverage_mean, 0.8, 1e-12); /* nothing of it in the frame */
    assert_true(e.hausdorff > 8e5);
}

/* ---- the leaves of a LOD, and its resolution ----------------------------------------------- */

static xyl_foliage *build(const xyl_leaf *l, uint32_t n, uint32_t sectors)
{
    xyl_foliage_desc d = {0};
    d.leaves = l;
    d.leaf_count = n;
    d.sectors = sectors;
    xyl_foliage *f = NULL;
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_build(&d, &f, &diag), XYL_OK);
    return f;
}

static void gather_counts_then_fills_the_two_ranges_of_each_sector(void **state)
{
    (void)state;
    xyl_leaf *l = crown(400, 11);
    xyl_foliage *f = build(l, 400, 3);
    uint32_t lods[3] = {0, f->sectors[1].merged_count / 2, f->sectors[2].merged_count};
    size_t n = 0;
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_gather(f, lods, 3, NULL, 0, &n, &diag), XYL_OK);
    size_t want = 0;
    for (int s = 0; s < 3; ++s) want += f->sectors[s].lods[lods[s]].a + f->sectors[s].lods[lods[s]].c;
    assert_int_equal(n, want);
    xyl_leaf *out = malloc(n * sizeof *out);
    assert_non_null(out);
    size_t m = 0;
    assert_int_equal(xyl_foliage_gather(f, lods, 3, out, n, &m, &diag), XYL_OK);
    assert_int_equal(m, n);
    size_t at = 0;
    uint32_t represented = 0;
    for (int s = 0; s < 3; ++s) {
        const xyl_foliage_sector *sec = &f->sectors[s];
        const xyl_foliage_lod *lod = &sec->lods[lods[s]];
        for (uint32_t k = 0; k < lod->a; ++k) assert_memory_equal(&out[at++], &f->leaves[sec->base + k], sizeof *out);
        for (uint32_t k = 0; k < lod->c; ++k)
            assert_memory_equal(&out[at++], &f->leaves[sec->base + lod->b + k], sizeof *out);
    }
    for (size_t k = 0; k < n; ++k) represented += out[k].count;
    assert_int_equal(represented, 400);
    /* bad calls leave out and count alone */
    size_t keep = 77;
    xyl_leaf first = out[0];
    assert_int_equal(xyl_foliage_gather(f, lods, 3, out, n - 1, &keep, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_gather(f, lods, 2, out, n, &keep, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_gather(NULL, lods, 3, out, n, &keep, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_gather(f, lods, 3, out, n, NULL, &diag), XYL_ERR_INVALID_ARGUMENT);
    lods[2] += 1;
    assert_int_equal(xyl_foliage_gather(f, lods, 3, out, n, &keep, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(diag.index, 2);
    assert_int_equal(keep, 77);
    assert_memory_equal(&out[0], &first, sizeof first);
    free(out);
    xyl_foliage_destroy(f);
    free(l);
}

static void lod_resolution_is_where_the_pick_starts_to_choose_the_lod(void **state)
{
    (void)state;
    xyl_leaf *l = crown(300, 12);
    xyl_foliage *f = build(l, 300, 1);
    const xyl_foliage_sector *s = &f->sectors[0];
    uint32_t res = 0;
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_lod_resolution(f, 0, 0, 0.0f, &res, &diag), XYL_OK);
    assert_int_equal(res, XYL_FOLIAGE_IMAGE_MAX_RESOLUTION);
    uint32_t lod = s->merged_count / 2;
    assert_int_equal(xyl_foliage_lod_resolution(f, 0, lod, 1.0f, &res, &diag), XYL_OK);
    assert_int_equal(res, (uint32_t)floor(2.0 * f->radius / s->lods[lod].error));
    /* a pixel of 2 radius / res world units is at least lods[lod].error: the pick allows it */
    assert_true(2.0 * f->radius / res >= s->lods[lod].error);
    assert_true(2.0 * f->radius / (res + 1) < s->lods[lod].error);
    assert_int_equal(xyl_foliage_lod_resolution(f, 0, s->merged_count, 0.0f, &res, &diag), XYL_OK);
    assert_true(res >= 1);
    assert_int_equal(xyl_foliage_lod_resolution(f, 1, 0, 0.0f, &res, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_lod_resolution(f, 0, s->merged_count + 1, 0.0f, &res, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_lod_resolution(f, 0, 0, -1.0f, &res, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_lod_resolution(f, 0, 0, NAN, &res, &diag), XYL_ERR_NON_FINITE);
    assert_int_equal(xyl_foliage_lod_resolution(NULL, 0, 0, 0.0f, &res, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_lod_resolution(f, 0, 0, 0.0f, NULL, &diag), XYL_ERR_INVALID_ARGUMENT);
    xyl_foliage_destroy(f);
    free(l);
}

/* LOD 0 is the reference; coarser LODs look worse, measured at one resolution. */
static void image_error_of_lods_is_zero_at_lod_0_and_grows(void **state)
{
    (void)state;
    xyl_leaf *l = crown(600, 13);
    xyl_foliage *f = build(l, 600, 1);
    xyl_leaf *g = malloc(600 * sizeof *g);
    assert_non_null(g);
    xyl_foliage_image_desc d = {0};
    d.resolution = 128;
    double last = -1.0, last_h = -1.0;
    const uint32_t lods[4] = {0, 300, 540, 599};
    for (int i = 0; i < 4; ++i) {
        size_t n = 0;
        assert_int_equal(xyl_foliage_gather(f, &lods[i], 1, g, 600, &n, NULL), XYL_OK);
        assert_int_equal(n, 600 - lods[i]);
        xyl_foliage_image_error e;
        assert_int_equal(xyl_foliage_image_error_of(l, 600, g, n, &d, &e, NULL), XYL_OK);
        if (i == 0) assert_true(e.coverage_mean == 0.0 && e.rmse_mean == 0.0 && e.hausdorff < 1e-7);
        assert_true(e.coverage_mean > last && e.hausdorff > last_h);
        last = e.coverage_mean, last_h = e.hausdorff;
    }
    free(g);
    xyl_foliage_destroy(f);
    free(l);
}


/* ---- the viewpoint-driven collapse --------------------------------------------------------- */

static xyl_foliage *build_viewpoint(const xyl_leaf *l, uint32_t n, uint32_t resolution, float max_distance)
{
    xyl_foliage_desc d = {0};
    d.leaves = l;
    d.leaf_count = n;
    d.cost = XYL_FOLIAGE_COST_VIEWPOINT;
    d.viewpoint.resolution = resolution;
    d.max_distance = max_distance;
    xyl_foliage *f = NULL;
    xyl_diag diag = {0};
    xyl_result r = xyl_foliage_build(&d, &f, &diag);
    if (r != XYL_OK) fail_msg("build: %s (%s)", xyl_result_string(r), diag.message);
    return f;
}

static void viewpoint_chain_is_deterministic(void **state)
{
    (void)state;
    xyl_leaf *l = crown(700, 21);
    xyl_foliage *f = build_viewpoint(l, 700, 96, 0.0f), *g = build_viewpoint(l, 700, 96, 0.0f);
    assert_int_equal(f->leaf_count, 2 * 700 - 1);
    assert_int_equal(g->leaf_count, f->leaf_count);
    assert_memory_equal(f->leaves, g->leaves, f->leaf_count * sizeof *f->leaves);
    assert_memory_equal(f->links, g->links, f->leaf_count * sizeof *f->links);
    assert_memory_equal(f->sectors[0].lods, g->sectors[0].lods, 700 * sizeof *f->sectors[0].lods);
    /* and it is not the Hidalgo chain */
    xyl_foliage *h = build(l, 700, 1);
    assert_true(memcmp(f->links, h->links, f->leaf_count * sizeof *f->links) != 0);
    xyl_foliage_destroy(f);
    xyl_foliage_destroy(g);
    xyl_foliage_destroy(h);
    free(l);
}

/* Two large leaves and a small one between them: the small one is the least visible in every
 * view, so the first merge takes it. */
static void viewpoint_chain_merges_the_least_visible_leaf_first(void **state)
{
    (void)state;
    xyl_leaf l[3] = {flat_leaf(-2, 0, 0, 1, 1), flat_leaf(2.5f, 0, 0, 1, 1), flat_leaf(0, 0, 0, 0.1f, 0.1f)};
    l[1].normal = (xyl_vec3){0, 1, 0};
    l[1].axis = (xyl_vec3){0, 0, -1};
    xyl_foliage *f = build_viewpoint(l, 3, 128, 0.0f);
    /* LOD 1 draws one original, stored first (originals by decreasing LOD of death): not it */
    assert_int_equal(f->sectors[0].lods[1].a, 1);
    for (size_t k = 0; k < 3; ++k)
        if (f->links[k].source == 2) assert_true(k >= 1);
    xyl_foliage_destroy(f);
}

static void viewpoint_chain_keeps_the_distance_threshold(void **state)
{
    (void)state;
    xyl_leaf *l = crown(600, 22);
    xyl_foliage *f = build_viewpoint(l, 600, 64, 0.3f);
    const xyl_foliage_sector *s = &f->sectors[0];
    assert_true(s->merged_count > 0 && s->merged_count < 599);
    assert_int_equal(f->coarsest_count, 600 - s->merged_count);
    for (size_t k = 0; k < f->leaf_count; ++k) {
        const xyl_leaf_link *ln = &f->links[k];
        if (ln->source != UINT32_MAX) continue;
        xyl_vec3 a = f->leaves[ln->children[0]].center, b = f->leaves[ln->children[1]].center;
        double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
        assert_true(sqrt(dx * dx + dy * dy + dz * dz) <= 0.3 * (1 + 1e-6));
    }
    xyl_foliage_destroy(f);
    free(l);
}

static void viewpoint_options_are_checked(void **state)
{
    (void)state;
    xyl_leaf l[2] = {flat_leaf(0, 0, 0, 1, 1), flat_leaf(3, 0, 0, 1, 1)};
    xyl_foliage_desc d = {0};
    d.leaves = l;
    d.leaf_count = 2;
    xyl_foliage *f = (xyl_foliage *)(uintptr_t)1;
    xyl_diag diag = {0};
    d.cost = (xyl_foliage_cost)2;
    assert_int_equal(xyl_foliage_build(&d, &f, &diag), XYL_ERR_INVALID_ARGUMENT);
    d.cost = XYL_FOLIAGE_COST_VIEWPOINT;
    d.viewpoint.resolution = XYL_FOLIAGE_IMAGE_MAX_RESOLUTION + 1;
    assert_int_equal(xyl_foliage_build(&d, &f, &diag), XYL_ERR_INVALID_ARGUMENT);
    d.viewpoint.resolution = 0;
    d.viewpoint.cell_leaves = 9;
    assert_int_equal(xyl_foliage_build(&d, &f, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_ptr_equal(f, (xyl_foliage *)(uintptr_t)1);
    d.viewpoint.cell_leaves = 1;
    d.viewpoint.resolution = 1;
    assert_int_equal(xyl_foliage_build(&d, &f, &diag), XYL_OK);
    assert_int_equal(f->sectors[0].merged_count, 1);
    xyl_foliage_destroy(f);
}

static void viewpoint_build_survives_every_allocation_failure(void **state)
{
    (void)state;
    xyl_leaf *l = crown(150, 23);
    for (size_t fail = 1;; ++fail) {
        tu_counter c = {0, 0, 0, fail};
        xyl_foliage_desc d = {0};
        d.leaves = l;
        d.leaf_count = 150;
        d.sectors = 2;
        d.cost = XYL_FOLIAGE_COST_VIEWPOINT;
        d.viewpoint.resolution = 32;
        d.alloc = tu_counting(&c);
        xyl_foliage *f = (xyl_foliage *)(uintptr_t)1;
        xyl_result r = xyl_foliage_build(&d, &f, NULL);
        if (c.attempts < fail) {
            assert_int_equal(r, XYL_OK);
            xyl_foliage_destroy(f);
            assert_int_equal(c.allocs, c.frees);
            break;
        }
        assert_int_equal(r, XYL_ERR_OUT_OF_MEMORY);
        assert_ptr_equal(f, (xyl_foliage *)(uintptr_t)1);
        assert_int_equal(c.allocs, c.frees);
    }
    free(l);
}

/* The coverage error of `live` leaves of a chain (replayed from its children) against the
 * originals. */
static double chain_coverage(const xyl_leaf *orig, const xyl_leaf *chain, const uint32_t *children,
                             uint32_t n, uint32_t live)
{
    uint8_t *alive = calloc(2 * n, 1);
    xyl_leaf *g = malloc(2 * n * sizeof *g);
    assert_true(alive && g);
    memset(alive, 1, n);
    uint32_t k = 0;
    for (; n - k > live; ++k) alive[children[2 * k]] = alive[children[2 * k + 1]] = 0, alive[n + k] = 1;
    size_t m = 0;
    for (uint32_t i = 0; i < n + k; ++i)
        if (alive[i]) g[m++] = chain[i];
    xyl_foliage_image_desc d = {0};
    d.resolution = 128;
    xyl_foliage_image_error e;
    assert_int_equal(xyl_foliage_image_error_of(orig, n, g, m, &d, &e, NULL), XYL_OK);
    free(alive);
    free(g);
    return e.coverage_mean;
}

/* Between renders the merged leaves' visible pixels are estimated; rendering after every
 * merge instead gives LODs that look nearly the same. */
static void viewpoint_estimates_stay_near_an_exact_recomputation(void **state)
{
    (void)state;
    enum { N = 240 };
    xyl_leaf *l = crown(N, 24);
    double cov[2][3];
    for (int exact = 0; exact < 2; ++exact) {
        xyl_leaf *c = malloc(2 * N * sizeof *c);
        float *e = malloc(2 * N * sizeof *e);
        uint32_t *ch = malloc(2 * N * sizeof *ch), m = 0;
        assert_true(c && e && ch);
        memcpy(c, l, N * sizeof *l);
        xyl__viewpoint_options o = {64, XYL__GRID_K, exact ? 1u : 0u, INFINITY, INFINITY};
        xyl__viewpoint_stats st;
        assert_int_equal(xyl__collapse_viewpoint(c, e, ch, N, &o, NULL, &m, &st, NULL), XYL_OK);
        assert_int_equal(m, N - 1);
        if (exact) assert_int_equal(st.renders, N - 1); /* before every merge but the first */
        else assert_true(st.renders < N / 3);
        const uint32_t live[3] = {N / 2, N / 4, N / 10};
        for (int i = 0; i < 3; ++i) cov[exact][i] = chain_coverage(l, c, ch, N, live[i]);
        free(c);
        free(e);
        free(ch);
    }
    for (int i = 0; i < 3; ++i) assert_near(cov[0][i], cov[1][i], 0.03);
    free(l);
}

/* ---- triangles against leaves ---------------------------------------------------------------- */

/* Leaves split into two triangles each: the same set, measured the same way. */
static void triangles_of_the_leaves_measure_as_the_leaves(void **state)
{
    (void)state;
    const uint32_t n = 300;
    xyl_leaf *l = crown(n, 11);
    float *pos = malloc(12 * n * sizeof *pos);
    uint32_t *idx = malloc(6 * n * sizeof *idx);
    assert_non_null(pos);
    assert_non_null(idx);
    for (uint32_t i = 0; i < n; ++i) {
        xyl__dvec3 c[4];
        xyl__leaf_corners(&l[i], c);
        for (int k = 0; k < 4; ++k) {
            pos[12 * i + 3 * k] = (float)c[k].x;
            pos[12 * i + 3 * k + 1] = (float)c[k].y;
            pos[12 * i + 3 * k + 2] = (float)c[k].z;
        }
        const uint32_t t[6] = {0, 1, 3, 0, 3, 2};
        for (int k = 0; k < 6; ++k) idx[6 * i + k] = 4 * i + t[k];
    }
    xyl_foliage_image_desc d = {0};
    d.resolution = 128;
    xyl_foliage_image_error e;
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_image_error_triangles(l, n, pos, 4 * n, idx, 2 * n, &d, &e, &diag), XYL_OK);
    assert_true(e.coverage_worst <= 1e-3); /* corners rounded to float may move a pixel centre */
    assert_true(e.rmse_worst <= 0.01);
    assert_true(e.hausdorff <= 1e-5);
    assert_int_equal(e.resolution, 128);
    /* and half of them missing shows */
    xyl_foliage_image_error half;
    assert_int_equal(xyl_foliage_image_error_triangles(l, n, pos, 4 * n, idx, n, &d, &half, &diag), XYL_OK);
    assert_true(half.coverage_mean > 0.2);
    free(pos);
    free(idx);
    free(l);
}

/* The unit square at z = 0 against the triangle of its lower-left half lifted to z = h: the
 * square's corner (1, 1, 0) lies sqrt(1/2 + h^2) from the triangle, every point of the
 * triangle h from the square. */
static void hausdorff_of_a_square_and_a_triangle(void **state)
{
    (void)state;
    const double heights[3] = {0.0, 0.25, 2.0};
    for (int i = 0; i < 3; ++i) {
        xyl_leaf sq = flat_leaf(0.5f, 0.5f, 0, 0.5f, 0.5f);
        float h = (float)heights[i];
        const float pos[9] = {0, 0, h, 1, 0, h, 0, 1, h};
        const uint32_t idx[3] = {0, 1, 2};
        xyl_foliage_image_desc d = {0};
        d.hausdorff_step = 0.01f;
        xyl_foliage_image_error e;
        assert_int_equal(xyl_foliage_image_error_triangles(&sq, 1, pos, 3, idx, 1, &d, &e, NULL), XYL_OK);
        double want = sqrt(0.5 + (double)h * h);
        assert_true(e.hausdorff <= want + 1e-6);
        assert_true(e.hausdorff >= want - 0.01 / sqrt(2.0));
    }
    /* a degenerate triangle counts as its segment: from (0, 0, 0) to (1, 0, 0) */
    xyl_leaf sq = flat_leaf(0.5f, 0.5f, 0, 0.5f, 0.5f);
    const float seg[9] = {0, 0, 0, 1, 0, 0, 0.5f, 0, 0};
    const uint32_t idx[3] = {0, 1, 2};
    xyl_foliage_image_error e;
    assert_int_equal(xyl_foliage_image_error_triangles(&sq, 1, seg, 3, idx, 1, NULL, &e, NULL), XYL_OK);
    assert_near(e.hausdorff, 1.0, 1e-6); /* the far edge y = 1 */
    for (int v = 0; v < XYL_FOLIAGE_IMAGE_VIEWS; ++v) assert_true(e.coverage[v] == 1.0 || e.coverage[v] == 0.0);
}

static void image_error_triangles_rejects_bad_input(void **state)
{
    (void)state;
    xyl_leaf sq = flat_leaf(0.5f, 0.5f, 0, 0.5f, 0.5f);
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    xyl_foliage_image_error e;
    memset(&e, 0x5a, sizeof e);
    xyl_foliage_image_error before = e;
    xyl_diag diag = {0};
    assert_int_equal(xyl_foliage_image_error_triangles(&sq, 1, pos, 3, idx, 2, NULL, &e, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(diag.index, 1);
    assert_non_null(strstr(diag.message, "vertex 3"));
    assert_int_equal(xyl_foliage_image_error_triangles(&sq, 1, NULL, 3, idx, 1, NULL, &e, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_image_error_triangles(&sq, 1, pos, 3, NULL, 1, NULL, &e, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_foliage_image_error_triangles(NULL, 0, pos, 3, idx, 1, NULL, &e, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    pos[4] = NAN;
    assert_int_equal(xyl_foliage_image_error_triangles(&sq, 1, pos, 3, idx, 1, NULL, &e, &diag), XYL_ERR_NON_FINITE);
    assert_int_equal(diag.index, 1);
    pos[4] = 3e6f;
    assert_int_equal(xyl_foliage_image_error_triangles(&sq, 1, pos, 3, idx, 1, NULL, &e, &diag),
                     XYL_ERR_LIMIT_EXCEEDED);
    pos[4] = 0;
    xyl_foliage_image_desc d = {0};
    d.limits.max_leaves = 1;
    assert_int_equal(xyl_foliage_image_error_triangles(&sq, 1, pos, 3, idx, 2, &d, &e, &diag),
                     XYL_ERR_LIMIT_EXCEEDED);
    assert_memory_equal(&e, &before, sizeof e);
    /* no triangles: nothing drawn, nothing near */
    assert_int_equal(xyl_foliage_image_error_triangles(&sq, 1, NULL, 0, NULL, 0, NULL, &e, &diag), XYL_OK);
    assert_true(isinf(e.hausdorff));
    assert_true(e.coverage_worst == 1.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(raster_covers_the_pixel_centres_inside_and_those_on_top_left_edges),
        cmocka_unit_test(raster_is_watertight_along_a_shared_edge),
        cmocka_unit_test(raster_keeps_the_nearest_leaf_and_skips_edge_on_ones),
        cmocka_unit_test(raster_is_exact_far_from_the_origin_and_for_huge_leaves),
        cmocka_unit_test(dodecahedron_views_are_twenty_unit_frames_framing_the_sphere),
        cmocka_unit_test(image_error_of_a_set_against_itself_is_zero),
        cmocka_unit_test(image_error_of_a_removed_square_is_its_coverage),
        cmocka_unit_test(hausdorff_of_parallel_squares_is_their_offset),
        cmocka_unit_test(hausdorff_matches_a_brute_force),
        cmocka_unit_test(image_error_is_deterministic),
        cmocka_unit_test(image_error_rejects_bad_input_with_its_code),
        cmocka_unit_test(gather_counts_then_fills_the_two_ranges_of_each_sector),
        cmocka_unit_test(lod_resolution_is_where_the_pick_starts_to_choose_the_lod),
        cmocka_unit_test(image_error_of_lods_is_zero_at_lod_0_and_grows),
        cmocka_unit_test(viewpoint_chain_is_deterministic),
        cmocka_unit_test(viewpoint_chain_merges_the_least_visible_leaf_first),
        cmocka_unit_test(viewpoint_chain_keeps_the_distance_threshold),
        cmocka_unit_test(viewpoint_options_are_checked),
        cmocka_unit_test(viewpoint_build_survives_every_allocation_failure),
        cmocka_unit_test(viewpoint_estimates_stay_near_an_exact_recomputation),
        cmocka_unit_test(triangles_of_the_leaves_measure_as_the_leaves),
        cmocka_unit_test(hausdorff_of_a_square_and_a_triangle),
        cmocka_unit_test(image_error_triangles_rejects_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(raster_covers_the_pixel_centres_inside_and_those_on_top_left_edges),
        cmocka_unit_test(raster_is_watertight_along_a_shared_edge),
        cmocka_unit_test(raster_keeps_the_nearest_leaf_and_skips_edge_on_ones),
        cmocka_unit_test(raster_is_exact_far_from_the_origin_and_for_huge_leaves),
        cmocka_unit_test(dodecahedron_views_are_twenty_unit_frames_framing_the_sphere),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

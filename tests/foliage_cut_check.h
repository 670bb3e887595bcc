/* The per-leaf cut's checks that the GL and Vulkan leaf tests share: a GPU's cut (record
 * indices in any order) against xyl_foliage_cut's in double, equal except below a node whose own
 * test is a tie within float rounding, and each a valid cut. Include after cmocka (test_util.h)
 * and foliage_internal.h. */
#ifndef XYL_TESTS_FOLIAGE_CUT_CHECK_H
#define XYL_TESTS_FOLIAGE_CUT_CHECK_H

#include <math.h>
#include <stdlib.h>

/* Leaf k's test of the cut in double and how near it is to a tie: |error - allowed| against
 * the float roundings of the distance (|eye - c| + r) and of the error. */
static bool cut_near_tie(const xyl_foliage *f, uint32_t k, const double eye[3],
                         double per_distance)
{
    const xyl_leaf *l = &f->leaves[k];
    double dx = eye[0] - l->center.x, dy = eye[1] - l->center.y, dz = eye[2] - l->center.z;
    double len = sqrt(dx * dx + dy * dy + dz * dz);
    double r = xyl__foliage_node_radius(l, &f->links[k]);
    double d = len - r, allowed = per_distance * (d > 0.0 ? d : 0.0);
    double e = f->links[k].error;
    return fabs(e - allowed) <= 1e-5 * (e + per_distance * (len + r));
}

/* Every original stood for by exactly one drawn leaf: itself or one ancestor. */
static void cut_expect_valid(const xyl_foliage *f, const uint8_t *drawn)
{
    for (size_t k = 0; k < f->leaf_count; ++k) {
        if (f->links[k].source == UINT32_MAX) continue;
        int covered = 0;
        for (int32_t p = (int32_t)k; p >= 0; p = f->links[p].parent) covered += drawn[p];
        if (covered != 1) fail_msg("original %zu is drawn %d times in the cut", k, covered);
    }
}

/* The GPU's n_gpu records against xyl_foliage_cut for view v; adds the leaves decided by a
 * float tie to *ties and returns the CPU cut's size. */
static size_t cut_compare(const xyl_foliage *f, const xyl_foliage_view *v, const uint32_t *gpu,
                          size_t n_gpu, size_t *ties)
{
    size_t n_cpu = 0;
    assert_int_equal(xyl_foliage_cut(f, v, NULL, 0, &n_cpu, NULL), XYL_OK);
    uint32_t *cpu = malloc((n_cpu + 1) * sizeof *cpu);
    uint8_t *dg = calloc(f->leaf_count, 1), *dc = calloc(f->leaf_count, 1);
    assert_true(cpu && dg && dc);
    assert_int_equal(xyl_foliage_cut(f, v, cpu, n_cpu, &n_cpu, NULL), XYL_OK);
    for (size_t i = 0; i < n_gpu; ++i) {
        assert_true(gpu[i] < f->leaf_count);
        assert_int_equal(dg[gpu[i]], 0); /* no record twice */
        dg[gpu[i]] = 1;
    }
    for (size_t i = 0; i < n_cpu; ++i) {
        if (i) assert_true(cpu[i] > cpu[i - 1]);
        dc[cpu[i]] = 1;
    }
    cut_expect_valid(f, dg);
    cut_expect_valid(f, dc);
    double eye[3] = {v->eye[0], v->eye[1], v->eye[2]};
    double per_distance = 0.0;
    assert_int_equal(xyl__foliage_view_resolve(v, eye, &per_distance, NULL), XYL_OK);
    for (size_t k = 0; k < f->leaf_count; ++k) {
        if (dg[k] == dc[k]) continue;
        bool tie = false;
        for (int32_t p = (int32_t)k; p >= 0 && !tie; p = f->links[p].parent)
            tie = cut_near_tie(f, (uint32_t)p, eye, per_distance);
        if (!tie)
            fail_msg("leaf %zu: GPU %s, CPU %s, and no tie on its path", k,
                     dg[k] ? "draws" : "skips", dc[k] ? "draws" : "skips");
        ++*ties;
    }
    free(cpu);
    free(dg);
    free(dc);
    return n_cpu;
}

/* The views both tests walk: the eye at the crown's centre, at its rim, and 1.5, 4, 20 and
 * 1000 radii away, along one direction; budgets of 0.5, 1 and 4 pixels. */
#define CUT_DISTANCES 6
#define CUT_BUDGETS 3
static xyl_foliage_view cut_view(const xyl_foliage *f, int distance, int budget)
{
    static const float dist[CUT_DISTANCES] = {0.0f, 1.0f, 1.5f, 4.0f, 20.0f, 1000.0f};
    static const float px[CUT_BUDGETS] = {0.5f, 1.0f, 4.0f};
    xyl_foliage_view v = {{f->center.x + dist[distance] * f->radius * 0.6f,
                           f->center.y + dist[distance] * f->radius * 0.3f,
                           f->center.z + dist[distance] * f->radius * 0.742f},
                          0.8f, 1080, px[budget]};
    return v;
}

#endif /* XYL_TESTS_FOLIAGE_CUT_CHECK_H */

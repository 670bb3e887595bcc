/* The foliage of a preset's leaf attachments, as the GPU leaf, billboard, forest and transition
 * tests draw it. Include after cmocka (test_util.h). */
#ifndef XYL_TESTS_FOLIAGE_TREE_H
#define XYL_TESTS_FOLIAGE_TREE_H

#include <stdlib.h>

#include <xylem/xyl_foliage.h>

/* The leaves of the skeleton's attachments with the default shape, built into sectors sectors
 * with the default collapse; any failure fails the test. */
static inline xyl_foliage *ft_foliage_of(const xyl_skeleton *sk, uint32_t sectors)
{
    size_t n = 0;
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, NULL, NULL, 0, &n, NULL), XYL_OK);
    assert_true(n > 0);
    xyl_leaf *leaves = malloc(n * sizeof *leaves);
    assert_non_null(leaves);
    assert_int_equal(xyl_foliage_leaves_from_skeleton(sk, NULL, leaves, n, &n, NULL), XYL_OK);
    xyl_foliage_desc fd = {0};
    fd.leaves = leaves;
    fd.leaf_count = n;
    fd.sectors = sectors;
    xyl_foliage *f = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_foliage_build(&fd, &f, &d);
    free(leaves);
    if (r != XYL_OK) fail_msg("xyl_foliage_build: %s (%s)", xyl_result_string(r), d.message);
    return f;
}

/* The same for a preset grown with the turtle's defaults. */
static inline xyl_foliage *ft_tree_foliage(const char *preset, uint32_t sectors)
{
    xyl_skeleton *sk = tu_grow(xyl_lsystem_preset_source(preset), NULL);
    xyl_foliage *f = ft_foliage_of(sk, sectors);
    xyl_skeleton_destroy(sk);
    return f;
}

#endif /* XYL_TESTS_FOLIAGE_TREE_H */

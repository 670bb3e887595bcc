/* Skeleton construction (xyl_skeleton_create/destroy) and the .skel / OBJ reader and writers. */
#define _POSIX_C_SOURCE 200809L

#include <dirent.h>
#include <fcntl.h>
#include <float.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "xylem/xyl_skeleton.h"
#include "test_util.h"

#define SKEL_DIR XYL_TEST_DATA "/skel/"

/* ---- helpers ------------------------------------------------------------------------------- */

static xyl_skel_node node(float x, float y, float z, float radius, int32_t parent)
{
    xyl_skel_node n = {{x, y, z}, radius, parent, 0, 0};
    return n;
}

static xyl_skel_leaf leaf(int32_t on, float x, float y, float z, float size)
{
    xyl_skel_leaf l = {{x, y, z}, {0, 1, 0}, {-1, 0, 0}, {0, 0, 1}, size, on};
    return l;
}

static xyl_diag fresh_diag(void)
{
    xyl_diag d;
    memset(&d, 0, sizeof d);
    return d;
}

/* A recognisable non-NULL value that a failing call must leave in *out. */
static xyl_skeleton untouched_view;
#define UNTOUCHED (&untouched_view)

static xyl_result create(const xyl_skel_node *nodes, size_t n, const xyl_skel_leaf *leaves,
                         size_t nl, xyl_skeleton **out, xyl_diag *diag)
{
    xyl_skeleton_desc d;
    memset(&d, 0, sizeof d);
    d.nodes = nodes;
    d.node_count = n;
    d.leaves = leaves;
    d.leaf_count = nl;
    return xyl_skeleton_create(&d, out, diag);
}

static xyl_result read_str(const char *text, xyl_skeleton **out, xyl_diag *diag)
{
    return xyl_skeleton_read_text(text, strlen(text), NULL, out, diag);
}

/* Reads text that must fail with code at line:column, leaving *out alone and explaining why. */
static void check_read_error(const char *text, xyl_result code, uint32_t line, uint32_t column)
{
    xyl_diag d = fresh_diag();
    xyl_skeleton *sk = UNTOUCHED;
    xyl_result r = read_str(text, &sk, &d);
    if (r != code || d.code != code || d.line != line || d.column != column) {
        print_error("text:\n%s\ngot '%s' at %u:%u (%s), expected '%s' at %u:%u\n", text,
                    xyl_result_string(r), d.line, d.column, d.message, xyl_result_string(code),
                    line, column);
        fail();
    }
    assert_ptr_equal(sk, UNTOUCHED);
    assert_true(strlen(d.message) > 0);
}

static char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    char *buf = malloc(1 << 16);
    assert_non_null(buf);
    *size = fread(buf, 1, 1 << 16, f);
    fclose(f);
    return buf;
}

static char *write_alloc(const xyl_skeleton *sk, xyl_skel_format format, size_t *len)
{
    size_t needed = 0;
    assert_int_equal(xyl_skeleton_write_text(sk, format, NULL, 0, &needed), XYL_OK);
    char *buf = malloc(needed + 1);
    assert_non_null(buf);
    assert_int_equal(xyl_skeleton_write_text(sk, format, buf, needed + 1, len), XYL_OK);
    assert_int_equal(*len, needed);
    assert_int_equal(strlen(buf), needed);
    return buf;
}

static size_t count_lines_starting(const char *text, const char *prefix)
{
    size_t count = 0, n = strlen(prefix);
    for (const char *p = text; *p; p = strchr(p, '\n') ? strchr(p, '\n') + 1 : p + strlen(p))
        count += strncmp(p, prefix, n) == 0;
    return count;
}

/* Counts and optionally fails allocations, so tests can prove nothing leaks. */
typedef struct counter {
    size_t attempts, allocs, frees, largest;
    size_t fail_at; /* 1-based attempt that returns NULL; 0 = never */
} counter;

static void *count_alloc(size_t size, void *user)
{
    counter *c = user;
    if (++c->attempts == c->fail_at) return NULL;
    c->allocs++;
    if (size > c->largest) c->largest = size;
    return malloc(size);
}

static void count_free(void *p, void *user)
{
    counter *c = user;
    c->frees++;
    free(p);
}

static xyl_allocator counting(counter *c)
{
    xyl_allocator a = {count_alloc, count_free, c};
    return a;
}

/* Bit-exact equality of everything two skeletons hold. */
static void assert_same_skeleton(const xyl_skeleton *a, const xyl_skeleton *b)
{
    assert_int_equal(a->node_count, b->node_count);
    assert_int_equal(a->leaf_count, b->leaf_count);
    assert_int_equal(a->branch_count, b->branch_count);
    assert_int_equal(a->root_count, b->root_count);
    assert_int_equal(a->max_order, b->max_order);
    if (a->node_count)
        assert_memory_equal(a->nodes, b->nodes, a->node_count * sizeof *a->nodes);
    if (a->leaf_count)
        assert_memory_equal(a->leaves, b->leaves, a->leaf_count * sizeof *a->leaves);
}

static void assert_round_trips(const xyl_skeleton *sk)
{
    size_t len;
    char *text = write_alloc(sk, XYL_SKEL_FORMAT_SKEL, &len);
    xyl_skeleton *back = NULL;
    xyl_diag d = fresh_diag();
    xyl_result r = xyl_skeleton_read_text(text, len, NULL, &back, &d);
    if (r != XYL_OK) print_error("%s at %u:%u\n%s\n", d.message, d.line, d.column, text);
    assert_int_equal(r, XYL_OK);
    assert_same_skeleton(sk, back);
    xyl_skeleton_destroy(back);
    free(text);
}

static uint64_t next_random(uint64_t *state)
{
    /* xorshift64*: deterministic, seeded by the caller, no global state. */
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    return *state * UINT64_C(2685821657736338717);
}

static float random_finite_float(uint64_t *state)
{
    for (;;) {
        uint32_t bits = (uint32_t)(next_random(state) >> 32);
        float f;
        memcpy(&f, &bits, sizeof f);
        if (isfinite(f)) return f;
    }
}

static xyl_vec3 random_vec3(uint64_t *state)
{
    xyl_vec3 v;
    v.x = random_finite_float(state);
    v.y = random_finite_float(state);
    v.z = random_finite_float(state);
    return v;
}

static float random_positive_float(uint64_t *state)
{
    float f = fabsf(random_finite_float(state));
    return f > 0.0f ? f : 1.0f;
}

/* ---- create -------------------------------------------------------------------------------- */

static void create_copies_arrays_and_derives_counts(void **state)
{
    (void)state;
    xyl_skel_node nodes[3] = {node(0, 0, 0, 0.1f, -1), node(0, 1, 0, 0.08f, 0),
                              node(0, 2, 0, 0.05f, 1)};
    xyl_skel_leaf leaves[1] = {leaf(2, 0, 2, 0, 0.3f)};
    nodes[1].branch = 77; /* derived fields are recomputed, not copied */
    xyl_skeleton *sk = NULL;
    xyl_diag d = fresh_diag();
    assert_int_equal(create(nodes, 3, leaves, 1, &sk, &d), XYL_OK);
    assert_int_equal(d.code, XYL_OK);
    assert_ptr_not_equal(sk->nodes, nodes);
    assert_int_equal(sk->node_count, 3);
    assert_int_equal(sk->leaf_count, 1);
    assert_int_equal(sk->root_count, 1);
    assert_int_equal(sk->branch_count, 1);
    assert_int_equal(sk->nodes[1].branch, 0);
    assert_true(sk->nodes[2].pos.y == 2.0f);
    assert_int_equal(sk->leaves[0].node, 2);
    xyl_skeleton_destroy(sk);
}

static void create_larger_radius_child_continues_branch(void **state)
{
    (void)state;
    xyl_skel_node nodes[3] = {node(0, 0, 0, 1, -1), node(-1, 1, 0, 0.2f, 0),
                              node(1, 1, 0, 0.5f, 0)};
    xyl_skeleton *sk = NULL;
    assert_int_equal(create(nodes, 3, NULL, 0, &sk, NULL), XYL_OK);
    assert_int_equal(sk->nodes[2].branch, sk->nodes[0].branch);
    assert_int_equal(sk->nodes[2].order, 0);
    assert_int_not_equal(sk->nodes[1].branch, sk->nodes[0].branch);
    assert_int_equal(sk->nodes[1].order, 1);
    assert_int_equal(sk->branch_count, 2);
    assert_int_equal(sk->max_order, 1);
    xyl_skeleton_destroy(sk);
}

static void create_radius_tie_goes_to_first_child(void **state)
{
    (void)state;
    xyl_skel_node nodes[3] = {node(0, 0, 0, 1, -1), node(-1, 1, 0, 0.5f, 0),
                              node(1, 1, 0, 0.5f, 0)};
    xyl_skeleton *sk = NULL;
    assert_int_equal(create(nodes, 3, NULL, 0, &sk, NULL), XYL_OK);
    assert_int_equal(sk->nodes[1].branch, 0);
    assert_int_equal(sk->nodes[1].order, 0);
    assert_int_equal(sk->nodes[2].branch, 1);
    assert_int_equal(sk->nodes[2].order, 1);
    xyl_skeleton_destroy(sk);
}

static void create_multi_root_numbers_branches_in_node_order(void **state)
{
    (void)state;
    xyl_skel_node nodes[5] = {node(0, 0, 0, 1, -1), node(5, 0, 0, 1, -1), node(0, 1, 0, 1, 0),
                              node(5, 1, 0, 0.5f, 1), node(6, 1, 0, 0.2f, 1)};
    xyl_skeleton *sk = NULL;
    assert_int_equal(create(nodes, 5, NULL, 0, &sk, NULL), XYL_OK);
    assert_int_equal(sk->root_count, 2);
    assert_int_equal(sk->branch_count, 3);
    uint32_t expect_branch[5] = {0, 1, 0, 1, 2};
    uint32_t expect_order[5] = {0, 0, 0, 0, 1};
    for (int i = 0; i < 5; ++i) {
        assert_int_equal(sk->nodes[i].branch, expect_branch[i]);
        assert_int_equal(sk->nodes[i].order, expect_order[i]);
    }
    xyl_skeleton_destroy(sk);
}

static void create_orders_grow_with_each_lateral_fork(void **state)
{
    (void)state;
    /* trunk 0-1-2; lateral 3 off 1; 3 forks into 4 (continues, larger) and 5 (lateral) */
    xyl_skel_node nodes[6] = {node(0, 0, 0, 1, -1), node(0, 1, 0, 0.9f, 0),
                              node(0, 2, 0, 0.8f, 1), node(1, 1, 0, 0.3f, 1),
                              node(2, 1, 0, 0.25f, 3), node(2, 2, 0, 0.1f, 3)};
    xyl_skeleton *sk = NULL;
    assert_int_equal(create(nodes, 6, NULL, 0, &sk, NULL), XYL_OK);
    uint32_t expect_order[6] = {0, 0, 0, 1, 1, 2};
    uint32_t expect_branch[6] = {0, 0, 0, 1, 1, 2};
    for (int i = 0; i < 6; ++i) {
        assert_int_equal(sk->nodes[i].order, expect_order[i]);
        assert_int_equal(sk->nodes[i].branch, expect_branch[i]);
    }
    assert_int_equal(sk->max_order, 2);
    assert_int_equal(sk->branch_count, 3);
    xyl_skeleton_destroy(sk);
}

static void create_accepts_empty_skeleton(void **state)
{
    (void)state;
    xyl_skeleton *sk = NULL;
    assert_int_equal(create(NULL, 0, NULL, 0, &sk, NULL), XYL_OK);
    assert_int_equal(sk->node_count, 0);
    assert_int_equal(sk->branch_count, 0);
    assert_int_equal(sk->root_count, 0);
    xyl_skeleton_destroy(sk);
}

static void create_rejects_null_arguments(void **state)
{
    (void)state;
    xyl_skeleton_desc desc;
    memset(&desc, 0, sizeof desc);
    xyl_skeleton *sk = UNTOUCHED;
    xyl_diag d = fresh_diag();
    assert_int_equal(xyl_skeleton_create(NULL, &sk, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(d.code, XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_skeleton_create(&desc, NULL, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_ptr_equal(sk, UNTOUCHED);
}

static void create_rejects_null_arrays_with_counts(void **state)
{
    (void)state;
    xyl_skel_node n = node(0, 0, 0, 1, -1);
    xyl_skeleton *sk = UNTOUCHED;
    assert_int_equal(create(NULL, 1, NULL, 0, &sk, NULL), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(create(&n, 1, NULL, 1, &sk, NULL), XYL_ERR_INVALID_ARGUMENT);
    assert_ptr_equal(sk, UNTOUCHED);
}

static void expect_create_error(const xyl_skel_node *nodes, size_t n, const xyl_skel_leaf *leaves,
                                size_t nl, xyl_result code, int64_t index)
{
    xyl_skeleton *sk = UNTOUCHED;
    xyl_diag d = fresh_diag();
    assert_int_equal(create(nodes, n, leaves, nl, &sk, &d), code);
    assert_int_equal(d.code, code);
    assert_int_equal(d.index, index);
    assert_true(strlen(d.message) > 0);
    assert_ptr_equal(sk, UNTOUCHED);
}

static void create_rejects_non_finite_values(void **state)
{
    (void)state;
    xyl_skel_node nodes[2] = {node(0, 0, 0, 1, -1), node(0, NAN, 0, 1, 0)};
    expect_create_error(nodes, 2, NULL, 0, XYL_ERR_NON_FINITE, 1);
    nodes[1] = node(0, 1, 0, INFINITY, 0);
    expect_create_error(nodes, 2, NULL, 0, XYL_ERR_NON_FINITE, 1);
    nodes[1] = node(0, 1, 0, 1, 0);
    xyl_skel_leaf leaves[2] = {leaf(0, 0, 0, 0, 1), leaf(1, 0, 1, 0, 1)};
    leaves[1].up.z = -INFINITY;
    expect_create_error(nodes, 2, leaves, 2, XYL_ERR_NON_FINITE, 1);
    leaves[1] = leaf(1, 0, 1, 0, NAN);
    expect_create_error(nodes, 2, leaves, 2, XYL_ERR_NON_FINITE, 1);
}

static void create_rejects_non_positive_radius(void **state)
{
    (void)state;
    xyl_skel_node nodes[2] = {node(0, 0, 0, 0, -1), node(0, 1, 0, 1, 0)};
    expect_create_error(nodes, 2, NULL, 0, XYL_ERR_INVALID_SKELETON, 0);
    nodes[0].radius = 1;
    nodes[1].radius = -0.5f;
    expect_create_error(nodes, 2, NULL, 0, XYL_ERR_INVALID_SKELETON, 1);
}

static void create_rejects_parent_not_before_child(void **state)
{
    (void)state;
    xyl_skel_node nodes[3] = {node(0, 0, 0, 1, -1), node(0, 1, 0, 1, 1), node(0, 2, 0, 1, 0)};
    expect_create_error(nodes, 3, NULL, 0, XYL_ERR_INVALID_SKELETON, 1); /* itself */
    nodes[1].parent = 2;
    expect_create_error(nodes, 3, NULL, 0, XYL_ERR_INVALID_SKELETON, 1); /* a later node */
    nodes[1].parent = 0;
    nodes[2].parent = -2;
    expect_create_error(nodes, 3, NULL, 0, XYL_ERR_INVALID_SKELETON, 2); /* below -1 */
}

static void create_rejects_bad_leaves(void **state)
{
    (void)state;
    xyl_skel_node nodes[1] = {node(0, 0, 0, 1, -1)};
    xyl_skel_leaf leaves[2] = {leaf(-1, 0, 0, 0, 1), leaf(0, 0, 0, 0, 0)};
    expect_create_error(nodes, 1, leaves, 2, XYL_ERR_INVALID_SKELETON, 1);
    leaves[1] = leaf(1, 0, 0, 0, 1);
    expect_create_error(nodes, 1, leaves, 2, XYL_ERR_INVALID_SKELETON, 1);
    leaves[1] = leaf(-2, 0, 0, 0, 1);
    expect_create_error(nodes, 1, leaves, 2, XYL_ERR_INVALID_SKELETON, 1);
}

static void create_rejects_counts_above_limits(void **state)
{
    (void)state;
    xyl_skel_node nodes[3] = {node(0, 0, 0, 1, -1), node(0, 1, 0, 1, 0), node(0, 2, 0, 1, 1)};
    xyl_skel_leaf leaves[2] = {leaf(0, 0, 0, 0, 1), leaf(0, 0, 0, 0, 1)};
    xyl_skeleton_desc d;
    memset(&d, 0, sizeof d);
    d.nodes = nodes;
    d.node_count = 3;
    d.leaves = leaves;
    d.leaf_count = 2;
    d.limits.max_nodes = 2;
    xyl_skeleton *sk = UNTOUCHED;
    assert_int_equal(xyl_skeleton_create(&d, &sk, NULL), XYL_ERR_LIMIT_EXCEEDED);
    d.limits.max_nodes = 3;
    d.limits.max_leaves = 1;
    assert_int_equal(xyl_skeleton_create(&d, &sk, NULL), XYL_ERR_LIMIT_EXCEEDED);
    assert_ptr_equal(sk, UNTOUCHED);
    d.limits.max_leaves = 2;
    assert_int_equal(xyl_skeleton_create(&d, &sk, NULL), XYL_OK);
    xyl_skeleton_destroy(sk);
}

static void create_survives_every_allocation_failure(void **state)
{
    (void)state;
    xyl_skel_node nodes[2] = {node(0, 0, 0, 1, -1), node(0, 1, 0, 1, 0)};
    xyl_skel_leaf leaves[1] = {leaf(1, 0, 1, 0, 1)};
    for (size_t k = 1;; ++k) {
        counter c = {0, 0, 0, 0, k};
        xyl_skeleton_desc d;
        memset(&d, 0, sizeof d);
        d.nodes = nodes;
        d.node_count = 2;
        d.leaves = leaves;
        d.leaf_count = 1;
        d.alloc = counting(&c);
        xyl_skeleton *sk = UNTOUCHED;
        xyl_result r = xyl_skeleton_create(&d, &sk, NULL);
        if (r == XYL_OK) {
            assert_true(c.allocs > 0);
            xyl_skeleton_destroy(sk);
            assert_int_equal(c.allocs, c.frees);
            assert_true(k > 1);
            break;
        }
        assert_int_equal(r, XYL_ERR_OUT_OF_MEMORY);
        assert_ptr_equal(sk, UNTOUCHED);
        assert_int_equal(c.allocs, c.frees);
        assert_true(k < 32);
    }
}

static void destroy_accepts_null(void **state)
{
    (void)state;
    xyl_skeleton_destroy(NULL);
}

/* ---- read: valid input --------------------------------------------------------------------- */

static void read_parses_documented_example(void **state)
{
    (void)state;
    xyl_skeleton *sk = NULL;
    xyl_diag d = fresh_diag();
    d.index = 5;
    assert_int_equal(xyl_skeleton_read_file(SKEL_DIR "example.skel", NULL, &sk, &d), XYL_OK);
    assert_int_equal(d.code, XYL_OK);
    assert_int_equal(d.index, -1);
    assert_int_equal(sk->node_count, 3);
    assert_int_equal(sk->leaf_count, 1);
    assert_int_equal(sk->nodes[0].parent, -1);
    assert_int_equal(sk->nodes[2].parent, 1);
    assert_true(sk->nodes[1].pos.y == 1.0f);
    assert_true(sk->nodes[0].radius == 0.1f);
    assert_true(sk->nodes[2].radius == 0.05f);
    const xyl_skel_leaf *l = &sk->leaves[0];
    assert_int_equal(l->node, 2);
    assert_true(l->pos.y == 2.0f && l->heading.y == 1.0f && l->left.x == -1.0f);
    assert_true(l->up.z == 1.0f && l->size == 0.3f);
    xyl_skeleton_destroy(sk);
}

typedef struct golden {
    const char *file;
    size_t nodes, leaves;
    uint32_t roots, branches, max_order;
} golden;

static const golden valid_files[] = {
    {"example.skel", 3, 1, 1, 1, 0},    {"multi_root.skel", 6, 0, 3, 3, 0},
    {"leaves.skel", 2, 3, 1, 1, 0},     {"kink90.skel", 3, 0, 1, 1, 0},
    {"coincident.skel", 4, 0, 1, 1, 0}, {"forks.skel", 7, 0, 1, 4, 1},
    {"crlf.skel", 2, 0, 1, 1, 0},       {"empty.skel", 0, 0, 0, 0, 0},
};

static void read_golden_valid_files(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof valid_files / sizeof valid_files[0]; ++i) {
        const golden *g = &valid_files[i];
        char path[512];
        snprintf(path, sizeof path, SKEL_DIR "%s", g->file);
        xyl_skeleton *sk = NULL;
        xyl_diag d = fresh_diag();
        xyl_result r = xyl_skeleton_read_file(path, NULL, &sk, &d);
        if (r != XYL_OK) print_error("%s:%u:%u: %s\n", g->file, d.line, d.column, d.message);
        assert_int_equal(r, XYL_OK);
        assert_int_equal(sk->node_count, g->nodes);
        assert_int_equal(sk->leaf_count, g->leaves);
        assert_int_equal(sk->root_count, g->roots);
        assert_int_equal(sk->branch_count, g->branches);
        assert_int_equal(sk->max_order, g->max_order);
        xyl_skeleton_destroy(sk);
    }
}

static void read_keeps_kinks_coincident_nodes_and_rootless_leaves(void **state)
{
    (void)state;
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_skeleton_read_file(SKEL_DIR "kink90.skel", NULL, &sk, NULL), XYL_OK);
    assert_true(sk->nodes[2].pos.x == 1.0f && sk->nodes[2].pos.y == 1.0f);
    xyl_skeleton_destroy(sk);
    assert_int_equal(xyl_skeleton_read_file(SKEL_DIR "coincident.skel", NULL, &sk, NULL), XYL_OK);
    assert_memory_equal(&sk->nodes[1].pos, &sk->nodes[2].pos, sizeof(xyl_vec3));
    xyl_skeleton_destroy(sk);
    assert_int_equal(xyl_skeleton_read_file(SKEL_DIR "leaves.skel", NULL, &sk, NULL), XYL_OK);
    assert_int_equal(sk->leaves[2].node, -1);
    assert_true(sk->leaves[2].size == 1e-3f);
    assert_true(sk->leaves[1].size == 0.125f);
    xyl_skeleton_destroy(sk);
}

static void read_derives_branches_like_create(void **state)
{
    (void)state;
    xyl_skeleton *read = NULL, *made = NULL;
    assert_int_equal(xyl_skeleton_read_file(SKEL_DIR "forks.skel", NULL, &read, NULL), XYL_OK);
    assert_int_equal(create(read->nodes, read->node_count, NULL, 0, &made, NULL), XYL_OK);
    assert_same_skeleton(read, made);
    /* 3 (largest) continues at fork 1; 5 wins the tie at fork 3. */
    assert_int_equal(read->nodes[3].branch, read->nodes[1].branch);
    assert_int_equal(read->nodes[5].branch, read->nodes[3].branch);
    assert_int_equal(read->nodes[2].order, 1);
    assert_int_equal(read->nodes[4].order, 1);
    assert_int_equal(read->nodes[6].order, 1);
    xyl_skeleton_destroy(read);
    xyl_skeleton_destroy(made);
}

static void read_accepts_crlf_line_endings(void **state)
{
    (void)state;
    const char *text = "xylem-skeleton 1\r\nnodes 2\r\nleaves 1\r\n# comment\r\n\r\n"
                       "n 0 -1 0 0 0 0.1\r\nn 1 0 0 1 0 0.05  \r\n"
                       "l 1 0 1 0 0 1 0 -1 0 0 0 0 1 0.5\r\nend\r\n";
    xyl_skeleton *sk = NULL;
    assert_int_equal(read_str(text, &sk, NULL), XYL_OK);
    assert_int_equal(sk->node_count, 2);
    assert_true(sk->leaves[0].size == 0.5f);
    xyl_skeleton_destroy(sk);
}

static void read_accepts_comments_and_blank_lines_anywhere(void **state)
{
    (void)state;
    const char *text = "# before the header\n\n  \t\nxylem-skeleton 1 # trailing\n"
                       "#\nnodes\t1#no space needed\n\n   leaves 0\n"
                       "\t n 0\t-1 0 0 0 1e-1\n# last\nend\n\n# after the end\n";
    xyl_skeleton *sk = NULL;
    xyl_diag d = fresh_diag();
    assert_int_equal(read_str(text, &sk, &d), XYL_OK);
    assert_int_equal(sk->node_count, 1);
    assert_true(sk->nodes[0].radius == 0.1f);
    xyl_skeleton_destroy(sk);
}

static void read_accepts_missing_final_newline(void **state)
{
    (void)state;
    xyl_skeleton *sk = NULL;
    assert_int_equal(read_str("xylem-skeleton 1\nnodes 0\nleaves 0\nend", &sk, NULL), XYL_OK);
    xyl_skeleton_destroy(sk);
    assert_int_equal(read_str("xylem-skeleton 1\nnodes 0\nleaves 0\nend # done", &sk, NULL),
                     XYL_OK);
    xyl_skeleton_destroy(sk);
}

static void read_uses_length_not_nul_terminator(void **state)
{
    (void)state;
    const char *valid = "xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 1\nend\n";
    size_t n = strlen(valid);
    /* Exactly sized, no NUL: an over-read is a sanitizer error. */
    char *exact = malloc(n);
    assert_non_null(exact);
    memcpy(exact, valid, n);
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_skeleton_read_text(exact, n, NULL, &sk, NULL), XYL_OK);
    xyl_skeleton_destroy(sk);
    /* Text after the length is ignored, even when it would be an error. */
    const char *longer = "xylem-skeleton 1\nnodes 0\nleaves 0\nend\nGARBAGE";
    assert_int_equal(xyl_skeleton_read_text(longer, strlen(longer) - 7, NULL, &sk, NULL), XYL_OK);
    xyl_skeleton_destroy(sk);
    /* ... and a length that cuts the text short makes it truncated, even with a NUL later. */
    assert_int_equal(xyl_skeleton_read_text(valid, n - 5, NULL, &sk, NULL), XYL_ERR_TRUNCATED);
    free(exact);
}

static void read_accepts_number_forms(void **state)
{
    (void)state;
    const char *text = "xylem-skeleton 1\nnodes 3\nleaves 0\n"
                       "n 0 -1 .5 5. +1 1E2\n"
                       "n 1 0 -0 0001.5000e-0 3.14159265358979323846264338327950288 "
                       "0.000000000000000000000000000000000000000000001401298464324817\n"
                       "n 2 1 123456789012345678901234567890 -98765432109876543210.5e-10 0 "
                       "1e-40\n"
                       "end\n";
    xyl_skeleton *sk = NULL;
    xyl_diag d = fresh_diag();
    assert_int_equal(read_str(text, &sk, &d), XYL_OK);
    assert_true(sk->nodes[0].pos.x == 0.5f);
    assert_true(sk->nodes[0].pos.y == 5.0f);
    assert_true(sk->nodes[0].pos.z == 1.0f);
    assert_true(sk->nodes[0].radius == 100.0f);
    assert_true(sk->nodes[1].pos.x == 0.0f && signbit(sk->nodes[1].pos.x));
    assert_true(sk->nodes[1].pos.y == 1.5f);
    assert_true(sk->nodes[1].pos.z == 3.14159265358979323846f);
    assert_true(sk->nodes[1].radius == 1.401298464324817e-45f); /* smallest subnormal */
    /* digits beyond the 19 kept still scale the value */
    assert_true(sk->nodes[2].pos.x == 123456789012345678901234567890.0f);
    assert_true(sk->nodes[2].pos.y == -9876543210.98765432105f);
    assert_true(sk->nodes[2].radius == 1e-40f);
    xyl_skeleton_destroy(sk);
}

static void read_rounds_just_above_flt_max_down(void **state)
{
    (void)state;
    xyl_skeleton *sk = NULL;
    const char *text = "xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 3.40282356e38 0 0 1\nend\n";
    assert_int_equal(read_str(text, &sk, NULL), XYL_OK);
    assert_true(sk->nodes[0].pos.x == FLT_MAX);
    xyl_skeleton_destroy(sk);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 3.40282357e38 0 0 1\nend\n",
                     XYL_ERR_NON_FINITE, 4, 8);
}

/* ---- read: errors -------------------------------------------------------------------------- */

typedef struct bad_golden {
    const char *file;
    xyl_result code;
    uint32_t line, column;
} bad_golden;

static const bad_golden invalid_files[] = {
    {"bad_truncated.skel", XYL_ERR_TRUNCATED, 6, 1},
    {"bad_missing_end.skel", XYL_ERR_TRUNCATED, 6, 1},
    {"bad_parent.skel", XYL_ERR_INVALID_SKELETON, 5, 5},
    {"bad_nan.skel", XYL_ERR_NON_FINITE, 5, 9},
    {"bad_negative_radius.skel", XYL_ERR_INVALID_SKELETON, 5, 13},
    {"bad_garbage.skel", XYL_ERR_PARSE, 1, 6},
    {"bad_version.skel", XYL_ERR_UNSUPPORTED, 1, 16},
    {"bad_node_id.skel", XYL_ERR_PARSE, 5, 3},
    {"bad_huge_count.skel", XYL_ERR_LIMIT_EXCEEDED, 2, 7},
    {"bad_extra_node.skel", XYL_ERR_PARSE, 5, 1},
};

static void read_golden_invalid_files(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof invalid_files / sizeof invalid_files[0]; ++i) {
        const bad_golden *g = &invalid_files[i];
        char path[512];
        snprintf(path, sizeof path, SKEL_DIR "%s", g->file);
        counter c = {0, 0, 0, 0, 0};
        xyl_skeleton_read_desc desc;
        memset(&desc, 0, sizeof desc);
        desc.alloc = counting(&c);
        xyl_skeleton *sk = UNTOUCHED;
        xyl_diag d = fresh_diag();
        xyl_result r = xyl_skeleton_read_file(path, &desc, &sk, &d);
        if (r != g->code || d.line != g->line || d.column != g->column)
            print_error("%s: got '%s' at %u:%u (%s)\n", g->file, xyl_result_string(r), d.line,
                        d.column, d.message);
        assert_int_equal(r, g->code);
        assert_int_equal(d.line, g->line);
        assert_int_equal(d.column, g->column);
        assert_ptr_equal(sk, UNTOUCHED);
        assert_int_equal(c.allocs, c.frees);
    }
}

static void read_rejects_embedded_nul(void **state)
{
    (void)state;
    const char text[] = "xylem-skeleton 1\nnodes 0\nleaves 0\nend # a\0b\n";
    xyl_skeleton *sk = UNTOUCHED;
    xyl_diag d = fresh_diag();
    assert_int_equal(xyl_skeleton_read_text(text, sizeof text - 1, NULL, &sk, &d), XYL_ERR_PARSE);
    assert_int_equal(d.line, 4);
    assert_int_equal(d.column, 8);
    assert_ptr_equal(sk, UNTOUCHED);
}

static void read_rejects_other_versions(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 2\nnodes 0\nleaves 0\nend\n", XYL_ERR_UNSUPPORTED, 1, 16);
    check_read_error("xylem-skeleton 0\n", XYL_ERR_UNSUPPORTED, 1, 16);
    check_read_error("xylem-skeleton 99999999999999999999999\n", XYL_ERR_UNSUPPORTED, 1, 16);
    check_read_error("xylem-skeleton 1.0\n", XYL_ERR_PARSE, 1, 16);
    check_read_error("xylem-skeleton\n", XYL_ERR_PARSE, 1, 15);
}

static void read_rejects_missing_header(void **state)
{
    (void)state;
    check_read_error("nodes 0\nleaves 0\nend\n", XYL_ERR_PARSE, 1, 1);
    check_read_error("\n\n  xylem-skeletons 1\n", XYL_ERR_PARSE, 3, 3);
    check_read_error("\xef\xbb\xbfxylem-skeleton 1\n", XYL_ERR_PARSE, 1, 1); /* BOM */
}

static void read_rejects_node_id_out_of_order(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nnodes 2\nleaves 0\nn 1 -1 0 0 0 1\n", XYL_ERR_PARSE, 4, 3);
    check_read_error("xylem-skeleton 1\nnodes 2\nleaves 0\nn 0 -1 0 0 0 1\nn 0 0 0 0 0 1\n",
                     XYL_ERR_PARSE, 5, 3);
    check_read_error("xylem-skeleton 1\nnodes 2\nleaves 0\nn -0 -1 0 0 0 1\n", XYL_ERR_PARSE, 4, 3);
}

static void read_rejects_parent_after_child(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nnodes 2\nleaves 0\nn 0 1 0 0 0 1\nn 1 -1 0 0 0 1\nend\n",
                     XYL_ERR_INVALID_SKELETON, 4, 5);
    check_read_error("xylem-skeleton 1\nnodes 2\nleaves 0\nn 0 -1 0 0 0 1\nn 1 1 0 0 0 1\nend\n",
                     XYL_ERR_INVALID_SKELETON, 5, 5);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -2 0 0 0 1\nend\n",
                     XYL_ERR_INVALID_SKELETON, 4, 5);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -99999999999999999999 0 0 0 1\n",
                     XYL_ERR_INVALID_SKELETON, 4, 5);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 x 0 0 0 1\n", XYL_ERR_PARSE, 4, 5);
}

static void read_reports_offending_node_index(void **state)
{
    (void)state;
    xyl_skeleton *sk = UNTOUCHED;
    xyl_diag d = fresh_diag();
    const char *text = "xylem-skeleton 1\nnodes 3\nleaves 0\nn 0 -1 0 0 0 1\nn 1 0 0 0 0 1\n"
                       "n 2 0 0 0 0 0\nend\n";
    assert_int_equal(read_str(text, &sk, &d), XYL_ERR_INVALID_SKELETON);
    assert_int_equal(d.index, 2);
    assert_int_equal(d.line, 6);
    assert_int_equal(d.column, 13);
}

static void read_rejects_nan_and_inf_tokens(void **state)
{
    (void)state;
    const char *head = "xylem-skeleton 1\nnodes 1\nleaves 0\n";
    const char *bad[] = {"nan", "NaN", "-inf", "+Infinity", "INF", "nan(0x1)"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        char text[256];
        snprintf(text, sizeof text, "%sn 0 -1 0 0 %s 1\nend\n", head, bad[i]);
        check_read_error(text, XYL_ERR_NON_FINITE, 4, 12);
    }
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 1e39 1\nend\n",
                     XYL_ERR_NON_FINITE, 4, 12);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 -1e999999999999 1\nend\n",
                     XYL_ERR_NON_FINITE, 4, 12);
    check_read_error("xylem-skeleton 1\nnodes 0\nleaves 1\nl -1 0 0 0 0 1 0 -1 0 0 0 0 inf 1\n",
                     XYL_ERR_NON_FINITE, 4, 29);
}

static void read_rejects_malformed_numbers(void **state)
{
    (void)state;
    const char *bad[] = {"1.2.3", "0x10", "1e",  "--1", "+",   ".",     "1,5",
                         "e5",    "1e+",  "1f",  "..1", "1e5.", "1 e5x", "\x01"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        char text[256];
        snprintf(text, sizeof text, "xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 %s 0 0 1\nend\n",
                 bad[i]);
        check_read_error(text, XYL_ERR_PARSE, 4, strcmp(bad[i], "1 e5x") == 0 ? 10 : 8);
    }
    /* a tiny number underflows to 0 rather than failing */
    xyl_skeleton *sk = NULL;
    assert_int_equal(read_str("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 1e-999999 0 0 1\nend\n",
                              &sk, NULL),
                     XYL_OK);
    assert_true(sk->nodes[0].pos.x == 0.0f);
    xyl_skeleton_destroy(sk);
}

static void read_rejects_non_positive_radius_and_leaf_size(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 0\nend\n",
                     XYL_ERR_INVALID_SKELETON, 4, 14);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 -0.5\nend\n",
                     XYL_ERR_INVALID_SKELETON, 4, 14);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 1\nn 0 -1 0 0 0 1\n"
                     "l 0 0 0 0 0 1 0 -1 0 0 0 0 1 0\nend\n",
                     XYL_ERR_INVALID_SKELETON, 5, 30);
}

static void read_rejects_leaf_on_missing_node(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 1\nn 0 -1 0 0 0 1\n"
                     "l 1 0 0 0 0 1 0 -1 0 0 0 0 1 1\nend\n",
                     XYL_ERR_INVALID_SKELETON, 5, 3);
    check_read_error("xylem-skeleton 1\nnodes 0\nleaves 1\nl -2 0 0 0 0 1 0 -1 0 0 0 0 1 1\nend\n",
                     XYL_ERR_INVALID_SKELETON, 4, 3);
}

static void read_rejects_fewer_records_than_announced(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nnodes 2\nleaves 0\nn 0 -1 0 0 0 1\nend\n",
                     XYL_ERR_TRUNCATED, 5, 1);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 2\nn 0 -1 0 0 0 1\n"
                     "l 0 0 0 0 0 1 0 -1 0 0 0 0 1 1\n  end\n",
                     XYL_ERR_TRUNCATED, 6, 3);
}

static void read_rejects_missing_end(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 1\n", XYL_ERR_TRUNCATED, 5,
                     1);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 1", XYL_ERR_TRUNCATED, 4,
                     15);
    check_read_error("xylem-skeleton 1\nnodes 1\n", XYL_ERR_TRUNCATED, 3, 1);
    check_read_error("xylem-skeleton 1\n# only comments\n\n", XYL_ERR_TRUNCATED, 4, 1);
}

static void read_rejects_empty_input(void **state)
{
    (void)state;
    check_read_error("", XYL_ERR_TRUNCATED, 1, 1);
    xyl_skeleton *sk = UNTOUCHED;
    assert_int_equal(xyl_skeleton_read_text(NULL, 0, NULL, &sk, NULL), XYL_ERR_TRUNCATED);
    assert_ptr_equal(sk, UNTOUCHED);
}

static void read_rejects_more_records_than_announced(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nnodes 0\nleaves 0\nn 0 -1 0 0 0 1\nend\n", XYL_ERR_PARSE, 4,
                     1);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 1\n"
                     "l 0 0 0 0 0 1 0 -1 0 0 0 0 1 1\nend\n",
                     XYL_ERR_PARSE, 5, 1);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 1\nn 0 -1 0 0 0 1\n"
                     "l 0 0 0 0 0 1 0 -1 0 0 0 0 1 1\n n 1 0 0 0 0 1\nend\n",
                     XYL_ERR_PARSE, 6, 2);
}

static void read_rejects_leaf_before_all_nodes(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nnodes 2\nleaves 1\nn 0 -1 0 0 0 1\n"
                     "l 0 0 0 0 0 1 0 -1 0 0 0 0 1 1\nn 1 0 0 0 0 1\nend\n",
                     XYL_ERR_PARSE, 5, 1);
}

static void read_rejects_missing_and_extra_fields(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0\nend\n", XYL_ERR_PARSE, 4,
                     13);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 # 0 1\nend\n", XYL_ERR_PARSE,
                     4, 11);
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 1 7\nend\n", XYL_ERR_PARSE,
                     4, 16);
    check_read_error("xylem-skeleton 1\nnodes 1 2\n", XYL_ERR_PARSE, 2, 9);
    check_read_error("xylem-skeleton 1\nnodes\n", XYL_ERR_PARSE, 2, 6);
    check_read_error("xylem-skeleton 1 x\n", XYL_ERR_PARSE, 1, 18);
    check_read_error("xylem-skeleton 1\nnodes 0\nleaves 0\nend now\n", XYL_ERR_PARSE, 4, 5);
}

static void read_rejects_counts_out_of_order(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nleaves 0\nnodes 0\nend\n", XYL_ERR_PARSE, 2, 1);
    check_read_error("xylem-skeleton 1\nnodes 0\nend\n", XYL_ERR_PARSE, 3, 1);
    check_read_error("xylem-skeleton 1\nnodes -1\n", XYL_ERR_PARSE, 2, 7);
    check_read_error("xylem-skeleton 1\nnodes 1e3\n", XYL_ERR_PARSE, 2, 7);
    check_read_error("xylem-skeleton 1\nxylem-skeleton 1\n", XYL_ERR_PARSE, 2, 1);
}

static void read_rejects_unknown_records_and_text_after_end(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nnodes 1\nleaves 0\nnode 0 -1 0 0 0 1\n", XYL_ERR_PARSE, 4,
                     1);
    check_read_error("xylem-skeleton 1\nnodes 0\nleaves 0\nend\nend\n", XYL_ERR_PARSE, 5, 1);
    check_read_error("xylem-skeleton 1\nnodes 0\nleaves 0\nend\n\nxylem-skeleton 1\n",
                     XYL_ERR_PARSE, 6, 1);
    check_read_error("xylem-skeleton 1\rnodes 0\rleaves 0\rend\r", XYL_ERR_PARSE, 1, 16);
}

static void read_rejects_counts_above_limits_before_allocating(void **state)
{
    (void)state;
    counter c = {0, 0, 0, 0, 0};
    xyl_skeleton_read_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.alloc = counting(&c);
    desc.limits.max_nodes = 2;
    desc.limits.max_leaves = 1;
    const char *cases[] = {"xylem-skeleton 1\nnodes 3\nleaves 0\n",
                           "xylem-skeleton 1\nnodes 2\nleaves 2\n",
                           "xylem-skeleton 1\nnodes 99999999999999999999\nleaves 0\n"};
    uint32_t lines[] = {2, 3, 2};
    for (int i = 0; i < 3; ++i) {
        xyl_skeleton *sk = UNTOUCHED;
        xyl_diag d = fresh_diag();
        assert_int_equal(xyl_skeleton_read_text(cases[i], strlen(cases[i]), &desc, &sk, &d),
                         XYL_ERR_LIMIT_EXCEEDED);
        assert_int_equal(d.line, lines[i]);
        assert_int_equal(d.column, 7 + (i == 1));
        assert_ptr_equal(sk, UNTOUCHED);
    }
    assert_int_equal(c.attempts, 0);
}

static void read_rejects_absurd_count_with_default_limits(void **state)
{
    (void)state;
    check_read_error("xylem-skeleton 1\nnodes 99999999999999999999999999999999999999\n",
                     XYL_ERR_LIMIT_EXCEEDED, 2, 7);
    check_read_error("xylem-skeleton 1\nnodes 0\nleaves 16777217\n", XYL_ERR_LIMIT_EXCEEDED, 3, 8);
}

static void read_reserves_no_more_than_the_text_can_hold(void **state)
{
    (void)state;
    counter c = {0, 0, 0, 0, 0};
    xyl_skeleton_read_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.alloc = counting(&c);
    const char *text = "xylem-skeleton 1\nnodes 16777216\nleaves 16777216\nn 0 -1 0 0 0 1\n";
    xyl_skeleton *sk = UNTOUCHED;
    assert_int_equal(xyl_skeleton_read_text(text, strlen(text), &desc, &sk, NULL),
                     XYL_ERR_TRUNCATED);
    assert_true(c.largest < 4096);
    assert_int_equal(c.allocs, c.frees);
}

static void read_rejects_null_arguments(void **state)
{
    (void)state;
    xyl_skeleton *sk = UNTOUCHED;
    xyl_diag d = fresh_diag();
    assert_int_equal(xyl_skeleton_read_text(NULL, 3, NULL, &sk, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(d.code, XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_skeleton_read_text("", 0, NULL, NULL, NULL), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_skeleton_read_file(NULL, NULL, &sk, NULL), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_skeleton_read_file(SKEL_DIR "example.skel", NULL, NULL, NULL),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_ptr_equal(sk, UNTOUCHED);
}

static void read_file_reports_missing_file_as_io(void **state)
{
    (void)state;
    xyl_skeleton *sk = UNTOUCHED;
    xyl_diag d = fresh_diag();
    assert_int_equal(xyl_skeleton_read_file(SKEL_DIR "no-such-file.skel", NULL, &sk, &d),
                     XYL_ERR_IO);
    assert_non_null(strstr(d.message, "no-such-file.skel"));
    assert_ptr_equal(sk, UNTOUCHED);
}

static void read_survives_every_allocation_failure(void **state)
{
    (void)state;
    for (size_t k = 1;; ++k) {
        counter c = {0, 0, 0, 0, k};
        xyl_skeleton_read_desc desc;
        memset(&desc, 0, sizeof desc);
        desc.alloc = counting(&c);
        xyl_skeleton *sk = UNTOUCHED;
        xyl_result r = xyl_skeleton_read_file(SKEL_DIR "leaves.skel", &desc, &sk, NULL);
        if (r == XYL_OK) {
            xyl_skeleton_destroy(sk);
            assert_int_equal(c.allocs, c.frees);
            break;
        }
        assert_int_equal(r, XYL_ERR_OUT_OF_MEMORY);
        assert_ptr_equal(sk, UNTOUCHED);
        assert_int_equal(c.allocs, c.frees);
        assert_true(k < 64);
    }
}

/* Cutting a valid file anywhere must fail cleanly until the 'end' keyword is complete. */
static void check_every_prefix(const char *text, size_t len)
{
    const char *end = NULL;
    for (const char *p = text; (p = strstr(p, "\nend")) != NULL && p < text + len; ++p) end = p;
    assert_non_null(end);
    size_t complete = (size_t)(end - text) + 4;
    for (size_t n = 0; n <= len; ++n) {
        char *copy = malloc(n ? n : 1);
        assert_non_null(copy);
        memcpy(copy, text, n);
        xyl_skeleton *sk = UNTOUCHED;
        xyl_diag d = fresh_diag();
        xyl_result r = xyl_skeleton_read_text(copy, n, NULL, &sk, &d);
        if ((r == XYL_OK) != (n >= complete))
            print_error("prefix of %zu bytes: %s (%s)\n", n, xyl_result_string(r), d.message);
        assert_int_equal(r == XYL_OK, n >= complete);
        if (r == XYL_OK) xyl_skeleton_destroy(sk);
        else assert_ptr_equal(sk, UNTOUCHED);
        assert_true(r == XYL_OK || d.line >= 1);
        free(copy);
    }
}

static void read_every_prefix_of_a_valid_file_fails_unless_complete(void **state)
{
    (void)state;
    const char *files[] = {"example.skel", "leaves.skel", "crlf.skel", "forks.skel"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        char path[512];
        snprintf(path, sizeof path, SKEL_DIR "%s", files[i]);
        size_t len;
        char *text = slurp(path, &len);
        text[len] = '\0';
        check_every_prefix(text, len);
        free(text);
    }
}

/* ---- write --------------------------------------------------------------------------------- */

static xyl_skeleton *example_skeleton(void)
{
    xyl_skel_node nodes[3] = {node(0, 0, 0, 0.1f, -1), node(0, 1, 0, 0.08f, 0),
                              node(0, 2, 0, 0.05f, 1)};
    xyl_skel_leaf leaves[1] = {leaf(2, 0, 2, 0, 0.3f)};
    xyl_skeleton *sk = NULL;
    assert_int_equal(create(nodes, 3, leaves, 1, &sk, NULL), XYL_OK);
    return sk;
}

static void write_skel_matches_documented_layout(void **state)
{
    (void)state;
    xyl_skeleton *sk = example_skeleton();
    size_t len;
    char *text = write_alloc(sk, XYL_SKEL_FORMAT_SKEL, &len);
    assert_string_equal(text, "xylem-skeleton 1\n"
                              "nodes 3\n"
                              "leaves 1\n"
                              "n 0 -1 0 0 0 0.1\n"
                              "n 1 0 0 1 0 0.08\n"
                              "n 2 1 0 2 0 0.05\n"
                              "l 2 0 2 0 0 1 0 -1 0 0 0 0 1 0.3\n"
                              "end\n");
    free(text);
    xyl_skeleton_destroy(sk);
}

static void write_skel_round_trips_golden_files(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof valid_files / sizeof valid_files[0]; ++i) {
        char path[512];
        snprintf(path, sizeof path, SKEL_DIR "%s", valid_files[i].file);
        xyl_skeleton *sk = NULL;
        assert_int_equal(xyl_skeleton_read_file(path, NULL, &sk, NULL), XYL_OK);
        assert_round_trips(sk);
        xyl_skeleton_destroy(sk);
    }
}

static void write_skel_round_trips_special_floats_bit_exact(void **state)
{
    (void)state;
    float specials[] = {FLT_MAX, -FLT_MAX, FLT_MIN, -FLT_MIN, 1.401298464e-45f, -0.0f, 0.0f,
                        1.0f / 3.0f, 16777217.0f, 0.1f, 1e-10f, 123456789.0f, 2.5e-39f};
    size_t n = sizeof specials / sizeof specials[0];
    xyl_skel_node nodes[16];
    for (size_t i = 0; i < n; ++i) {
        float r = fabsf(specials[i]) > 0.0f ? fabsf(specials[i]) : FLT_MIN;
        nodes[i] = node(specials[i], -specials[i], specials[(i + 1) % n], r, (int32_t)i - 1);
    }
    xyl_skeleton *sk = NULL;
    assert_int_equal(create(nodes, n, NULL, 0, &sk, NULL), XYL_OK);
    assert_round_trips(sk);
    xyl_skeleton_destroy(sk);
}

static void write_skel_round_trips_random_bits(void **state)
{
    (void)state;
    enum { N = 2000, L = 500 };
    xyl_skel_node *nodes = calloc(N, sizeof *nodes);
    xyl_skel_leaf *leaves = calloc(L, sizeof *leaves);
    assert_non_null(nodes);
    assert_non_null(leaves);
    uint64_t seed = UINT64_C(0x9E3779B97F4A7C15);
    for (int i = 0; i < N; ++i) {
        nodes[i].pos = random_vec3(&seed);
        nodes[i].radius = random_positive_float(&seed);
        nodes[i].parent = (int32_t)(next_random(&seed) % (uint64_t)(i + 1)) - 1;
    }
    for (int i = 0; i < L; ++i) {
        leaves[i].pos = random_vec3(&seed);
        leaves[i].heading = random_vec3(&seed);
        leaves[i].left = random_vec3(&seed);
        leaves[i].up = random_vec3(&seed);
        leaves[i].size = random_positive_float(&seed);
        leaves[i].node = (int32_t)(next_random(&seed) % (N + 1)) - 1;
    }
    xyl_skeleton *sk = NULL;
    assert_int_equal(create(nodes, N, leaves, L, &sk, NULL), XYL_OK);
    assert_round_trips(sk);
    xyl_skeleton_destroy(sk);
    free(nodes);
    free(leaves);
}

static void write_obj_has_one_vertex_per_node_and_one_line_per_segment(void **state)
{
    (void)state;
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_skeleton_read_file(SKEL_DIR "multi_root.skel", NULL, &sk, NULL), XYL_OK);
    size_t len;
    char *text = write_alloc(sk, XYL_SKEL_FORMAT_OBJ, &len);
    assert_int_equal(count_lines_starting(text, "v "), 6);
    assert_int_equal(count_lines_starting(text, "l "), 3); /* 6 nodes - 3 roots */
    assert_int_equal(count_lines_starting(text, "#"), 1);
    assert_int_equal(count_lines_starting(text, ""), 10);
    assert_true(text[len - 1] == '\n');
    free(text);
    xyl_skeleton_destroy(sk);
}

static void write_obj_uses_one_based_parent_child_indices(void **state)
{
    (void)state;
    xyl_skeleton *sk = example_skeleton();
    size_t len;
    char *text = write_alloc(sk, XYL_SKEL_FORMAT_OBJ, &len);
    assert_string_equal(text, "# xylem skeleton: nodes 3, segments 2, leaves 1 "
                              "(leaves are not written to OBJ)\n"
                              "v 0 0 0\n"
                              "v 0 1 0\n"
                              "v 0 2 0\n"
                              "l 1 2\n"
                              "l 2 3\n");
    free(text);
    xyl_skeleton_destroy(sk);
}

static void write_text_with_null_buffer_reports_needed_size(void **state)
{
    (void)state;
    xyl_skeleton *sk = example_skeleton();
    for (int f = 0; f < 2; ++f) {
        size_t needed = 0, len;
        assert_int_equal(xyl_skeleton_write_text(sk, (xyl_skel_format)f, NULL, 12345, &needed),
                         XYL_OK);
        char *text = write_alloc(sk, (xyl_skel_format)f, &len);
        assert_int_equal(needed, strlen(text));
        free(text);
    }
    xyl_skeleton_destroy(sk);
}

static void write_text_rejects_too_small_buffer_and_leaves_it_untouched(void **state)
{
    (void)state;
    xyl_skeleton *sk = example_skeleton();
    size_t needed = 0;
    assert_int_equal(xyl_skeleton_write_text(sk, XYL_SKEL_FORMAT_SKEL, NULL, 0, &needed), XYL_OK);
    char *buf = malloc(needed + 1);
    assert_non_null(buf);
    memset(buf, 'Z', needed + 1);
    size_t got = 0;
    /* needed bytes leave no room for the NUL */
    assert_int_equal(xyl_skeleton_write_text(sk, XYL_SKEL_FORMAT_SKEL, buf, needed, &got),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(got, needed);
    for (size_t i = 0; i <= needed; ++i) assert_int_equal(buf[i], 'Z');
    assert_int_equal(xyl_skeleton_write_text(sk, XYL_SKEL_FORMAT_SKEL, buf, 1, &got),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(buf[0], 'Z');
    /* needed + 1 fits; the needed pointer is optional when a buffer is given */
    assert_int_equal(xyl_skeleton_write_text(sk, XYL_SKEL_FORMAT_SKEL, buf, needed + 1, NULL),
                     XYL_OK);
    assert_int_equal(strlen(buf), needed);
    free(buf);
    xyl_skeleton_destroy(sk);
}

static void write_text_rejects_bad_arguments(void **state)
{
    (void)state;
    xyl_skeleton *sk = example_skeleton();
    size_t needed = 99;
    assert_int_equal(xyl_skeleton_write_text(NULL, XYL_SKEL_FORMAT_SKEL, NULL, 0, &needed),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_skeleton_write_text(sk, (xyl_skel_format)7, NULL, 0, &needed),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_skeleton_write_text(sk, XYL_SKEL_FORMAT_SKEL, NULL, 0, NULL),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(needed, 99);
    xyl_skeleton_destroy(sk);
}

static void write_text_checks_a_caller_made_view(void **state)
{
    (void)state;
    xyl_skel_node nodes[2] = {node(0, 0, 0, 1, -1), node(0, NAN, 0, 1, 0)};
    xyl_skeleton view;
    memset(&view, 0, sizeof view);
    view.nodes = nodes;
    view.node_count = 2;
    size_t needed = 99;
    assert_int_equal(xyl_skeleton_write_text(&view, XYL_SKEL_FORMAT_SKEL, NULL, 0, &needed),
                     XYL_ERR_NON_FINITE);
    nodes[1] = node(0, 1, 0, 1, 5);
    assert_int_equal(xyl_skeleton_write_text(&view, XYL_SKEL_FORMAT_OBJ, NULL, 0, &needed),
                     XYL_ERR_INVALID_SKELETON);
    assert_int_equal(needed, 99);
}

static void write_text_ignores_the_locale_decimal_point(void **state)
{
    (void)state;
    const char *names[] = {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "ru_RU.UTF-8"};
    const char *found = NULL;
    for (size_t i = 0; i < 4 && !found; ++i)
        if (setlocale(LC_NUMERIC, names[i])) found = names[i];
    if (!found) skip(); /* no locale with a decimal comma installed */
    xyl_skeleton *sk = example_skeleton();
    size_t len;
    char *text = write_alloc(sk, XYL_SKEL_FORMAT_SKEL, &len);
    setlocale(LC_NUMERIC, "C");
    assert_non_null(strstr(text, " 0.1\n"));
    assert_round_trips(sk);
    free(text);
    xyl_skeleton_destroy(sk);
}

/* ---- write_file ---------------------------------------------------------------------------- */

typedef struct tmpdir {
    char path[64];
} tmpdir;

static void make_tmpdir(tmpdir *t)
{
    snprintf(t->path, sizeof t->path, "/tmp/xyl_skel_XXXXXX");
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

static void join(char *out, size_t size, const tmpdir *t, const char *name)
{
    snprintf(out, size, "%s/%s", t->path, name);
}

static void write_file_round_trips_through_read_file(void **state)
{
    (void)state;
    tmpdir t;
    make_tmpdir(&t);
    char path[128];
    join(path, sizeof path, &t, "tree.skel");
    xyl_skeleton *sk = NULL, *back = NULL;
    assert_int_equal(xyl_skeleton_read_file(SKEL_DIR "forks.skel", NULL, &sk, NULL), XYL_OK);
    xyl_diag d = fresh_diag();
    assert_int_equal(xyl_skeleton_write_file(sk, path, XYL_SKEL_FORMAT_SKEL, NULL, &d), XYL_OK);
    assert_int_equal(d.code, XYL_OK);
    assert_int_equal(xyl_skeleton_read_file(path, NULL, &back, NULL), XYL_OK);
    assert_same_skeleton(sk, back);
    assert_int_equal(dir_entries(t.path), 1);
    join(path, sizeof path, &t, "tree.obj");
    assert_int_equal(xyl_skeleton_write_file(sk, path, XYL_SKEL_FORMAT_OBJ, NULL, NULL), XYL_OK);
    size_t len, expect_len;
    char *text = slurp(path, &len);
    char *expect = write_alloc(sk, XYL_SKEL_FORMAT_OBJ, &expect_len);
    assert_int_equal(len, expect_len);
    assert_memory_equal(text, expect, len);
    free(text);
    free(expect);
    unlink(path);
    join(path, sizeof path, &t, "tree.skel");
    unlink(path);
    rmdir(t.path);
    xyl_skeleton_destroy(sk);
    xyl_skeleton_destroy(back);
}

static void write_file_into_missing_directory_fails_with_io_and_leaves_nothing(void **state)
{
    (void)state;
    tmpdir t;
    make_tmpdir(&t);
    char path[128];
    join(path, sizeof path, &t, "missing/tree.skel");
    xyl_skeleton *sk = example_skeleton();
    xyl_diag d = fresh_diag();
    assert_int_equal(xyl_skeleton_write_file(sk, path, XYL_SKEL_FORMAT_SKEL, NULL, &d), XYL_ERR_IO);
    assert_int_equal(d.code, XYL_ERR_IO);
    assert_true(strlen(d.message) > 0);
    assert_int_equal(dir_entries(t.path), 0);
    rmdir(t.path);
    xyl_skeleton_destroy(sk);
}

static void write_file_replaces_existing_file_atomically(void **state)
{
    (void)state;
    tmpdir t;
    make_tmpdir(&t);
    char path[128];
    join(path, sizeof path, &t, "tree.skel");
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs("old contents\n", f);
    fclose(f);
    /* A reader holding the old file keeps seeing it whole: the new one arrives by rename. */
    int old_fd = open(path, O_RDONLY);
    assert_true(old_fd >= 0);
    xyl_skeleton *sk = example_skeleton(), *back = NULL;
    assert_int_equal(xyl_skeleton_write_file(sk, path, XYL_SKEL_FORMAT_SKEL, NULL, NULL), XYL_OK);
    char old[32] = {0};
    assert_int_equal(read(old_fd, old, sizeof old - 1), 13);
    assert_string_equal(old, "old contents\n");
    close(old_fd);
    assert_int_equal(xyl_skeleton_read_file(path, NULL, &back, NULL), XYL_OK);
    assert_same_skeleton(sk, back);
    assert_int_equal(dir_entries(t.path), 1); /* no temporary file left behind */
    unlink(path);
    rmdir(t.path);
    xyl_skeleton_destroy(sk);
    xyl_skeleton_destroy(back);
}

static void write_file_rejects_bad_arguments(void **state)
{
    (void)state;
    xyl_skeleton *sk = example_skeleton();
    xyl_diag d = fresh_diag();
    assert_int_equal(xyl_skeleton_write_file(NULL, "/tmp/x.skel", XYL_SKEL_FORMAT_SKEL, NULL, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(d.code, XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_skeleton_write_file(sk, NULL, XYL_SKEL_FORMAT_SKEL, NULL, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_skeleton_write_file(sk, "", XYL_SKEL_FORMAT_SKEL, NULL, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_skeleton_write_file(sk, "/tmp/x.skel", (xyl_skel_format)9, NULL, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    xyl_skeleton_destroy(sk);
}

/* The stem mesher's hard cases (tests/data/stems, made by scripts/make_hard_cases.py) are valid
 * skeletons: at least 40 of them, each one read without error. */
static void count_nodes(const char *name, const xyl_skeleton *sk, void *ctx)
{
    (void)name;
    assert_true(sk->node_count >= 1);
    ++*(int *)ctx;
}

static void every_stem_hard_case_reads(void **state)
{
    (void)state;
    int seen = 0;
    int count = tu_for_each_hard_case(count_nodes, &seen);
    assert_true(count >= 40);
    assert_int_equal(seen, count);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_stem_hard_case_reads),
        cmocka_unit_test(create_copies_arrays_and_derives_counts),
        cmocka_unit_test(create_larger_radius_child_continues_branch),
        cmocka_unit_test(create_radius_tie_goes_to_first_child),
        cmocka_unit_test(create_multi_root_numbers_branches_in_node_order),
        cmocka_unit_test(create_orders_grow_with_each_lateral_fork),
        cmocka_unit_test(create_accepts_empty_skeleton),
        cmocka_unit_test(create_rejects_null_arguments),
        cmocka_unit_test(create_rejects_null_arrays_with_counts),
        cmocka_unit_test(create_rejects_non_finite_values),
        cmocka_unit_test(create_rejects_non_positive_radius),
        cmocka_unit_test(create_rejects_parent_not_before_child),
        cmocka_unit_test(create_rejects_bad_leaves),
        cmocka_unit_test(create_rejects_counts_above_limits),
        cmocka_unit_test(create_survives_every_allocation_failure),
        cmocka_unit_test(destroy_accepts_null),
        cmocka_unit_test(read_parses_documented_example),
        cmocka_unit_test(read_golden_valid_files),
        cmocka_unit_test(read_keeps_kinks_coincident_nodes_and_rootless_leaves),
        cmocka_unit_test(read_derives_branches_like_create),
        cmocka_unit_test(read_accepts_crlf_line_endings),
        cmocka_unit_test(read_accepts_comments_and_blank_lines_anywhere),
        cmocka_unit_test(read_accepts_missing_final_newline),
        cmocka_unit_test(read_uses_length_not_nul_terminator),
        cmocka_unit_test(read_accepts_number_forms),
        cmocka_unit_test(read_rounds_just_above_flt_max_down),
        cmocka_unit_test(read_golden_invalid_files),
        cmocka_unit_test(read_rejects_embedded_nul),
        cmocka_unit_test(read_rejects_other_versions),
        cmocka_unit_test(read_rejects_missing_header),
        cmocka_unit_test(read_rejects_node_id_out_of_order),
        cmocka_unit_test(read_rejects_parent_after_child),
        cmocka_unit_test(read_reports_offending_node_index),
        cmocka_unit_test(read_rejects_nan_and_inf_tokens),
        cmocka_unit_test(read_rejects_malformed_numbers),
        cmocka_unit_test(read_rejects_non_positive_radius_and_leaf_size),
        cmocka_unit_test(read_rejects_leaf_on_missing_node),
        cmocka_unit_test(read_rejects_fewer_records_than_announced),
        cmocka_unit_test(read_rejects_missing_end),
        cmocka_unit_test(read_rejects_empty_input),
        cmocka_unit_test(read_rejects_more_records_than_announced),
        cmocka_unit_test(read_rejects_leaf_before_all_nodes),
        cmocka_unit_test(read_rejects_missing_and_extra_fields),
        cmocka_unit_test(read_rejects_counts_out_of_order),
        cmocka_unit_test(read_rejects_unknown_records_and_text_after_end),
        cmocka_unit_test(read_rejects_counts_above_limits_before_allocating),
        cmocka_unit_test(read_rejects_absurd_count_with_default_limits),
        cmocka_unit_test(read_reserves_no_more_than_the_text_can_hold),
        cmocka_unit_test(read_rejects_null_arguments),
        cmocka_unit_test(read_file_reports_missing_file_as_io),
        cmocka_unit_test(read_survives_every_allocation_failure),
        cmocka_unit_test(read_every_prefix_of_a_valid_file_fails_unless_complete),
        cmocka_unit_test(write_skel_matches_documented_layout),
        cmocka_unit_test(write_skel_round_trips_golden_files),
        cmocka_unit_test(write_skel_round_trips_special_floats_bit_exact),
        cmocka_unit_test(write_skel_round_trips_random_bits),
        cmocka_unit_test(write_obj_has_one_vertex_per_node_and_one_line_per_segment),
        cmocka_unit_test(write_obj_uses_one_based_parent_child_indices),
        cmocka_unit_test(write_text_with_null_buffer_reports_needed_size),
        cmocka_unit_test(write_text_rejects_too_small_buffer_and_leaves_it_untouched),
        cmocka_unit_test(write_text_rejects_bad_arguments),
        cmocka_unit_test(write_text_checks_a_caller_made_view),
        cmocka_unit_test(write_text_ignores_the_locale_decimal_point),
        cmocka_unit_test(write_file_round_trips_through_read_file),
        cmocka_unit_test(write_file_into_missing_directory_fails_with_io_and_leaves_nothing),
        cmocka_unit_test(write_file_replaces_existing_file_atomically),
        cmocka_unit_test(write_file_rejects_bad_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

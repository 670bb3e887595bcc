/* The common layer: result names, diagnostics, allocation helpers, safe vector math, frames,
 * atomic file writes. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <pthread.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "test_util.h"
#include "xyl_internal.h"

static void every_result_has_a_distinct_name(void **state)
{
    (void)state;
    for (int i = 0; i < XYL_RESULT_COUNT_; ++i) {
        const char *a = xyl_result_string((xyl_result)i);
        assert_non_null(a);
        assert_string_not_equal(a, "unknown result");
        for (int j = 0; j < i; ++j) assert_string_not_equal(a, xyl_result_string((xyl_result)j));
    }
    assert_string_equal(xyl_result_string(XYL_OK), "ok");
    assert_string_equal(xyl_result_string((xyl_result)9999), "unknown result");
    assert_string_equal(xyl_result_string((xyl_result)-1), "unknown result");
}

static void diag_keeps_the_first_warning_and_counts_all(void **state)
{
    (void)state;
    xyl_diag d = {0};
    assert_int_equal(xyl__fail(&d, XYL_ERR_PARSE, 3, 4, 7, "bad %s", "thing"), XYL_ERR_PARSE);
    assert_int_equal(d.code, XYL_ERR_PARSE);
    assert_string_equal(d.message, "bad thing");
    assert_int_equal(d.line, 3);
    assert_int_equal(d.column, 4);
    assert_int_equal(d.index, 7);
    xyl__warn(&d, "first %d", 1);
    xyl__warn(&d, "second %d", 2);
    assert_int_equal(d.warning_count, 2);
    assert_string_equal(d.warning, "first 1");
    xyl__diag_ok(&d);
    assert_int_equal(d.code, XYL_OK);
    assert_string_equal(d.message, "");
    assert_int_equal(d.warning_count, 2);
    assert_int_equal(xyl__fail(NULL, XYL_ERR_IO, 0, 0, -1, "x"), XYL_ERR_IO);
    xyl__warn(NULL, "x");
}

static void grow_and_calloc_refuse_overflowing_sizes(void **state)
{
    (void)state;
    assert_null(xyl__calloc(NULL, SIZE_MAX / 2, 4));
    void *p = NULL;
    size_t cap = 0;
    assert_false(xyl__grow(NULL, &p, &cap, 0, SIZE_MAX / 2, 8));
    assert_null(p);
    assert_true(xyl__grow(NULL, &p, &cap, 0, 100, 8));
    assert_true(cap >= 100);
    ((char *)p)[799] = 1;
    xyl__free(NULL, p);
}

static bool all_bytes_are(const unsigned char *p, size_t n, unsigned char v)
{
    for (size_t i = 0; i < n; ++i)
        if (p[i] != v) return false;
    return true;
}

/* Blocks from XYL__LARGE_BLOCK on are mapped and, once freed, cached: calloc must still zero a
 * reused (dirty) block, a request of about the same size gets the cached block back, the cache
 * keeps at most XYL__CACHE_BYTES, and xyl_memory_trim empties it. Sanitizer builds use malloc
 * for everything and keep no cache. */
static void big_blocks_are_zeroed_reused_bounded_and_trimmed(void **state)
{
    (void)state;
    xyl_memory_trim();
    size_t big = 3 * XYL__LARGE_BLOCK;
    unsigned char *p = xyl__calloc(NULL, big, 1);
    assert_non_null(p);
    assert_true(all_bytes_are(p, big, 0));
    memset(p, 0xab, big);
    xyl__free(NULL, p);
    unsigned char *q = xyl__calloc(NULL, big - 4096, 1);
    assert_non_null(q);
    assert_true(all_bytes_are(q, big - 4096, 0));
    memset(q, 0xcd, big - 4096);
    xyl__free(NULL, q);
    unsigned char *r = xyl__alloc(NULL, big);
    assert_non_null(r);
    r[big - 1] = 1;
    xyl__free(NULL, r);
#if defined(XYL__LARGE_BLOCKS)
    assert_ptr_equal(q, p); /* the cached block came back */
    assert_ptr_equal(r, p);
    size_t kept = xyl_memory_trim();
    assert_true(kept >= big && kept <= 2 * big);
#endif
    assert_int_equal(xyl_memory_trim(), 0);

    /* more than the cache may keep, in bytes and in blocks: the oldest go back to the system */
    enum { N = 2 * XYL__CACHE_SLOTS };
    void *blocks[N];
    size_t sizes[2] = {XYL__CACHE_BYTES / 8, XYL__LARGE_BLOCK};
    for (int t = 0; t < 2; ++t) {
        for (int i = 0; i < N; ++i) assert_non_null(blocks[i] = xyl__alloc(NULL, sizes[t]));
        for (int i = 0; i < N; ++i) xyl__free(NULL, blocks[i]);
        size_t cached = xyl_memory_trim();
        assert_true(cached <= XYL__CACHE_BYTES);
        if (t == 1) assert_true(cached <= XYL__CACHE_SLOTS * 2 * sizes[t]);
#if defined(XYL__LARGE_BLOCKS)
        if (t == 0) assert_true(cached >= XYL__CACHE_BYTES / 2);
        else assert_true(cached >= XYL__CACHE_SLOTS * sizes[t]);
#endif
    }
    /* small blocks never enter the cache */
    void *s = xyl__alloc(NULL, 100);
    xyl__free(NULL, s);
    assert_int_equal(xyl_memory_trim(), 0);
}

/* Threads allocating and freeing big blocks at once: every block keeps what its thread wrote,
 * so the cache never hands one block to two owners. */
static void *churn(void *arg)
{
    uint64_t seed = (uint64_t)(uintptr_t)arg;
    unsigned char *held[4] = {0}, fill[4] = {0};
    size_t sizes[4] = {0};
    bool ok = true;
    for (int i = 0; i < 400 && ok; ++i) {
        int slot = i % 4;
        if (held[slot]) {
            ok = all_bytes_are(held[slot], sizes[slot], fill[slot]);
            xyl__free(NULL, held[slot]);
        }
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        sizes[slot] = XYL__LARGE_BLOCK / 2 + (size_t)(seed >> 40) % (4 * XYL__LARGE_BLOCK);
        fill[slot] = (unsigned char)(seed >> 56);
        if (!(held[slot] = xyl__alloc(NULL, sizes[slot]))) return NULL;
        memset(held[slot], fill[slot], sizes[slot]);
    }
    for (int j = 0; j < 4; ++j) xyl__free(NULL, held[j]);
    return ok ? arg : NULL;
}

static void big_blocks_survive_threads(void **state)
{
    (void)state;
    enum { T = 4 };
    pthread_t t[T];
    for (uintptr_t i = 0; i < T; ++i)
        assert_int_equal(pthread_create(&t[i], NULL, churn, (void *)(i + 1)), 0);
    for (int i = 0; i < T; ++i) {
        void *r = NULL;
        assert_int_equal(pthread_join(t[i], &r), 0);
        assert_ptr_equal(r, (void *)(uintptr_t)(i + 1));
    }
    assert_int_equal(xyl__alloc_blocks_in_use(), 0);
    xyl_memory_trim();
}

static int u64_order(const void *pa, const void *pb)
{
    uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;
    return (a > b) - (a < b);
}

/* 12-byte elements ordered by their first word only: ties are told apart by the rest. */
typedef struct keyed {
    uint32_t key, a, b;
} keyed;

static int keyed_order(const void *pa, const void *pb)
{
    const keyed *x = pa, *y = pb;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->a != y->a ? (x->a < y->a ? -1 : 1) : (x->b > y->b) - (x->b < y->b);
}

/* A test array of n keys: random with repeats, ascending, descending, all equal, or rising then
 * falling (the shapes that unbalance a quicksort's partitions). */
static uint64_t sort_key(int shape, size_t i, size_t n, uint64_t *seed)
{
    *seed = *seed * 6364136223846793005ull + 1442695040888963407ull;
    switch (shape) {
    case 0: return (*seed >> 33) % (n / 2 + 1);
    case 1: return i;
    case 2: return n - i;
    case 3: return 7;
    default: return i < n / 2 ? i : n - i;
    }
}

/* xyl__sort gives what qsort gives, for any length and shape, with and without repeated keys,
 * for 8-byte elements and 12-byte ones (ordered by all their words, ties told apart). */
static void sort_orders_like_qsort(void **state)
{
    (void)state;
    enum { N = 5000 };
    static uint64_t a[N], b[N];
    static keyed ka[N], kb[N];
    uint64_t seed = 11;
    for (int shape = 0; shape < 5; ++shape)
        for (size_t n = 0; n <= N; n = n < 40 ? n + 1 : n * 2 + 3) {
            size_t len = n < N ? n : N;
            for (size_t i = 0; i < len; ++i) {
                a[i] = b[i] = sort_key(shape, i, len, &seed);
                ka[i] = (keyed){(uint32_t)a[i], (uint32_t)(seed >> 40) & 7u, (uint32_t)i};
                kb[i] = ka[i];
            }
            xyl__sort(a, len, sizeof a[0], u64_order);
            qsort(b, len, sizeof b[0], u64_order);
            assert_memory_equal(a, b, len * sizeof a[0]);
            xyl__sort(ka, len, sizeof ka[0], keyed_order);
            qsort(kb, len, sizeof kb[0], keyed_order);
            assert_memory_equal(ka, kb, len * sizeof ka[0]);
        }
}

static void normalising_a_zero_or_nan_vector_gives_the_fallback(void **state)
{
    (void)state;
    xyl__dvec3 fb = xyl__d3(0, 0, 1);
    xyl__dvec3 r = xyl__d3_normalize_or(xyl__d3(0, 0, 0), fb);
    assert_true(r.x == 0 && r.y == 0 && r.z == 1);
    r = xyl__d3_normalize_or(xyl__d3(NAN, 1, 0), fb);
    assert_true(r.z == 1);
    r = xyl__d3_normalize_or(xyl__d3(1e-200, 0, 0), fb);
    assert_true(r.z == 1); /* squared length underflows: no direction */
    r = xyl__d3_normalize_or(xyl__d3(1e-100, 0, 0), fb);
    assert_true(fabs(r.x - 1.0) < 1e-15);
    r = xyl__d3_normalize_or(xyl__d3(3e150, 4e150, 0), fb);
    assert_true(fabs(r.x - 0.6) < 1e-15 && fabs(r.y - 0.8) < 1e-15);
}

static uint64_t splitmix(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double unit_random(uint64_t *s)
{
    return (double)(splitmix(s) >> 11) / 9007199254740992.0 * 2.0 - 1.0;
}

static void any_orthogonal_is_unit_and_orthogonal_everywhere(void **state)
{
    (void)state;
    uint64_t seed = 5;
    xyl__dvec3 special[] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {0, 1e-9, -1}};
    for (int i = 0; i < 100005; ++i) {
        xyl__dvec3 n = i < 5 ? special[i]
                             : xyl__d3(unit_random(&seed), unit_random(&seed), unit_random(&seed));
        n = xyl__d3_normalize_or(n, xyl__d3(0, 0, 1));
        xyl__dvec3 t = xyl__d3_any_orthogonal(n);
        assert_true(fabs(xyl__d3_len(t) - 1.0) < 1e-12);
        assert_true(fabs(xyl__d3_dot(t, n)) < 1e-12);
    }
}

static void rotation_preserves_length_and_turns_by_the_angle(void **state)
{
    (void)state;
    xyl__dvec3 v = xyl__d3_rotate(xyl__d3(1, 0, 0), xyl__d3(0, 0, 1), 3.14159265358979323846 / 2);
    assert_true(fabs(v.x) < 1e-15 && fabs(v.y - 1.0) < 1e-15 && fabs(v.z) < 1e-15);
    xyl__frame f = {xyl__d3(0, 1, 0), xyl__d3(-1, 0, 0), xyl__d3(0, 0, 1)};
    assert_true(xyl__frame_error(&f) == 0.0);
    f.h = xyl__d3(0.1, 2, 0);
    f.l = xyl__d3(-1, 0.3, 0.2);
    xyl__frame_orthonormalize(&f);
    assert_true(xyl__frame_error(&f) < 1e-15);
    xyl__frame bad = {xyl__d3(NAN, 0, 0), xyl__d3(0, 0, 0), xyl__d3(0, 0, 0)};
    xyl__frame_orthonormalize(&bad); /* degenerate input still yields a frame */
    assert_true(xyl__frame_error(&bad) < 1e-15);
}

static void atomic_write_replaces_whole_files_and_reports_errors(void **state)
{
    (void)state;
    char dir[] = "/tmp/xyl-test-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/out.txt", dir);
    xyl_diag d = {0};
    assert_int_equal(xyl__write_file_atomic(path, "first", 5, NULL, &d), XYL_OK);
    assert_int_equal(xyl__write_file_atomic(path, "second", 6, NULL, &d), XYL_OK);
    char *buf = NULL;
    size_t n = 0;
    assert_int_equal(xyl__read_file(path, 100, NULL, &buf, &n, &d), XYL_OK);
    assert_int_equal(n, 6);
    assert_string_equal(buf, "second");
    xyl__free(NULL, buf);
    assert_int_equal(xyl__read_file(path, 3, NULL, &buf, &n, &d), XYL_ERR_LIMIT_EXCEEDED);
    char missing[300];
    snprintf(missing, sizeof missing, "%s/no/such/dir/out.txt", dir);
    assert_int_equal(xyl__write_file_atomic(missing, "x", 1, NULL, &d), XYL_ERR_IO);
    assert_non_null(strstr(d.message, "cannot create"));
    assert_int_equal(xyl__read_file(missing, 100, NULL, &buf, &n, &d), XYL_ERR_IO);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_true((st.st_mode & 0044) != 0 || (st.st_mode & 0600) == 0600);
    assert_int_equal(unlink(path), 0);
    assert_int_equal(rmdir(dir), 0); /* nothing temporary was left behind */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_result_has_a_distinct_name),
        cmocka_unit_test(diag_keeps_the_first_warning_and_counts_all),
        cmocka_unit_test(grow_and_calloc_refuse_overflowing_sizes),
        cmocka_unit_test(big_blocks_are_zeroed_reused_bounded_and_trimmed),
        cmocka_unit_test(big_blocks_survive_threads),
        cmocka_unit_test(sort_orders_like_qsort),
        cmocka_unit_test(normalising_a_zero_or_nan_vector_gives_the_fallback),
        cmocka_unit_test(any_orthogonal_is_unit_and_orthogonal_everywhere),
        cmocka_unit_test(rotation_preserves_length_and_turns_by_the_angle),
        cmocka_unit_test(atomic_write_replaces_whole_files_and_reports_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

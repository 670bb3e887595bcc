/* Shared helpers for the cmocka suites. */
#ifndef XYL_TEST_UTIL_H
#define XYL_TEST_UTIL_H

#include <dirent.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include <xylem/xyl_lsystem.h>
#include <xylem/xyl_stems.h>

/* 1 in AddressSanitizer builds (scripts/test.sh stage 2), where suites that run 10-50x slower
 * trim their slowest matrices; Release runs them whole. */
#if defined(__SANITIZE_ADDRESS__)
#define SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SANITIZED 1
#endif
#endif
#ifndef SANITIZED
#define SANITIZED 0
#endif

/* ---- allocation counting and failure injection ---------------------------------------------- */

/* Counts what goes through it and fails the fail_at-th attempt (1-based; 0: none). */
typedef struct tu_counter {
    size_t attempts, allocs, frees;
    size_t fail_at;
} tu_counter;

static inline void *tu_count_alloc(size_t size, void *user)
{
    tu_counter *c = user;
    if (++c->attempts == c->fail_at) return NULL;
    void *p = malloc(size);
    if (p) c->allocs++;
    return p;
}

static inline void tu_count_free(void *p, void *user)
{
    tu_counter *c = user;
    c->frees++;
    free(p);
}

static inline xyl_allocator tu_counting(tu_counter *c)
{
    xyl_allocator a = {tu_count_alloc, tu_count_free, c};
    return a;
}

/* Parses text; fails the test with the diagnostic if it does not parse. */
static inline xyl_grammar *tu_parse(const char *text)
{
    xyl_grammar_desc gd = {0};
    gd.source = text;
    xyl_grammar *g = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_grammar_parse(&gd, &g, &d);
    if (r != XYL_OK) fail_msg("parse failed: %s at %u:%u: %s", xyl_result_string(r), d.line, d.column, d.message);
    return g;
}

/* Expects text to fail to parse with code at line:column (column 0 = don't care). */
static inline void tu_parse_fails(const char *text, xyl_result code, uint32_t line, uint32_t column)
{
    xyl_grammar_desc gd = {0};
    gd.source = text;
    xyl_grammar *g = (xyl_grammar *)(uintptr_t)1; /* must stay untouched */
    xyl_diag d = {0};
    xyl_result r = xyl_grammar_parse(&gd, &g, &d);
    if (r != code || d.line != line || (column && d.column != column))
        fail_msg("expected %s at %u:%u, got %s at %u:%u (%s) for:\n%s", xyl_result_string(code), line,
                 column, xyl_result_string(r), d.line, d.column, d.message, text);
    assert_int_equal(d.code, code);
    assert_true(strlen(d.message) > 0);
    assert_ptr_equal(g, (xyl_grammar *)(uintptr_t)1);
}

/* Derives text with depth and seed; fails the test unless the result is expect. */
static inline xyl_lstring *tu_derive(const char *text, uint32_t depth, uint64_t seed,
                                     xyl_result expect, xyl_diag *diag)
{
    xyl_grammar *g = tu_parse(text);
    xyl_derive_desc dd = {0};
    dd.has_depth = true;
    dd.depth = depth;
    dd.has_seed = true;
    dd.seed = seed;
    xyl_lstring *s = NULL;
    xyl_diag local = {0};
    xyl_diag *d = diag ? diag : &local;
    xyl_result r = xyl_lsystem_derive(g, &dd, &s, d);
    xyl_grammar_destroy(g);
    if (r != expect)
        fail_msg("expected %s, got %s (%s)", xyl_result_string(expect), xyl_result_string(r),
                 d->message);
    return s;
}

/* Grows text at its own #depth and seed into a skeleton with the turtle options td (NULL:
 * defaults); fails the test if any step fails. */
static inline xyl_skeleton *tu_grow(const char *text, const xyl_turtle_desc *td)
{
    xyl_grammar *g = tu_parse(text);
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_lsystem_derive(g, NULL, &s, NULL), XYL_OK);
    assert_int_equal(xyl_lsystem_interpret(g, s, td, &sk, NULL), XYL_OK);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return sk;
}

/* Derives text to the given depth and returns the formatted string (malloc'd). */
static inline char *tu_derive_text(const char *text, uint32_t depth, uint64_t seed)
{
    xyl_lstring *s = tu_derive(text, depth, seed, XYL_OK, NULL);
    size_t need = 0;
    assert_int_equal(xyl_lstring_format(s, NULL, 0, &need), XYL_OK);
    char *buf = malloc(need + 1);
    assert_non_null(buf);
    assert_int_equal(xyl_lstring_format(s, buf, need + 1, &need), XYL_OK);
    xyl_lstring_destroy(s);
    return buf;
}

static inline void tu_assert_derives(const char *text, uint32_t depth, const char *expected)
{
    char *got = tu_derive_text(text, depth, 1);
    if (strcmp(got, expected) != 0) fail_msg("depth %u: expected\n  %s\ngot\n  %s", depth, expected, got);
    free(got);
}

/* Calls fn on every hard-case skeleton in tests/data/stems (scripts/make_hard_cases.py);
 * returns how many there were. A file that does not read fails the test. */
typedef void (*tu_skeleton_fn)(const char *name, const xyl_skeleton *sk, void *ctx);

static inline int tu_for_each_hard_case(tu_skeleton_fn fn, void *ctx)
{
    char dir[512];
    snprintf(dir, sizeof dir, "%s/stems", XYL_TEST_DATA);
    DIR *d = opendir(dir);
    assert_non_null(d);
    int count = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        size_t n = strlen(e->d_name);
        if (n < 6 || strcmp(e->d_name + n - 5, ".skel") != 0) continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        xyl_skeleton *sk = NULL;
        xyl_diag diag = {0};
        if (xyl_skeleton_read_file(path, NULL, &sk, &diag) != XYL_OK)
            fail_msg("%s: %s", e->d_name, diag.message);
        fn(e->d_name, sk, ctx);
        xyl_skeleton_destroy(sk);
        ++count;
    }
    closedir(d);
    return count;
}

/* The default tree (depth 0: the grammar's own) meshed with k sides and a subdivision. */
static inline xyl_mesh *tu_tree_mesh(uint32_t depth, uint32_t sides, xyl_subdivision subdivision)
{
    xyl_grammar *g = tu_parse(xyl_lsystem_preset_source(xyl_lsystem_default_preset()));
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    xyl_derive_desc dd = {0};
    dd.has_depth = depth != 0;
    dd.depth = depth;
    assert_int_equal(xyl_lsystem_derive(g, &dd, &s, NULL), XYL_OK);
    assert_int_equal(xyl_lsystem_interpret(g, s, NULL, &sk, NULL), XYL_OK);
    xyl_stems_desc sd = {0};
    sd.sides = sides;
    sd.subdivision = subdivision;
    xyl_mesh *m = NULL;
    assert_int_equal(xyl_stems_build(sk, &sd, &m, NULL, NULL), XYL_OK);
    xyl_skeleton_destroy(sk);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return m;
}

/* A bent tube: `count` nodes of radius r on a circle in the xy plane, a unit apart, turning `deg`
 * degrees each (node i at angle i * deg around the origin). *bend_radius gets the circle's
 * radius, 1 / (2 sin(deg / 2)). */
static inline xyl_skeleton *tu_bent_tube(int count, double deg, double r, double *bend_radius)
{
    const double step = deg * 3.14159265358979323846 / 180.0, big = 1.0 / (2.0 * sin(step / 2.0));
    xyl_skel_node *n = calloc((size_t)count, sizeof *n);
    assert_non_null(n);
    for (int i = 0; i < count; ++i) {
        n[i].pos = (xyl_vec3){(float)(big * cos(step * i)), (float)(big * sin(step * i)), 0.0f};
        n[i].radius = (float)r;
        n[i].parent = i - 1;
    }
    xyl_skeleton_desc skd = {0};
    skd.nodes = n;
    skd.node_count = (size_t)count;
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_skeleton_create(&skd, &sk, NULL), XYL_OK);
    free(n);
    *bend_radius = big;
    return sk;
}

#endif

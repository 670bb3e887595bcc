/* Grammar parsing: every error class with its code, line and column; header values;
 * expression semantics (precedence, functions in degrees); the syntax corner cases; the
 * built-in presets, and the leafy trees' leaves that must leave the book's nodes alone. */
#include <math.h>
#include <stdbool.h>

#include "test_util.h"

/* Parses "axiom: A(<expr>)" and returns the one parameter. */
static double eval_const(const char *expr)
{
    char text[512];
    snprintf(text, sizeof text, "axiom: A(%s)\n", expr);
    xyl_grammar *g = tu_parse(text);
    xyl_derive_desc dd = {0};
    dd.has_depth = true;
    xyl_lstring *s = NULL;
    assert_int_equal(xyl_lsystem_derive(g, &dd, &s, NULL), XYL_OK);
    xyl_module_view m;
    assert_int_equal(xyl_lstring_module(s, 0, &m), XYL_OK);
    assert_int_equal(m.param_count, 1);
    double v = m.params[0];
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return v;
}

static void expressions_follow_precedence_and_associativity(void **state)
{
    (void)state;
    assert_true(eval_const("2^3^2") == 512.0);
    assert_true(eval_const("-2^2") == -4.0);
    assert_true(eval_const("2^-1") == 0.5);
    assert_true(eval_const("1+2*3") == 7.0);
    assert_true(eval_const("(1+2)*3") == 9.0);
    assert_true(eval_const("7/2") == 3.5);
    assert_true(eval_const("10-4-3") == 3.0);
    assert_true(eval_const("1<2 && 2<1 || 1") == 1.0);
    assert_true(eval_const("1<2 && 2<1") == 0.0);
    assert_true(eval_const("!0") == 1.0);
    assert_true(eval_const("!(2>=2)") == 0.0);
    assert_true(eval_const("3!=3") == 0.0);
    assert_true(eval_const("3==3") == 1.0);
    assert_true(eval_const("2<=1") == 0.0);
    assert_true(eval_const("1.5e3") == 1500.0);
    assert_true(eval_const(".25") == 0.25);
}

static void functions_take_and_return_degrees(void **state)
{
    (void)state;
    assert_true(fabs(eval_const("sin(90)") - 1.0) < 1e-15);
    assert_true(fabs(eval_const("cos(60)") - 0.5) < 1e-15);
    assert_true(fabs(eval_const("tan(45)") - 1.0) < 1e-15);
    assert_true(fabs(eval_const("atan2(1,1)") - 45.0) < 1e-12);
    assert_true(fabs(eval_const("asin(1)") - 90.0) < 1e-12);
    assert_true(fabs(eval_const("acos(0)") - 90.0) < 1e-12);
    assert_true(fabs(eval_const("atan(1)") - 45.0) < 1e-12);
    assert_true(eval_const("min(3,4)") == 3.0);
    assert_true(eval_const("max(3,4)") == 4.0);
    assert_true(eval_const("abs(-2)") == 2.0);
    assert_true(eval_const("floor(2.7)") == 2.0);
    assert_true(eval_const("ceil(2.1)") == 3.0);
    assert_true(eval_const("sqrt(16)") == 4.0);
    assert_true(eval_const("exp(0)") == 1.0);
    assert_true(eval_const("log(1)") == 0.0);
}

static void numbers_are_correctly_rounded(void **state)
{
    (void)state;
    assert_true(eval_const("0.1") == 0.1);
    assert_true(eval_const("123456789012345678901234567890") == 123456789012345678901234567890.0);
    assert_true(eval_const("2.2250738585072014e-308") == 2.2250738585072014e-308);
    assert_true(eval_const("0.30000000000000004") == 0.30000000000000004);
}

static void defines_are_constants_usable_in_later_lines(void **state)
{
    (void)state;
    tu_assert_derives("#define a 2\n#define b a*3\naxiom: A(b)\nA(x) -> B(x+a)\n", 1, "B(8)");
}

static void header_values_reach_grammar_info(void **state)
{
    (void)state;
    xyl_grammar *g = tu_parse("#angle 90\n#step 2\n#width 0.5\n#depth 7\n#seed 99\n"
                              "#tropism 0 -1 0 0.25\naxiom: F\n");
    xyl_grammar_info in;
    xyl_grammar_get_info(g, &in);
    assert_true(fabs(in.angle - 3.14159265358979323846 / 2) < 1e-15);
    assert_true(in.step == 2.0 && in.width == 0.5 && in.depth == 7 && in.seed == 99);
    assert_true(in.tropism[0] == 0.0 && in.tropism[1] == -1.0 && in.tropism[2] == 0.0);
    assert_true(in.elasticity == 0.25);
    xyl_grammar_destroy(g);
    g = tu_parse("axiom: F\n");
    xyl_grammar_get_info(g, &in);
    assert_int_equal(in.depth, 4);
    assert_int_equal(in.seed, 1);
    assert_true(fabs(in.angle - 25.0 * 3.14159265358979323846 / 180.0) < 1e-15);
    assert_true(in.step == 1.0 && in.width == 0.1);
    xyl_grammar_destroy(g);
}

static void labels_stars_comments_and_rolls_parse(void **state)
{
    (void)state;
    tu_assert_derives("axiom: A   // a comment\n"
                      "// a whole comment line\n"
                      "p1: A : * -> F/////F // rolls are not comments\n",
                      1, "F/////F");
    tu_assert_derives("axiom: A\nA : 1 > 0 -> B\n", 1, "B");
    tu_assert_derives("axiom: 0 1 0\n0 < 1 > 0 -> 2\n", 1, "020");
    tu_assert_derives("axiom:A\r\nA->B\r\n", 1, "B");
    tu_assert_derives("axiom: A\nA -> \n", 1, "");
}

static void rejects_unknown_directive(void **state)
{
    (void)state;
    tu_parse_fails("axiom: F\n#angel 20\n", XYL_ERR_INVALID_GRAMMAR, 2, 1);
}

static void rejects_missing_and_second_axiom(void **state)
{
    (void)state;
    tu_parse_fails("F -> FF\n", XYL_ERR_INVALID_GRAMMAR, 2, 0);
    tu_parse_fails("axiom: F\naxiom: G\n", XYL_ERR_INVALID_GRAMMAR, 2, 7);
}

static void rejects_unbalanced_brackets_with_their_column(void **state)
{
    (void)state;
    tu_parse_fails("axiom: F\nF -> F]F\n", XYL_ERR_INVALID_GRAMMAR, 2, 7);
    tu_parse_fails("axiom: F\nF -> F[F[F]\n", XYL_ERR_INVALID_GRAMMAR, 2, 7);
    tu_parse_fails("axiom: F[\n", XYL_ERR_INVALID_GRAMMAR, 1, 9);
}

static void rejects_lines_that_are_not_productions(void **state)
{
    (void)state;
    tu_parse_fails("axiom: F\nF FF\n", XYL_ERR_INVALID_GRAMMAR, 2, 1);
    tu_parse_fails("axiom: F\nAB -> C\n", XYL_ERR_INVALID_GRAMMAR, 2, 1);
    tu_parse_fails("axiom: F\n -> C\n", XYL_ERR_INVALID_GRAMMAR, 2, 2);
    tu_parse_fails("axiom: F\nA -> B<C\n", XYL_ERR_INVALID_GRAMMAR, 2, 7);
    tu_parse_fails("axiom: F\n[ -> C\n", XYL_ERR_INVALID_GRAMMAR, 2, 1);
    tu_parse_fails("axiom: F\nA[B] < C -> D\n", XYL_ERR_INVALID_GRAMMAR, 2, 2);
    tu_parse_fails("axiom: F\nA < -> D\n", XYL_ERR_INVALID_GRAMMAR, 2, 0);
    tu_parse_fails("axiom: F\nA > -> D\n", XYL_ERR_INVALID_GRAMMAR, 2, 4);
}

static void rejects_bad_expressions(void **state)
{
    (void)state;
    tu_parse_fails("axiom: F\nA(x) -> B(y)\n", XYL_ERR_INVALID_GRAMMAR, 2, 11);
    tu_parse_fails("axiom: F\nA(x) -> B((x)\n", XYL_ERR_INVALID_GRAMMAR, 2, 10);
    tu_parse_fails("axiom: F\nA(x) -> B(min(x))\n", XYL_ERR_INVALID_GRAMMAR, 2, 0);
    tu_parse_fails("axiom: F\nA(x) -> B(x +)\n", XYL_ERR_INVALID_GRAMMAR, 2, 0);
    tu_parse_fails("axiom: F\nA(x) -> B(x @ 2)\n", XYL_ERR_INVALID_GRAMMAR, 2, 13);
    tu_parse_fails("axiom: F\nA(x) : x > -> B\n", XYL_ERR_INVALID_GRAMMAR, 2, 0);
    tu_parse_fails("axiom: F\nA(x,x) -> B\n", XYL_ERR_INVALID_GRAMMAR, 2, 5);
    tu_parse_fails("axiom: F\nA(x,) -> B\n", XYL_ERR_INVALID_GRAMMAR, 2, 5);
    tu_parse_fails("axiom: A(1e)\n", XYL_ERR_INVALID_GRAMMAR, 1, 12);
    tu_parse_fails("axiom: A(rand())\n", XYL_ERR_INVALID_GRAMMAR, 1, 0);
}

static void rejects_non_finite_constants(void **state)
{
    (void)state;
    tu_parse_fails("axiom: A(1e999)\n", XYL_ERR_NON_FINITE, 1, 10);
    tu_parse_fails("#define z 0\n#angle 1/z\naxiom: F\n", XYL_ERR_NON_FINITE, 2, 8);
    tu_parse_fails("#width 0\naxiom: F\n", XYL_ERR_INVALID_GRAMMAR, 1, 8);
    tu_parse_fails("#tropism 0 -1\naxiom: F\n", XYL_ERR_INVALID_GRAMMAR, 1, 0);
    tu_parse_fails("#depth -1\naxiom: F\n", XYL_ERR_INVALID_GRAMMAR, 1, 8);
    tu_parse_fails("#depth 99999999999\naxiom: F\n", XYL_ERR_LIMIT_EXCEEDED, 1, 8);
}

static void rejects_repeated_head_without_weights(void **state)
{
    (void)state;
    tu_parse_fails("axiom: F\nF -> G\nF  ->  H\n", XYL_ERR_INVALID_GRAMMAR, 3, 1);
    tu_parse_fails("axiom: F\nF -> (1) G\nF -> H\n", XYL_ERR_INVALID_GRAMMAR, 3, 1);
    /* same predecessor with different conditions is fine */
    xyl_grammar_destroy(tu_parse("axiom: F\nA(x) : x > 1 -> G\nA(x) : x <= 1 -> H\n"));
}

static void rejects_nul_bytes_and_null_arguments(void **state)
{
    (void)state;
    const char text[] = "axiom: F\nF -> F\0F\n";
    xyl_grammar_desc gd = {0};
    gd.source = text;
    gd.length = sizeof text - 1;
    xyl_grammar *g = NULL;
    xyl_diag d = {0};
    assert_int_equal(xyl_grammar_parse(&gd, &g, &d), XYL_ERR_INVALID_GRAMMAR);
    assert_int_equal(d.line, 2);
    assert_int_equal(d.column, 7);
    assert_null(g);
    assert_int_equal(xyl_grammar_parse(NULL, &g, &d), XYL_ERR_INVALID_ARGUMENT);
    gd.source = NULL;
    assert_int_equal(xyl_grammar_parse(&gd, &g, &d), XYL_ERR_INVALID_ARGUMENT);
    gd.source = "axiom: F";
    assert_int_equal(xyl_grammar_parse(&gd, NULL, &d), XYL_ERR_INVALID_ARGUMENT);
    xyl_grammar_destroy(NULL);
}

static void parse_limits_return_limit_exceeded(void **state)
{
    (void)state;
    xyl_grammar_desc gd = {0};
    xyl_grammar *g = NULL;
    xyl_diag d = {0};
    gd.source = "axiom: A(((((((((1)))))))))\n";
    gd.limits.max_expr_depth = 5;
    assert_int_equal(xyl_grammar_parse(&gd, &g, &d), XYL_ERR_LIMIT_EXCEEDED);
    assert_int_equal(d.line, 1);
    gd.source = "axiom: A(1,2,3,4)\n";
    gd.limits.max_expr_depth = 0;
    gd.limits.max_params = 3;
    assert_int_equal(xyl_grammar_parse(&gd, &g, &d), XYL_ERR_LIMIT_EXCEEDED);
    assert_int_equal(d.column, 16);
    gd.limits.max_params = 0;
    gd.limits.max_source_bytes = 8;
    assert_int_equal(xyl_grammar_parse(&gd, &g, &d), XYL_ERR_LIMIT_EXCEEDED);
    gd.limits.max_source_bytes = 0;
    gd.limits.max_params = 1000;
    assert_int_equal(xyl_grammar_parse(&gd, &g, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_null(g);
    /* a 10 000-deep expression is refused by the default limit, not by the C stack */
    size_t n = 10000;
    char *deep = malloc(2 * n + 32);
    assert_non_null(deep);
    strcpy(deep, "axiom: A(");
    size_t at = strlen(deep);
    for (size_t i = 0; i < n; ++i) deep[at++] = '-';
    deep[at++] = '1';
    deep[at++] = ')';
    deep[at] = '\0';
    gd.source = deep;
    gd.limits.max_params = 0;
    assert_int_equal(xyl_grammar_parse(&gd, &g, &d), XYL_ERR_LIMIT_EXCEEDED);
    free(deep);
}

static void every_preset_parses(void **state)
{
    (void)state;
    assert_true(xyl_lsystem_preset_count() >= 8);
    assert_non_null(xyl_lsystem_preset_source(xyl_lsystem_default_preset()));
    assert_null(xyl_lsystem_preset_source("no-such-preset"));
    assert_null(xyl_lsystem_preset_name(xyl_lsystem_preset_count()));
    for (size_t i = 0; i < xyl_lsystem_preset_count(); ++i) {
        const char *name = xyl_lsystem_preset_name(i);
        assert_non_null(xyl_lsystem_preset_summary(i));
        xyl_grammar_destroy(tu_parse(xyl_lsystem_preset_source(name)));
    }
}

/* A leafy tree next to its bare grammar in tests/data/grammars: the leaves must add nothing but
 * leaves, so both grow the same nodes bit for bit under every turtle mode, and every leaf hangs
 * from a tip (only the youngest twigs keep their fans). */
typedef struct leafy_preset {
    const char *name;
    const char *bare; /* file in tests/data/grammars */
    size_t min_leaves;
} leafy_preset;

static const leafy_preset leafy_presets[] = {
    {"abop-2.6-monopodial", "abop-2.6-monopodial-bare.lsys", 5000},
    {"abop-2.7-sympodial", "abop-2.7-sympodial-bare.lsys", 5000},
    {"abop-2.8-ternary", "abop-2.8-ternary-bare.lsys", 5000},
};

static char *read_grammar_file(const char *file)
{
    char path[512];
    snprintf(path, sizeof path, "%s/grammars/%s", XYL_TEST_DATA, file);
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("cannot open %s", path);
    char *text = calloc(1, 1 << 16);
    assert_non_null(text);
    size_t n = fread(text, 1, (1 << 16) - 1, f);
    assert_true(feof(f) && n > 0);
    fclose(f);
    return text;
}

static void assert_leaves_on_tips(const xyl_skeleton *sk, size_t min_leaves)
{
    assert_true(sk->leaf_count >= min_leaves);
    bool *has_child = calloc(sk->node_count, sizeof *has_child);
    assert_non_null(has_child);
    for (size_t i = 0; i < sk->node_count; ++i)
        if (sk->nodes[i].parent >= 0) has_child[sk->nodes[i].parent] = true;
    for (size_t i = 0; i < sk->leaf_count; ++i) {
        const xyl_skel_leaf *l = &sk->leaves[i];
        assert_true(isfinite(l->size) && l->size > 0.0f);
        assert_true(l->node >= 0 && (size_t)l->node < sk->node_count);
        assert_false(has_child[l->node]);
    }
    free(has_child);
}

static void leafy_presets_grow_the_bare_trees_nodes_and_leaves_on_their_tips(void **state)
{
    (void)state;
    xyl_turtle_desc modes[4] = {{0}, {0}, {0}, {0}};
    modes[1].merge_collinear = true;
    modes[2].radius_mode = XYL_RADIUS_GRAMMAR;
    modes[3].angle_mode = XYL_ANGLES_MURRAY;
    modes[3].radius_exponent = 3.0;
    for (size_t i = 0; i < sizeof leafy_presets / sizeof leafy_presets[0]; ++i) {
        const leafy_preset *p = &leafy_presets[i];
        char *bare = read_grammar_file(p->bare);
        for (size_t m = 0; m < sizeof modes / sizeof modes[0]; ++m) {
            xyl_skeleton *a = tu_grow(xyl_lsystem_preset_source(p->name), &modes[m]);
            xyl_skeleton *b = tu_grow(bare, &modes[m]);
            assert_int_equal(b->leaf_count, 0);
            assert_int_equal(a->node_count, b->node_count);
            assert_memory_equal(a->nodes, b->nodes, a->node_count * sizeof *a->nodes);
            assert_int_equal(a->branch_count, b->branch_count);
            assert_int_equal(a->clamped_forks, b->clamped_forks);
            assert_leaves_on_tips(a, p->min_leaves);
            xyl_skeleton_destroy(a);
            xyl_skeleton_destroy(b);
        }
        free(bare);
    }
}

/* xylem presets shows the leaf counts; the summaries say it too, for every preset with leaves. */
static void presets_with_leaves_say_so_in_their_summary(void **state)
{
    (void)state;
    size_t leafy = 0;
    for (size_t i = 0; i < xyl_lsystem_preset_count(); ++i) {
        xyl_skeleton *sk = tu_grow(xyl_lsystem_preset_source(xyl_lsystem_preset_name(i)), NULL);
        const char *summary = xyl_lsystem_preset_summary(i);
        bool says = strstr(summary, "leaves") || strstr(summary, "leafy");
        if (says != (sk->leaf_count > 0))
            fail_msg("%s: %zu leaves, summary '%s'", xyl_lsystem_preset_name(i), sk->leaf_count,
                     summary);
        if (sk->leaf_count > 0) ++leafy;
        xyl_skeleton_destroy(sk);
    }
    assert_true(leafy >= 2 + sizeof leafy_presets / sizeof leafy_presets[0]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(expressions_follow_precedence_and_associativity),
        cmocka_unit_test(functions_take_and_return_degrees),
        cmocka_unit_test(numbers_are_correctly_rounded),
        cmocka_unit_test(defines_are_constants_usable_in_later_lines),
        cmocka_unit_test(header_values_reach_grammar_info),
        cmocka_unit_test(labels_stars_comments_and_rolls_parse),
        cmocka_unit_test(rejects_unknown_directive),
        cmocka_unit_test(rejects_missing_and_second_axiom),
        cmocka_unit_test(rejects_unbalanced_brackets_with_their_column),
        cmocka_unit_test(rejects_lines_that_are_not_productions),
        cmocka_unit_test(rejects_bad_expressions),
        cmocka_unit_test(rejects_non_finite_constants),
        cmocka_unit_test(rejects_repeated_head_without_weights),
        cmocka_unit_test(rejects_nul_bytes_and_null_arguments),
        cmocka_unit_test(parse_limits_return_limit_exceeded),
        cmocka_unit_test(every_preset_parses),
        cmocka_unit_test(leafy_presets_grow_the_bare_trees_nodes_and_leaves_on_their_tips),
        cmocka_unit_test(presets_with_leaves_say_so_in_their_summary),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

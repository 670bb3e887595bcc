/* Derivation: known lengths, ABOP context rules, parametric and stochastic rewriting, the cut
 * symbol, determinism, and every bound. */
#include <locale.h>
#include <math.h>

#include "test_util.h"

#define derive tu_derive

static size_t count_symbol(const xyl_lstring *s, char c)
{
    size_t n = 0;
    for (size_t i = 0; i < xyl_lstring_count(s); ++i) {
        xyl_module_view m;
        assert_int_equal(xyl_lstring_module(s, i, &m), XYL_OK);
        n += m.symbol == c;
    }
    return n;
}

static void algae_lengths_are_fibonacci_numbers(void **state)
{
    (void)state;
    /* length at depth n is Fib(n + 2), Fib(1) = Fib(2) = 1 */
    uint64_t fib_prev = 1, fib = 1;
    for (uint32_t n = 0; n <= 30; ++n) {
        xyl_lstring *s = derive("axiom: A\nA -> AB\nB -> A\n", n, 1, XYL_OK, NULL);
        assert_int_equal(xyl_lstring_count(s), fib);
        xyl_lstring_destroy(s);
        uint64_t t = fib + fib_prev;
        fib_prev = fib;
        fib = t;
    }
    tu_assert_derives("axiom: A\nA -> AB\nB -> A\n", 5, "ABAABABAABAAB");
}

static void koch_curve_counts_follow_the_recurrence(void **state)
{
    (void)state;
    /* ABOP 1.9b quadratic Koch: F -> F+F-F-F+F. F(n) = 5^n, signs(n) = signs(n-1) + 4 F(n-1). */
    uint64_t f = 1, signs = 0;
    for (uint32_t n = 0; n <= 8; ++n) {
        xyl_lstring *s = derive("#angle 90\naxiom: F\nF -> F+F-F-F+F\n", n, 1, XYL_OK, NULL);
        assert_int_equal(count_symbol(s, 'F'), f);
        assert_int_equal(xyl_lstring_count(s), f + signs);
        xyl_lstring_destroy(s);
        signs += 4 * f;
        f *= 5;
    }
}

static void acropetal_signal_moves_one_module_per_step(void **state)
{
    (void)state;
    const char *g = "axiom: baaaaaaa\nb < a -> b\nb -> a\n";
    tu_assert_derives(g, 1, "abaaaaaa");
    tu_assert_derives(g, 3, "aaabaaaa");
    tu_assert_derives(g, 7, "aaaaaaab");
    tu_assert_derives(g, 8, "aaaaaaaa");
}

static void basipetal_signal_moves_back(void **state)
{
    (void)state;
    const char *g = "axiom: aaaab\na > b -> b\nb -> a\n";
    tu_assert_derives(g, 1, "aaaba");
    tu_assert_derives(g, 4, "baaaa");
}

static void left_context_skips_branches_and_climbs_out_of_them(void **state)
{
    (void)state;
    /* The a inside [a] sees b through '['; the a after ] sees b by skipping [a]. */
    const char *g = "axiom: b[a]a[a]a\nb < a -> b\nb -> a\n";
    tu_assert_derives(g, 1, "a[b]b[a]a");
    tu_assert_derives(g, 2, "a[a]a[b]b");
}

static void ignored_symbols_are_transparent_to_context(void **state)
{
    (void)state;
    tu_assert_derives("#ignore + -\naxiom: b+-a\nb < a -> c\n", 1, "b+-c");
    tu_assert_derives("axiom: b+-a\nb < a -> c\n", 1, "b+-a");
}

static void right_context_skips_or_enters_branches(void **state)
{
    (void)state;
    tu_assert_derives("axiom: a[x]b\na > b -> Y\n", 1, "Y[x]b");
    tu_assert_derives("axiom: a[x]b\na > [x]b -> Y\n", 1, "Y[x]b");
    tu_assert_derives("axiom: a[x]b\na > [b] -> Y\n", 1, "a[x]b");
    /* ']' in a pattern skips the rest of the current branch, whatever it holds */
    tu_assert_derives("axiom: a[xq]b\nx > ] -> Z\n", 1, "a[Zq]b");
    tu_assert_derives("axiom: a[xq]b\nx > ]b -> Z\n", 1, "a[Zq]b");
    tu_assert_derives("axiom: a[xq]c\nx > ]b -> Z\n", 1, "a[xq]c");
    tu_assert_derives("axiom: ax\nx > ] -> Z\n", 1, "ax");
    tu_assert_derives("axiom: a[x]b\nx > ] -> Z\n", 1, "a[Z]b");
    tu_assert_derives("axiom: a[x[q]]b\nx > ] -> Z\n", 1, "a[Z[q]]b");
}

static void context_binds_parameters_of_neighbours(void **state)
{
    (void)state;
    tu_assert_derives("axiom: A(1)B(2)C(3)\nA(a) < B(b) > C(c) -> B(a+b*10+c*100)\n", 1,
                      "A(1)B(321)C(3)");
}

static void parametric_condition_stops_growth(void **state)
{
    (void)state;
    const char *g = "axiom: A(0)\nA(x) : x < 3 -> A(x+1)B(x)\n";
    tu_assert_derives(g, 5, "A(3)B(2)B(1)B(0)");
}

static void first_matching_production_in_file_order_wins(void **state)
{
    (void)state;
    tu_assert_derives("axiom: A(5)\nA(x) : x > 1 -> B\nA(x) : x > 2 -> C\n", 1, "B");
    tu_assert_derives("axiom: A(1)\nA(x) : x > 1 -> B\nA(x) -> C\n", 1, "C");
    tu_assert_derives("axiom: A(1)A\nA -> B\n", 1, "A(1)B"); /* arity must match */
}

static void equal_seeds_give_identical_strings_and_different_seeds_differ(void **state)
{
    (void)state;
    const char *g = "axiom: F\nF -> (1) F[+F]F\nF -> (1) F[-F]F\nF -> (1) FF\n";
    char *a = tu_derive_text(g, 6, 42);
    char *b = tu_derive_text(g, 6, 42);
    char *c = tu_derive_text(g, 6, 43);
    assert_string_equal(a, b);
    assert_true(strcmp(a, c) != 0);
    free(a);
    free(b);
    free(c);
    /* rand() in parameters follows the seed too */
    char *r1 = tu_derive_text("axiom: A(0)\nA(x) -> A(rand())\n", 1, 7);
    char *r2 = tu_derive_text("axiom: A(0)\nA(x) -> A(rand())\n", 1, 7);
    assert_string_equal(r1, r2);
    free(r1);
    free(r2);
}

static void stochastic_choice_follows_the_weights(void **state)
{
    (void)state;
    /* 200 000 independent choices with weights 1:3 */
    char text[128];
    snprintf(text, sizeof text, "axiom: S\nS -> %s\nA -> (1) x\nA -> (3) y\n", "AAAAAAAAAA");
    xyl_grammar *g = tu_parse(text);
    xyl_derive_desc dd = {0};
    dd.has_depth = true;
    dd.depth = 1;
    size_t x = 0, total = 0;
    for (uint64_t seed = 1; seed <= 20000; ++seed) {
        dd.has_seed = true;
        dd.seed = seed;
        xyl_lstring *s = NULL;
        assert_int_equal(xyl_lsystem_derive(g, &dd, &s, NULL), XYL_OK);
        /* depth 1 only rewrote S; derive one more step to choose */
        xyl_lstring_destroy(s);
        dd.depth = 2;
        assert_int_equal(xyl_lsystem_derive(g, &dd, &s, NULL), XYL_OK);
        dd.depth = 1;
        x += count_symbol(s, 'x');
        total += xyl_lstring_count(s);
        xyl_lstring_destroy(s);
    }
    double frac = (double)x / (double)total;
    assert_int_equal(total, 200000);
    assert_true(fabs(frac - 0.25) < 0.005); /* 5 sigma is 0.0048 */
    xyl_grammar_destroy(g);
}

static void zero_weights_leave_the_module_unchanged(void **state)
{
    (void)state;
    tu_assert_derives("axiom: A(0)\nA(x) -> (x) B\nA(x) -> (x) C\n", 3, "A(0)");
}

static void cut_erases_the_rest_of_the_branch(void **state)
{
    (void)state;
    tu_assert_derives("axiom: A\nA -> B[C%D[E]F]G%H\n", 1, "B[C]G");
    tu_assert_derives("axiom: A[B%C]D\n", 0, "A[B]D");
    tu_assert_derives("axiom: A[B]C\nB -> %\n", 1, "A[]C");
}

static void non_finite_parameters_are_reported_with_their_line(void **state)
{
    (void)state;
    xyl_diag d = {0};
    xyl_lstring *s = derive("axiom: A(1)\n\nA(x) -> A(x-1)B(log(x-1))\n", 3, 1, XYL_ERR_NON_FINITE, &d);
    assert_null(s);
    assert_int_equal(d.line, 3);
    s = derive("axiom: A(1)\nA(x) -> A(x*1e200)\n", 5, 1, XYL_ERR_NON_FINITE, &d);
    assert_int_equal(d.line, 2);
    s = derive("axiom: A(1)\nA(x) -> (0/0) B\nA(x) -> (1) C\n", 1, 1, XYL_ERR_NON_FINITE, &d);
    s = derive("axiom: A(1)\nA(x) -> (-1) B\nA(x) -> (1) C\n", 1, 1, XYL_ERR_INVALID_GRAMMAR, &d);
    assert_int_equal(d.line, 2);
}

static void limits_stop_derivation_with_limit_exceeded(void **state)
{
    (void)state;
    xyl_grammar *g = tu_parse("axiom: F\nF -> F[F]F\n");
    xyl_derive_desc dd = {0};
    xyl_lstring *s = (xyl_lstring *)(uintptr_t)1;
    xyl_diag d = {0};
    dd.has_depth = true;
    dd.depth = 65;
    assert_int_equal(xyl_lsystem_derive(g, &dd, &s, &d), XYL_ERR_LIMIT_EXCEEDED);
    dd.depth = 8;
    dd.limits.max_modules = 1000;
    assert_int_equal(xyl_lsystem_derive(g, &dd, &s, &d), XYL_ERR_LIMIT_EXCEEDED);
    assert_non_null(strstr(d.message, "module count"));
    dd.limits.max_modules = 0;
    dd.limits.max_bytes = 4096;
    assert_int_equal(xyl_lsystem_derive(g, &dd, &s, &d), XYL_ERR_LIMIT_EXCEEDED);
    assert_non_null(strstr(d.message, "byte"));
    assert_ptr_equal(s, (xyl_lstring *)(uintptr_t)1);
    xyl_grammar_destroy(g);

    g = tu_parse("axiom: A\nA -> [A]\n");
    dd.limits.max_bytes = 0;
    dd.depth = 20;
    dd.limits.max_nesting = 10;
    assert_int_equal(xyl_lsystem_derive(g, &dd, &s, &d), XYL_ERR_LIMIT_EXCEEDED);
    assert_non_null(strstr(d.message, "nesting"));
    dd.limits.max_nesting = 0;
    assert_int_equal(xyl_lsystem_derive(g, &dd, &s, &d), XYL_OK);
    assert_int_equal(xyl_lstring_count(s), 41);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    assert_int_equal(xyl_lsystem_derive(NULL, &dd, &s, &d), XYL_ERR_INVALID_ARGUMENT);
}

static void string_accessors_check_their_arguments(void **state)
{
    (void)state;
    xyl_lstring *s = derive("axiom: A(1.5,2)[B]\n", 0, 1, XYL_OK, NULL);
    xyl_module_view m;
    assert_int_equal(xyl_lstring_module(s, 0, &m), XYL_OK);
    assert_int_equal(m.symbol, 'A');
    assert_int_equal(m.param_count, 2);
    assert_true(m.params[0] == 1.5 && m.params[1] == 2.0);
    assert_int_equal(xyl_lstring_module(s, 4, &m), XYL_ERR_INVALID_ARGUMENT);
    size_t need = 0;
    assert_int_equal(xyl_lstring_format(s, NULL, 0, &need), XYL_OK);
    assert_int_equal(need, strlen("A(1.5,2)[B]"));
    char small[4];
    assert_int_equal(xyl_lstring_format(s, small, sizeof small, &need), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_lstring_count(NULL), 0);
    xyl_lstring_destroy(s);
    xyl_lstring_destroy(NULL);
}

/* A host that calls setlocale (most GUI toolkits do) must still get '.' between digits: a
 * decimal comma would read as a parameter separator. */
static void format_ignores_the_locale_decimal_point(void **state)
{
    (void)state;
    const char *names[] = {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "ru_RU.UTF-8"};
    const char *found = NULL;
    for (size_t i = 0; i < sizeof names / sizeof names[0] && !found; ++i)
        if (setlocale(LC_NUMERIC, names[i])) found = names[i];
    if (!found) skip(); /* no locale with a decimal comma installed */
    xyl_lstring *s = derive("axiom: A(1.5,2,-0.25)B(1e-7,123456.789)\n", 0, 1, XYL_OK, NULL);
    char text[64];
    size_t need = 0;
    xyl_result r = xyl_lstring_format(s, text, sizeof text, &need);
    setlocale(LC_NUMERIC, "C");
    assert_int_equal(r, XYL_OK);
    assert_string_equal(text, "A(1.5,2,-0.25)B(1e-07,123456.789)");
    assert_int_equal(need, strlen(text));
    xyl_lstring_destroy(s);
}

static void derivation_uses_the_grammar_depth_and_seed_by_default(void **state)
{
    (void)state;
    xyl_grammar *g = tu_parse("#depth 3\naxiom: A\nA -> AA\n");
    xyl_lstring *s = NULL;
    assert_int_equal(xyl_lsystem_derive(g, NULL, &s, NULL), XYL_OK);
    assert_int_equal(xyl_lstring_count(s), 8);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
}

static void every_preset_derives_deterministically(void **state)
{
    (void)state;
    for (size_t i = 0; i < xyl_lsystem_preset_count(); ++i) {
        const char *src = xyl_lsystem_preset_source(xyl_lsystem_preset_name(i));
        xyl_grammar *g = tu_parse(src);
        xyl_lstring *a = NULL, *b = NULL;
        assert_int_equal(xyl_lsystem_derive(g, NULL, &a, NULL), XYL_OK);
        assert_int_equal(xyl_lsystem_derive(g, NULL, &b, NULL), XYL_OK);
        assert_true(xyl_lstring_count(a) > 10);
        assert_int_equal(xyl_lstring_count(a), xyl_lstring_count(b));
        for (size_t k = 0; k < xyl_lstring_count(a); ++k) {
            xyl_module_view ma, mb;
            xyl_lstring_module(a, k, &ma);
            xyl_lstring_module(b, k, &mb);
            assert_int_equal(ma.symbol, mb.symbol);
            assert_int_equal(ma.param_count, mb.param_count);
            if (ma.param_count)
                assert_memory_equal(ma.params, mb.params, ma.param_count * sizeof(double));
        }
        xyl_lstring_destroy(a);
        xyl_lstring_destroy(b);
        xyl_grammar_destroy(g);
    }
}

static void context_sensitive_preset_fires_its_signal(void **state)
{
    (void)state;
    xyl_grammar *g = tu_parse(xyl_lsystem_preset_source("abop-1.31a"));
    xyl_lstring *s = NULL;
    assert_int_equal(xyl_lsystem_derive(g, NULL, &s, NULL), XYL_OK);
    assert_true(count_symbol(s, '[') > 5); /* branches appear only where a signal arrived */
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
}

/* Counts every allocation to prove all of them go through the hooks and are freed. */
typedef struct counter {
    long live, total;
} counter;
static void *count_alloc(size_t n, void *u)
{
    counter *c = u;
    ++c->live;
    ++c->total;
    return malloc(n);
}
static void count_free(void *p, void *u)
{
    --((counter *)u)->live;
    free(p);
}

static void custom_allocator_sees_every_allocation(void **state)
{
    (void)state;
    counter c = {0, 0};
    xyl_allocator a = {count_alloc, count_free, &c};
    xyl_grammar_desc gd = {0};
    gd.source = xyl_lsystem_preset_source("abop-2.6-monopodial");
    gd.alloc = a;
    xyl_grammar *g = NULL;
    assert_int_equal(xyl_grammar_parse(&gd, &g, NULL), XYL_OK);
    xyl_derive_desc dd = {0};
    dd.alloc = a;
    xyl_lstring *s = NULL;
    assert_int_equal(xyl_lsystem_derive(g, &dd, &s, NULL), XYL_OK);
    assert_true(c.total > 3);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    assert_int_equal(c.live, 0);
    /* a failing parse frees everything too */
    gd.source = "axiom: F\nF -> G(\n";
    assert_int_equal(xyl_grammar_parse(&gd, &g, NULL), XYL_ERR_INVALID_GRAMMAR);
    assert_int_equal(c.live, 0);
}

/* Non-parametric constant grammars take the byte path; an unused parametric production forces
 * the same grammar through the general path. Both must give the same strings. */
static void byte_path_and_general_path_agree(void **state)
{
    (void)state;
    static const char *grammars[] = {
        "axiom: F\nF -> F[+F]F[-F]F\n",
        "axiom: X\nX -> F-[[X]+X]+F[+FX]-X\nF -> FF\n",
        "axiom: A\nA -> B[C%D[E]F]G%A\nB -> [B]\n",
        "axiom: A[B%C]D\nA -> AB\nB -> \n",
        "axiom: F\nF -> F+F-F-F+F\n+ -> -\n",
        "axiom: AAAAAAAAAAAAAAAAAAAA\nA -> ABCDEFGHIJKLMNOPQRSTUVWXYZ\n",
    };
    for (size_t i = 0; i < sizeof grammars / sizeof grammars[0]; ++i) {
        char general[512];
        snprintf(general, sizeof general, "%sZ(x) -> Z(x+1)\n", grammars[i]);
        for (uint32_t depth = 0; depth <= 4; ++depth) {
            char *a = tu_derive_text(grammars[i], depth, 1);
            char *b = tu_derive_text(general, depth, 1);
            if (strcmp(a, b) != 0) fail_msg("grammar %zu depth %u:\n  %s\n  %s", i, depth, a, b);
            free(a);
            free(b);
        }
    }
}

static void byte_path_refuses_oversized_steps_before_rewriting(void **state)
{
    (void)state;
    xyl_grammar *g = tu_parse("axiom: F\nF -> FFFFFFFFFF\n");
    xyl_derive_desc dd = {0};
    dd.has_depth = true;
    dd.depth = 12; /* 10^12 modules: refused from the predicted size, nothing is allocated */
    xyl_lstring *s = NULL;
    xyl_diag d = {0};
    assert_int_equal(xyl_lsystem_derive(g, &dd, &s, &d), XYL_ERR_LIMIT_EXCEEDED);
    assert_non_null(strstr(d.message, "step 9 exceeds the module count"));
    assert_null(s);
    xyl_grammar_destroy(g);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(algae_lengths_are_fibonacci_numbers),
        cmocka_unit_test(koch_curve_counts_follow_the_recurrence),
        cmocka_unit_test(acropetal_signal_moves_one_module_per_step),
        cmocka_unit_test(basipetal_signal_moves_back),
        cmocka_unit_test(left_context_skips_branches_and_climbs_out_of_them),
        cmocka_unit_test(ignored_symbols_are_transparent_to_context),
        cmocka_unit_test(right_context_skips_or_enters_branches),
        cmocka_unit_test(context_binds_parameters_of_neighbours),
        cmocka_unit_test(parametric_condition_stops_growth),
        cmocka_unit_test(first_matching_production_in_file_order_wins),
        cmocka_unit_test(equal_seeds_give_identical_strings_and_different_seeds_differ),
        cmocka_unit_test(stochastic_choice_follows_the_weights),
        cmocka_unit_test(zero_weights_leave_the_module_unchanged),
        cmocka_unit_test(cut_erases_the_rest_of_the_branch),
        cmocka_unit_test(non_finite_parameters_are_reported_with_their_line),
        cmocka_unit_test(limits_stop_derivation_with_limit_exceeded),
        cmocka_unit_test(string_accessors_check_their_arguments),
        cmocka_unit_test(derivation_uses_the_grammar_depth_and_seed_by_default),
        cmocka_unit_test(every_preset_derives_deterministically),
        cmocka_unit_test(context_sensitive_preset_fires_its_signal),
        cmocka_unit_test(custom_allocator_sees_every_allocation),
        cmocka_unit_test(byte_path_and_general_path_agree),
        cmocka_unit_test(byte_path_refuses_oversized_steps_before_rewriting),
        cmocka_unit_test(format_ignores_the_locale_decimal_point),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* The turtle (xyl_lsystem_interpret): symbols, frames, radius rules, Murray angles, merging,
 * leaves, tropism, limits and errors. Module strings are built by a tiny test-only reader so
 * the suite does not depend on the grammar parser. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "skeleton_internal.h"
#include "turtle_internal.h"

#define DEG (XYL__PI / 180.0)
#define BUSHY "F(2)[+(35)F(1.5)[-(20)F[&(30)F]F]F(1.2)[^(25)F]F]F(1)[&(40)F(0.9)[/(60)+F]F]" \
              "F(0.5)[-(50)F[+F][-F]F]F"

/* ---- test-only module strings and grammars ------------------------------------------------- */

/* "F(1)[+(90)F]": one character per module, optional comma-separated parameters read with
 * strtod (so "nan" and "inf" work); spaces are skipped. */
static xyl_lstring *lstring_new(const char *text)
{
    size_t n = strlen(text);
    xyl_lstring *s = calloc(1, sizeof *s);
    assert_non_null(s);
    s->sym = calloc(n + 1, 1);
    s->np = calloc(n + 1, 1);
    s->poff = calloc(n + 1, sizeof *s->poff);
    s->params = calloc(n + 1, sizeof *s->params);
    assert_true(s->sym && s->np && s->poff && s->params);
    const char *p = text;
    while (*p) {
        if (*p == ' ') {
            ++p;
            continue;
        }
        size_t m = s->count++;
        s->sym[m] = (uint8_t)*p++;
        s->poff[m] = (uint32_t)s->nparams;
        if (*p != '(') continue;
        do {
            char *end;
            s->params[s->nparams++] = strtod(p + 1, &end);
            s->np[m]++;
            p = end;
        } while (*p == ',');
        assert_int_equal(*p, ')');
        ++p;
    }
    s->cap = n + 1;
    s->pcap = n + 1;
    return s;
}

static void lstring_free(xyl_lstring *s)
{
    free(s->sym);
    free(s->np);
    free(s->poff);
    free(s->params);
    free(s);
}

/* Zero except the header values the turtle reads. */
static struct xyl_grammar *grammar_new(double angle_deg)
{
    struct xyl_grammar *g = calloc(1, sizeof *g);
    assert_non_null(g);
    g->info.depth = 4;
    g->info.seed = 1;
    g->info.angle = angle_deg * DEG;
    g->info.step = 1.0;
    g->info.width = 0.1;
    g->limits.max_nesting = 64;
    return g;
}

static void set_tropism(struct xyl_grammar *g, double x, double y, double z, double e)
{
    g->info.tropism[0] = x;
    g->info.tropism[1] = y;
    g->info.tropism[2] = z;
    g->info.elasticity = e;
    g->has_tropism = true;
}

#define SENTINEL ((xyl_skeleton *)(uintptr_t)0x5eed)

/* Runs the turtle; on failure checks that *out was left alone. */
static xyl_result run(const struct xyl_grammar *g, const char *text, const xyl_turtle_desc *d,
                      xyl_skeleton **out, xyl_diag *diag)
{
    xyl_lstring *s = lstring_new(text);
    *out = SENTINEL;
    xyl_result r = xyl_lsystem_interpret(g, s, d, out, diag);
    lstring_free(s);
    if (r != XYL_OK) assert_ptr_equal(*out, SENTINEL);
    if (diag) assert_int_equal(diag->code, r);
    return r;
}

static xyl_skeleton *run_ok(const struct xyl_grammar *g, const char *text,
                            const xyl_turtle_desc *d, xyl_diag *diag)
{
    xyl_diag local = {0};
    xyl_skeleton *sk = NULL;
    xyl_result r = run(g, text, d, &sk, diag ? diag : &local);
    if (r != XYL_OK) fail_msg("'%s': %s", text, (diag ? diag : &local)->message);
    /* what the turtle hands to xyl__skeleton_adopt must pass the public checks */
    xyl_skeleton_desc check = {sk->nodes, sk->node_count, sk->leaves, sk->leaf_count, {0}, {0},
                               {sk->origin[0], sk->origin[1], sk->origin[2]}};
    assert_int_equal(xyl__skeleton_validate(&check, &local), XYL_OK);
    return sk;
}

static xyl_result run_code(const struct xyl_grammar *g, const char *text,
                           const xyl_turtle_desc *d, xyl_diag *diag)
{
    xyl_skeleton *sk = NULL;
    xyl_result r = run(g, text, d, &sk, diag);
    if (r == XYL_OK) xyl_skeleton_destroy(sk);
    return r;
}

/* ---- geometry helpers ---------------------------------------------------------------------- */

static xyl__dvec3 node_pos(const xyl_skeleton *sk, size_t i)
{
    return xyl__from_f3(sk->nodes[i].pos);
}

static xyl__dvec3 seg_vec(const xyl_skeleton *sk, size_t i)
{
    return xyl__d3_sub(node_pos(sk, i), node_pos(sk, (size_t)sk->nodes[i].parent));
}

static xyl__dvec3 unit(xyl__dvec3 v)
{
    return xyl__d3_scale(v, 1.0 / xyl__d3_len(v));
}

/* Direction of the segment entering node i; the initial heading for a root. */
static xyl__dvec3 in_dir(const xyl_skeleton *sk, size_t i)
{
    return sk->nodes[i].parent < 0 ? xyl__d3(0, 1, 0) : unit(seg_vec(sk, i));
}

static double angle_between(xyl__dvec3 a, xyl__dvec3 b)
{
    double c = xyl__d3_dot(unit(a), unit(b));
    return acos(c > 1.0 ? 1.0 : c < -1.0 ? -1.0 : c);
}

static void assert_near(double got, double want, double tol)
{
    if (!(fabs(got - want) <= tol)) fail_msg("got %.12g, want %.12g (tol %g)", got, want, tol);
}

static void assert_vec_near(xyl__dvec3 got, xyl__dvec3 want, double tol)
{
    assert_near(got.x, want.x, tol);
    assert_near(got.y, want.y, tol);
    assert_near(got.z, want.z, tol);
}

static size_t child_count(const xyl_skeleton *sk, size_t f, size_t *kids, size_t cap)
{
    size_t k = 0;
    for (size_t i = f + 1; i < sk->node_count; ++i)
        if (sk->nodes[i].parent == (int32_t)f && k < cap) kids[k++] = i;
    return k;
}

static double frame_error_f(xyl_vec3 h, xyl_vec3 l, xyl_vec3 u)
{
    xyl__frame f = {xyl__from_f3(h), xyl__from_f3(l), xyl__from_f3(u)};
    xyl__dvec3 hxl = xyl__d3_cross(f.h, f.l);
    double e = xyl__frame_error(&f);
    double handed = xyl__d3_len(xyl__d3_sub(hxl, f.u));
    return e > handed ? e : handed;
}

/* ---- frame and symbols --------------------------------------------------------------------- */

static void interpret_closes_a_square_with_right_angle_turns(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(90.0);
    xyl_skeleton *sk = run_ok(g, "F+F+F+F", NULL, NULL);
    assert_int_equal(sk->node_count, 5);
    assert_vec_near(node_pos(sk, 1), xyl__d3(0, 1, 0), 1e-7);
    assert_vec_near(node_pos(sk, 2), xyl__d3(-1, 1, 0), 1e-7); /* '+' turns towards L = -x */
    assert_vec_near(node_pos(sk, 4), xyl__d3(0, 0, 0), 1e-6);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void check_tip(const struct xyl_grammar *g, const char *text, xyl__dvec3 want)
{
    xyl_skeleton *sk = run_ok(g, text, NULL, NULL);
    assert_true(sk->node_count >= 2);
    assert_vec_near(node_pos(sk, sk->node_count - 1), want, 1e-6);
    xyl_skeleton_destroy(sk);
}

static void interpret_turn_symbols_follow_abop(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(30.0);
    check_tip(g, "+(90)F", xyl__d3(-1, 0, 0));         /* turn left, towards L */
    check_tip(g, "-(90)F", xyl__d3(1, 0, 0));
    check_tip(g, "&(90)F", xyl__d3(0, 0, -1));         /* pitch down, away from U */
    check_tip(g, "^(90)F", xyl__d3(0, 0, 1));
    check_tip(g, "\\(90)+(90)F", xyl__d3(0, 0, 1));    /* roll left: L becomes U */
    check_tip(g, "/(90)+(90)F", xyl__d3(0, 0, -1));
    check_tip(g, "|F", xyl__d3(0, -1, 0));
    check_tip(g, "+F", xyl__d3(-sin(30 * DEG), cos(30 * DEG), 0)); /* #angle, radians */
    check_tip(g, "+(90,7,8)F(2,5)", xyl__d3(-2, 0, 0));          /* first parameter only */
    check_tip(g, "A(1)B+(90)CF", xyl__d3(-1, 0, 0));             /* other symbols ignored */
    free(g);
}

static const xyl_skel_leaf *only_leaf(const xyl_skeleton *sk)
{
    assert_int_equal(sk->leaf_count, 1);
    return &sk->leaves[0];
}

static void interpret_dollar_rolls_left_vector_horizontal(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(30.0);
    xyl_skeleton *a = run_ok(g, "&(30)\\(40)$L", NULL, NULL);
    xyl_skeleton *b = run_ok(g, "&(30)\\(40)L", NULL, NULL);
    const xyl_skel_leaf *la = only_leaf(a), *lb = only_leaf(b);
    assert_near(la->left.y, 0.0, 1e-7);
    assert_true(fabs(lb->left.y) > 0.1); /* the roll really tilted it */
    assert_vec_near(xyl__from_f3(la->heading), xyl__from_f3(lb->heading), 1e-7);
    assert_true(frame_error_f(la->heading, la->left, la->up) < 1e-6);
    assert_true(la->up.y > 0.0f); /* up stays on the upper side */
    xyl_skeleton_destroy(a);
    xyl_skeleton_destroy(b);
    /* vertical heading: no horizontal direction is defined, the frame is kept */
    a = run_ok(g, "\\(40)$L", NULL, NULL);
    b = run_ok(g, "\\(40)L", NULL, NULL);
    assert_vec_near(xyl__from_f3(only_leaf(a)->left), xyl__from_f3(only_leaf(b)->left), 1e-7);
    xyl_skeleton_destroy(a);
    xyl_skeleton_destroy(b);
    free(g);
}

static uint64_t splitmix64(uint64_t *s)
{
    uint64_t z = (*s += UINT64_C(0x9E3779B97F4A7C15));
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

static void frame_stays_orthonormal_after_a_million_random_turns(void **state)
{
    (void)state;
    static const char symbols[] = "+-&^\\/";
    xyl__frame f = {xyl__d3(0, 1, 0), xyl__d3(-1, 0, 0), xyl__d3(0, 0, 1)};
    uint64_t seed = 42;
    double worst = 0.0;
    for (int i = 0; i < 1000000; ++i) {
        uint64_t r = splitmix64(&seed);
        double angle = ((double)(r >> 11) * 0x1p-53 - 0.5) * 2.0 * XYL__PI;
        assert_true(xyl__lsys_turtle_rotate(&f, symbols[r % 6], angle));
        double e = xyl__frame_error(&f);
        if (e > worst) worst = e;
    }
    double handed = xyl__d3_len(xyl__d3_sub(xyl__d3_cross(f.h, f.l), f.u));
    print_message("worst frame error over 10^6 turns: %.3g\n", worst);
    assert_true(worst < 1e-9);
    assert_true(handed < 1e-9);
    assert_false(xyl__lsys_turtle_rotate(&f, 'F', 1.0));
}

/* ---- radii --------------------------------------------------------------------------------- */

static void check_pipe_rule(const xyl_skeleton *sk, double n, double tip)
{
    double *sum = calloc(sk->node_count, sizeof *sum);
    size_t *kids = calloc(sk->node_count, sizeof *kids);
    assert_true(sum && kids);
    for (size_t i = 0; i < sk->node_count; ++i)
        if (sk->nodes[i].parent >= 0) {
            sum[sk->nodes[i].parent] += pow(sk->nodes[i].radius, n);
            kids[sk->nodes[i].parent]++;
        }
    size_t forks = 0;
    for (size_t i = 0; i < sk->node_count; ++i) {
        double r = sk->nodes[i].radius;
        if (kids[i] == 0) assert_near(r, tip, tip * 1e-6);
        if (kids[i] == 0) continue;
        forks += kids[i] >= 2;
        assert_true(fabs(pow(r, n) - sum[i]) <= 1e-5 * pow(r, n));
    }
    assert_true(forks >= 5);
    free(sum);
    free(kids);
}

static void pipe_rule_holds_at_every_fork(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    const double exponents[] = {2.0, 2.5, 3.0};
    for (int i = 0; i < 3; ++i) {
        xyl_turtle_desc d = {0};
        d.radius_exponent = exponents[i];
        d.tip_radius = i == 1 ? 0.02 : 0.0; /* 0: #width / 2 */
        xyl_skeleton *sk = run_ok(g, BUSHY, &d, NULL);
        check_pipe_rule(sk, exponents[i], i == 1 ? 0.02 : 0.05);
        xyl_skeleton_destroy(sk);
    }
    /* a one-child node has exactly its child's radius */
    xyl_skeleton *sk = run_ok(g, "FF[+F]F", NULL, NULL);
    assert_true(sk->nodes[0].radius == sk->nodes[1].radius);
    assert_near(sk->nodes[1].radius, 0.05 * sqrt(2.0), 1e-7);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void grammar_width_mode_uses_half_the_width(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_turtle_desc d = {0};
    d.radius_mode = XYL_RADIUS_GRAMMAR;
    xyl_skeleton *sk = run_ok(g, "!(0.4)F!(0.2)[+F!(0.06)]F", &d, NULL);
    const float want[] = {0.2f, 0.2f, 0.1f, 0.1f};
    assert_int_equal(sk->node_count, 4);
    for (int i = 0; i < 4; ++i) assert_near(sk->nodes[i].radius, want[i], 1e-7);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "!(0.4)F!F", &d, NULL); /* '!' without a parameter keeps the width */
    assert_near(sk->nodes[2].radius, 0.2, 1e-7);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "F", &d, NULL); /* #width */
    assert_near(sk->nodes[1].radius, 0.05, 1e-7);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void grammar_width_mode_rejects_nonpositive_width(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_turtle_desc d = {0};
    d.radius_mode = XYL_RADIUS_GRAMMAR;
    xyl_diag diag = {0};
    assert_int_equal(run_code(g, "F!(0)F", &d, &diag), XYL_ERR_INVALID_GRAMMAR);
    assert_int_equal(diag.index, 2);
    assert_int_equal(run_code(g, "!(-1)F", &d, &diag), XYL_ERR_INVALID_GRAMMAR);
    assert_int_equal(run_code(g, "!(1e300)F", &d, &diag), XYL_ERR_NON_FINITE);
    d.radius_mode = XYL_RADIUS_PIPE; /* widths do not matter to the pipe rule */
    assert_int_equal(run_code(g, "F!(0)F", &d, &diag), XYL_OK);
    free(g);
}

/* ---- Murray angles ------------------------------------------------------------------------- */

static xyl_turtle_desc murray_desc(double n)
{
    xyl_turtle_desc d = {0};
    d.angle_mode = XYL_ANGLES_MURRAY;
    d.radius_exponent = n;
    return d;
}

/* theta_i as the library must compute it, from the output radii. */
static double expected_angle(const xyl_skeleton *sk, size_t f, const size_t *kids, size_t k,
                             size_t i, double n, double lo, double hi)
{
    double w0 = pow(sk->nodes[f].radius, 2.0), wi = pow(sk->nodes[kids[i]].radius, 2.0);
    double rest = 0.0;
    for (size_t j = 0; j < k; ++j)
        if (j != i) rest += pow(sk->nodes[kids[j]].radius, n);
    double wr = pow(rest, 2.0 / n);
    double c = (w0 * w0 + wi * wi - wr * wr) / (2.0 * w0 * wi);
    double theta = acos(c > 1.0 ? 1.0 : c < -1.0 ? -1.0 : c);
    return theta < lo ? lo : theta > hi ? hi : theta;
}

static void check_fork_angles(const xyl_skeleton *sk, size_t f, double n)
{
    size_t kids[16];
    size_t k = child_count(sk, f, kids, 16);
    for (size_t i = 0; i < k; ++i) {
        double want = expected_angle(sk, f, kids, k, i, n, 10 * DEG, 90 * DEG);
        assert_near(angle_between(in_dir(sk, f), seg_vec(sk, kids[i])), want, 1e-5);
    }
}

/* |w0 d0 - sum wi di| relative to w0. */
static double balance_error(const xyl_skeleton *sk, size_t f)
{
    size_t kids[16];
    size_t k = child_count(sk, f, kids, 16);
    double w0 = pow(sk->nodes[f].radius, 2.0);
    xyl__dvec3 net = xyl__d3_scale(in_dir(sk, f), w0);
    for (size_t i = 0; i < k; ++i) {
        double wi = pow(sk->nodes[kids[i]].radius, 2.0);
        net = xyl__d3_sub(net, xyl__d3_scale(unit(seg_vec(sk, kids[i])), wi));
    }
    return xyl__d3_len(net) / w0;
}

static void murray_two_children_balance_forces_for_n3(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_turtle_desc d = murray_desc(3.0);
    xyl_diag diag = {0};
    xyl_skeleton *sk = run_ok(g, "F(1)[+(30)F(1)[-(20)F(1)]F(1)]-(15)F(1)", &d, &diag);
    assert_int_equal(sk->node_count, 6);
    assert_int_equal(sk->nodes[5].parent, 1);
    const size_t forks[] = {1, 2};
    for (int i = 0; i < 2; ++i) {
        check_fork_angles(sk, forks[i], 3.0);
        assert_true(balance_error(sk, forks[i]) < 1e-5);
    }
    for (size_t i = 0; i < sk->node_count; ++i) assert_near(sk->nodes[i].pos.z, 0.0, 1e-6);
    assert_int_equal(sk->clamped_forks, 0);
    assert_int_equal(diag.warning_count, 0);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void murray_area_rule_clamps_to_min_angle_and_warns(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_turtle_desc d = murray_desc(2.0);
    xyl_diag diag = {0};
    xyl_skeleton *sk = run_ok(g, "F[+F]F", &d, &diag);
    assert_near(angle_between(in_dir(sk, 1), seg_vec(sk, 2)), 10 * DEG, 1e-5);
    assert_near(angle_between(in_dir(sk, 1), seg_vec(sk, 3)), 10 * DEG, 1e-5);
    assert_true(sk->nodes[2].pos.x < 0.0f && sk->nodes[3].pos.x > 0.0f); /* opposite sides */
    assert_int_equal(sk->clamped_forks, 1);
    assert_int_equal(diag.warning_count, 1);
    assert_non_null(strstr(diag.warning, "clamped at 1 of 1 forks"));
    xyl_skeleton_destroy(sk);
    /* a custom minimum */
    d.murray_min_angle = 20 * DEG;
    sk = run_ok(g, "F[+F]F", &d, NULL);
    assert_near(angle_between(in_dir(sk, 1), seg_vec(sk, 2)), 20 * DEG, 1e-5);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void murray_thin_parent_clamps_to_max_angle(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_turtle_desc d = murray_desc(3.0);
    d.radius_mode = XYL_RADIUS_GRAMMAR;
    xyl_diag diag = {0};
    /* w0 = 0.01 <= |0.25 - 0.01|: no triangle of forces exists */
    xyl_skeleton *sk = run_ok(g, "!(0.2)F[!(1)+(30)F]-(30)F", &d, &diag);
    assert_near(angle_between(in_dir(sk, 1), seg_vec(sk, 2)), 10 * DEG, 1e-5); /* thick */
    assert_near(angle_between(in_dir(sk, 1), seg_vec(sk, 3)), 90 * DEG, 1e-5); /* thin */
    assert_int_equal(sk->clamped_forks, 1);
    assert_int_equal(diag.warning_count, 1);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void check_parallel_fork(const char *text, size_t fork)
{
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_turtle_desc d = murray_desc(3.0);
    xyl_skeleton *sk = run_ok(g, text, &d, NULL);
    size_t kids[4];
    assert_int_equal(child_count(sk, fork, kids, 4), 2);
    double want = acos(pow(2.0, 2.0 / 3.0) / 2.0); /* equal children, n = 3: 37.47 deg */
    xyl__dvec3 d0 = in_dir(sk, fork);
    xyl__dvec3 a = unit(seg_vec(sk, kids[0])), b = unit(seg_vec(sk, kids[1]));
    assert_near(angle_between(d0, a), want, 1e-5);
    assert_near(angle_between(d0, b), want, 1e-5);
    xyl__dvec3 pa = xyl__d3_sub(a, xyl__d3_scale(d0, xyl__d3_dot(a, d0)));
    xyl__dvec3 pb = xyl__d3_sub(b, xyl__d3_scale(d0, xyl__d3_dot(b, d0)));
    assert_near(angle_between(pa, pb), XYL__PI, 1e-5);
    assert_true(balance_error(sk, fork) < 1e-5);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void murray_splits_children_parallel_to_a_vertical_stem(void **state)
{
    (void)state;
    check_parallel_fork("F[F]F", 1);
    check_parallel_fork("[F]F", 0); /* a fork at the root: d0 is the initial heading */
}

static void murray_spreads_eight_children_at_one_node(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_turtle_desc d = murray_desc(3.0);
    const char *text = "F[+(40)F][-(40)F][&(40)F][^(40)F][+(20)&(20)F][-(20)^(20)F][F]F";
    xyl_skeleton *sk = run_ok(g, text, &d, NULL);
    size_t kids[16];
    assert_int_equal(child_count(sk, 1, kids, 16), 8);
    check_fork_angles(sk, 1, 3.0);
    for (size_t i = 0; i < 8; ++i) {
        assert_near(xyl__d3_len(seg_vec(sk, kids[i])), 1.0, 1e-5);
        for (size_t j = 0; j < i; ++j)
            assert_true(angle_between(seg_vec(sk, kids[i]), seg_vec(sk, kids[j])) > 1e-3);
    }
    xyl_skeleton_destroy(sk);
    /* eight children all drawn along the stem still spread around it */
    sk = run_ok(g, "F[F][F][F][F][F][F][F]F", &d, NULL);
    assert_int_equal(child_count(sk, 1, kids, 16), 8);
    check_fork_angles(sk, 1, 3.0);
    for (size_t i = 0; i < 8; ++i)
        for (size_t j = 0; j < i; ++j)
            assert_true(angle_between(seg_vec(sk, kids[i]), seg_vec(sk, kids[j])) > 1e-3);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void murray_rotation_keeps_lengths_and_leaves_attached(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    const char *text = "F(2)[+F(1.5)L(0.3)[-F(0.7)L]F(1.2)L]F(1)[&F(0.9)L(0.2)]F(0.5)\\(30)L"
                       "[^F(0.4)L]F(0.3)L";
    xyl_turtle_desc plain = {0};
    plain.radius_exponent = 2.5;
    xyl_turtle_desc d = murray_desc(2.5);
    xyl_skeleton *a = run_ok(g, text, &plain, NULL);
    xyl_skeleton *b = run_ok(g, text, &d, NULL);
    assert_int_equal(a->node_count, b->node_count);
    assert_int_equal(a->leaf_count, b->leaf_count);
    assert_true(a->leaf_count >= 6);
    bool moved = false;
    for (size_t i = 0; i < a->node_count; ++i) {
        assert_int_equal(a->nodes[i].parent, b->nodes[i].parent);
        if (a->nodes[i].parent < 0) continue;
        double la = xyl__d3_len(seg_vec(a, i)), lb = xyl__d3_len(seg_vec(b, i));
        assert_true(fabs(la - lb) <= 1e-5 * la);
        moved |= xyl__d3_len(xyl__d3_sub(node_pos(a, i), node_pos(b, i))) > 1e-3;
    }
    assert_true(moved);
    for (size_t i = 0; i < b->leaf_count; ++i) {
        const xyl_skel_leaf *la = &a->leaves[i], *lb = &b->leaves[i];
        assert_int_equal(la->node, lb->node);
        assert_true(la->size == lb->size);
        assert_vec_near(xyl__from_f3(lb->pos), node_pos(b, (size_t)lb->node), 1e-5);
        assert_true(frame_error_f(lb->heading, lb->left, lb->up) < 1e-5);
        /* rigid: the leaf keeps its angle to the segment it hangs from */
        double ca = xyl__d3_dot(xyl__from_f3(la->heading), in_dir(a, (size_t)la->node));
        double cb = xyl__d3_dot(xyl__from_f3(lb->heading), in_dir(b, (size_t)lb->node));
        assert_near(ca, cb, 1e-5);
    }
    xyl_skeleton_destroy(a);
    xyl_skeleton_destroy(b);
    free(g);
}

/* ---- merging ------------------------------------------------------------------------------- */

static xyl_turtle_desc merge_desc(void)
{
    xyl_turtle_desc d = {0};
    d.merge_collinear = true;
    return d;
}

static void merge_collinear_joins_straight_runs(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_turtle_desc d = merge_desc();
    xyl_skeleton *sk = run_ok(g, "FFF", &d, NULL);
    assert_int_equal(sk->node_count, 2);
    assert_vec_near(node_pos(sk, 1), xyl__d3(0, 3, 0), 1e-6);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "FFF", NULL, NULL);
    assert_int_equal(sk->node_count, 4);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void merge_collinear_keeps_branch_points(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_turtle_desc d = merge_desc();
    xyl_skeleton *sk = run_ok(g, "F[F]F", &d, NULL);
    assert_int_equal(sk->node_count, 4);
    assert_vec_near(node_pos(sk, 1), xyl__d3(0, 1, 0), 1e-6);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "FF[+F]FF", &d, NULL);
    assert_int_equal(sk->node_count, 4);
    assert_vec_near(node_pos(sk, 1), xyl__d3(0, 2, 0), 1e-6);
    assert_vec_near(node_pos(sk, 3), xyl__d3(0, 4, 0), 1e-6);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "FF[]F", &d, NULL); /* saved on the stack: pinned even with no branch */
    assert_int_equal(sk->node_count, 3);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void merge_collinear_stops_at_turns_widths_and_leaves(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_turtle_desc d = merge_desc();
    const char *texts[] = {"F+(10)F", "F!(0.05)F", "FLF", "F\\(30)F"};
    const size_t want[] = {3, 3, 3, 2}; /* a roll keeps the direction: merged */
    for (int i = 0; i < 4; ++i) {
        xyl_skeleton *sk = run_ok(g, texts[i], &d, NULL);
        assert_int_equal(sk->node_count, want[i]);
        xyl_skeleton_destroy(sk);
    }
    free(g);
}

/* ---- leaves, tropism, moves ---------------------------------------------------------------- */

static void leaves_carry_position_frame_and_size(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_skeleton *sk = run_ok(g, "F(2)+(90)L(0.25)", NULL, NULL);
    const xyl_skel_leaf *l = only_leaf(sk);
    assert_vec_near(xyl__from_f3(l->pos), xyl__d3(0, 2, 0), 1e-7);
    assert_vec_near(xyl__from_f3(l->heading), xyl__d3(-1, 0, 0), 1e-7);
    assert_vec_near(xyl__from_f3(l->left), xyl__d3(0, -1, 0), 1e-7);
    assert_vec_near(xyl__from_f3(l->up), xyl__d3(0, 0, 1), 1e-7);
    assert_near(l->size, 0.25, 1e-7);
    assert_int_equal(l->node, 1);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "LF(3)L", NULL, NULL); /* default size #step / 2; before any node: -1 */
    assert_int_equal(sk->leaf_count, 2);
    assert_int_equal(sk->leaves[0].node, -1);
    assert_near(sk->leaves[1].size, 0.5, 1e-7);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "FL(0)L(-1)", NULL, NULL); /* no leaf for a size <= 0 */
    assert_int_equal(sk->leaf_count, 0);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void tropism_bends_a_horizontal_branch_toward_the_vector(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    set_tropism(g, 0, -1, 0, 0.25);
    xyl_skeleton *sk = run_ok(g, "+(90)FFFF", NULL, NULL);
    assert_vec_near(node_pos(sk, 1), xyl__d3(-1, 0, 0), 1e-7); /* bends after each F */
    /* alpha = e |H x T| = 0.25 for a horizontal heading */
    assert_near(angle_between(seg_vec(sk, 2), xyl__d3(-1, 0, 0)), 0.25, 1e-6);
    for (size_t i = 2; i < sk->node_count; ++i) {
        assert_true(seg_vec(sk, i).y < seg_vec(sk, i - 1).y - 1e-3);
        assert_near(sk->nodes[i].pos.z, 0.0, 1e-6);
    }
    xyl_skeleton_destroy(sk);
    g->info.elasticity = 0.0;
    sk = run_ok(g, "+(90)FFFF", NULL, NULL);
    assert_near(sk->nodes[4].pos.y, 0.0, 1e-7);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void elasticity_module_sets_and_resets(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    set_tropism(g, 0, -1, 0, 0.0);
    xyl_skeleton *sk = run_ok(g, "+(90)[T(0.3)FF]FF", NULL, NULL);
    assert_true(sk->nodes[2].pos.y < -0.1f); /* the branch bent */
    assert_near(sk->nodes[4].pos.y, 0.0, 1e-7); /* ']' restored elasticity 0 */
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "+(90)T(0.3)TFF", NULL, NULL); /* 'T' alone: back to #tropism's e */
    assert_near(sk->nodes[2].pos.y, 0.0, 1e-7);
    xyl_skeleton_destroy(sk);
    set_tropism(g, 0, 0, 0, 0.3); /* no vector: nothing bends */
    sk = run_ok(g, "+(90)FF", NULL, NULL);
    assert_near(sk->nodes[2].pos.y, 0.0, 1e-7);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void move_starts_a_new_root(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_skeleton *sk = run_ok(g, "Ff(2)FL", NULL, NULL);
    assert_int_equal(sk->node_count, 4);
    assert_int_equal(sk->root_count, 2);
    assert_int_equal(sk->nodes[2].parent, -1);
    assert_vec_near(node_pos(sk, 2), xyl__d3(0, 3, 0), 1e-7);
    assert_int_equal(sk->leaves[0].node, 3);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "Ff[L]", NULL, NULL);
    assert_int_equal(sk->leaves[0].node, -1);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "[+F][-F]", NULL, NULL); /* branches saved at one place share a root */
    assert_int_equal(sk->root_count, 1);
    assert_int_equal(sk->node_count, 3);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "[f+F][-F]", NULL, NULL);
    assert_int_equal(sk->root_count, 2);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void zero_and_negative_lengths(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_skeleton *sk = run_ok(g, "F(0)", NULL, NULL);
    assert_int_equal(sk->node_count, 0);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "FF(0)f(0)F", NULL, NULL);
    assert_int_equal(sk->node_count, 3);
    assert_int_equal(sk->root_count, 1);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "F(-1)", NULL, NULL); /* draws backwards */
    assert_vec_near(node_pos(sk, 1), xyl__d3(0, -1, 0), 1e-7);
    xyl_skeleton_destroy(sk);
    xyl_turtle_desc d = merge_desc(); /* F(1)F(-1) reverses: no merge */
    sk = run_ok(g, "F(1)F(-1)F(-1)", &d, NULL);
    assert_int_equal(sk->node_count, 3);
    assert_vec_near(node_pos(sk, 2), xyl__d3(0, -1, 0), 1e-7);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void percent_cuts_the_rest_of_the_branch(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_skeleton *sk = run_ok(g, "F[+F%F[F]F]F", NULL, NULL);
    assert_int_equal(sk->node_count, 4);
    assert_int_equal(sk->nodes[3].parent, 1);
    xyl_skeleton_destroy(sk);
    sk = run_ok(g, "F%F[F]F", NULL, NULL);
    assert_int_equal(sk->node_count, 2);
    xyl_skeleton_destroy(sk);
    free(g);
}

static void interpret_handles_empty_string_and_null_desc(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_diag diag = {0};
    diag.index = 7;
    xyl_skeleton *sk = run_ok(g, "", NULL, &diag);
    assert_int_equal(sk->node_count, 0);
    assert_int_equal(sk->leaf_count, 0);
    assert_int_equal(diag.index, -1);
    xyl_skeleton_destroy(sk);
    free(g);
}

/* ---- errors -------------------------------------------------------------------------------- */

static void interpret_rejects_unbalanced_close_bracket(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_diag diag = {0};
    assert_int_equal(run_code(g, "F]F", NULL, &diag), XYL_ERR_INVALID_GRAMMAR);
    assert_int_equal(diag.index, 1);
    assert_int_equal(run_code(g, "[F]]", NULL, &diag), XYL_ERR_INVALID_GRAMMAR);
    assert_int_equal(diag.index, 3);
    free(g);
}

static void interpret_rejects_unclosed_open_bracket(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_diag diag = {0};
    assert_int_equal(run_code(g, "F[F[F]", NULL, &diag), XYL_ERR_INVALID_GRAMMAR);
    assert_int_equal(diag.index, 1);
    free(g);
}

static void interpret_rejects_nesting_beyond_limit(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    g->limits.max_nesting = 3;
    xyl_diag diag = {0};
    assert_int_equal(run_code(g, "[[[F]]]", NULL, &diag), XYL_OK);
    assert_int_equal(run_code(g, "[[[[F]]]]", NULL, &diag), XYL_ERR_LIMIT_EXCEEDED);
    assert_int_equal(diag.index, 3);
    g->limits.max_nesting = 0; /* default 4096 */
    char text[2 * 4097 + 1];
    for (size_t depth = 4096; depth <= 4097; ++depth) {
        memset(text, '[', depth);
        memset(text + depth, ']', depth);
        text[2 * depth] = '\0';
        xyl_result want = depth == 4096 ? XYL_OK : XYL_ERR_LIMIT_EXCEEDED;
        assert_int_equal(run_code(g, text, NULL, &diag), want);
    }
    free(g);
}

static void interpret_rejects_non_finite_numbers(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_diag diag = {0};
    const char *texts[] = {"F(nan)", "F+(inf)F", "FF!(nan)", "L(-nan)", "FT(inf)",
                           "F(1e38)F(1e38)F(1e38)F(1e38)", "f(1e300)", "F(2,nan)"};
    const xyl_result want[] = {XYL_ERR_NON_FINITE, XYL_ERR_NON_FINITE, XYL_ERR_NON_FINITE,
                               XYL_ERR_NON_FINITE, XYL_ERR_NON_FINITE, XYL_ERR_NON_FINITE,
                               XYL_ERR_NON_FINITE, XYL_OK}; /* unused parameters are not read */
    const int64_t index[] = {0, 1, 2, 0, 1, 3, 0, -1};
    for (int i = 0; i < 8; ++i) {
        assert_int_equal(run_code(g, texts[i], NULL, &diag), want[i]);
        assert_int_equal(diag.index, index[i]);
    }
    xyl_turtle_desc d = {0};
    d.tip_radius = 3e38; /* pipe radii grow past the float range */
    assert_int_equal(run_code(g, "F[F][F]F", &d, &diag), XYL_ERR_NON_FINITE);
    assert_int_equal(diag.index, 0);
    g->info.step = NAN;
    assert_int_equal(run_code(g, "F", NULL, &diag), XYL_ERR_NON_FINITE);
    free(g);
}

static void expect_bad_option(const struct xyl_grammar *g, xyl_turtle_desc d)
{
    xyl_diag diag = {0};
    assert_int_equal(run_code(g, "F[+F]F", &d, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_true(strlen(diag.message) > 0);
}

static void interpret_rejects_bad_options(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    const double exponents[] = {0.5, 0.3, -2.0, 8.01, NAN, INFINITY};
    for (int i = 0; i < 6; ++i) {
        xyl_turtle_desc d = {0};
        d.radius_exponent = exponents[i];
        expect_bad_option(g, d);
    }
    xyl_turtle_desc d = {0};
    d.radius_exponent = 8.0; /* the top of the range is fine */
    assert_int_equal(run_code(g, "F[+F]F", &d, NULL), XYL_OK);
    d = (xyl_turtle_desc){0};
    d.tip_radius = -0.1;
    expect_bad_option(g, d);
    d.tip_radius = NAN;
    expect_bad_option(g, d);
    d.tip_radius = 1e-60; /* zero as a float */
    expect_bad_option(g, d);
    d = (xyl_turtle_desc){0};
    d.murray_min_angle = NAN;
    expect_bad_option(g, d);
    d.murray_min_angle = 100 * DEG; /* above the default maximum */
    expect_bad_option(g, d);
    d = (xyl_turtle_desc){0};
    d.murray_max_angle = 4.0; /* > pi */
    expect_bad_option(g, d);
    d = (xyl_turtle_desc){0};
    d.radius_mode = (xyl_radius_mode)7;
    expect_bad_option(g, d);
    d = (xyl_turtle_desc){0};
    d.angle_mode = (xyl_angle_mode)-1;
    expect_bad_option(g, d);
    xyl_lstring *s = lstring_new("F");
    xyl_skeleton *sk = SENTINEL;
    assert_int_equal(xyl_lsystem_interpret(NULL, s, NULL, &sk, NULL), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_lsystem_interpret(g, NULL, NULL, &sk, NULL), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_lsystem_interpret(g, s, NULL, NULL, NULL), XYL_ERR_INVALID_ARGUMENT);
    assert_ptr_equal(sk, SENTINEL);
    lstring_free(s);
    free(g);
}

static void interpret_enforces_node_and_leaf_limits(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    xyl_turtle_desc d = {0};
    xyl_diag diag = {0};
    d.limits.max_nodes = 3;
    assert_int_equal(run_code(g, "FF", &d, &diag), XYL_OK);
    assert_int_equal(run_code(g, "FFF", &d, &diag), XYL_ERR_LIMIT_EXCEEDED);
    assert_int_equal(diag.index, 2);
    d.merge_collinear = true; /* merged nodes do not count */
    assert_int_equal(run_code(g, "FFFFF", &d, &diag), XYL_OK);
    d = (xyl_turtle_desc){0};
    d.limits.max_leaves = 1;
    assert_int_equal(run_code(g, "FL", &d, &diag), XYL_OK);
    assert_int_equal(run_code(g, "FLL", &d, &diag), XYL_ERR_LIMIT_EXCEEDED);
    assert_int_equal(diag.index, 2);
    free(g);
}

/* ---- allocation and determinism ------------------------------------------------------------ */

typedef struct counting {
    long live, calls, fail_at;
} counting;

static void *counting_alloc(size_t size, void *user)
{
    counting *c = user;
    if (c->calls++ == c->fail_at) return NULL;
    c->live++;
    return malloc(size);
}

static void counting_free(void *p, void *user)
{
    ((counting *)user)->live--;
    free(p);
}

static void interpret_frees_everything_when_allocation_fails(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(25.0);
    set_tropism(g, 0, -1, 0, 0.1);
    xyl_lstring *s = lstring_new(BUSHY "L[L]");
    for (long n = 0;; ++n) {
        counting c = {0, 0, n};
        xyl_turtle_desc d = murray_desc(3.0);
        d.alloc = (xyl_allocator){counting_alloc, counting_free, &c};
        xyl_skeleton *sk = SENTINEL;
        xyl_result r = xyl_lsystem_interpret(g, s, &d, &sk, NULL);
        if (r == XYL_OK) {
            assert_true(c.live > 0);
            xyl_skeleton_destroy(sk);
            assert_int_equal(c.live, 0);
            assert_true(n > 3);
            break;
        }
        assert_int_equal(r, XYL_ERR_OUT_OF_MEMORY);
        assert_ptr_equal(sk, SENTINEL);
        assert_int_equal(c.live, 0);
    }
    lstring_free(s);
    free(g);
}

static void interpret_is_deterministic(void **state)
{
    (void)state;
    struct xyl_grammar *g = grammar_new(22.5);
    set_tropism(g, 0.2, -1, 0.1, 0.15);
    xyl_turtle_desc d = murray_desc(2.4);
    xyl_skeleton *a = run_ok(g, BUSHY "L" BUSHY, &d, NULL);
    xyl_skeleton *b = run_ok(g, BUSHY "L" BUSHY, &d, NULL);
    assert_int_equal(a->node_count, b->node_count);
    assert_int_equal(a->leaf_count, b->leaf_count);
    assert_memory_equal(a->nodes, b->nodes, a->node_count * sizeof *a->nodes);
    assert_memory_equal(a->leaves, b->leaves, a->leaf_count * sizeof *a->leaves);
    assert_int_equal(a->clamped_forks, b->clamped_forks);
    xyl_skeleton_destroy(a);
    xyl_skeleton_destroy(b);
    free(g);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(interpret_closes_a_square_with_right_angle_turns),
        cmocka_unit_test(interpret_turn_symbols_follow_abop),
        cmocka_unit_test(interpret_dollar_rolls_left_vector_horizontal),
        cmocka_unit_test(frame_stays_orthonormal_after_a_million_random_turns),
        cmocka_unit_test(pipe_rule_holds_at_every_fork),
        cmocka_unit_test(grammar_width_mode_uses_half_the_width),
        cmocka_unit_test(grammar_width_mode_rejects_nonpositive_width),
        cmocka_unit_test(murray_two_children_balance_forces_for_n3),
        cmocka_unit_test(murray_area_rule_clamps_to_min_angle_and_warns),
        cmocka_unit_test(murray_thin_parent_clamps_to_max_angle),
        cmocka_unit_test(murray_splits_children_parallel_to_a_vertical_stem),
        cmocka_unit_test(murray_spreads_eight_children_at_one_node),
        cmocka_unit_test(murray_rotation_keeps_lengths_and_leaves_attached),
        cmocka_unit_test(merge_collinear_joins_straight_runs),
        cmocka_unit_test(merge_collinear_keeps_branch_points),
        cmocka_unit_test(merge_collinear_stops_at_turns_widths_and_leaves),
        cmocka_unit_test(leaves_carry_position_frame_and_size),
        cmocka_unit_test(tropism_bends_a_horizontal_branch_toward_the_vector),
        cmocka_unit_test(elasticity_module_sets_and_resets),
        cmocka_unit_test(move_starts_a_new_root),
        cmocka_unit_test(zero_and_negative_lengths),
        cmocka_unit_test(percent_cuts_the_rest_of_the_branch),
        cmocka_unit_test(interpret_handles_empty_string_and_null_desc),
        cmocka_unit_test(interpret_rejects_unbalanced_close_bracket),
        cmocka_unit_test(interpret_rejects_unclosed_open_bracket),
        cmocka_unit_test(interpret_rejects_nesting_beyond_limit),
        cmocka_unit_test(interpret_rejects_non_finite_numbers),
        cmocka_unit_test(interpret_rejects_bad_options),
        cmocka_unit_test(interpret_enforces_node_and_leaf_limits),
        cmocka_unit_test(interpret_frees_everything_when_allocation_fails),
        cmocka_unit_test(interpret_is_deterministic),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

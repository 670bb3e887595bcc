/* lsystem: a grammar in, a branch skeleton out.
 * Parses a small stochastic grammar, derives it from a seed and lets the turtle grow the
 * skeleton with pipe-rule radii and Murray fork angles. Prints what grew. */
#include <stdio.h>

#include <xylem/xyl_lsystem.h>

static const char grammar[] =
    "#angle 25.7\n"
    "#depth 4\n"
    "#seed 7\n"
    "axiom: F\n"
    "F -> (1) F[+F]F[-F]F\n"
    "F -> (1) F[+F]F\n"
    "F -> (1) F[-F]F\n";

int main(void)
{
    xyl_diag diag = {0};
    xyl_grammar_desc gd = {0};
    gd.source = grammar;
    xyl_grammar *g = NULL;
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    xyl_turtle_desc td = {0};              /* zero: pipe rule, exponent 2 */
    td.angle_mode = XYL_ANGLES_MURRAY;     /* fork angles balance like forces */
    xyl_result r = xyl_grammar_parse(&gd, &g, &diag);
    if (!r) r = xyl_lsystem_derive(g, NULL, &s, &diag);   /* the grammar's #depth and #seed */
    if (!r) r = xyl_lsystem_interpret(g, s, &td, &sk, &diag);
    if (r) {
        fprintf(stderr, "%u:%u: %s: %s\n", diag.line, diag.column, xyl_result_string(r),
                diag.message);
        return 1;
    }
    printf("%zu modules -> %zu nodes, %u branches, max order %u, root radius %.4f\n",
           xyl_lstring_count(s), sk->node_count, sk->branch_count, sk->max_order,
           (double)sk->nodes[0].radius);
    int ok = sk->node_count > 1 && sk->branch_count > 1;
    xyl_skeleton_destroy(sk);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return ok ? 0 : 1;
}

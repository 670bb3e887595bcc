/* Grows the default tree through the installed headers and library only. */
#include <stdio.h>

#include <xylem/xyl_lsystem.h>

int main(void)
{
    xyl_grammar_desc gd = {0};
    gd.source = xyl_lsystem_preset_source(xyl_lsystem_default_preset());
    xyl_grammar *g = NULL;
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_grammar_parse(&gd, &g, &d);
    if (!r) r = xyl_lsystem_derive(g, NULL, &s, &d);
    if (!r) r = xyl_lsystem_interpret(g, s, NULL, &sk, &d);
    if (r || sk->node_count == 0) {
        fprintf(stderr, "consumer: %s: %s\n", xyl_result_string(r), d.message);
        return 1;
    }
    printf("consumer: default tree has %zu nodes and %u branches\n", sk->node_count,
           sk->branch_count);
    xyl_skeleton_destroy(sk);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return 0;
}

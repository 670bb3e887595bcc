/* libFuzzer target: arbitrary bytes as grammar text, then a bounded derivation and a turtle run.
 * Any result code is fine; crashes, leaks, sanitizer reports and broken invariants are not. */
#include <stdlib.h>
#include <string.h>

#include <xylem/xyl_lsystem.h>

int LLVMFuzzerTestOneInput(const unsigned char *data, size_t size);

int LLVMFuzzerTestOneInput(const unsigned char *data, size_t size)
{
    xyl_grammar_desc gd = {0};
    gd.source = (const char *)data;
    gd.length = size;
    if (size == 0) return 0;
    gd.limits.max_source_bytes = 1 << 16;
    xyl_grammar *g = NULL;
    xyl_diag d = {0};
    if (xyl_grammar_parse(&gd, &g, &d) != XYL_OK) {
        if (d.message[0] == '\0' || d.code == XYL_OK) abort();
        return 0;
    }
    xyl_derive_desc dd = {0};
    dd.limits.max_modules = 20000;
    dd.limits.max_depth = 12;
    xyl_grammar_info info;
    xyl_grammar_get_info(g, &info);
    dd.has_depth = true;
    dd.depth = info.depth > 12 ? 12 : info.depth;
    xyl_lstring *s = NULL;
    if (xyl_lsystem_derive(g, &dd, &s, &d) == XYL_OK) {
        if (xyl_lstring_count(s) > 20000) abort(); /* a limit must never be exceeded silently */
        size_t need = 0;
        if (xyl_lstring_format(s, NULL, 0, &need) != XYL_OK) abort();
        char *buf = malloc(need + 1);
        if (buf && xyl_lstring_format(s, buf, need + 1, &need) != XYL_OK) abort();
        free(buf);
        xyl_turtle_desc td = {0};
        td.limits.max_nodes = 50000;
        td.angle_mode = (size & 1) ? XYL_ANGLES_MURRAY : XYL_ANGLES_GRAMMAR;
        xyl_skeleton *sk = NULL;
        if (xyl_lsystem_interpret(g, s, &td, &sk, &d) == XYL_OK) xyl_skeleton_destroy(sk);
        xyl_lstring_destroy(s);
    }
    xyl_grammar_destroy(g);
    return 0;
}

/* bench_lsystem: derivation and turtle throughput of the lsystem module, and the same
 * non-parametric grammars through the npm package `lindenmayer` (samples/bench/) in the same run.
 *
 *   bench_lsystem [--quick] [--no-peer] [--repeats N] [--peer-script PATH] [--node PATH]
 *
 * Every figure is the median of N samples (CLOCK_MONOTONIC); a sample of a fast case runs it
 * several times back to back so that one sample lasts at least 5 ms (1 ms with --quick). Only the
 * call itself is timed: destroying its result is not. Single-threaded; pin it with taskset for
 * steadier figures. scripts/bench.sh installs the peer, builds in Release and runs this.
 *
 * Exit status: 0, also when a throughput target is missed or the peer is unavailable; 1 when
 * a grammar fails to parse or derive or the peer's string differs from ours; 2 on bad usage. */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <xylem/xyl_lsystem.h>

#include "bench_common.h"

#define MAX_BATCH 100000u
#define PEER_SCRIPT "samples/bench/lindenmayer_bench.mjs"
#define PEER_HINT "lindenmayer: not available (run scripts/bench.sh to install)"
#define TARGET_PEER_RATIO 10.0
#define TARGET_PARAM_RATE 1e7


/* ---- timing -------------------------------------------------------------------------------- */


/* A warm-up call picks the batch size; then the median of o->repeats samples. */
static xyl_result measure(const options *o, job_fn job, void *ctx, timing *out, xyl_diag *diag)
{
    double first = 0.0, v[MAX_SAMPLES];
    xyl_result r = job(ctx, &first, diag);
    if (r) return r;
    double want = ceil(o->min_sample_s / (first > 1e-9 ? first : 1e-9));
    unsigned batch = want < 1.0 ? 1u : want > MAX_BATCH ? MAX_BATCH : (unsigned)want;
    for (int i = 0; i < o->repeats; ++i)
        if ((r = run_batch(job, ctx, batch, &v[i], diag))) return r;
    out->samples = o->repeats;
    out->batch = batch;
    out->median_s = median_of(v, o->repeats);
    out->min_s = v[0];
    return XYL_OK;
}

/* ---- jobs: derivation and interpretation --------------------------------------------------- */

typedef struct derive_job {
    const xyl_grammar *g;
    uint32_t depth;
    size_t modules; /* of the last string derived */
} derive_job;

static xyl_result derive_once(void *ctx, double *seconds, xyl_diag *diag)
{
    derive_job *j = ctx;
    xyl_lstring *s = NULL;
    double t0 = now_s();
    xyl_result r = derive_at(j->g, j->depth, &s, diag);
    *seconds = now_s() - t0;
    if (r) return r;
    j->modules = xyl_lstring_count(s);
    xyl_lstring_destroy(s);
    return XYL_OK;
}

typedef struct turtle_job {
    const xyl_grammar *g;
    const xyl_lstring *s;
    size_t nodes;
} turtle_job;

static xyl_result interpret_once(void *ctx, double *seconds, xyl_diag *diag)
{
    turtle_job *j = ctx;
    xyl_skeleton *sk = NULL;
    double t0 = now_s();
    xyl_result r = xyl_lsystem_interpret(j->g, j->s, NULL, &sk, diag);
    *seconds = now_s() - t0;
    if (r) return r;
    j->nodes = sk->node_count;
    xyl_skeleton_destroy(sk);
    return XYL_OK;
}

/* Modules written over all steps 1..depth (untimed: one derivation per depth). */
static xyl_result modules_all_steps(const xyl_grammar *g, uint32_t depth, uint64_t *total,
                                    xyl_diag *diag)
{
    *total = 0;
    for (uint32_t k = 1; k <= depth; ++k) {
        xyl_lstring *s = NULL;
        xyl_result r = derive_at(g, k, &s, diag);
        if (r) return r;
        *total += xyl_lstring_count(s);
        xyl_lstring_destroy(s);
    }
    return XYL_OK;
}

/* FNV-1a (32 bits) over the module symbols: the text of a non-parametric string. */
static uint32_t symbols_hash(const xyl_lstring *s)
{
    uint32_t h = 0x811c9dc5u;
    size_t n = xyl_lstring_count(s);
    for (size_t i = 0; i < n; ++i) {
        xyl_module_view m;
        if (xyl_lstring_module(s, i, &m)) break;
        h = (h ^ (uint8_t)m.symbol) * 0x01000193u;
    }
    return h;
}

static xyl_result parse(const char *source, xyl_grammar **g, xyl_diag *diag)
{
    xyl_grammar_desc gd = {0};
    gd.source = source;
    return xyl_grammar_parse(&gd, g, diag);
}

/* ---- 1. presets ---------------------------------------------------------------------------- */

static void print_derive_header(const char *first)
{
    printf("%-22s %5s %11s %11s %10s %9s %9s\n", first, "depth", "modules", "all steps",
           "median ms", "Mmod/s", "Mall/s");
}

static void print_derive_row(const char *name, uint32_t depth, size_t modules, uint64_t all,
                             const timing *t)
{
    printf("%-22s %5u %11zu %11llu %10.3f %9.1f %9.1f\n", name, depth, modules,
           (unsigned long long)all, t->median_s * 1e3, rate((double)modules, t->median_s) / 1e6,
           rate((double)all, t->median_s) / 1e6);
}

static void bench_turtle(const options *o, const char *name, const xyl_grammar *g,
                         const xyl_lstring *s)
{
    xyl_diag diag = {0};
    turtle_job j = {g, s, 0};
    timing t = {0};
    xyl_result r = measure(o, interpret_once, &j, &t, &diag);
    if (r) {
        printf("%-22s turtle: %s%s%s\n", name, xyl_result_string(r), diag.message[0] ? ": " : "",
               diag.message);
        return;
    }
    size_t n = xyl_lstring_count(s);
    printf("%-22s %11zu %11zu %10.3f %9.1f %9.1f\n", name, n, j.nodes, t.median_s * 1e3,
           rate((double)j.nodes, t.median_s) / 1e6, rate((double)n, t.median_s) / 1e6);
}

/* Derives every preset at its #depth; keeps the strings in *strings for the turtle. */
static int bench_presets(const options *o, xyl_grammar **grammars, xyl_lstring **strings)
{
    int failures = 0;
    printf("\n== derivation: built-in presets at their default depth ==\n");
    print_derive_header("preset");
    for (size_t i = 0; i < xyl_lsystem_preset_count(); ++i) {
        const char *name = xyl_lsystem_preset_name(i);
        xyl_diag diag = {0};
        xyl_grammar_info info;
        xyl_result r = parse(xyl_lsystem_preset_source(name), &grammars[i], &diag);
        if (!r) {
            xyl_grammar_get_info(grammars[i], &info);
            derive_job j = {grammars[i], info.depth, 0};
            timing t = {0};
            uint64_t all = 0;
            if (!(r = measure(o, derive_once, &j, &t, &diag)) &&
                !(r = modules_all_steps(grammars[i], info.depth, &all, &diag)) &&
                !(r = derive_at(grammars[i], info.depth, &strings[i], &diag)))
                print_derive_row(name, info.depth, j.modules, all, &t);
        }
        if (r) {
            report_error(name, r, &diag);
            ++failures;
        }
    }
    return failures;
}

static void bench_presets_turtle(const options *o, xyl_grammar **grammars, xyl_lstring **strings)
{
    printf("\n== turtle: xyl_lsystem_interpret on the preset strings (default options) ==\n");
    printf("%-22s %11s %11s %10s %9s %9s\n", "preset", "modules", "nodes", "median ms",
           "Mnodes/s", "Mmod/s");
    for (size_t i = 0; i < xyl_lsystem_preset_count(); ++i)
        if (strings[i]) bench_turtle(o, xyl_lsystem_preset_name(i), grammars[i], strings[i]);
}

/* ---- 2. large grammars --------------------------------------------------------------------- */

typedef struct big_case {
    const char *name;
    bool parametric;
    const char *source;
    uint32_t depth, quick_depth;
} big_case;

/* Sizes chosen so that the final string holds >= 10^7 modules (the --quick depths do not). */
static const big_case big_cases[] = {
    {"abop-1.24a F[+F]F[-F]F", false, "axiom: F\nF -> F[+F]F[-F]F\n", 10, 7},
    {"abop-1.24d X,F->FF", false, "axiom: X\nX -> F[+X]F[-X]+X\nF -> FF\n", 14, 9},
    /* Ternary tree: every module but the brackets and turns is rewritten with expressions and
     * a condition each step, so this is the parametric path's worst case, not its copy path. */
    {"ternary-expr", true,
     "#define r 0.8\n#define wr 0.7\n#define a 30\n#define d 120\n"
     "axiom: A(1,0.2)\n"
     "A(l,w) : l > 0.0001 -> !(w)F(l)[&(a)A(l*r,w*wr)]/(d)[&(a)A(l*r,w*wr)]/(d)A(l*r,w*wr)\n"
     "F(l) : * -> F(l*1.05)\n"
     "!(w) : * -> !(w*1.4)\n",
     14, 9},
    /* ABOP figure 2.7 as the book draws it, without the preset's leaf fans, so the figures in
     * docs/BENCHMARKS.md measure the same work whatever the preset grows. */
    {"abop-2.7-sympodial", true,
     "#define r1 0.9\n#define r2 0.7\n#define a1 10\n#define a2 60\n#define wr 0.707\n"
     "axiom: A(1,0.6)\n"
     "p1: A(l,w) : * -> !(w)F(l)[&(a1)B(l*r1,w*wr)]/(180)[&(a2)B(l*r2,w*wr)]\n"
     "p2: B(l,w) : * -> !(w)F(l)[+(a1)$B(l*r1,w*wr)][-(a2)$B(l*r2,w*wr)]\n",
     20, 12},
};

#define BIG_COUNT (sizeof big_cases / sizeof big_cases[0])

typedef struct big_result {
    bool ok;
    size_t modules;
    double rate; /* final modules per second */
} big_result;

static int bench_big(const options *o, big_result *res)
{
    int failures = 0;
    printf("\n== derivation: large grammars (one core) ==\n");
    print_derive_header("grammar");
    for (size_t i = 0; i < BIG_COUNT; ++i) {
        const big_case *c = &big_cases[i];
        const char *src = c->source ? c->source : xyl_lsystem_preset_source(c->name);
        uint32_t depth = o->quick ? c->quick_depth : c->depth;
        xyl_diag diag = {0};
        xyl_grammar *g = NULL;
        xyl_result r = src ? parse(src, &g, &diag) : XYL_ERR_NOT_FOUND;
        derive_job j = {g, depth, 0};
        timing t = {0};
        uint64_t all = 0;
        if (!r && !(r = measure(o, derive_once, &j, &t, &diag)) &&
            !(r = modules_all_steps(g, depth, &all, &diag))) {
            print_derive_row(c->name, depth, j.modules, all, &t);
            res[i].ok = true;
            res[i].modules = j.modules;
            res[i].rate = rate((double)j.modules, t.median_s);
        }
        if (r) {
            report_error(c->name, r, &diag);
            ++failures;
        }
        xyl_grammar_destroy(g);
    }
    return failures;
}

/* ---- 3. the peer: lindenmayer under node --------------------------------------------------- */

typedef struct peer_case {
    const char *name;
    const char *axiom;
    const char *rules[2]; /* "<symbol>=<successor>", NULL-terminated when shorter */
    uint32_t depth;
    bool quick; /* also run with --quick */
} peer_case;

static const peer_case peer_cases[] = {
    {"abop-1.24a", "F", {"F=F[+F]F[-F]F", NULL}, 5, true},
    {"abop-1.24a", "F", {"F=F[+F]F[-F]F", NULL}, 7, false},
    {"abop-1.24a", "F", {"F=F[+F]F[-F]F", NULL}, 8, false},
    {"abop-1.24a", "F", {"F=F[+F]F[-F]F", NULL}, 9, false},
    {"abop-1.24d", "X", {"X=F[+X]F[-X]+X", "F=FF"}, 10, false},
};

#define PEER_COUNT (sizeof peer_cases / sizeof peer_cases[0])
#define MAX_PATH_LEN 4096

typedef struct peer_result {
    bool ok;
    unsigned long long modules;
    double median_s;
    uint32_t hash;
    char version[32];
} peer_result;

static bool parse_peer_line(const char *line, peer_result *out)
{
    const char *m = strstr(line, " modules="), *t = strstr(line, " median_ns="),
               *h = strstr(line, " fnv1a32="), *v = strstr(line, " version=");
    if (strncmp(line, "lindenmayer version=", 20) != 0 || !m || !t || !h || !v) return false;
    double ns = strtod(t + 11, NULL);
    out->modules = strtoull(m + 9, NULL, 10);
    out->hash = (uint32_t)strtoul(h + 9, NULL, 16);
    out->median_s = ns * 1e-9;
    sscanf(v + 9, "%31s", out->version);
    out->ok = ns > 0.0;
    return out->ok;
}

/* Runs the script; on failure leaves its first output line in why. */
static void run_peer(const options *o, const char *script, const peer_case *c, peer_result *out,
                     char *why, size_t why_cap)
{
    char cmd[2 * MAX_PATH_LEN], arg[32];
    cmd[0] = '\0';
    bool ok = append_quoted(cmd, sizeof cmd, o->node) && append_quoted(cmd, sizeof cmd, script) &&
              append_quoted(cmd, sizeof cmd, c->axiom);
    snprintf(arg, sizeof arg, "%u", c->depth);
    ok = ok && append_quoted(cmd, sizeof cmd, arg);
    snprintf(arg, sizeof arg, "%d", o->repeats);
    ok = ok && append_quoted(cmd, sizeof cmd, arg);
    for (int k = 0; k < 2 && c->rules[k]; ++k)
        ok = ok && append_quoted(cmd, sizeof cmd, c->rules[k]);
    ok = ok && strlen(cmd) + 16 < sizeof cmd;
    copy_text(why, why_cap, ok ? "no output" : "command too long");
    if (!ok) return;
    strcat(cmd, " 2>&1");
    FILE *p = popen(cmd, "r");
    if (!p) return;
    char line[1024];
    bool first = true;
    while (fgets(line, sizeof line, p)) {
        line[strcspn(line, "\r\n")] = '\0';
        if (parse_peer_line(line, out)) continue;
        if (first) copy_text(why, why_cap, line);
        first = false;
    }
    pclose(p);
}

/* The xylem side of a peer case: median time, module count and symbol hash. */
static xyl_result derive_peer_case(const options *o, const peer_case *c, size_t *modules,
                                   double *median_s, uint32_t *hash, xyl_diag *diag)
{
    char src[256];
    int n = snprintf(src, sizeof src, "axiom: %s\n", c->axiom);
    for (int k = 0; k < 2 && c->rules[k]; ++k)
        n += snprintf(src + n, sizeof src - (size_t)n, "%c -> %s\n", c->rules[k][0],
                      c->rules[k] + 2);
    xyl_grammar *g = NULL;
    xyl_lstring *s = NULL;
    xyl_result r = parse(src, &g, diag);
    derive_job j = {g, c->depth, 0};
    timing t = {0};
    if (!r && !(r = measure(o, derive_once, &j, &t, diag)) &&
        !(r = derive_at(g, c->depth, &s, diag))) {
        *modules = xyl_lstring_count(s);
        *median_s = t.median_s;
        *hash = symbols_hash(s);
    }
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return r;
}

typedef struct peer_summary {
    int compared;
    double min_ratio;
    int failures;
} peer_summary;

static void peer_row(const options *o, const char *script, const peer_case *c, peer_summary *sum)
{
    size_t modules = 0;
    double ours = 0.0;
    uint32_t hash = 0;
    xyl_diag diag = {0};
    xyl_result r = derive_peer_case(o, c, &modules, &ours, &hash, &diag);
    if (r) {
        report_error(c->name, r, &diag);
        ++sum->failures;
        return;
    }
    peer_result pr = {0};
    char why[256];
    run_peer(o, script, c, &pr, why, sizeof why);
    if (!pr.ok) {
        printf("%-12s %5u %10zu  %s (%s)\n", c->name, c->depth, modules, PEER_HINT, why);
        return;
    }
    bool same = pr.modules == modules && pr.hash == hash;
    double ratio = pr.median_s / ours;
    printf("%-12s %5u %10zu %9.3f %9.3f %8.1f %8.1f %7.1fx  %s\n", c->name, c->depth, modules,
           ours * 1e3, pr.median_s * 1e3, rate((double)modules, ours) / 1e6,
           rate((double)pr.modules, pr.median_s) / 1e6, ratio,
           same ? "same (count, fnv1a)" : "MISMATCH");
    if (!same) {
        printf("  lindenmayer %s: %llu modules, fnv1a32 0x%08x; xylem: %zu modules, 0x%08x\n",
               pr.version, pr.modules, (unsigned)pr.hash, modules, (unsigned)hash);
        ++sum->failures;
        return;
    }
    if (!sum->compared || ratio < sum->min_ratio) sum->min_ratio = ratio;
    ++sum->compared;
}

static peer_summary bench_peer(const options *o)
{
    peer_summary sum = {0, 0.0, 0};
    printf("\n== peer: the same grammar through lindenmayer (node), same run ==\n");
    char script[MAX_PATH_LEN];
    if (!find_script(o, PEER_SCRIPT, script, sizeof script)) {
        printf("%s (no %s)\n", PEER_HINT, PEER_SCRIPT);
        return sum;
    }
    printf("%-12s %5s %10s %9s %9s %8s %8s %8s  %s\n", "grammar", "depth", "modules", "xylem ms",
           "peer ms", "xyl M/s", "peer M/s", "ratio", "strings");
    for (size_t i = 0; i < PEER_COUNT; ++i)
        if (!o->quick || peer_cases[i].quick) peer_row(o, script, &peer_cases[i], &sum);
    return sum;
}

/* ---- main ---------------------------------------------------------------------------------- */

static void print_targets(const options *o, const big_result *big, const peer_summary *peer)
{
    printf("\n== targets ==\n");
    if (!o->peer) printf("non-parametric >= %.0fx lindenmayer: not measured (--no-peer)\n",
                         TARGET_PEER_RATIO);
    else if (!peer->compared) printf("non-parametric >= %.0fx lindenmayer: not measured\n",
                                     TARGET_PEER_RATIO);
    else printf("non-parametric >= %.0fx lindenmayer: %s (lowest ratio %.1fx over %d cases)%s\n",
                TARGET_PEER_RATIO, peer->min_ratio >= TARGET_PEER_RATIO ? "MET" : "NOT MET",
                peer->min_ratio, peer->compared, o->quick ? " [--quick sizes]" : "");
    for (size_t i = 0; i < BIG_COUNT; ++i) {
        if (!big_cases[i].parametric || !big[i].ok) continue;
        printf("parametric >= %.0e modules/s (%s, %zu modules): %s (%.1f M modules/s)%s\n",
               TARGET_PARAM_RATE, big_cases[i].name, big[i].modules,
               big[i].rate >= TARGET_PARAM_RATE ? "MET" : "NOT MET", big[i].rate / 1e6,
               o->quick ? " [--quick sizes]" : "");
    }
}

int main(int argc, char **argv)
{
    options o = {0};
    int rc = bench_parse_options(argc, argv, &o, "bench_lsystem");
    if (rc) return rc == 1 ? 0 : rc;

    printf("bench_lsystem: xylem %d.%d.%d, %s build, median of %d samples%s\n", XYL_VERSION_MAJOR,
           XYL_VERSION_MINOR, XYL_VERSION_PATCH,
#ifdef NDEBUG
           "optimised (NDEBUG)",
#else
           "assertions-on",
#endif
           o.repeats, o.quick ? ", --quick sizes" : "");

    size_t np = xyl_lsystem_preset_count();
    xyl_grammar **grammars = calloc(np ? np : 1, sizeof *grammars);
    xyl_lstring **strings = calloc(np ? np : 1, sizeof *strings);
    if (!grammars || !strings) {
        fprintf(stderr, "bench_lsystem: out of memory\n");
        return 1;
    }
    int failures = bench_presets(&o, grammars, strings);
    bench_presets_turtle(&o, grammars, strings);
    for (size_t i = 0; i < np; ++i) {
        xyl_lstring_destroy(strings[i]);
        xyl_grammar_destroy(grammars[i]);
    }
    free(strings);
    free(grammars);

    big_result big[BIG_COUNT];
    memset(big, 0, sizeof big);
    failures += bench_big(&o, big);

    peer_summary peer = {0, 0.0, 0};
    if (o.peer) peer = bench_peer(&o);
    else printf("\n== peer: skipped (--no-peer) ==\n");
    failures += peer.failures;

    print_targets(&o, big, &peer);
    if (failures) printf("\n%d failure(s)\n", failures);
    return failures ? 1 : 0;
}

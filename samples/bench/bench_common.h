/* Helpers shared by the benchmark programs (bench_lsystem, bench_stems, bench_tess): options, monotonic
 * timing with medians of batched samples, and finding and quoting a node peer script. */
#ifndef XYL_BENCH_COMMON_H
#define XYL_BENCH_COMMON_H

#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include <xylem/xyl_lsystem.h>

#define MAX_SAMPLES 101 /* most samples a figure is the median of */

typedef struct options {
    bool quick;
    bool peer;
    int repeats;
    double min_sample_s;     /* a sample of a fast case repeats it until it lasts this long */
    const char *peer_script; /* NULL: look next to the working directory and the executable */
    const char *node;
    const char *argv0;
} options;

/* One timed call: does the work, returns in *seconds how long the measured part took. */
typedef xyl_result (*job_fn)(void *ctx, double *seconds, xyl_diag *diag);

typedef struct timing {
    double median_s, min_s;
    int samples;
    unsigned batch; /* calls per sample */
} timing;

static inline double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static inline int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static inline double median_of(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static inline xyl_result run_batch(job_fn job, void *ctx, unsigned batch, double *seconds, xyl_diag *diag)
{
    double sum = 0.0;
    for (unsigned b = 0; b < batch; ++b) {
        double t = 0.0;
        xyl_result r = job(ctx, &t, diag);
        if (r) return r;
        sum += t;
    }
    *seconds = sum / batch;
    return XYL_OK;
}

static inline xyl_result derive_at(const xyl_grammar *g, uint32_t depth, xyl_lstring **out,
                            xyl_diag *diag)
{
    xyl_derive_desc dd = {0};
    dd.has_depth = true;
    dd.depth = depth;
    return xyl_lsystem_derive(g, &dd, out, diag);
}

static inline void report_error(const char *what, xyl_result r, const xyl_diag *diag)
{
    printf("%s: error: %s", what, xyl_result_string(r));
    if (diag->message[0]) printf(" (%s)", diag->message);
    printf("\n");
}

static inline double rate(double count, double seconds)
{
    return seconds > 0.0 ? count / seconds : 0.0;
}

static inline bool file_exists(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f) fclose(f);
    return f != NULL;
}

/* The peer script: --peer-script, else relative to the working directory (the repository root),
 * else relative to the executable (build-dir/samples/bench_lsystem). */
static inline bool find_script(const options *o, const char *relative, char *path, size_t cap)
{
    if (o->peer_script) {
        snprintf(path, cap, "%s", o->peer_script);
        return file_exists(path);
    }
    static const char *const ups[] = {"", "../../", "../", "../../../"};
    const char *slash = strrchr(o->argv0, '/');
    int dir_len = slash ? (int)(slash - o->argv0) : 1;
    const char *dir = slash ? o->argv0 : ".";
    for (size_t i = 0; i < sizeof ups / sizeof ups[0]; ++i) {
        if (i == 0) snprintf(path, cap, "%s", relative);
        else snprintf(path, cap, "%.*s/%s%s", dir_len, dir, ups[i], relative);
        if (file_exists(path)) return true;
    }
    return false;
}

/* Appends s single-quoted for /bin/sh. */
static inline bool append_quoted(char *cmd, size_t cap, const char *s)
{
    size_t n = strlen(cmd);
    if (n + 3 >= cap) return false;
    cmd[n++] = ' ';
    cmd[n++] = '\'';
    for (; *s; ++s) {
        const char *piece = *s == '\'' ? "'\\''" : NULL;
        size_t len = piece ? 4 : 1;
        if (n + len + 2 >= cap) return false;
        if (piece) memcpy(cmd + n, piece, len);
        else cmd[n] = *s;
        n += len;
    }
    cmd[n++] = '\'';
    cmd[n] = '\0';
    return true;
}

static inline void copy_text(char *dst, size_t cap, const char *src)
{
    size_t n = strlen(src);
    if (n >= cap) n = cap - 1;
    memcpy(dst, src, n);
    dst[n] = '\0';
}

static inline void bench_usage(FILE *f, const char *program)
{
    fprintf(f, "usage: %s [--quick] [--no-peer] [--repeats N] [--peer-script PATH] [--node PATH]\n",
            program);
}

/* Fills o from the command line; returns 0, 1 after --help, 2 on bad usage. */
static inline int bench_parse_options(int argc, char **argv, options *o, const char *program)
{
    o->argv0 = argc > 0 ? argv[0] : program;
    o->peer = true;
    o->node = "node";
    const char *repeats = NULL;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        bool has_value = i + 1 < argc;
        if (strcmp(a, "--quick") == 0) o->quick = true;
        else if (strcmp(a, "--no-peer") == 0) o->peer = false;
        else if (strcmp(a, "--repeats") == 0 && has_value) repeats = argv[++i];
        else if (strcmp(a, "--peer-script") == 0 && has_value) o->peer_script = argv[++i];
        else if (strcmp(a, "--node") == 0 && has_value) o->node = argv[++i];
        else if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            bench_usage(stdout, program);
            return 1;
        } else {
            bench_usage(stderr, program);
            return 2;
        }
    }
    char *end = NULL;
    long n = repeats ? strtol(repeats, &end, 10) : (o->quick ? 3 : 9);
    if ((repeats && *end) || n < 1 || n > MAX_SAMPLES) {
        fprintf(stderr, "%s: --repeats must be 1..%d\n", program, MAX_SAMPLES);
        return 2;
    }
    o->repeats = (int)n;
    o->min_sample_s = o->quick ? 1e-3 : 5e-3;
    return 0;
}

#endif

/* bench_stems: meshing throughput of xyl_stems_build on L-system trees from 10^3 to 10^6
 * segments, the whole pipeline (derive + turtle + mesh) on the same trees, and the npm package
 * `@dgreenheck/ez-tree` (samples/bench/eztree_bench.mjs) on trees of comparable triangle counts
 * in the same run, and the chain of stem LODs (xyl_stems_lods_build) against the finest mesh.
 *
 *   bench_stems [--quick] [--no-peer] [--repeats N] [--peer-script PATH] [--node PATH]
 *
 * Every figure is the median of N samples (CLOCK_MONOTONIC); trees above LARGE_SEGMENTS segments
 * take at most LARGE_REPEATS samples, and a sample of a fast case runs it several times back to
 * back so that one sample lasts at least 5 ms (1 ms with --quick). Only the calls themselves are
 * timed: destroying their results is not. Single-threaded; pin it with taskset for steadier
 * figures. scripts/bench.sh installs the peer, builds in Release and runs this.
 *
 * Exit status: 0, also when a throughput target is missed or the peer is unavailable; 1 when
 * a grammar fails to parse or derive or a mesh fails to build; 2 on bad usage. */
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
#include <xylem/xyl_stems.h>

#define MAX_BATCH 100000u
#define LARGE_SEGMENTS 500000u
#define LARGE_REPEATS 5
#define MAX_DEPTH 18
#define PEER_SCRIPT "samples/bench/eztree_bench.mjs"
#define PEER_HINT "ez-tree: not available (run scripts/bench.sh to install)"
#define PEER_SETTLE_S 1.0 /* idle time between an ez-tree step's node and our tree */
#define TARGET_PEER_RATIO 20.0
#define TARGET_VERTEX_RATE 1e7
#define TARGET_SUBDIVISION_RATIO 10.0 /* pre-subdivision time over the plain mesh time */
#define SUBDIVISION_TARGET_DEPTH 15   /* the ratio target holds from this depth up */
#define TARGET_LOD_RATIO 3.0          /* the whole stem LOD chain over the finest mesh */

/* ABOP figure 2.7 (Aono & Kunii's sympodial tree, the preset abop-2.7-sympodial) with every
 * internode drawn as four segments, as real branches are several segments long, and a light
 * gravitropism that bends them. Widths shrink by 0.707 at each binary fork (da Vinci: the two
 * children's cross-sections add up to the parent's) and the turtle takes them as radii
 * (XYL_RADIUS_GRAMMAR): the trunk keeps its width at every depth and no segment is shorter than
 * 1.7 radii. The pipe rule starts from a fixed tip radius, so its trunk would thicken with the
 * tip count (512 tip radii at depth 18) while the lengths stay the same.
 * Depth d gives 4 (2^d - 1) segments. */
static const char tree_source[] =
    "#define r1 0.9   // contraction ratio, first child\n"
    "#define r2 0.7   // contraction ratio, second child\n"
    "#define a1 10    // branching angle, first child\n"
    "#define a2 60    // branching angle, second child\n"
    "#define wr 0.707 // width ratio at a fork\n"
    "#tropism 0 -1 0 0.05\n"
    "axiom: A(1,0.25)\n"
    "p1: A(l,w) : * -> !(w)F(l/4)F(l/4)F(l/4)F(l/4)[&(a1)B(l*r1,w*wr)]/(180)[&(a2)B(l*r2,w*wr)]\n"
    "p2: B(l,w) : * -> !(w)F(l/4)F(l/4)F(l/4)F(l/4)[+(a1)$B(l*r1,w*wr)][-(a2)$B(l*r2,w*wr)]\n";

#define TREE_NAME "sympodial, 4 segments per internode"

/* The size ladder: about 10^3, 10^4, 3 10^4, 10^5 and 10^6 segments. */
static const uint32_t ladder_full[] = {8, 11, 13, 15, 18};
static const uint32_t ladder_quick[] = {5, 8};
#define MIDDLE_FULL 15  /* depth of the k = 8 and Catmull-Clark rows */
#define MIDDLE_QUICK 8


/* ---- timing -------------------------------------------------------------------------------- */


/* A warm-up call picks the batch size; then the median of `repeats` samples. */
static xyl_result measure(const options *o, int repeats, job_fn job, void *ctx, timing *out,
                          xyl_diag *diag)
{
    double first = 0.0, v[MAX_SAMPLES];
    xyl_result r = job(ctx, &first, diag);
    if (r) return r;
    double want = ceil(o->min_sample_s / (first > 1e-9 ? first : 1e-9));
    unsigned batch = want < 1.0 ? 1u : want > MAX_BATCH ? MAX_BATCH : (unsigned)want;
    for (int i = 0; i < repeats; ++i)
        if ((r = run_batch(job, ctx, batch, &v[i], diag))) return r;
    out->samples = repeats;
    out->batch = batch;
    out->median_s = median_of(v, repeats);
    out->min_s = v[0];
    return XYL_OK;
}

/* ---- growing the trees --------------------------------------------------------------------- */

static xyl_result interpret(const xyl_grammar *g, const xyl_lstring *s, xyl_skeleton **out,
                            xyl_diag *diag)
{
    xyl_turtle_desc td = {0};
    td.radius_mode = XYL_RADIUS_GRAMMAR;
    return xyl_lsystem_interpret(g, s, &td, out, diag);
}

static xyl_result grow(const xyl_grammar *g, uint32_t depth, xyl_skeleton **out, xyl_diag *diag)
{
    xyl_lstring *s = NULL;
    xyl_result r = derive_at(g, depth, &s, diag);
    if (!r) r = interpret(g, s, out, diag);
    xyl_lstring_destroy(s);
    return r;
}

static size_t segments_of(const xyl_skeleton *sk)
{
    return sk->node_count - sk->root_count;
}

/* ---- jobs: meshing alone, and the whole pipeline ------------------------------------------- */

/* The ladder, the pipeline and the peer comparison time the construction alone; the checked
 * build (the library's default) is timed beside it in the variants (docs/BENCHMARKS.md). */
static const xyl_stems_desc unchecked = {.joints = XYL_JOINTS_UNCHECKED};

typedef struct mesh_job {
    const xyl_skeleton *sk;
    xyl_stems_desc desc;
    size_t vertices, triangles; /* of the last mesh built */
    xyl_stems_stats stats;      /* of the last mesh built */
} mesh_job;

static xyl_result mesh_once(void *ctx, double *seconds, xyl_diag *diag)
{
    mesh_job *j = ctx;
    xyl_mesh *m = NULL;
    double t0 = now_s();
    xyl_result r = xyl_stems_build(j->sk, &j->desc, &m, &j->stats, diag);
    *seconds = now_s() - t0;
    if (r) return r;
    j->vertices = m->vertex_count;
    j->triangles = m->tri_view_count;
    xyl_mesh_destroy(m);
    return XYL_OK;
}

typedef struct pipeline_job {
    const xyl_grammar *g;
    uint32_t depth;
    size_t triangles;
} pipeline_job;

/* Derive, turtle and mesh back to back; the three results are destroyed after the clock stops. */
static xyl_result pipeline_once(void *ctx, double *seconds, xyl_diag *diag)
{
    pipeline_job *j = ctx;
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    xyl_mesh *m = NULL;
    double t0 = now_s();
    xyl_result r = derive_at(j->g, j->depth, &s, diag);
    if (!r) r = interpret(j->g, s, &sk, diag);
    if (!r) r = xyl_stems_build(sk, &unchecked, &m, NULL, diag);
    *seconds = now_s() - t0;
    if (!r) j->triangles = m->tri_view_count;
    xyl_mesh_destroy(m);
    xyl_skeleton_destroy(sk);
    xyl_lstring_destroy(s);
    return r;
}

/* ---- one tree size: skeleton, mesh timing, pipeline timing --------------------------------- */

typedef struct size_result {
    bool ok;
    size_t segments, vertices, triangles;
    timing mesh, pipeline;
} size_result;

static int repeats_for(const options *o, size_t segments)
{
    return segments > LARGE_SEGMENTS && o->repeats > LARGE_REPEATS ? LARGE_REPEATS : o->repeats;
}

static xyl_result measure_mesh(const options *o, const xyl_skeleton *sk,
                               const xyl_stems_desc *desc, mesh_job *j, timing *t,
                               xyl_diag *diag)
{
    j->sk = sk;
    j->desc = *desc;
    return measure(o, repeats_for(o, segments_of(sk)), mesh_once, j, t, diag);
}

/* Measures depth `depth` once; later calls return the stored figures. */
static xyl_result measure_size(const options *o, const xyl_grammar *g, uint32_t depth,
                               size_result *res, xyl_diag *diag)
{
    if (res->ok) return XYL_OK;
    xyl_skeleton *sk = NULL;
    xyl_stems_desc desc = unchecked;
    mesh_job mj = {0};
    xyl_result r = grow(g, depth, &sk, diag);
    if (!r) r = measure_mesh(o, sk, &desc, &mj, &res->mesh, diag);
    if (!r) {
        res->segments = segments_of(sk);
        res->vertices = mj.vertices;
        res->triangles = mj.triangles;
        pipeline_job pj = {g, depth, 0};
        r = measure(o, repeats_for(o, res->segments), pipeline_once, &pj, &res->pipeline, diag);
    }
    xyl_skeleton_destroy(sk);
    res->ok = !r;
    return r;
}

/* ---- 1. the ladder ------------------------------------------------------------------------- */

static void print_skeleton_row(uint32_t depth, const xyl_skeleton *sk)
{
    printf("%5u %9zu %6u %10zu %8u %6u\n", depth, sk->node_count, sk->root_count,
           segments_of(sk), sk->branch_count, sk->max_order);
}

static int bench_skeletons(const xyl_grammar *g, const uint32_t *depths, size_t n)
{
    int failures = 0;
    printf("\n== skeletons: %s, grammar radii ==\n", TREE_NAME);
    printf("%5s %9s %6s %10s %8s %6s\n", "depth", "nodes", "roots", "segments", "branches",
           "order");
    for (size_t i = 0; i < n; ++i) {
        xyl_diag diag = {0};
        xyl_skeleton *sk = NULL;
        xyl_result r = grow(g, depths[i], &sk, &diag);
        if (r) {
            report_error("grow", r, &diag);
            ++failures;
        } else {
            print_skeleton_row(depths[i], sk);
        }
        xyl_skeleton_destroy(sk);
    }
    return failures;
}

static void print_mesh_header(void)
{
    printf("%-14s %10s %10s %10s %9s %7s %8s %8s %7s %7s %4s\n", "case", "segments",
           "vertices", "triangles", "median ms", "Mseg/s", "Mvert/s", "Mtri/s", "ns/tri",
           "ns/seg", "N");
}

static void print_mesh_row(const char *label, size_t segments, size_t vertices, size_t triangles,
                           const timing *t)
{
    double s = t->median_s;
    printf("%-14s %10zu %10zu %10zu %9.3f %7.2f %8.2f %8.2f %7.1f %7.1f %4d\n", label, segments,
           vertices, triangles, s * 1e3, rate((double)segments, s) / 1e6,
           rate((double)vertices, s) / 1e6, rate((double)triangles, s) / 1e6,
           s * 1e9 / (double)triangles, s * 1e9 / (double)segments, t->samples);
}

static int bench_ladder(const options *o, const xyl_grammar *g, const uint32_t *depths, size_t n,
                        size_result *by_depth)
{
    int failures = 0;
    printf("\n== mesh: xyl_stems_build (k = 4, no subdivision, branch normals, joints unchecked) "
           "==\n");
    print_mesh_header();
    for (size_t i = 0; i < n; ++i) {
        xyl_diag diag = {0};
        size_result *res = &by_depth[depths[i]];
        char label[32];
        snprintf(label, sizeof label, "depth %u", depths[i]);
        xyl_result r = measure_size(o, g, depths[i], res, &diag);
        if (r) {
            report_error(label, r, &diag);
            ++failures;
            continue;
        }
        print_mesh_row(label, res->segments, res->vertices, res->triangles, &res->mesh);
    }
    return failures;
}

static void print_linearity(const uint32_t *depths, size_t n, const size_result *by_depth)
{
    double lo = 0.0, hi = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const size_result *res = &by_depth[depths[i]];
        if (!res->ok) continue;
        double ns = res->mesh.median_s * 1e9 / (double)res->segments;
        if (lo == 0.0 || ns < lo) lo = ns;
        if (ns > hi) hi = ns;
    }
    if (lo > 0.0)
        printf("linearity: mesh time per segment %.1f .. %.1f ns over the ladder (max/min %.2f)\n",
               lo, hi, hi / lo);
}

/* k = 8 and Catmull-Clark pre-subdivision at one size. */
static int bench_variants(const options *o, const xyl_grammar *g, uint32_t depth)
{
    static const struct {
        const char *label;
        uint32_t sides;
        xyl_subdivision scheme;
        xyl_joint_check joints;
    } variants[] = {{"k=8", 8, XYL_SUBDIVIDE_NONE, XYL_JOINTS_UNCHECKED},
                    {"k=4 catmark", 4, XYL_SUBDIVIDE_CATMARK, XYL_JOINTS_UNCHECKED},
                    {"k=4 checked", 4, XYL_SUBDIVIDE_NONE, XYL_JOINTS_CHECKED}};
    xyl_diag diag = {0};
    xyl_skeleton *sk = NULL;
    xyl_result r = grow(g, depth, &sk, &diag);
    if (r) {
        report_error("grow", r, &diag);
        return 1;
    }
    int failures = 0;
    printf("\n== mesh: variants at depth %u ==\n", depth);
    print_mesh_header();
    for (size_t i = 0; i < sizeof variants / sizeof variants[0]; ++i) {
        xyl_stems_desc desc = {0};
        desc.sides = variants[i].sides;
        desc.subdivision = variants[i].scheme;
        desc.joints = variants[i].joints;
        mesh_job j = {0};
        timing t = {0};
        if ((r = measure_mesh(o, sk, &desc, &j, &t, &diag)) == XYL_ERR_UNSUPPORTED &&
            desc.subdivision != XYL_SUBDIVIDE_NONE) {
            printf("%-14s skipped: this xylem is built without OpenSubdiv\n", variants[i].label);
            continue;
        }
        if (r) {
            report_error(variants[i].label, r, &diag);
            ++failures;
            continue;
        }
        print_mesh_row(variants[i].label, segments_of(sk), j.vertices, j.triangles, &t);
        if (desc.joints == XYL_JOINTS_CHECKED)
            printf("%-14s %u builds, %zu pairs at joints, %u laterals start later, %u hidden "
                   "whole, %zu of %zu faces kept\n", "", j.stats.builds, j.stats.joint_pairs_first,
                   j.stats.laterals_started_later, j.stats.laterals_hidden,
                   j.stats.faces_checked, j.stats.faces_first);
    }
    xyl_skeleton_destroy(sk);
    return failures;
}

/* Pre-subdivision over the ladder: the plain mesh (the ladder's figure) against one level of
 * Catmull-Clark and of Loop on the same tree, k = 4, joints unchecked. *worst is the largest
 * ratio at SUBDIVISION_TARGET_DEPTH and above (0: not measured). */
static int bench_subdivision(const options *o, const xyl_grammar *g, const uint32_t *depths,
                             size_t n, const size_result *by_depth, double *worst)
{
    static const struct {
        const char *label;
        xyl_subdivision scheme;
    } schemes[] = {{"catmark", XYL_SUBDIVIDE_CATMARK}, {"loop", XYL_SUBDIVIDE_LOOP}};
    int failures = 0;
    *worst = 0.0;
    printf("\n== pre-subdivision: xyl_stems_build (k = 4, branch normals, joints unchecked), one "
           "level on the limit surface ==\n");
    printf("%-9s %10s %9s %-8s %10s %10s %9s %7s %4s\n", "depth", "segments", "plain ms",
           "scheme", "vertices", "triangles", "median ms", "x plain", "N");
    for (size_t i = 0; i < n; ++i) {
        const size_result *plain = &by_depth[depths[i]];
        if (!plain->ok) continue;
        xyl_diag diag = {0};
        xyl_skeleton *sk = NULL;
        xyl_result r = grow(g, depths[i], &sk, &diag);
        if (r) {
            report_error("grow", r, &diag);
            ++failures;
            continue;
        }
        for (size_t s = 0; s < sizeof schemes / sizeof schemes[0]; ++s) {
            xyl_stems_desc desc = unchecked;
            desc.subdivision = schemes[s].scheme;
            mesh_job j = {0};
            timing t = {0};
            r = measure_mesh(o, sk, &desc, &j, &t, &diag);
            if (r == XYL_ERR_UNSUPPORTED) {
                printf("depth %-3u skipped: this xylem is built without OpenSubdiv\n", depths[i]);
                break;
            }
            if (r) {
                report_error(schemes[s].label, r, &diag);
                ++failures;
                continue;
            }
            double ratio = t.median_s / plain->mesh.median_s;
            if (depths[i] >= SUBDIVISION_TARGET_DEPTH && ratio > *worst) *worst = ratio;
            printf("depth %-3u %10zu %9.3f %-8s %10zu %10zu %9.3f %7.1f %4d\n", depths[i],
                   plain->segments, plain->mesh.median_s * 1e3, schemes[s].label, j.vertices,
                   j.triangles, t.median_s * 1e3, ratio, t.samples);
        }
        xyl_skeleton_destroy(sk);
    }
    return failures;
}

/* ---- the stem LOD chain -------------------------------------------------------------------- */

typedef struct lods_job {
    const xyl_skeleton *sk;
    xyl_stems_lod_desc desc;
    uint32_t lods;
    size_t faces[XYL_STEMS_LOD_MAX];
    float errors[XYL_STEMS_LOD_MAX];
} lods_job;

static xyl_result lods_once(void *ctx, double *seconds, xyl_diag *diag)
{
    lods_job *j = ctx;
    xyl_stems_lods *c = NULL;
    double t0 = now_s();
    xyl_result r = xyl_stems_lods_build(j->sk, &j->desc, &c, diag);
    *seconds = now_s() - t0;
    if (r) return r;
    j->lods = c->lod_count;
    for (uint32_t i = 0; i < c->lod_count; ++i) {
        j->faces[i] = c->lods[i].face_count;
        j->errors[i] = c->lods[i].error;
    }
    xyl_stems_lods_destroy(c);
    return XYL_OK;
}

/* The whole chain (defaults: up to 8 LODs, E0 = 0, factor 2) against the finest mesh alone:
 * joints unchecked (as the ladder) on the deepest tree of the ladder, and checked (the
 * library's default, about 100x slower) on the variants' tree, as the variants time it.
 * *worst: the larger ratio (0: not measured). */
static int bench_lods(const options *o, const xyl_grammar *g, uint32_t deepest, uint32_t middle,
                      double *worst)
{
    static const struct {
        const char *label;
        xyl_joint_check joints;
    } checks[] = {{"unchecked", XYL_JOINTS_UNCHECKED}, {"checked", XYL_JOINTS_CHECKED}};
    *worst = 0.0;
    int failures = 0;
    printf("\n== stem LODs: xyl_stems_lods_build (up to 8 LODs, E0 = 0, budgets x2) against "
           "xyl_stems_build, k = 4 ==\n");
    printf("%-10s %6s %10s %12s %12s %7s %4s  %s\n", "joints", "depth", "segments", "finest ms",
           "chain ms", "x finest", "N", "faces (error) per LOD");
    for (size_t i = 0; i < sizeof checks / sizeof checks[0]; ++i) {
        uint32_t depth = checks[i].joints == XYL_JOINTS_CHECKED ? middle : deepest;
        xyl_diag diag = {0};
        xyl_skeleton *sk = NULL;
        xyl_result r = grow(g, depth, &sk, &diag);
        if (r) {
            report_error("grow", r, &diag);
            ++failures;
            continue;
        }
        xyl_stems_desc desc = {0};
        desc.joints = checks[i].joints;
        mesh_job mj = {0};
        timing fine = {0}, chain = {0};
        lods_job lj = {0};
        lj.sk = sk;
        lj.desc.stems = desc;
        r = measure_mesh(o, sk, &desc, &mj, &fine, &diag);
        if (!r) r = measure(o, repeats_for(o, segments_of(sk)), lods_once, &lj, &chain, &diag);
        if (r) {
            report_error(checks[i].label, r, &diag);
            xyl_skeleton_destroy(sk);
            ++failures;
            continue;
        }
        double ratio = chain.median_s / fine.median_s;
        if (ratio > *worst) *worst = ratio;
        printf("%-10s %6u %10zu %12.3f %12.3f %7.2f %4d ", checks[i].label, depth,
               segments_of(sk), fine.median_s * 1e3, chain.median_s * 1e3, ratio, chain.samples);
        for (uint32_t k = 0; k < lj.lods; ++k)
            printf(" %zu (%.3g)", lj.faces[k], (double)lj.errors[k]);
        printf("\n");
        xyl_skeleton_destroy(sk);
    }
    return failures;
}

static void bench_pipeline(const uint32_t *depths, size_t n, const size_result *by_depth)
{
    printf("\n== pipeline: derive + turtle + mesh (k = 4), grammar parsed once ==\n");
    printf("%-14s %10s %10s %9s %9s %7s %8s %4s\n", "case", "segments", "triangles", "median ms",
           "mesh ms", "ns/tri", "Mvert/s", "N");
    for (size_t i = 0; i < n; ++i) {
        const size_result *res = &by_depth[depths[i]];
        if (!res->ok) continue;
        double s = res->pipeline.median_s;
        printf("depth %-8u %10zu %10zu %9.3f %9.3f %7.1f %8.2f %4d\n", depths[i], res->segments,
               res->triangles, s * 1e3, res->mesh.median_s * 1e3,
               s * 1e9 / (double)res->triangles, rate((double)res->vertices, s) / 1e6,
               res->pipeline.samples);
    }
}

/* ---- 2. the peer: ez-tree under node ------------------------------------------------------- */

#define MAX_PATH_LEN 4096

typedef struct peer_case {
    char name[48];
    char version[32];
    unsigned long long triangles, vertices;
    double median_s;
    bool wrapped; /* its Uint16 indices wrap: the mesh three would draw is not the one built */
} peer_case;

/* The value of " key=" in a key=value line, up to the next space; false if absent. */
static bool peer_value(const char *line, const char *key, char *out, size_t cap)
{
    char pat[40];
    snprintf(pat, sizeof pat, " %s=", key);
    const char *p = strstr(line, pat);
    if (!p) return false;
    p += strlen(pat);
    size_t n = strcspn(p, " ");
    if (n >= cap) n = cap - 1;
    memcpy(out, p, n);
    out[n] = '\0';
    return n > 0;
}

static bool parse_peer_line(const char *line, peer_case *out)
{
    char tri[32], vert[32], ns[32], wrapped[32];
    if (strncmp(line, "eztree version=", 15) != 0) return false;
    if (!peer_value(line, "version", out->version, sizeof out->version) ||
        !peer_value(line, "case", out->name, sizeof out->name) ||
        !peer_value(line, "branch_triangles", tri, sizeof tri) ||
        !peer_value(line, "branch_vertices", vert, sizeof vert) ||
        !peer_value(line, "median_ns", ns, sizeof ns) ||
        !peer_value(line, "index_wrapped", wrapped, sizeof wrapped))
        return false;
    out->triangles = strtoull(tri, NULL, 10);
    out->vertices = strtoull(vert, NULL, 10);
    out->median_s = strtod(ns, NULL) * 1e-9;
    out->wrapped = strtoull(wrapped, NULL, 10) > 0;
    return out->triangles > 0 && out->median_s > 0.0;
}

/* The script's command line with `args` (NULL-terminated) after it, stderr joined to stdout. */
static bool build_peer_command(const options *o, const char *script, const char *const *args,
                               char *cmd, size_t cap)
{
    cmd[0] = '\0';
    bool ok = append_quoted(cmd, cap, o->node) && append_quoted(cmd, cap, script);
    for (; ok && *args; ++args) ok = append_quoted(cmd, cap, *args);
    ok = ok && strlen(cmd) + 8 < cap;
    if (ok) strcat(cmd, " 2>&1");
    return ok;
}

/* Runs the script once with `args`; returns the cases it printed (at most cap), and on none its
 * first line in why. If steps is not NULL, a line "eztree steps=N" sets it. */
static size_t run_peer(const options *o, const char *script, const char *const *args,
                       peer_case *cases, size_t cap, unsigned *steps, char *why, size_t why_cap)
{
    char cmd[2 * MAX_PATH_LEN];
    bool ok = build_peer_command(o, script, args, cmd, sizeof cmd);
    copy_text(why, why_cap, ok ? "no output" : "command too long");
    if (!ok) return 0;
    fflush(stdout);
    FILE *p = popen(cmd, "r");
    if (!p) return 0;
    char line[2048];
    size_t n = 0;
    bool first = true;
    while (fgets(line, sizeof line, p)) {
        line[strcspn(line, "\r\n")] = '\0';
        if (n < cap && parse_peer_line(line, &cases[n])) {
            ++n;
            continue;
        }
        if (steps && strncmp(line, "eztree steps=", 13) == 0) {
            *steps = (unsigned)strtoul(line + 13, NULL, 10);
            continue;
        }
        if (first) copy_text(why, why_cap, line);
        first = false;
    }
    pclose(p);
    return n;
}

/* Triangle counts of the k = 4 mesh by depth, built untimed when first asked. */
typedef struct tri_counts {
    size_t by_depth[MAX_DEPTH + 1];
} tri_counts;

static xyl_result triangles_at(const xyl_grammar *g, uint32_t depth, tri_counts *tc,
                               xyl_diag *diag)
{
    if (tc->by_depth[depth]) return XYL_OK;
    xyl_skeleton *sk = NULL;
    xyl_mesh *m = NULL;
    xyl_result r = grow(g, depth, &sk, diag);
    if (!r) r = xyl_stems_build(sk, &unchecked, &m, NULL, diag);
    if (!r) tc->by_depth[depth] = m->tri_view_count;
    xyl_mesh_destroy(m);
    xyl_skeleton_destroy(sk);
    return r;
}

/* The depth whose triangle count is nearest (in ratio) to `want`. */
static xyl_result match_depth(const xyl_grammar *g, unsigned long long want, tri_counts *tc,
                              uint32_t *depth, xyl_diag *diag)
{
    double best = INFINITY;
    for (uint32_t d = 1; d <= MAX_DEPTH; ++d) {
        xyl_result r = triangles_at(g, d, tc, diag);
        if (r) return r;
        double off = fabs(log((double)tc->by_depth[d] / (double)want));
        if (off < best) {
            best = off;
            *depth = d;
        }
        if (tc->by_depth[d] >= want) break;
    }
    return XYL_OK;
}

typedef struct peer_summary {
    int compared;
    double min_mesh_ratio, min_pipeline_ratio;
    bool any_wrapped;
    int failures;
} peer_summary;

static void print_peer_header(void)
{
    printf("%-16s %9s %9s %8s | %5s %9s %8s %8s %7s | %7s %7s\n", "ez-tree case", "tris",
           "ms/tree", "ns/tri", "depth", "tris", "mesh", "pipeline", "ns/tri", "mesh", "pipe");
    printf("%-16s %9s %9s %8s | %5s %9s %8s %8s %7s | %7s %7s\n", "", "(branch)", "", "", "",
           "", "ms", "ms", "(mesh)", "ratio", "ratio");
}

static void pause_s(double seconds)
{
    struct timespec ts = {(time_t)seconds, (long)((seconds - (double)(time_t)seconds) * 1e9)};
    while (nanosleep(&ts, &ts) != 0) {}
}

/* Step `step` of the script's ladder, in a node of its own, then the matched tree, measured
 * after that node has exited: the two sides of a ratio are taken seconds apart and each on an
 * otherwise idle machine. (Samples interleaved one by one with a node left running were up to
 * 2x slower on xylem's side: docs/BENCHMARKS.md, "The peer a step at a time".) */
static void peer_row(const options *o, const xyl_grammar *g, const char *script, unsigned step,
                     tri_counts *tc, peer_summary *sum)
{
    char step_arg[16], repeats_arg[16], why[256];
    snprintf(step_arg, sizeof step_arg, "%u", step);
    snprintf(repeats_arg, sizeof repeats_arg, "%d", o->repeats);
    const char *const args[] = {"--step", step_arg, "--repeats", repeats_arg, NULL};
    peer_case pc;
    if (!run_peer(o, script, args, &pc, 1, NULL, why, sizeof why)) {
        printf("ez-tree step %u: error: %s\n", step, why);
        ++sum->failures;
        return;
    }
    if (!sum->compared) {
        printf("ez-tree %s: time per tree includes growing its skeleton and leaves; its branch "
               "mesh is open tubes\n", pc.version);
        print_peer_header();
    }
    xyl_diag diag = {0};
    uint32_t depth = 0;
    size_result x;
    memset(&x, 0, sizeof x);
    xyl_result r = match_depth(g, pc.triangles, tc, &depth, &diag);
    pause_s(PEER_SETTLE_S);
    if (!r) r = measure_size(o, g, depth, &x, &diag);
    if (r) {
        report_error(pc.name, r, &diag);
        ++sum->failures;
        return;
    }
    double peer_ns = pc.median_s * 1e9 / (double)pc.triangles;
    double mesh_ns = x.mesh.median_s * 1e9 / (double)x.triangles;
    double pipe_ns = x.pipeline.median_s * 1e9 / (double)x.triangles;
    printf("%-16s %9llu %9.2f %8.1f | %5u %9zu %8.3f %8.3f %7.1f | %6.1fx %6.1fx%s\n", pc.name,
           pc.triangles, pc.median_s * 1e3, peer_ns, depth, x.triangles, x.mesh.median_s * 1e3,
           x.pipeline.median_s * 1e3, mesh_ns, peer_ns / mesh_ns, peer_ns / pipe_ns,
           pc.wrapped ? " *" : "");
    if (!sum->compared || peer_ns / mesh_ns < sum->min_mesh_ratio)
        sum->min_mesh_ratio = peer_ns / mesh_ns;
    if (!sum->compared || peer_ns / pipe_ns < sum->min_pipeline_ratio)
        sum->min_pipeline_ratio = peer_ns / pipe_ns;
    sum->any_wrapped |= pc.wrapped;
    ++sum->compared;
}

static peer_summary bench_peer(const options *o, const xyl_grammar *g)
{
    peer_summary sum = {0, 0.0, 0.0, false, 0};
    printf("\n== peer: ez-tree (node), same run, a step at a time; xylem tree of the nearest "
           "triangle count, measured right after ==\n");
    char script[MAX_PATH_LEN], why[256];
    if (!find_script(o, PEER_SCRIPT, script, sizeof script)) {
        printf("%s (no %s)\n", PEER_HINT, PEER_SCRIPT);
        return sum;
    }
    unsigned steps = 0;
    const char *const args[] = {"--steps", NULL};
    run_peer(o, script, args, NULL, 0, &steps, why, sizeof why);
    if (!steps) {
        printf("%s (%s)\n", PEER_HINT, why);
        return sum;
    }
    if (o->quick && steps > 2) steps = 2; /* --quick: the two smallest steps */
    tri_counts tc;
    memset(&tc, 0, sizeof tc);
    for (unsigned i = 0; i < steps; ++i) peer_row(o, g, script, i, &tc, &sum);
    if (!sum.compared) return sum;
    printf("ratio = ez-tree ns per branch triangle / xylem ns per output triangle "
           "(mesh: xyl_stems_build alone; pipe: derive + turtle + mesh)\n");
    if (sum.any_wrapped)
        printf("* ez-tree's Uint16 indices wrap at this size: the mesh three.js would draw is "
               "not the one it built (docs/peer-eztree.md)\n");
    return sum;
}

/* ---- main ---------------------------------------------------------------------------------- */

static void print_vertex_target(const options *o, const uint32_t *depths, size_t n,
                                const size_result *by_depth)
{
    double lo = 0.0, hi = 0.0;
    size_t lo_seg = 0;
    for (size_t i = 0; i < n; ++i) {
        const size_result *res = &by_depth[depths[i]];
        if (!res->ok) continue;
        double v = rate((double)res->vertices, res->mesh.median_s);
        if (lo == 0.0 || v < lo) {
            lo = v;
            lo_seg = res->segments;
        }
        if (v > hi) hi = v;
    }
    if (lo == 0.0) {
        printf(">= %.0e output vertices/s per core: not measured\n", TARGET_VERTEX_RATE);
        return;
    }
    printf(">= %.0e output vertices/s per core (xyl_stems_build, k = 4): %s (%.2f .. %.2f M/s "
           "over the ladder, lowest at %zu segments)%s\n", TARGET_VERTEX_RATE,
           lo >= TARGET_VERTEX_RATE   ? "MET"
           : hi >= TARGET_VERTEX_RATE ? "NOT MET (met at some sizes only)"
                                      : "NOT MET",
           lo / 1e6, hi / 1e6, lo_seg, o->quick ? " [--quick sizes]" : "");
}

static void print_targets(const options *o, const uint32_t *depths, size_t n,
                          const size_result *by_depth, const peer_summary *peer,
                          double subdivision_ratio, double lod_ratio)
{
    printf("\n== targets ==\n");
    for (int pipe = 0; pipe < 2; ++pipe) {
        const char *stage = pipe ? "full pipeline" : "mesh only";
        double ratio = pipe ? peer->min_pipeline_ratio : peer->min_mesh_ratio;
        printf(">= %.0fx ez-tree per output triangle (%s): ", TARGET_PEER_RATIO, stage);
        if (!o->peer) printf("not measured (--no-peer)\n");
        else if (!peer->compared) printf("not measured\n");
        else printf("%s (lowest ratio %.1fx over %d cases)%s\n",
                    ratio >= TARGET_PEER_RATIO ? "MET" : "NOT MET", ratio, peer->compared,
                    o->quick ? " [--quick sizes]" : "");
    }
    print_vertex_target(o, depths, n, by_depth);
    printf("<= %.0fx the plain mesh for Catmull-Clark and Loop pre-subdivision (depth >= %d): ",
           TARGET_SUBDIVISION_RATIO, SUBDIVISION_TARGET_DEPTH);
    if (subdivision_ratio == 0.0) printf("not measured%s\n", o->quick ? " [--quick sizes]" : "");
    else printf("%s (highest %.1fx)\n", subdivision_ratio <= TARGET_SUBDIVISION_RATIO ? "MET"
                                                                                : "NOT MET",
                subdivision_ratio);
    printf("<= %.0fx the finest mesh for the whole stem LOD chain: ",
           TARGET_LOD_RATIO);
    if (lod_ratio == 0.0) printf("not measured\n");
    else printf("%s (highest %.2fx)%s\n", lod_ratio <= TARGET_LOD_RATIO ? "MET" : "NOT MET",
                lod_ratio, o->quick ? " [--quick sizes]" : "");
}

int main(int argc, char **argv)
{
    options o = {0};
    int rc = bench_parse_options(argc, argv, &o, "bench_stems");
    if (rc) return rc == 1 ? 0 : rc;

    printf("bench_stems: xylem %d.%d.%d, %s build, median of %d samples (at most %d above %u "
           "segments)%s\n", XYL_VERSION_MAJOR, XYL_VERSION_MINOR, XYL_VERSION_PATCH,
#ifdef NDEBUG
           "optimised (NDEBUG)",
#else
           "assertions-on",
#endif
           o.repeats, LARGE_REPEATS, LARGE_SEGMENTS, o.quick ? ", --quick sizes" : "");

    const uint32_t *depths = o.quick ? ladder_quick : ladder_full;
    size_t n = o.quick ? sizeof ladder_quick / sizeof *ladder_quick
                       : sizeof ladder_full / sizeof *ladder_full;
    xyl_diag diag = {0};
    xyl_grammar *g = NULL;
    xyl_grammar_desc gd = {0};
    gd.source = tree_source;
    xyl_result r = xyl_grammar_parse(&gd, &g, &diag);
    if (r) {
        report_error("grammar", r, &diag);
        return 1;
    }
    size_result by_depth[MAX_DEPTH + 1];
    memset(by_depth, 0, sizeof by_depth);
    int failures = bench_skeletons(g, depths, n);
    failures += bench_ladder(&o, g, depths, n, by_depth);
    print_linearity(depths, n, by_depth);
    double subdivision_ratio = 0.0;
    failures += bench_subdivision(&o, g, depths, n, by_depth, &subdivision_ratio);
    failures += bench_variants(&o, g, o.quick ? MIDDLE_QUICK : MIDDLE_FULL);
    double lod_ratio = 0.0;
    failures += bench_lods(&o, g, depths[n - 1], o.quick ? MIDDLE_QUICK : MIDDLE_FULL, &lod_ratio);
    bench_pipeline(depths, n, by_depth);

    peer_summary peer = {0, 0.0, 0.0, false, 0};
    if (o.peer) peer = bench_peer(&o, g);
    else printf("\n== peer: skipped (--no-peer) ==\n");
    failures += peer.failures;

    print_targets(&o, depths, n, by_depth, &peer, subdivision_ratio, lod_ratio);
    xyl_grammar_destroy(g);
    if (failures) printf("\n%d failure(s)\n", failures);
    return failures ? 1 : 0;
}

/* bench_foliage's comparison with meshoptimizer (foliage_peer.h).
 *
 * The same leaves go to both: to xyl_foliage_build as leaves, to meshoptimizer as two triangles
 * a leaf (4 vertices, none shared, as a glTF export draws them). For each row a fraction of the
 * leaves is kept: xylem's LOD with that many leaves, and meshopt_simplify and
 * meshopt_simplifySloppy asked for the same triangle count (target_error 1, the whole mesh, so
 * only the count stops them). All three are judged against the full leaves by the same
 * measure, from the 20 dodecahedron views at the resolution at which xyl_foliage_pick (1080 px,
 * 0.8 rad, 0.5 px) starts to use the LOD, and by the Hausdorff distance sampled every 1/128 of
 * the crown's radius. A simplifier that stops short of the count (more than 5 % over it) has no
 * error at that count and is left out of the best. */
#define _POSIX_C_SOURCE 200809L

#include "foliage_peer.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_common.h"

#if defined(XYL_HAVE_MESHOPTIMIZER)
#include <meshoptimizer.h>
#endif

#define MIN_RESOLUTION 16
#define MAX_RESOLUTION 1024
/* The scene's range: an eye 2 to 64 crown radii from the crown's centre. */
#define NEAR_RADII 2.0
#define FAR_RADII 64.0
#define VIEW_HEIGHT 1080.0
#define VIEW_FOVY 0.8
#define BUDGET_PX 0.5

typedef struct measured {
    size_t triangles;
    double seconds;
    xyl_foliage_image_error e;
    bool ok; /* reached the count and was measured */
} measured;

static void print_measured(const measured *m)
{
    if (m->ok)
        printf(" %8zu %8.4f %7.4f %8.3g", m->triangles, m->e.rmse_mean, m->e.coverage_mean, m->e.hausdorff);
    else if (m->triangles)
        printf(" %8zu %8s %7s %8s", m->triangles, "short", "-", "-");
    else
        printf(" %8s %8s %7s %8s", "-", "-", "-", "-");
}

#if defined(XYL_HAVE_MESHOPTIMIZER)
/* Runs one simplifier for target triangles and measures what it gives. */
static int peer_run(bool sloppy, const float *pos, size_t vertices, const uint32_t *idx, size_t triangles,
                    size_t target, const xyl_leaf *leaves, size_t n, const xyl_foliage_image_desc *d,
                    uint32_t *scratch, measured *m)
{
    memset(m, 0, sizeof *m);
    double t0 = now_s();
    size_t got = sloppy ? meshopt_simplifySloppy(scratch, idx, 3 * triangles, pos, vertices, 3 * sizeof(float),
                                                 3 * target, 1.0f, NULL)
                        : meshopt_simplify(scratch, idx, 3 * triangles, pos, vertices, 3 * sizeof(float),
                                           3 * target, 1.0f, 0, NULL);
    m->seconds = now_s() - t0;
    m->triangles = got / 3;
    if ((double)m->triangles > 1.05 * (double)target) return 0; /* stopped short */
    xyl_diag diag = {0};
    xyl_result r = xyl_foliage_image_error_triangles(leaves, n, pos, vertices, scratch, m->triangles, d, &m->e, &diag);
    if (r) {
        report_error(sloppy ? "meshopt_simplifySloppy" : "meshopt_simplify", r, &diag);
        return 1;
    }
    m->ok = true;
    return 0;
}
#endif

/* Two triangles a leaf, corners as xyl_leaf defines them. */
static bool leaves_as_triangles(const xyl_leaf *l, size_t n, float **pos, uint32_t **idx)
{
    *pos = malloc(12 * n * sizeof **pos);
    *idx = malloc(6 * n * sizeof **idx);
    if (!*pos || !*idx) return false;
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 4; ++k) {
            double s = k & 1 ? 1.0 : -1.0, t = k & 2 ? 1.0 : -1.0;
            (*pos)[12 * i + 3 * k] = (float)(l[i].center.x + s * l[i].side.x + t * l[i].axis.x);
            (*pos)[12 * i + 3 * k + 1] = (float)(l[i].center.y + s * l[i].side.y + t * l[i].axis.y);
            (*pos)[12 * i + 3 * k + 2] = (float)(l[i].center.z + s * l[i].side.z + t * l[i].axis.z);
        }
        static const uint32_t quad[6] = {0, 1, 3, 0, 3, 2};
        for (int k = 0; k < 6; ++k) (*idx)[6 * i + k] = (uint32_t)(4 * i) + quad[k];
    }
    return true;
}

int bench_foliage_peer(const char *name, const xyl_leaf *leaves, size_t n, bool quick, FILE *dat,
                       peer_summary *summary)
{
    static const double fractions[] = {0.5, 0.2, 0.1, 0.05, 0.02, 0.01};
    memset(summary, 0, sizeof *summary);
    xyl_diag diag = {0};
    xyl_foliage_desc fd = {0};
    fd.leaves = leaves;
    fd.leaf_count = n;
    xyl_foliage *f = NULL;
    double t0 = now_s();
    xyl_result r = xyl_foliage_build(&fd, &f, &diag);
    double chain_s = now_s() - t0;
    if (r) {
        report_error(name, r, &diag);
        return 1;
    }
    float *pos = NULL;
    uint32_t *idx = NULL, *scratch = malloc(6 * (n ? n : 1) * sizeof *scratch);
    xyl_leaf *lod_leaves = malloc((n ? n : 1) * sizeof *lod_leaves);
    int failures = 0;
    if (!scratch || !lod_leaves || !leaves_as_triangles(leaves, n, &pos, &idx)) {
        fprintf(stderr, "%s: out of memory\n", name);
        failures = 1;
        goto done;
    }
    char peer[64];
#if defined(XYL_HAVE_MESHOPTIMIZER)
    summary->measured = true;
    snprintf(peer, sizeof peer, "meshoptimizer %d.%d", MESHOPTIMIZER_VERSION / 1000,
             MESHOPTIMIZER_VERSION % 1000 / 10);
#else
    snprintf(peer, sizeof peer, "meshoptimizer not built in");
#endif
    printf("\n== %s: %zu leaves, chain %.3f s; image error against meshoptimizer at equal "
           "triangle count (%s) ==\n", name, n, chain_s, peer);
    printf("%6s %7s %8s %6s %6s | %-34s | %-34s | %-34s | %6s\n", "kept", "leaves", "radii", "res",
           "ms", "xylem: tris  rmse    cover   hausd", "simplify: tris  rmse  cover  hausd",
           "sloppy: tris  rmse   cover   hausd", "ratio");
    char tag[64]; /* the name as one word, for the dat file's first column */
    snprintf(tag, sizeof tag, "%s", name);
    for (char *c = tag; *c; ++c)
        if (*c == ' ') *c = '-';
    const xyl_foliage_sector *s = &f->sectors[0];
    size_t rows = quick ? 3 : sizeof fractions / sizeof *fractions;
    for (size_t k = 0; k < rows; ++k) {
        size_t keep = (size_t)ceil(fractions[k] * (double)n);
        size_t floor_keep = n - s->merged_count;
        if (keep < floor_keep) keep = floor_keep;
        uint32_t lod = (uint32_t)(n - keep);
        size_t count = 0;
        r = xyl_foliage_gather(f, &lod, 1, lod_leaves, n, &count, &diag);
        uint32_t res = 0;
        if (r == XYL_OK) r = xyl_foliage_lod_resolution(f, 0, lod, BUDGET_PX, &res, &diag);
        if (r) {
            report_error(name, r, &diag);
            failures = 1;
            break;
        }
        /* where the pick starts to use the LOD: a pixel of error / budget world units */
        double pixel = (double)s->lods[lod].error / BUDGET_PX;
        double radii = 1.0 + pixel * VIEW_HEIGHT / (2.0 * tan(0.5 * VIEW_FOVY)) / f->radius;
        bool in_range = radii >= NEAR_RADII && radii <= FAR_RADII;
        uint32_t used = res < MIN_RESOLUTION ? MIN_RESOLUTION : res > MAX_RESOLUTION ? MAX_RESOLUTION : res;
        xyl_foliage_image_desc d = {0};
        d.resolution = used;
        d.hausdorff_step = f->radius / 128.0f;
        measured ours, simple, sloppy;
        memset(&ours, 0, sizeof ours), memset(&simple, 0, sizeof simple), memset(&sloppy, 0, sizeof sloppy);
        ours.triangles = 2 * count;
        r = xyl_foliage_image_error_of(leaves, n, lod_leaves, count, &d, &ours.e, &diag);
        if (r) {
            report_error(name, r, &diag);
            failures = 1;
            break;
        }
        ours.ok = true;
#if defined(XYL_HAVE_MESHOPTIMIZER)
        if (peer_run(false, pos, 4 * n, idx, 2 * n, 2 * count, leaves, n, &d, scratch, &simple) ||
            peer_run(true, pos, 4 * n, idx, 2 * n, 2 * count, leaves, n, &d, scratch, &sloppy)) {
            failures = 1;
            break;
        }
#endif
        double best = INFINITY;
        if (simple.ok) best = fmin(best, simple.e.rmse_mean);
        if (sloppy.ok) best = fmin(best, sloppy.e.rmse_mean);
        double ratio = best > 0.0 ? ours.e.rmse_mean / best : INFINITY;
        printf("%5.0f%% %7zu %7.1f%s %6u %6.1f |", 100.0 * fractions[k], count, radii, in_range ? "*" : " ",
               used, 1e3 * (simple.seconds + sloppy.seconds));
        print_measured(&ours);
        printf("  |");
        print_measured(&simple);
        printf("  |");
        print_measured(&sloppy);
        if (isfinite(ratio)) printf("  | %6.3f\n", ratio);
        else printf("  | %6s\n", "-");
        summary->in_range += in_range;
        if (isfinite(ratio)) {
            summary->rows++;
            summary->rows_met += ratio <= 0.5;
            summary->worst_ratio = fmax(summary->worst_ratio, ratio);
            summary->best_ratio = summary->rows == 1 ? ratio : fmin(summary->best_ratio, ratio);
        }
        if (dat)
            fprintf(dat, "%s %zu %zu %g %u %zu %.6g %.6g %zu %.6g %.6g %zu %.6g %.6g\n", tag, n, count, radii,
                    used, ours.triangles, ours.e.rmse_mean, ours.e.coverage_mean, simple.ok ? simple.triangles : 0,
                    simple.ok ? simple.e.rmse_mean : -1.0, simple.ok ? simple.e.coverage_mean : -1.0,
                    sloppy.ok ? sloppy.triangles : 0, sloppy.ok ? sloppy.e.rmse_mean : -1.0,
                    sloppy.ok ? sloppy.e.coverage_mean : -1.0);
    }
    printf("kept: the fraction of the leaves; radii: eye distance from the crown's centre, in crown "
           "radii, at which the pick starts to use the LOD (* in the scene's range, %.0f-%.0f); res: "
           "the views' resolution there (clamped to %d-%d); ms: meshoptimizer's two calls; rmse and "
           "cover: mean over the 20 views; hausd: world units; ratio: xylem's RMSE / meshoptimizer's "
           "best; short: stopped above the count\n", NEAR_RADII, FAR_RADII, MIN_RESOLUTION, MAX_RESOLUTION);
done:
    free(pos);
    free(idx);
    free(scratch);
    free(lod_leaves);
    xyl_foliage_destroy(f);
    return failures;
}

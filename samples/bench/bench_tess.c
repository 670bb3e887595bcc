/* bench_tess: speed against error of PN tessellation (docs/BENCHMARKS.md, "Tessellation").
 *
 * For ring sides k, pre-subdivision, handle variant and level: the triangles drawn for the
 * default tree, the geometric error of the refined surface against the skeleton's generalized
 * cylinder (max and RMS radial error in % of the radius, normal error in degrees) measured on a
 * curved test branch away from its caps, and the median wall time per frame (render and
 * readback of a size x size image) on each backend and path. Then the Pareto front: for each
 * error target the cheapest configuration.
 *
 * usage: bench_tess [--quick] [--no-gpu] [--frames N] [--size PX] [--dat FILE]
 *                   [--budget E]
 *   --dat FILE writes every row to FILE and the Pareto front to FILE.front (scripts/plot_tess.gp
 *   plots both). --budget E prints the budget rows instead (CPU only): for the default tree and
 *   two leafy presets' stems at three camera distances, fixed k = 4 with adaptive levels at E px
 *   against one budget of E px choosing pruning, ring sides and levels (budget_rows). */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_common.h"
#include <xylem/xyl_lsystem.h>
#include <xylem/xyl_stems.h>
#include <xylem/xyl_tess_gl.h>
#ifdef XYL_HAVE_VULKAN
#include <xylem/xyl_tess_vk.h> /* needs <vulkan/vulkan.h> */
#endif
#include <xylem/xyl_tessellate.h>

#define PI 3.14159265358979323846

typedef struct bench_opts {
    bool quick, gpu;
    int frames;
    uint32_t size;
    const char *dat;
    uint32_t sides[8], nsides;  /* --sides: ring sides to run; default 3, 4, 6, 8 */
    double max_triangles;       /* --max-triangles: configurations above it are skipped */
    double budget_px;           /* --budget E: the budget rows alone */
} bench_opts;

typedef struct row {
    uint32_t k, subdiv, variant, level;
    uint64_t triangles;
    double max_err, rms_err, max_normal_deg; /* % of radius, degrees */
    double ms[3];                              /* GL instanced, GL hardware, Vulkan; < 0: none */
} row;

static const char *subdiv_name[] = {"none", "catmark", "loop"};
static const char *variant_name[] = {"pn", "rounded", "circle", "arc"};
static const char *path_name[] = {"gl-instanced", "gl-hardware", "vk-instanced"};

static void die(const char *what, xyl_result r, const xyl_diag *d)
{
    fprintf(stderr, "bench_tess: %s: %s: %s\n", what, xyl_result_string(r), d ? d->message : "");
    exit(1);
}

/* ---- test skeletons ------------------------------------------------------------------------ */

/* A curved branch of constant radius: 25 nodes a unit apart, turning 4 degrees per node in a
 * plane that slowly twists. Its generalized cylinder is the sweep of the radius along it. */
#define ARC_NODES 25
#define ARC_RADIUS 0.25f

static xyl_skeleton *arc_skeleton(void)
{
    xyl_skel_node n[ARC_NODES];
    memset(n, 0, sizeof n);
    double p[3] = {0, 0, 0}, h = 0.0;
    for (int i = 0; i < ARC_NODES; ++i) {
        n[i].pos = (xyl_vec3){(float)p[0], (float)p[1], (float)p[2]};
        n[i].radius = ARC_RADIUS;
        n[i].parent = i - 1;
        double tw = 0.05 * i;
        p[0] += sin(h) * cos(tw);
        p[1] += cos(h);
        p[2] += sin(h) * sin(tw);
        h += 4.0 * PI / 180.0;
    }
    xyl_skeleton_desc sd = {0};
    sd.nodes = n;
    sd.node_count = ARC_NODES;
    xyl_skeleton *sk = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_skeleton_create(&sd, &sk, &d);
    if (r) die("arc skeleton", r, &d);
    return sk;
}

static xyl_skeleton *preset_tree(const char *name)
{
    xyl_grammar_desc gd = {0};
    gd.source = xyl_lsystem_preset_source(name);
    xyl_grammar *g = NULL;
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_grammar_parse(&gd, &g, &d);
    if (!r) r = xyl_lsystem_derive(g, NULL, &s, &d);
    if (!r) r = xyl_lsystem_interpret(g, s, NULL, &sk, &d);
    if (r) die(name, r, &d);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return sk;
}

static xyl_skeleton *default_tree(void)
{
    return preset_tree(xyl_lsystem_default_preset());
}

static xyl_mesh *mesh_of(const xyl_skeleton *sk, uint32_t k, uint32_t subdiv)
{
    xyl_stems_desc sd = {0};
    sd.sides = k;
    sd.subdivision = (xyl_subdivision)subdiv;
    xyl_mesh *m = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_stems_build(sk, &sd, &m, NULL, &d);
    if (r == XYL_ERR_UNSUPPORTED && subdiv) return NULL; /* a build without OpenSubdiv */
    if (r) die("stems", r, &d);
    return m;
}

/* ---- error against the generalized cylinder -------------------------------------------------- */

typedef struct err_acc {
    double max, sum2, max_normal;
    size_t n;
} err_acc;

/* The arc's reference tube is the sweep of its radius along a SMOOTH centreline through the
 * nodes (a uniform Catmull-Rom spline, sampled CENTRE_STEPS times per segment), not along the
 * node polyline: the mesher's rings sit at the nodes of a branch meant to be smooth, and a
 * polyline tube would count the sagitta between the nodes (L^2 / 8R = 3.5 % of the radius
 * here) as error. Two smooth curves through the same nodes differ by O(h^4) terms, far below
 * the figures reported. */
#define CENTRE_STEPS 128
#define CENTRE_SAMPLES ((ARC_NODES - 1) * CENTRE_STEPS + 1)

static double centre[CENTRE_SAMPLES][3];

static void arc_centreline(const xyl_skeleton *sk)
{
    const size_t n = sk->node_count;
    for (size_t s = 0; s + 1 < n; ++s) {
        double q[4][3];
        for (int c = 0; c < 4; ++c) {
            /* end tangents from reflected nodes */
            long i = (long)s - 1 + c;
            const xyl_vec3 a = sk->nodes[i < 0 ? 0 : (i >= (long)n ? n - 1 : (size_t)i)].pos;
            q[c][0] = a.x, q[c][1] = a.y, q[c][2] = a.z;
            if (i < 0 || i >= (long)n) {
                const xyl_vec3 b = sk->nodes[i < 0 ? 1 : n - 2].pos;
                q[c][0] = 2 * a.x - b.x, q[c][1] = 2 * a.y - b.y, q[c][2] = 2 * a.z - b.z;
            }
        }
        for (int j = 0; j <= CENTRE_STEPS; ++j) {
            double t = (double)j / CENTRE_STEPS, t2 = t * t, t3 = t2 * t;
            double w[4] = {-0.5 * t3 + t2 - 0.5 * t, 1.5 * t3 - 2.5 * t2 + 1, -1.5 * t3 + 2 * t2 + 0.5 * t,
                           0.5 * t3 - 0.5 * t2};
            for (int c = 0; c < 3; ++c)
                centre[s * CENTRE_STEPS + (size_t)j][c] =
                    w[0] * q[0][c] + w[1] * q[1][c] + w[2] * q[2][c] + w[3] * q[3][c];
        }
    }
}

/* Distance from p to the centreline's sample segment [i, i + 1], with the radial direction
 * and the parameter along the segment. */
static double segment_distance(const float p[3], size_t i, double dir[3], double *t_out)
{
    const double *a = centre[i], *b = centre[i + 1];
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    double t = (w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    double q[3] = {w[0] - t * d[0], w[1] - t * d[1], w[2] - t * d[2]};
    double dist = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    for (int c = 0; c < 3; ++c) dir[c] = q[c] / (dist > 0 ? dist : 1);
    *t_out = t;
    return dist;
}

/* Radial error (fraction of the radius) of p against the reference tube, with the radial
 * direction; false within 2.5 node spacings of the ends, where caps (and after subdivision
 * their rounding) make the tube no cylinder. The nearest node segment is found first, then the
 * nearest sample segment in it and its neighbours. */
static bool arc_error(const xyl_skeleton *sk, const float p[3], double *err, double dir[3])
{
    size_t seg = 0;
    double best = INFINITY, t = 0.0;
    for (size_t s = 0; s + 1 < sk->node_count; ++s) {
        double d = segment_distance(p, s * CENTRE_STEPS, dir, &t) +
                   segment_distance(p, (s + 1) * CENTRE_STEPS - 1, dir, &t);
        if (d < best) best = d, seg = s;
    }
    size_t lo = seg ? (seg - 1) * CENTRE_STEPS : 0;
    size_t hi = (seg + 2 < sk->node_count ? seg + 2 : sk->node_count - 1) * CENTRE_STEPS;
    best = INFINITY;
    double along = 0.0, d3[3];
    for (size_t i = lo; i < hi; ++i) {
        double dd = segment_distance(p, i, d3, &t);
        if (dd < best) {
            best = dd;
            along = ((double)i + t) / CENTRE_STEPS;
            memcpy(dir, d3, sizeof d3);
        }
    }
    if (along < 2.5 || along > (double)(sk->node_count - 1) - 2.5) return false;
    *err = (best - ARC_RADIUS) / ARC_RADIUS;
    return true;
}

static void add_point(err_acc *a, const xyl_skeleton *sk, const float p[3], const float *n)
{
    double e, dir[3];
    if (!arc_error(sk, p, &e, dir)) return;
    a->max = fmax(a->max, fabs(e));
    a->sum2 += e * e;
    a->n++;
    if (n) {
        double c = (n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2]);
        c = c > 1 ? 1 : (c < -1 ? -1 : c);
        a->max_normal = fmax(a->max_normal, acos(c) * 180.0 / PI);
    }
}

/* Every refined vertex (position and normal), and inside every flat triangle the centroid and
 * edge midpoints: what the rasterizer shows between vertices. */
static void measure(const xyl_skeleton *sk, const xyl_mesh *refined, err_acc *a)
{
    for (size_t v = 0; v < refined->vertex_count; ++v) {
        xyl_vec3 pv = refined->positions[v], nv = refined->normals[v];
        const float p[3] = {pv.x, pv.y, pv.z}, n[3] = {nv.x, nv.y, nv.z};
        add_point(a, sk, p, n);
    }
    static const float w[4][3] = {{1 / 3.f, 1 / 3.f, 1 / 3.f}, {.5f, .5f, 0}, {0, .5f, .5f}, {.5f, 0, .5f}};
    for (size_t t = 0; t < refined->triangle_count; ++t) {
        float c[3][3];
        for (int i = 0; i < 3; ++i) {
            xyl_vec3 q = refined->positions[refined->triangles[3 * t + (size_t)i]];
            c[i][0] = q.x; c[i][1] = q.y; c[i][2] = q.z;
        }
        for (int s = 0; s < 4; ++s) {
            float p[3];
            for (int k = 0; k < 3; ++k) p[k] = w[s][0] * c[0][k] + w[s][1] * c[1][k] + w[s][2] * c[2][k];
            add_point(a, sk, p, NULL);
        }
    }
}

static void refine_fixed(const xyl_mesh *m, uint32_t variant, uint32_t level,
                         const xyl_tess_patterns *pat, xyl_tess_patches **tp,
                         xyl_tess_batches *b, xyl_mesh **refined)
{
    xyl_tess_patches_desc pd = {0};
    pd.variant = (xyl_tess_variant)variant;
    xyl_diag d = {0};
    xyl_result r = xyl_tess_patches_create(m, &pd, tp, &d);
    xyl_tess_view view = {0};
    view.fixed_level = level;
    if (!r) r = xyl_tess_select(*tp, pat, &view, b, &d);
    if (!r && refined) r = xyl_tess_refine(*tp, pat, b, NULL, NULL, refined, &d);
    if (r) die("tessellate", r, &d);
}

/* ---- GPU timing ------------------------------------------------------------------------------ */

typedef struct gpu {
    xyl_gl_context *ctx;
    xyl_tess_gl *gl;
#ifdef XYL_HAVE_VULKAN
    xyl_tess_vk *vk;
#endif
    uint8_t *rgba;
} gpu;

#if defined(XYL_HAVE_GL) && defined(XYL_HAVE_VULKAN)
#define HAVE_GPU 1

/* Median wall milliseconds of `frames` renders of the tree through one backend and path. */
static double time_path(gpu *g, int path, const xyl_tess_patches *tp, const xyl_tess_batches *b,
                        const xyl_tess_camera *cam, uint32_t variant, const bench_opts *o)
{
    xyl_tess_frame f;
    memset(&f, 0, sizeof f);
    f.variant = variant;
    f.light_dir[1] = 1.0f;
    f.color[0] = f.color[1] = f.color[2] = 0.5f;
    xyl_tess_image_desc img = {0};
    img.width = img.height = o->size;
    xyl_diag d = {0};
    xyl_result r = xyl_tess_camera_matrix(cam, path == 2 ? XYL_TESS_CLIP_VULKAN : XYL_TESS_CLIP_GL,
                                          f.view_proj, &d);
    if (!r) r = path == 2 ? xyl_tess_vk_set_patches(g->vk, tp, &d) : xyl_tess_gl_set_patches(g->gl, tp, &d);
    if (r) die("upload", r, &d);
    double ms[MAX_SAMPLES];
    int n = o->frames < MAX_SAMPLES ? o->frames : MAX_SAMPLES;
    /* one warm-up frame (pipeline compiles, first uploads), then wall time per frame: a CPU
     * rasterizer's timer queries do not see the deferred rasterization, so the figure is the
     * whole render_rgba call, readback included (the same for every path). */
    for (int i = -1; i < n; ++i) {
        double t0 = now_s();
        r = path == 2 ? xyl_tess_vk_render_rgba(g->vk, b, &f, &img, g->rgba, &d)
                      : xyl_tess_gl_render_rgba(g->gl, b, &f, (xyl_tess_path)path, &img, g->rgba, &d);
        if (r) die(path_name[path], r, &d);
        if (i >= 0) ms[i] = (now_s() - t0) * 1e3;
    }
    return median_of(ms, n);
}

static void gpu_open(gpu *g, const xyl_tess_patterns *pat, const bench_opts *o)
{
    xyl_diag d = {0};
    xyl_result r = xyl_gl_context_create_headless(NULL, &g->ctx, &d);
    if (!r) r = xyl_tess_gl_create(NULL, pat, &g->gl, &d);
    if (r) die("GL backend", r, &d);
    xyl_tess_vk_desc vd = {0};
    r = xyl_tess_vk_create(&vd, pat, &g->vk, &d);
    if (r) die("Vulkan backend", r, &d);
    g->rgba = malloc((size_t)o->size * o->size * 4);
    printf("GPU: GL %s; Vulkan %s\n", xyl_gl_context_renderer(g->ctx), xyl_tess_vk_device_name(g->vk));
}

static void gpu_close(gpu *g)
{
    xyl_tess_vk_destroy(g->vk);
    xyl_tess_gl_destroy(g->gl);
    xyl_gl_context_destroy(g->ctx);
    free(g->rgba);
}

#else
#define HAVE_GPU 0
static double time_path(gpu *g, int path, const xyl_tess_patches *tp, const xyl_tess_batches *b,
                        const xyl_tess_camera *cam, uint32_t variant, const bench_opts *o)
{
    (void)g, (void)path, (void)tp, (void)b, (void)cam, (void)variant, (void)o;
    return -1.0;
}
static void gpu_open(gpu *g, const xyl_tess_patterns *pat, const bench_opts *o)
{
    (void)g, (void)pat, (void)o;
}
static void gpu_close(gpu *g) { (void)g; }
#endif

/* ---- table ----------------------------------------------------------------------------------- */

static void run_config(row *rw, const xyl_skeleton *arc, const xyl_mesh *arc_mesh,
                       const xyl_mesh *tree_mesh, const xyl_tess_patterns *pat, gpu *g,
                       const xyl_tess_camera *cam, const bench_opts *o)
{
    xyl_tess_patches *tp = NULL;
    xyl_tess_batches *b = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_tess_batches_create(NULL, &b, &d);
    if (r) die("batches", r, &d);
    xyl_mesh *refined = NULL;
    refine_fixed(arc_mesh, rw->variant, rw->level, pat, &tp, b, &refined);
    err_acc a = {0};
    measure(arc, refined, &a);
    rw->max_err = 100.0 * a.max;
    rw->rms_err = a.n ? 100.0 * sqrt(a.sum2 / (double)a.n) : 0.0;
    rw->max_normal_deg = a.max_normal;
    xyl_mesh_destroy(refined);
    xyl_tess_patches_destroy(tp);
    tp = NULL;
    refine_fixed(tree_mesh, rw->variant, rw->level, pat, &tp, b, NULL);
    rw->triangles = b->triangles;
    for (int p = 0; p < 3; ++p) rw->ms[p] = -1.0;
    /* The variants differ only in the handle rule (a square root and a division more for
     * circle): pn is timed at every level, the others at level 8 to show that difference;
     * and only what a CPU rasterizer draws in seconds rather than minutes. */
    bool timed = g && (rw->variant == XYL_TESS_PN || rw->level == 8) &&
                 (rw->k == 4 || !o->quick) && rw->triangles <= 8000000u;
    for (int p = 0; timed && p < 3; ++p) rw->ms[p] = time_path(g, p, tp, b, cam, rw->variant, o);
    xyl_tess_batches_destroy(b);
    xyl_tess_patches_destroy(tp);
}

static void print_row(FILE *f, const row *r)
{
    fprintf(f, "| %u | %s | %s | %u | %llu | %.3f | %.3f | %.2f |", r->k, subdiv_name[r->subdiv],
            variant_name[r->variant], r->level, (unsigned long long)r->triangles, r->max_err,
            r->rms_err, r->max_normal_deg);
    for (int p = 0; p < 3; ++p)
        if (r->ms[p] >= 0) fprintf(f, " %.2f |", r->ms[p]);
        else fprintf(f, " |");
    fprintf(f, "\n");
}

/* For each error target: the configuration with the fewest triangles whose max error meets it. */
static void print_pareto(const row *rows, size_t n)
{
    static const double targets[] = {20, 10, 5, 2, 1, 0.5, 0.2, 0.1, 0.05};
    printf("\nPareto front (fewest triangles for the default tree meeting a max radial error):\n");
    printf("| max error <= %% | k | subdivision | variant | level | triangles | max %% | RMS %% |\n");
    printf("|---|---|---|---|---|---|---|---|\n");
    for (size_t t = 0; t < sizeof targets / sizeof targets[0]; ++t) {
        const row *best = NULL;
        for (size_t i = 0; i < n; ++i)
            if (rows[i].max_err <= targets[t] && (!best || rows[i].triangles < best->triangles))
                best = &rows[i];
        if (best)
            printf("| %.2f | %u | %s | %s | %u | %llu | %.3f | %.3f |\n", targets[t], best->k,
                   subdiv_name[best->subdiv], variant_name[best->variant], best->level,
                   (unsigned long long)best->triangles, best->max_err, best->rms_err);
        else
            printf("| %.2f | none | | | | | | |\n", targets[t]);
    }
}

static int by_triangles(const void *a, const void *b)
{
    const row *x = *(const row *const *)a, *y = *(const row *const *)b;
    if (x->triangles != y->triangles) return x->triangles < y->triangles ? -1 : 1;
    return (x->max_err > y->max_err) - (x->max_err < y->max_err);
}

/* The whole front: configurations that no cheaper one matches in max error, cheapest first;
 * printed, and written to `path` (triangles, max error %) for the plot when path is set. */
static int write_front(const row *rows, size_t n, const char *path)
{
    const row **order = malloc((n ? n : 1) * sizeof *order);
    if (!order) return 71;
    for (size_t i = 0; i < n; ++i) order[i] = &rows[i];
    qsort(order, n, sizeof *order, by_triangles);
    FILE *f = path ? fopen(path, "w") : NULL;
    if (path && !f) {
        perror(path);
        free(order);
        return 73;
    }
    printf("\nPareto front (no cheaper configuration has a lower max error):\n");
    printf("| triangles | max %% | RMS %% | k | subdivision | variant | level |\n|---|---|---|---|---|---|---|\n");
    double best = INFINITY;
    for (size_t i = 0; i < n; ++i) {
        const row *r = order[i];
        if (!(r->max_err < best)) continue;
        best = r->max_err;
        printf("| %llu | %.3f | %.3f | %u | %s | %s | %u |\n", (unsigned long long)r->triangles,
               r->max_err, r->rms_err, r->k, subdiv_name[r->subdiv], variant_name[r->variant],
               r->level);
        if (f) fprintf(f, "%llu %.6f\n", (unsigned long long)r->triangles, r->max_err);
    }
    free(order);
    if (f && fclose(f) != 0) {
        perror(path);
        return 73;
    }
    return 0;
}

/* ---- one budget for the whole tree (--budget E) ---------------------------------------------
 *
 * Screen-space error of a drawn stem surface against a reference surface, in pixels at each
 * point's own distance from the eye. The reference is the UNPRUNED tree meshed at k = 16 and
 * refined with the circle rule at a 16th of the budget (its own error: at most E / 16 px from
 * its limit surface, k = 16 rings 7e-8 r from round). The mesher's joints and tips are not the
 * same at every k (a lateral's bridge strip and a one-band twig's tip ring follow its k), and
 * that difference counts: it makes the max and the 99th percentile at the nearer distances
 * (docs/tessellation.md, "One budget for the whole tree"). Points: every refined vertex, and in every flat triangle
 * its centroid and edge midpoints; each one's error is its exact distance to the nearest
 * reference triangle (a uniform grid of the triangles, searched in growing shells). A node that
 * pruning removed counts once more with its projected width 2 r (the surface it had is gone). */

typedef struct ref_grid {
    const xyl_mesh *m;
    float lo[3], h; /* cell size */
    int g[3];
    uint32_t *start, *tri; /* CSR: the triangles overlapping each cell */
} ref_grid;

static int cell_of(const ref_grid *r, float x, int k)
{
    int c = (int)floorf((x - r->lo[k]) / r->h);
    return c < 0 ? 0 : (c >= r->g[k] ? r->g[k] - 1 : c);
}

static void ref_grid_build(ref_grid *r, const xyl_mesh *m)
{
    float hi[3];
    xyl_mesh_bounds(m, r->lo, hi);
    float ext = 0.0f;
    for (int k = 0; k < 3; ++k) ext = fmaxf(ext, hi[k] - r->lo[k]);
    r->m = m;
    r->h = ext / 200.0f;
    size_t cells = 1;
    for (int k = 0; k < 3; ++k) {
        r->g[k] = (int)((hi[k] - r->lo[k]) / r->h) + 1;
        cells *= (size_t)r->g[k];
    }
    r->start = calloc(cells + 1, sizeof *r->start);
    if (!r->start) die("grid", XYL_ERR_OUT_OF_MEMORY, NULL);
    for (int pass = 0; pass < 2; ++pass) {
        for (size_t t = 0; t < m->triangle_count; ++t) {
            int c0[3], c1[3];
            for (int k = 0; k < 3; ++k) {
                float mn = INFINITY, mx = -INFINITY;
                for (int i = 0; i < 3; ++i) {
                    const xyl_vec3 q = m->positions[m->triangles[3 * t + (size_t)i]];
                    float x = k == 0 ? q.x : (k == 1 ? q.y : q.z);
                    mn = fminf(mn, x), mx = fmaxf(mx, x);
                }
                c0[k] = cell_of(r, mn, k), c1[k] = cell_of(r, mx, k);
            }
            for (int z = c0[2]; z <= c1[2]; ++z)
                for (int y = c0[1]; y <= c1[1]; ++y)
                    for (int x = c0[0]; x <= c1[0]; ++x) {
                        size_t c = ((size_t)z * r->g[1] + (size_t)y) * r->g[0] + (size_t)x;
                        if (pass == 0) r->start[c + 1]++;
                        else r->tri[r->start[c]++] = (uint32_t)t;
                    }
        }
        if (pass == 0) {
            for (size_t c = 0; c < cells; ++c) r->start[c + 1] += r->start[c];
            r->tri = malloc((r->start[cells] ? r->start[cells] : 1) * sizeof *r->tri);
            if (!r->tri) die("grid", XYL_ERR_OUT_OF_MEMORY, NULL);
        } else { /* start[c] now holds the end of cell c: shift back */
            for (size_t c = cells; c > 0; --c) r->start[c] = r->start[c - 1];
            r->start[0] = 0;
        }
    }
}

/* Squared distance from p to triangle abc (Ericson, Real-Time Collision Detection, 5.1.5). */
static double point_triangle2(const double p[3], const double a[3], const double b[3],
                              const double c[3])
{
    double ab[3], ac[3], ap[3], q[3];
    for (int k = 0; k < 3; ++k) ab[k] = b[k] - a[k], ac[k] = c[k] - a[k], ap[k] = p[k] - a[k];
#define DOT(u, v) ((u)[0] * (v)[0] + (u)[1] * (v)[1] + (u)[2] * (v)[2])
    double d1 = DOT(ab, ap), d2 = DOT(ac, ap), v, w;
    double bp[3], cp[3];
    for (int k = 0; k < 3; ++k) bp[k] = p[k] - b[k], cp[k] = p[k] - c[k];
    double d3 = DOT(ab, bp), d4 = DOT(ac, bp), d5 = DOT(ab, cp), d6 = DOT(ac, cp);
    double va = d3 * d6 - d5 * d4, vb = d5 * d2 - d1 * d6, vc = d1 * d4 - d3 * d2;
#undef DOT
    if (d1 <= 0 && d2 <= 0) v = 0, w = 0;
    else if (d3 >= 0 && d4 <= d3) v = 1, w = 0;
    else if (d6 >= 0 && d5 <= d6) v = 0, w = 1;
    else if (vc <= 0 && d1 >= 0 && d3 <= 0) v = d1 / (d1 - d3), w = 0;
    else if (vb <= 0 && d2 >= 0 && d6 <= 0) v = 0, w = d2 / (d2 - d6);
    else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        v = 1 - w;
    } else {
        double den = 1 / (va + vb + vc);
        v = vb * den, w = vc * den;
    }
    double e2 = 0.0;
    for (int k = 0; k < 3; ++k) q[k] = a[k] + ab[k] * v + ac[k] * w - p[k], e2 += q[k] * q[k];
    return e2;
}

/* Distance from p to the nearest reference triangle: shells of cells around p's cell until the
 * best found is within the shell (a nearer triangle would overlap a cell already searched). */
static double ref_distance(const ref_grid *r, const float pf[3])
{
    const double p[3] = {pf[0], pf[1], pf[2]};
    int c[3];
    for (int k = 0; k < 3; ++k) c[k] = cell_of(r, pf[k], k);
    double best2 = INFINITY;
    int gmax = r->g[0] > r->g[1] ? r->g[0] : r->g[1];
    gmax = gmax > r->g[2] ? gmax : r->g[2];
    for (int s = 0; s <= gmax; ++s) {
        for (int z = c[2] - s; z <= c[2] + s; ++z)
            for (int y = c[1] - s; y <= c[1] + s; ++y)
                for (int x = c[0] - s; x <= c[0] + s; ++x) {
                    if (abs(z - c[2]) != s && abs(y - c[1]) != s && abs(x - c[0]) != s) continue;
                    if (x < 0 || y < 0 || z < 0 || x >= r->g[0] || y >= r->g[1] || z >= r->g[2])
                        continue;
                    size_t cell = ((size_t)z * r->g[1] + (size_t)y) * r->g[0] + (size_t)x;
                    for (uint32_t i = r->start[cell]; i < r->start[cell + 1]; ++i) {
                        const uint32_t *t = &r->m->triangles[3 * (size_t)r->tri[i]];
                        double v[3][3];
                        for (int j = 0; j < 3; ++j) {
                            const xyl_vec3 q = r->m->positions[t[j]];
                            v[j][0] = q.x, v[j][1] = q.y, v[j][2] = q.z;
                        }
                        double e2 = point_triangle2(p, v[0], v[1], v[2]);
                        if (e2 < best2) best2 = e2;
                    }
                }
        /* p lies in its clamped cell or outside the grid; anything not yet searched is at
         * least s cells (s h) from p's cell */
        double reach = (double)s * r->h;
        if (best2 <= reach * reach) break;
    }
    return sqrt(best2);
}

typedef struct screen_err {
    double max, sum2;
    size_t n, cap;
    double *v; /* every point's error, for the 99th percentile */
    float worst[3]; /* the drawn point of the largest error, and that error in world units */
    double worst_world;
    bool worst_pruned; /* the largest error is a pruned node's width */
} screen_err;

static void screen_add(screen_err *e, double px)
{
    if (e->n == e->cap) {
        e->cap = e->cap ? 2 * e->cap : 4096;
        e->v = realloc(e->v, e->cap * sizeof *e->v);
        if (!e->v) die("errors", XYL_ERR_OUT_OF_MEMORY, NULL);
    }
    e->v[e->n++] = px;
    e->max = fmax(e->max, px);
    e->sum2 += px * px;
}

/* The 99th percentile (nearest rank) and the RMS; frees the values. */
static void screen_finish(screen_err *e, double *p99, double *rms)
{
    qsort(e->v, e->n, sizeof *e->v, cmp_double);
    *p99 = e->n ? e->v[(size_t)ceil(0.99 * (double)e->n) - 1] : 0.0;
    *rms = e->n ? sqrt(e->sum2 / (double)e->n) : 0.0;
    free(e->v);
    e->v = NULL;
}

static void screen_point(screen_err *e, const ref_grid *ref, const float p[3], const float eye[3],
                         double per_distance)
{
    double dist = sqrt(((double)p[0] - eye[0]) * (p[0] - eye[0]) +
                       ((double)p[1] - eye[1]) * (p[1] - eye[1]) +
                       ((double)p[2] - eye[2]) * (p[2] - eye[2]));
    double world = ref_distance(ref, p), px = world / (dist * per_distance);
    if (px > e->max) {
        memcpy(e->worst, p, sizeof e->worst);
        e->worst_world = world;
        e->worst_pruned = false;
    }
    screen_add(e, px);
}

static void screen_mesh(screen_err *e, const ref_grid *ref, const xyl_mesh *m, const float eye[3],
                        double per_distance)
{
    for (size_t v = 0; v < m->vertex_count; ++v) {
        const float p[3] = {m->positions[v].x, m->positions[v].y, m->positions[v].z};
        screen_point(e, ref, p, eye, per_distance);
    }
    static const float w[4][3] = {{1 / 3.f, 1 / 3.f, 1 / 3.f}, {.5f, .5f, 0}, {0, .5f, .5f}, {.5f, 0, .5f}};
    for (size_t t = 0; t < m->triangle_count; ++t) {
        xyl_vec3 c[3];
        for (int i = 0; i < 3; ++i) c[i] = m->positions[m->triangles[3 * t + (size_t)i]];
        for (int s = 0; s < 4; ++s) {
            const float p[3] = {w[s][0] * c[0].x + w[s][1] * c[1].x + w[s][2] * c[2].x,
                                w[s][0] * c[0].y + w[s][1] * c[1].y + w[s][2] * c[2].y,
                                w[s][0] * c[0].z + w[s][1] * c[1].z + w[s][2] * c[2].z};
            screen_point(e, ref, p, eye, per_distance);
        }
    }
}

/* Nodes of sk that pruning removed: the kept ones are in pruned in the same order with the same
 * position and radius, so one walk pairs them; each removed node counts its projected width. */
static size_t screen_pruned(screen_err *e, const xyl_skeleton *sk, const xyl_skeleton *pruned,
                            const float eye[3], double per_distance)
{
    size_t j = 0, removed = 0;
    for (size_t i = 0; i < sk->node_count; ++i) {
        const xyl_skel_node *n = &sk->nodes[i];
        if (j < pruned->node_count && pruned->nodes[j].radius == n->radius &&
            pruned->nodes[j].pos.x == n->pos.x && pruned->nodes[j].pos.y == n->pos.y &&
            pruned->nodes[j].pos.z == n->pos.z) {
            ++j;
            continue;
        }
        double dx = n->pos.x - eye[0], dy = n->pos.y - eye[1], dz = n->pos.z - eye[2];
        double px = 2.0 * n->radius / (sqrt(dx * dx + dy * dy + dz * dz) * per_distance);
        if (px > e->max) {
            e->worst[0] = n->pos.x, e->worst[1] = n->pos.y, e->worst[2] = n->pos.z;
            e->worst_world = 2.0 * n->radius;
            e->worst_pruned = true;
        }
        screen_add(e, px);
        ++removed;
    }
    return removed;
}

/* Where the worst point of a row lies: the skeleton node nearest to it, its radius and how many
 * children it has (0: a tip). */
static int worst_note(char *buf, size_t cap, const char *what, const screen_err *e,
                      const xyl_skeleton *sk)
{
    size_t best = 0, kids = 0;
    double bd = INFINITY;
    for (size_t i = 0; i < sk->node_count; ++i) {
        double dx = sk->nodes[i].pos.x - e->worst[0], dy = sk->nodes[i].pos.y - e->worst[1];
        double dz = sk->nodes[i].pos.z - e->worst[2], dd = sqrt(dx * dx + dy * dy + dz * dz);
        if (dd < bd) bd = dd, best = i;
    }
    for (size_t i = 0; i < sk->node_count; ++i) kids += sk->nodes[i].parent == (int32_t)best;
    return snprintf(buf, cap, "%s: %.3f px = %.4g world units from the reference, %.4g from node "
                    "%zu (r %.4g, %zu children)", what, e->max, e->worst_world, bd, best,
                    (double)sk->nodes[best].radius, kids);
}

/* The stems of sk meshed with desc, levels chosen for view, refined on the CPU. */
static xyl_mesh *refine_view(const xyl_skeleton *sk, const xyl_stems_desc *desc,
                             const xyl_tess_patterns *pat, const xyl_tess_view *view,
                             uint64_t *triangles, xyl_stems_stats *st)
{
    xyl_mesh *m = NULL, *refined = NULL;
    xyl_tess_patches *tp = NULL;
    xyl_tess_batches *b = NULL;
    xyl_tess_patches_desc pd = {0};
    pd.variant = XYL_TESS_CIRCLE;
    xyl_diag d = {0};
    xyl_result r = xyl_stems_build(sk, desc, &m, st, &d);
    if (!r) r = xyl_tess_patches_create(m, &pd, &tp, &d);
    if (!r) r = xyl_tess_batches_create(NULL, &b, &d);
    if (!r) r = xyl_tess_select(tp, pat, view, b, &d);
    if (!r) r = xyl_tess_refine(tp, pat, b, NULL, NULL, &refined, &d);
    if (r) die("budget row", r, &d);
    *triangles = b->triangles;
    xyl_tess_batches_destroy(b);
    xyl_tess_patches_destroy(tp);
    xyl_mesh_destroy(m);
    return refined;
}

static void budget_rows(const xyl_tess_patterns *pat, const bench_opts *o)
{
    const char *trees[] = {xyl_lsystem_default_preset(), "faycal-leaves", "abop-2.6-monopodial"};
    static const float zooms[] = {1.0f, 4.0f, 16.0f};
    const double E = o->budget_px;
    printf("Budget rows: stems only, circle rule, %u px viewport, E = %g px; (a) k = 4, nothing "
           "pruned, levels at E px; (b) E px -> W world units at the tree's near side: twigs under "
           "W pruned, sides within W/2 (refined arcs, up to 16), levels at E (1 - ring error / W) px. "
           "Error: against the unpruned k = 16 mesh refined at E/16 px, in px at each point's "
           "distance; a pruned node counts its projected width.\n", o->size, E);
    printf("| tree | distance | W | (a) triangles | (a) max px | (a) RMS px | (b) triangles | "
           "(b) max px | (b) RMS px | (b) nodes pruned | (b)/(a) triangles | (a) p99 px | (b) p99 px | "
           "reference triangles |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    char notes[9][512];
    size_t nn = 0;
    for (size_t ti = 0; ti < sizeof trees / sizeof trees[0]; ++ti) {
        xyl_skeleton *sk = preset_tree(trees[ti]);
        xyl_mesh *k4 = mesh_of(sk, 4, 0);
        float lo[3], hi[3], c[3], r2 = 0.0f, size = 0.0f;
        xyl_mesh_bounds(k4, lo, hi);
        for (int k = 0; k < 3; ++k) {
            c[k] = 0.5f * (lo[k] + hi[k]);
            r2 += 0.25f * (hi[k] - lo[k]) * (hi[k] - lo[k]);
            size = fmaxf(size, hi[k] - lo[k]);
        }
        xyl_mesh_destroy(k4);
        for (size_t zi = 0; zi < 3; ++zi) {
            xyl_tess_camera cam;
            xyl_tess_camera_frame(lo, hi, 0.5f, 0.2f, 0.8f, 1.0f, &cam);
            if (zooms[zi] != 1.0f) xyl_tess_camera_zoom(&cam, zooms[zi]);
            xyl_tess_view v = {0};
            memcpy(v.eye, cam.eye, sizeof v.eye);
            v.fovy = cam.fovy;
            v.viewport_height = o->size;
            v.error_px = (float)E;
            v.near_distance = fmaxf(1e-3f * size, 1e-30f);
            double per_distance = 2.0 * tan(0.5 * (double)cam.fovy) / o->size;
            /* the reference: unpruned, k = 16, circle rule at E / 16 px */
            xyl_stems_desc dr = {0};
            dr.sides = 16;
            xyl_tess_view vr = v;
            vr.error_px = (float)(E / 16.0);
            uint64_t tr = 0;
            xyl_stems_stats st = {0};
            xyl_mesh *refm = refine_view(sk, &dr, pat, &vr, &tr, &st);
            ref_grid ref = {0};
            ref_grid_build(&ref, refm);
            /* (a) */
            xyl_stems_desc da = {0};
            da.sides = 4;
            uint64_t ta = 0, tb = 0;
            xyl_mesh *ra = refine_view(sk, &da, pat, &v, &ta, &st);
            screen_err ea = {0};
            screen_mesh(&ea, &ref, ra, v.eye, per_distance);
            xyl_mesh_destroy(ra);
            /* (b) */
            float w = 0.0f;
            xyl_diag d = {0};
            xyl_skeleton *pruned = NULL;
            xyl_result r = xyl_tess_view_world_error(&v, c, sqrtf(r2), &w, &d);
            if (!r) r = xyl_skeleton_prune(sk, w, NULL, &pruned, NULL, &d);
            if (r) die("budget", r, &d);
            xyl_stems_desc db = {0};
            db.sides = 16;
            db.error_world = 0.5f * w;
            db.sides_refined = true;
            /* meshed first to learn the rings' error: the tessellation gets what they leave */
            xyl_mesh *mb = NULL;
            r = xyl_stems_build(pruned, &db, &mb, &st, &d);
            if (r) die("budget mesh", r, &d);
            xyl_mesh_destroy(mb);
            xyl_tess_view vb = v;
            vb.error_px = (float)(E * fmax(0.5, 1.0 - st.ring_error_max / w));
            xyl_mesh *rb = refine_view(pruned, &db, pat, &vb, &tb, &st);
            screen_err eb = {0};
            screen_mesh(&eb, &ref, rb, v.eye, per_distance);
            size_t removed = screen_pruned(&eb, sk, pruned, v.eye, per_distance);
            xyl_mesh_destroy(rb);
            xyl_skeleton_destroy(pruned);
            free(ref.start);
            free(ref.tri);
            xyl_mesh_destroy(refm);
            int at = snprintf(notes[nn], sizeof notes[nn], "%s %gx: ", trees[ti],
                              (double)zooms[zi]);
            at += worst_note(notes[nn] + at, sizeof notes[nn] - (size_t)at, "(a) worst", &ea, sk);
            if (!eb.worst_pruned)
                worst_note(notes[nn] + at, sizeof notes[nn] - (size_t)at, "; (b) worst", &eb, sk);
            else
                snprintf(notes[nn] + at, sizeof notes[nn] - (size_t)at,
                         "; (b) worst: a pruned node, %.3f px (its width %.4g)", eb.max,
                         eb.worst_world);
            ++nn;
            double pa, qa, pb, qb;
            screen_finish(&ea, &pa, &qa);
            screen_finish(&eb, &pb, &qb);
            printf("| %s | %gx | %.4g | %llu | %.3f | %.3f | %llu | %.3f | %.3f | %zu of %zu | "
                   "%.3f | %.3f | %.3f | %llu |\n", trees[ti], (double)zooms[zi], (double)w,
                   (unsigned long long)ta, ea.max, qa, (unsigned long long)tb, eb.max, qb, removed,
                   sk->node_count, ta ? (double)tb / (double)ta : 0.0, pa, pb,
                   (unsigned long long)tr);
            fflush(stdout);
        }
        xyl_skeleton_destroy(sk);
    }
    printf("\nWhere each row's largest error is:\n");
    for (size_t i = 0; i < nn; ++i) printf("- %s\n", notes[i]);
}

static void parse(int argc, char **argv, bench_opts *o)
{
    o->gpu = true;
    o->frames = 7;
    o->size = 1024;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--quick") == 0) o->quick = true;
        else if (strcmp(argv[i], "--no-gpu") == 0) o->gpu = false;
        else if (strcmp(argv[i], "--frames") == 0 && i + 1 < argc) o->frames = atoi(argv[++i]);
        else if (strcmp(argv[i], "--size") == 0 && i + 1 < argc) o->size = (uint32_t)atoi(argv[++i]);
        else if (strcmp(argv[i], "--dat") == 0 && i + 1 < argc) o->dat = argv[++i];
        else if (strcmp(argv[i], "--budget") == 0 && i + 1 < argc) {
            o->budget_px = atof(argv[++i]);
            if (!(o->budget_px > 0.0 && o->budget_px <= 1e6)) {
                fprintf(stderr, "bench_tess: --budget takes a positive number of pixels\n");
                exit(64);
            }
        }
        else if (strcmp(argv[i], "--max-triangles") == 0 && i + 1 < argc) {
            o->max_triangles = atof(argv[++i]);
            if (!(o->max_triangles >= 1.0)) {
                fprintf(stderr, "bench_tess: --max-triangles takes a positive count\n");
                exit(64);
            }
        } else if (strcmp(argv[i], "--sides") == 0 && i + 1 < argc) {
            char *list = argv[++i], *end = list;
            o->nsides = 0;
            while (*end) {
                long k = strtol(list, &end, 10);
                if (end == list || k < 3 || k > 32 || o->nsides == 8 || (*end && *end != ',')) {
                    fprintf(stderr, "bench_tess: --sides takes up to 8 ring sides 3..32, "
                                    "comma-separated\n");
                    exit(64);
                }
                o->sides[o->nsides++] = (uint32_t)k;
                list = *end ? end + 1 : end;
            }
        } else {
            bool help = strcmp(argv[i], "--help") == 0;
            fprintf(help ? stdout : stderr,
                    "usage: bench_tess [--quick] [--no-gpu] [--frames N] [--size PX] [--dat FILE]"
                    " [--sides K,K,...] [--max-triangles N] [--budget E]\n");
            exit(help ? 0 : 64);
        }
    }
    if (o->frames < 1 || o->size < 16 || o->size > 8192) {
        fprintf(stderr, "bench_tess: --frames >= 1, --size 16..8192\n");
        exit(64);
    }
    if (!HAVE_GPU && o->gpu) {
        printf("bench_tess: built without the GL and Vulkan backends: no GPU timings\n");
        o->gpu = false;
    }
    if (o->quick) o->frames = o->frames < 3 ? o->frames : 3, o->size = o->size < 256 ? o->size : 256;
}

int main(int argc, char **argv)
{
    bench_opts o = {0};
    parse(argc, argv, &o);
    static const uint32_t default_ks[] = {3, 4, 6, 8}, levels[] = {1, 2, 3, 4, 6, 8, 12, 16, 24, 32};
    if (!o.nsides) {
        memcpy(o.sides, default_ks, sizeof default_ks);
        o.nsides = 4;
    }
    const uint32_t *ks = o.sides;
    xyl_tess_patterns *pat = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_tess_patterns_create(0, NULL, &pat, &d);
    if (r) die("patterns", r, &d);
    if (o.budget_px > 0.0) {
        budget_rows(pat, &o);
        xyl_tess_patterns_destroy(pat);
        return 0;
    }
    xyl_skeleton *arc = arc_skeleton(), *tree = default_tree();
    arc_centreline(arc);
    gpu g = {0};
    if (o.gpu) gpu_open(&g, pat, &o);
    size_t cap = o.nsides * 3 * XYL_TESS_VARIANT_COUNT * 10, n = 0;
    row *rows = calloc(cap, sizeof *rows);
    printf("| k | subdivision | variant | level | triangles (tree) | max radial error %% | RMS %% "
           "| max normal error deg | %s ms | %s ms | %s ms |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
           path_name[0], path_name[1], path_name[2]);
    for (size_t ki = 0; ki < o.nsides; ++ki) {
        if (o.quick && ks[ki] != 4) continue;
        for (uint32_t sdv = 0; sdv < 3; ++sdv) {
            xyl_mesh *am = mesh_of(arc, ks[ki], sdv), *tm = mesh_of(tree, ks[ki], sdv);
            if (!am || !tm) {
                printf("| %u | %s | skipped: this xylem is built without OpenSubdiv |\n", ks[ki],
                       subdiv_name[sdv]);
                xyl_mesh_destroy(am);
                xyl_mesh_destroy(tm);
                continue;
            }
            float lo[3], hi[3];
            xyl_mesh_bounds(tm, lo, hi);
            xyl_tess_camera cam;
            xyl_tess_camera_frame(lo, hi, 0.5f, 0.2f, 0.8f, 1.0f, &cam);
            for (uint32_t var = 0; var < XYL_TESS_VARIANT_COUNT; ++var)
                for (size_t li = 0; li < 10; ++li) {
                    if (o.quick && levels[li] != 1 && levels[li] != 4) continue;
                    double l2 = (double)levels[li] * levels[li];
                    if (o.max_triangles > 0.0 &&
                        (2.0 * (double)tm->quad_count + (double)tm->triangle_count) * l2 >
                            o.max_triangles)
                        continue;
                    row *rw = &rows[n++];
                    rw->k = ks[ki]; rw->subdiv = sdv; rw->variant = var; rw->level = levels[li];
                    run_config(rw, arc, am, tm, pat, o.gpu ? &g : NULL, &cam, &o);
                    print_row(stdout, rw);
                    fflush(stdout);
                }
            xyl_mesh_destroy(am);
            xyl_mesh_destroy(tm);
        }
    }
    print_pareto(rows, n);
    char front_path[1024];
    if (o.dat) snprintf(front_path, sizeof front_path, "%s.front", o.dat);
    int rc = write_front(rows, n, o.dat ? front_path : NULL);
    if (rc) return rc;
    if (o.dat) {
        FILE *f = fopen(o.dat, "w");
        if (!f) { perror(o.dat); return 73; }
        fprintf(f, "# k subdiv variant level triangles max_err_pct rms_err_pct normal_deg gl_inst_ms gl_hw_ms vk_ms\n");
        for (size_t i = 0; i < n; ++i)
            fprintf(f, "%u %u %u %u %llu %.6f %.6f %.4f %.4f %.4f %.4f\n", rows[i].k, rows[i].subdiv,
                    rows[i].variant, rows[i].level, (unsigned long long)rows[i].triangles,
                    rows[i].max_err, rows[i].rms_err, rows[i].max_normal_deg, rows[i].ms[0],
                    rows[i].ms[1], rows[i].ms[2]);
        fclose(f);
    }
    free(rows);
    if (o.gpu) gpu_close(&g);
    xyl_skeleton_destroy(arc);
    xyl_skeleton_destroy(tree);
    xyl_tess_patterns_destroy(pat);
    return 0;
}

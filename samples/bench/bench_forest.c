/* bench_forest: xyl_forest_gl on forests of the default tree (1, 100, 10 000 and 100 000
 * instances on a jittered grid) along a fixed camera path, in five modes: full (every leaf
 * and the stems of every instance), two-range LOD (each instance at the leaf level its
 * distance allows, stems only where the thickest stem still projects over the budget),
 * per-leaf LOD (the same, but the M instances nearest the eye, --per-leaf M, default 16, each
 * get a per-leaf cut of their own on the GPU; their leaves are read back from the draws, so
 * a per-leaf row that is not drawn leaves them out), billboards (the same, and a cross billboard of 4 planes baked from the tree past the leaf
 * levels) and impostors (the same with an octahedral impostor of 8 x 8 views instead). The
 * LOD modes cross-fade over --fade F of each switch distance (default 0.1; 0: hard
 * switches); "twice" counts the instances inside a band, drawn at two levels. Per size and
 * mode, each the mean over the path's views: leaves and triangles drawn, the share of
 * the visible instances' full-detail leaves that is drawn, draws, the frame time (median of N
 * frames of clear + forest + glFinish), the CPU time of the LOD choice (its median) and the
 * RMSE of the picture against the full-detail one (8-bit RGB over every pixel, root mean square
 * over the views) where drawing the full forest is affordable (at most --max-full-triangles in
 * a view); otherwise the full mode is counted, not drawn.
 *
 *   bench_forest [--quick] [--frames N] [--size WxH] [--error-px E] [--views N]
 *                [--max-full-triangles T] [--max-triangles T] [--fade F] [--per-leaf M]
 *
 * The error budget is E pixels (default 1): a leaf level's collapse error, a billboard's error
 * (the tree's radius about its axis) and the stems' radius all project under E pixels where
 * they are used. Path: a dolly out, N views (default 3) looking at the forest's centre from
 * azimuths 0.6, 1.3, 2.0, ... radians, view v at 3^v times the distance R (1.2 times the
 * forest's half-width plus two trees) and at (0.2 R plus a third of a tree's height) 3^v above the ground. S: default 320 x 240, one sample a pixel. Modes
 * whose choice puts more than --max-triangles (default 60 M) in one view are counted and not
 * drawn either. On Mesa's llvmpipe the times are CPU figures: only their ratios mean anything.
 * Exit status: 0; 1 when GL or a build fails; 2 on bad usage. */
#define _POSIX_C_SOURCE 200809L

#include <epoxy/gl.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../cli/leaf_texture.h"
#include <xylem/xyl_billboard_gl.h>
#include <xylem/xyl_foliage.h>
#include <xylem/xyl_forest_gl.h>
#include <xylem/xyl_lsystem.h>
#include <xylem/xyl_stems.h>
#include <xylem/xyl_tess_gl.h>
#include <xylem/xyl_tessellate.h>

#define MAX_FRAMES 31
#define MAX_VIEWS 8

typedef struct bench_options {
    int frames, views;
    uint32_t width, height;
    float error_px, fade;
    uint32_t per_leaf;
    double max_full_triangles, max_triangles;
    bool quick;
} bench_options;

typedef struct tree {
    xyl_mesh *stems;
    xyl_foliage *foliage;
    float stem_width;
    float lo[3], hi[3];
} tree;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static xyl_result default_tree(tree *t, xyl_diag *d)
{
    xyl_grammar_desc gd = {0};
    gd.source = xyl_lsystem_preset_source(xyl_lsystem_default_preset());
    xyl_grammar *g = NULL;
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    xyl_leaf *leaves = NULL;
    size_t n = 0;
    xyl_result r = xyl_grammar_parse(&gd, &g, d);
    if (r == XYL_OK) r = xyl_lsystem_derive(g, NULL, &s, d);
    if (r == XYL_OK) r = xyl_lsystem_interpret(g, s, NULL, &sk, d);
    if (r == XYL_OK) r = xyl_stems_build(sk, NULL, &t->stems, NULL, d);
    if (r == XYL_OK) r = xyl_foliage_leaves_from_skeleton(sk, NULL, NULL, 0, &n, d);
    if (r == XYL_OK && (leaves = malloc((n ? n : 1) * sizeof *leaves)) == NULL)
        r = XYL_ERR_OUT_OF_MEMORY;
    if (r == XYL_OK) r = xyl_foliage_leaves_from_skeleton(sk, NULL, leaves, n, &n, d);
    if (r == XYL_OK) {
        xyl_foliage_desc fd = {0};
        fd.leaves = leaves;
        fd.leaf_count = n;
        r = xyl_foliage_build(&fd, &t->foliage, d);
    }
    for (size_t k = 0; r == XYL_OK && k < sk->node_count; ++k)
        t->stem_width = fmaxf(t->stem_width, 2.0f * sk->nodes[k].radius);
    if (r == XYL_OK) {
        xyl_mesh_bounds(t->stems, t->lo, t->hi);
        xyl_foliage_bounds(t->foliage, t->lo, t->hi);
    }
    free(leaves);
    xyl_skeleton_destroy(sk);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return r;
}

/* The billboard's bake draws the whole tree with a one-instance forest at full detail. */
static xyl_result bake_tree(void *user, const float view_proj[16], const float light[3],
                            xyl_diag *d)
{
    xyl_forest_gl *one = user;
    xyl_forest_gl_frame fr = {0};
    memcpy(fr.view_proj, view_proj, sizeof fr.view_proj);
    memcpy(fr.light_dir, light, sizeof fr.light_dir);
    fr.error_px = 1.0f;
    fr.mode = XYL_FOREST_FULL;
    fr.no_cull = true;
    fr.leaf_color[0] = fr.leaf_color[1] = fr.leaf_color[2] = fr.leaf_color[3] = 1.0f;
    return xyl_forest_gl_draw(one, &fr, NULL, d);
}

static xyl_result make_forest(const tree *t, xyl_billboard_gl *bb, const uint8_t *tex,
                              xyl_forest_gl **out, xyl_diag *d)
{
    xyl_forest_gl_species_desc sd = {0};
    sd.foliage = t->foliage;
    sd.stems = t->stems;
    sd.billboard = bb;
    sd.stem_width = bb ? t->stem_width : 0.0f; /* the bake's tree keeps its stems */
    uint32_t species = 0;
    xyl_result r = xyl_forest_gl_create(NULL, out, d);
    if (r == XYL_OK) r = xyl_forest_gl_add_species(*out, &sd, &species, d);
    if (r == XYL_OK)
        r = xyl_forest_gl_set_texture(*out, tex, XYL_LEAF_TEXTURE_WIDTH, XYL_LEAF_TEXTURE_HEIGHT, d);
    return r;
}

static xyl_result bake_billboard(const tree *t, const uint8_t *tex, bool impostor,
                                 xyl_billboard_gl **bb, xyl_diag *d)
{
    xyl_forest_gl *one = NULL;
    xyl_forest_instance inst = {{0, 0, 0}, 63u << 24}; /* scale 1, no turn */
    xyl_result r = make_forest(t, NULL, tex, &one, d);
    if (r == XYL_OK) r = xyl_forest_gl_set_instances(one, &inst, 1, d);
    xyl_billboard_gl_desc bd = {0};
    bd.kind = impostor ? XYL_BILLBOARD_OCTAHEDRAL : XYL_BILLBOARD_CROSS;
    bd.planes = impostor ? 0 : 4;
    bd.grid = impostor ? 8 : 0;
    bd.resolution = impostor ? 128 : 256;
    memcpy(bd.lo, t->lo, sizeof bd.lo);
    memcpy(bd.hi, t->hi, sizeof bd.hi);
    if (r == XYL_OK) r = xyl_billboard_gl_bake(&bd, bake_tree, one, bb, d);
    xyl_forest_gl_destroy(one);
    return r;
}

typedef enum mode {
    MODE_FULL, MODE_LOD, MODE_PER_LEAF, MODE_BILLBOARD, MODE_IMPOSTOR, MODE_COUNT
} mode;
static const char *const mode_names[MODE_COUNT] = {"full", "two-range LOD", "per-leaf LOD",
                                                   "billboards", "impostors"};
static const xyl_forest_mode forest_modes[MODE_COUNT] = {
    XYL_FOREST_FULL, XYL_FOREST_LEAF_LEVELS, XYL_FOREST_LEAF_LEVELS, XYL_FOREST_LOD,
    XYL_FOREST_LOD};

typedef struct view {
    xyl_forest_gl_frame fr;
} view;

static xyl_result path_views(const tree *t, uint64_t count, float spacing, const bench_options *o,
                             view *views, xyl_diag *d)
{
    uint64_t side = (uint64_t)ceil(sqrt((double)count));
    double half = 0.5 * (double)(side - 1) * spacing, width = t->hi[0] - t->lo[0];
    double radius = 1.2 * half + 2.0 * width, height = 0.2 * radius + t->hi[1] / 3.0;
    for (int v = 0; v < o->views; ++v) {
        double a = 0.6 + 0.7 * v, k = pow(3.0, v);
        xyl_tess_camera cam = {0};
        cam.eye[0] = (float)(k * radius * cos(a)), cam.eye[1] = (float)(k * height);
        cam.eye[2] = (float)(k * radius * sin(a));
        cam.target[1] = 0.5f * (t->lo[1] + t->hi[1]);
        cam.fovy = 0.8f;
        cam.aspect = (float)o->width / (float)o->height;
        cam.near_plane = (float)(0.02 * width);
        cam.far_plane = (float)(4.0 * k * radius + 2.0 * half);
        xyl_forest_gl_frame *fr = &views[v].fr;
        memset(fr, 0, sizeof *fr);
        xyl_result r = xyl_tess_camera_matrix(&cam, XYL_TESS_CLIP_GL, fr->view_proj, d);
        if (r != XYL_OK) return r;
        memcpy(fr->eye, cam.eye, sizeof fr->eye);
        fr->fovy = cam.fovy;
        fr->viewport_height = o->height;
        fr->error_px = o->error_px;
        fr->light_dir[0] = 0.42f, fr->light_dir[1] = 0.78f, fr->light_dir[2] = 0.46f;
        fr->leaf_color[0] = fr->leaf_color[1] = fr->leaf_color[2] = fr->leaf_color[3] = 1.0f;
    }
    return XYL_OK;
}

typedef struct row {
    double frame_ms, choose_ms, sq_err, leaves, triangles, full_leaves, draws, twice;
    bool drawn, compared;
} row;

static void draw_frame(xyl_forest_gl *f, const xyl_forest_gl_frame *fr, xyl_forest_gl_stats *st,
                       xyl_result *r, xyl_diag *d)
{
    glClearColor(0.86f, 0.9f, 0.95f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    *r = xyl_forest_gl_draw(f, fr, st, d);
    glFinish();
}

static double sq_error(const uint8_t *a, const uint8_t *b, size_t pixels)
{
    double sum = 0.0;
    for (size_t p = 0; p < pixels; ++p)
        for (int c = 0; c < 3; ++c) {
            double e = (double)a[4 * p + c] - b[4 * p + c];
            sum += e * e;
        }
    return sum / (3.0 * (double)pixels);
}

/* One mode over the path: counted by a choice, drawn when affordable, compared with ref. */
static xyl_result run_mode(xyl_forest_gl *f, mode m, view *views, const bench_options *o,
                           uint8_t **ref, bool *ref_ok, uint8_t *img, row *out, xyl_diag *d)
{
    size_t pixels = (size_t)o->width * o->height;
    memset(out, 0, sizeof *out);
    out->drawn = true;
    out->compared = m != MODE_FULL;
    xyl_result r = XYL_OK;
    for (int v = 0; r == XYL_OK && v < o->views; ++v) {
        xyl_forest_gl_frame fr = views[v].fr;
        fr.mode = forest_modes[m];
        fr.fade = o->fade;
        fr.per_leaf = m == MODE_PER_LEAF ? o->per_leaf : 0;
        xyl_forest_gl_stats st;
        double choose[MAX_FRAMES], frame[MAX_FRAMES];
        r = xyl_forest_gl_choose(f, &fr, &st, d);
        if (r != XYL_OK) break;
        /* the choice alone does not count the per-leaf instances' cuts: the draws do */
        double chosen_leaves = (double)st.leaves, chosen_triangles = (double)st.triangles;
        out->leaves += chosen_leaves;
        out->triangles += chosen_triangles;
        out->twice += (double)st.faded;
        /* the visible instances' full-detail leaves */
        xyl_forest_gl_species_info info;
        r = xyl_forest_gl_species(f, 0, &info, d);
        out->full_leaves += (double)st.visible * info.level_leaves[0];
        double cap = m == MODE_FULL ? o->max_full_triangles : o->max_triangles;
        if ((double)st.triangles > cap) {
            out->drawn = false;
            out->compared = false;
            if (m == MODE_FULL) ref_ok[v] = false;
            continue;
        }
        for (int i = 0; r == XYL_OK && i <= o->frames; ++i) { /* frame 0 warms up */
            double t0 = now_s();
            draw_frame(f, &fr, &st, &r, d);
            if (i) frame[i - 1] = (now_s() - t0) * 1e3, choose[i - 1] = st.choose_ms;
        }
        if (r != XYL_OK) break;
        out->leaves += (double)st.leaves - chosen_leaves;
        out->triangles += (double)st.triangles - chosen_triangles;
        out->draws += (double)st.draws;
        out->frame_ms += median(frame, o->frames);
        out->choose_ms += median(choose, o->frames);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        uint8_t *dst = m == MODE_FULL ? ref[v] : img;
        glReadPixels(0, 0, (GLsizei)o->width, (GLsizei)o->height, GL_RGBA, GL_UNSIGNED_BYTE, dst);
        if (m == MODE_FULL) ref_ok[v] = true;
        else if (ref_ok[v]) out->sq_err += sq_error(ref[v], img, pixels);
        else out->compared = false;
    }
    if (out->compared) out->sq_err = sqrt(out->sq_err / o->views);
    double per = 1.0 / o->views; /* figures per view (frame) */
    out->leaves *= per, out->triangles *= per, out->full_leaves *= per, out->draws *= per;
    out->twice *= per;
    out->frame_ms *= per, out->choose_ms *= per;
    return r;
}

static void print_row(uint64_t n, mode m, const row *w)
{
    char frame[32], choose[32], rmse[32];
    if (w->drawn) snprintf(frame, sizeof frame, "%.2f", w->frame_ms);
    else snprintf(frame, sizeof frame, "not drawn");
    snprintf(choose, sizeof choose, w->drawn ? "%.3f" : "-", w->choose_ms);
    if (w->compared) snprintf(rmse, sizeof rmse, "%.3f", w->sq_err);
    else snprintf(rmse, sizeof rmse, m == MODE_FULL ? "(ref)" : "-");
    double share = w->full_leaves > 0.0 ? w->leaves / w->full_leaves : 0.0;
    printf("%9llu  %-14s %12.0f %9.5f %13.0f %7.0f %8.1f %11s %10s %8s\n",
           (unsigned long long)n, mode_names[m], w->leaves, share, w->triangles, w->draws,
           w->twice, frame, choose, rmse);
}

static int usage(const char *msg)
{
    fprintf(stderr, "bench_forest: %s\nusage: bench_forest [--quick] [--frames N] [--size WxH] "
                    "[--error-px E] [--views N] [--max-full-triangles T] [--max-triangles T] "
                    "[--fade F] [--per-leaf M]\n",
            msg);
    return 2;
}

static int parse(int argc, char **argv, bench_options *o)
{
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--quick") == 0) {
            o->quick = true, o->frames = 1, o->views = 2, o->width = 96, o->height = 64;
            o->max_full_triangles = 4e6, o->max_triangles = 4e6;
        } else if (strcmp(a, "--frames") == 0 && val) {
            o->frames = atoi(val), ++i;
            if (o->frames < 1 || o->frames > MAX_FRAMES) return usage("--frames takes 1 to 31");
        } else if (strcmp(a, "--views") == 0 && val) {
            o->views = atoi(val), ++i;
            if (o->views < 1 || o->views > MAX_VIEWS) return usage("--views takes 1 to 8");
        } else if (strcmp(a, "--size") == 0 && val) {
            unsigned w = 0, h = 0;
            if (sscanf(val, "%ux%u", &w, &h) != 2 || w < 16 || h < 16 || w > 4096 || h > 4096)
                return usage("--size takes WxH, each 16 to 4096");
            o->width = w, o->height = h, ++i;
        } else if (strcmp(a, "--error-px") == 0 && val) {
            o->error_px = (float)atof(val), ++i;
            if (!(o->error_px > 0.0f && o->error_px <= 100.0f)) return usage("--error-px takes (0, 100]");
        } else if (strcmp(a, "--per-leaf") == 0 && val) {
            o->per_leaf = (uint32_t)atoi(val), ++i;
            if (o->per_leaf < 1 || o->per_leaf > XYL_FOREST_MAX_PER_LEAF)
                return usage("--per-leaf takes 1 to 64");
        } else if (strcmp(a, "--fade") == 0 && val) {
            o->fade = (float)atof(val), ++i;
            if (!(o->fade >= 0.0f && o->fade <= XYL_FOREST_MAX_FADE)) return usage("--fade takes [0, 4]");
        } else if (strcmp(a, "--max-full-triangles") == 0 && val) {
            o->max_full_triangles = atof(val), ++i;
            if (!(o->max_full_triangles > 0.0)) return usage("--max-full-triangles takes > 0");
        } else if (strcmp(a, "--max-triangles") == 0 && val) {
            o->max_triangles = atof(val), ++i;
            if (!(o->max_triangles > 0.0)) return usage("--max-triangles takes > 0");
        } else {
            return usage("unknown option or missing value");
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    bench_options o = {5, 3, 320, 240, 1.0f, 0.1f, 16, 40e6, 60e6, false};
    int rc = parse(argc, argv, &o);
    if (rc) return rc;
    xyl_diag d = {0};
    tree t;
    memset(&t, 0, sizeof t);
    for (int k = 0; k < 3; ++k) t.lo[k] = INFINITY, t.hi[k] = -INFINITY;
    xyl_gl_context *ctx = NULL;
    xyl_billboard_gl *bb = NULL, *imp = NULL;
    xyl_forest_gl *f = NULL, *fi = NULL; /* fi: the impostor's */
    size_t px = (size_t)o.width * o.height * 4;
    uint8_t *tex = malloc((size_t)XYL_LEAF_TEXTURE_WIDTH * XYL_LEAF_TEXTURE_HEIGHT * 4);
    uint8_t *img = malloc(px), *ref[MAX_VIEWS] = {0};
    bool ref_ok[MAX_VIEWS] = {0};
    xyl_result r = tex && img ? XYL_OK : XYL_ERR_OUT_OF_MEMORY;
    for (int v = 0; r == XYL_OK && v < o.views; ++v)
        if ((ref[v] = malloc(px)) == NULL) r = XYL_ERR_OUT_OF_MEMORY;
    if (r == XYL_OK) r = default_tree(&t, &d);
    if (r == XYL_OK) r = xyl_gl_context_create_headless(NULL, &ctx, &d);
    if (tex) xyl_leaf_texture(tex, XYL_LEAF_TEXTURE_WIDTH, XYL_LEAF_TEXTURE_HEIGHT);
    if (r == XYL_OK) r = bake_billboard(&t, tex, false, &bb, &d);
    if (r == XYL_OK) r = bake_billboard(&t, tex, true, &imp, &d);
    if (r == XYL_OK) r = make_forest(&t, bb, tex, &f, &d);
    if (r == XYL_OK) r = make_forest(&t, imp, tex, &fi, &d);
    GLuint fbo = 0, rb[2] = {0, 0};
    xyl_forest_gl_species_info info;
    if (r == XYL_OK) r = xyl_forest_gl_species(f, 0, &info, &d);
    if (r == XYL_OK) {
        glCreateRenderbuffers(2, rb);
        glNamedRenderbufferStorage(rb[0], GL_RGBA8, (GLsizei)o.width, (GLsizei)o.height);
        glNamedRenderbufferStorage(rb[1], GL_DEPTH_COMPONENT24, (GLsizei)o.width, (GLsizei)o.height);
        glCreateFramebuffers(1, &fbo);
        glNamedFramebufferRenderbuffer(fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
        glNamedFramebufferRenderbuffer(fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        glViewport(0, 0, (GLsizei)o.width, (GLsizei)o.height);
        printf("device: %s; default tree: %u leaves, %llu stem triangles, %u leaf levels, "
               "stems at levels below %u, cross billboard of 4 planes, octahedral impostor of "
               "8 x 8 views\n",
               xyl_gl_context_renderer(ctx), info.level_leaves[0],
               (unsigned long long)info.stem_triangles, info.level_count, info.stem_levels);
        printf("budget %.3g px at %u x %u, fade %.3g, %u per-leaf, %d views a size, frame and choice times "
               "the median of %d frames, each figure the mean of the views; 16 bytes an "
               "instance\n", (double)o.error_px, o.width, o.height, (double)o.fade, o.per_leaf,
               o.views,
               o.frames);
        printf("%9s  %-14s %12s %9s %13s %7s %8s %11s %10s %8s\n", "instances", "mode",
               "leaves", "of full", "triangles", "draws", "twice", "frame ms", "choice ms",
               "RMSE");
    }
    const uint64_t sizes[4] = {1, 100, 10000, 100000};
    int size_count = o.quick ? 2 : 4;
    xyl_forest_instance *inst = malloc(100000 * sizeof *inst);
    if (!inst && r == XYL_OK) r = XYL_ERR_OUT_OF_MEMORY;
    for (int si = 0; r == XYL_OK && si < size_count; ++si) {
        float spacing = 1.1f * fmaxf(t.hi[0] - t.lo[0], t.hi[2] - t.lo[2]);
        xyl_forest_grid_desc gd = {0};
        gd.count = sizes[si], gd.spacing = spacing, gd.jitter = 0.6f, gd.seed = 1;
        gd.scale_min = 0.8f, gd.scale_max = 1.2f;
        view views[MAX_VIEWS];
        r = xyl_forest_grid(&gd, inst, 100000, &d);
        if (r == XYL_OK) r = xyl_forest_gl_set_instances(f, inst, gd.count, &d);
        if (r == XYL_OK) r = xyl_forest_gl_set_instances(fi, inst, gd.count, &d);
        if (r == XYL_OK) r = path_views(&t, gd.count, spacing, &o, views, &d);
        for (int m = 0; r == XYL_OK && m < MODE_COUNT; ++m) {
            row w;
            r = run_mode(m == MODE_IMPOSTOR ? fi : f, (mode)m, views, &o, ref, ref_ok, img, &w,
                         &d);
            if (r == XYL_OK) print_row(gd.count, (mode)m, &w);
            fflush(stdout);
        }
    }
    if (fbo) {
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glDeleteFramebuffers(1, &fbo);
        glDeleteRenderbuffers(2, rb);
    }
    if (r != XYL_OK) fprintf(stderr, "bench_forest: %s: %s\n", xyl_result_string(r), d.message);
    xyl_forest_gl_destroy(f);
    xyl_forest_gl_destroy(fi);
    xyl_billboard_gl_destroy(bb);
    xyl_billboard_gl_destroy(imp);
    xyl_gl_context_destroy(ctx);
    xyl_foliage_destroy(t.foliage);
    xyl_mesh_destroy(t.stems);
    free(inst);
    free(tex);
    free(img);
    for (int v = 0; v < MAX_VIEWS; ++v) free(ref[v]);
    return r == XYL_OK ? 0 : 1;
}

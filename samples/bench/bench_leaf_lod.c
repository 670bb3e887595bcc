/* bench_leaf_lod: the GL leaf renderer's two LOD modes against all the leaves, on the same
 * views of the default tree: per sector one LOD as two ranges (xyl_foliage_pick, then
 * xyl_foliage_gl_draw) and per leaf, the GPU's cut of the collapse forest
 * (xyl_foliage_gl_draw_adaptive). For a near, a middle and a far view: leaves drawn, the RMSE of
 * the picture against the full-detail one (8-bit RGB over every pixel) and the share of pixels
 * that differ, and the frame time (median of N frames of clear + leaves + glFinish, for the
 * per-leaf mode its compute pass included).
 *
 *   bench_leaf_lod [--quick] [--frames N] [--size S] [--error-px E] [--sectors N]
 *
 * The views frame the leaves' bounding box from azimuth 30, elevation 20 degrees, the eye at 1,
 * 4 and 16 times the framing distance. Leaves only (no stems), the samples' procedural leaf
 * texture, one sample a pixel, S x S pixels (default 512), the pixel budget E (default 0.5, the
 * library's) for both modes, the foliage in N sectors (default 1). On Mesa's llvmpipe the
 * times are CPU figures: only their ratios mean anything. Exit status: 0; 1 when GL or a build
 * fails; 2 on bad usage. */
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
#include <xylem/xyl_foliage.h>
#include <xylem/xyl_foliage_gl.h>
#include <xylem/xyl_lsystem.h>
#include <xylem/xyl_tess_gl.h>
#include <xylem/xyl_tessellate.h>

#define MAX_FRAMES 101

typedef struct bench_options {
    int frames;
    uint32_t size, sectors;
    float error_px;
} bench_options;

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

static xyl_foliage *default_foliage(uint32_t sectors, xyl_diag *d)
{
    xyl_grammar_desc gd = {0};
    gd.source = xyl_lsystem_preset_source(xyl_lsystem_default_preset());
    xyl_grammar *g = NULL;
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    xyl_leaf *leaves = NULL;
    xyl_foliage *f = NULL;
    size_t n = 0;
    if (!xyl_grammar_parse(&gd, &g, d) && !xyl_lsystem_derive(g, NULL, &s, d) &&
        !xyl_lsystem_interpret(g, s, NULL, &sk, d) &&
        !xyl_foliage_leaves_from_skeleton(sk, NULL, NULL, 0, &n, d) && n &&
        (leaves = malloc(n * sizeof *leaves)) != NULL &&
        !xyl_foliage_leaves_from_skeleton(sk, NULL, leaves, n, &n, d)) {
        xyl_foliage_desc fd = {0};
        fd.leaves = leaves;
        fd.leaf_count = n;
        fd.sectors = sectors;
        if (xyl_foliage_build(&fd, &f, d)) f = NULL;
    }
    free(leaves);
    xyl_skeleton_destroy(sk);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return f;
}

/* The leaves' box framed from (30, 20) degrees, the eye at zoom times the framing distance. */
static void view_camera(const xyl_foliage *f, float zoom, xyl_tess_camera *cam)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    xyl_foliage_bounds(f, lo, hi); /* the originals' quads */
    const float deg = 3.14159265f / 180.0f;
    xyl_tess_camera_frame(lo, hi, 30.0f * deg, 20.0f * deg, 0.8f, 1.0f, cam);
    float d2 = 0.0f, r2 = 0.0f;
    for (int i = 0; i < 3; ++i) {
        cam->eye[i] = cam->target[i] + zoom * (cam->eye[i] - cam->target[i]);
        d2 += (cam->eye[i] - cam->target[i]) * (cam->eye[i] - cam->target[i]);
        r2 += 0.25f * (hi[i] - lo[i]) * (hi[i] - lo[i]);
    }
    float dist = sqrtf(d2), r = sqrtf(r2);
    cam->near_plane = fmaxf(dist - 2.0f * r, 1e-3f * dist);
    cam->far_plane = dist + 2.0f * r;
}

typedef struct target {
    GLuint fbo, rb[2];
    uint32_t side;
} target;

typedef enum mode { MODE_FULL, MODE_LOD, MODE_ADAPTIVE } mode;
static const char *const mode_names[3] = {"full", "two-range LOD", "per-leaf cut"};

typedef struct run {
    size_t drawn;
    double frame_ms, rmse, changed;
} run;

/* One frame of a mode into the target: clear, leaves, glFinish. */
static xyl_result draw_once(xyl_foliage_gl *gl, const xyl_foliage *f, mode m,
                            const xyl_foliage_gl_frame *fr, const xyl_foliage_view *v,
                            const uint32_t *lods, xyl_diag *d)
{
    glClearColor(0.86f, 0.9f, 0.95f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    xyl_result r = m == MODE_ADAPTIVE ? xyl_foliage_gl_draw_adaptive(gl, fr, v, d)
                                      : xyl_foliage_gl_draw(gl, fr, lods, f->sector_count, d);
    glFinish();
    return r;
}

static xyl_result run_mode(xyl_foliage_gl *gl, const xyl_foliage *f, mode m,
                           const xyl_foliage_gl_frame *fr, const xyl_foliage_view *v, int frames,
                           uint8_t *rgba, uint32_t side, run *out, xyl_diag *d)
{
    uint32_t lods[XYL_FOLIAGE_MAX_SECTORS] = {0};
    xyl_result r = XYL_OK;
    if (m == MODE_LOD) r = xyl_foliage_pick(f, v, lods, XYL_FOLIAGE_MAX_SECTORS, d);
    if (r == XYL_OK && m != MODE_ADAPTIVE)
        r = xyl_foliage_gather(f, lods, f->sector_count, NULL, 0, &out->drawn, d);
    double t[MAX_FRAMES];
    for (int i = 0; r == XYL_OK && i <= frames; ++i) { /* frame 0 warms the driver up */
        double t0 = now_s();
        r = draw_once(gl, f, m, fr, v, lods, d);
        if (i) t[i - 1] = (now_s() - t0) * 1e3;
    }
    if (r == XYL_OK && m == MODE_ADAPTIVE) r = xyl_foliage_gl_last_cut(gl, NULL, 0, &out->drawn, d);
    if (r != XYL_OK) return r;
    qsort(t, (size_t)frames, sizeof *t, cmp_double);
    out->frame_ms = frames % 2 ? t[frames / 2] : 0.5 * (t[frames / 2 - 1] + t[frames / 2]);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, (GLsizei)side, (GLsizei)side, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    return XYL_OK;
}

static void compare(const uint8_t *ref, const uint8_t *img, uint32_t side, run *out)
{
    double sum = 0.0;
    size_t changed = 0, n = (size_t)side * side;
    for (size_t p = 0; p < n; ++p) {
        bool diff = false;
        for (int c = 0; c < 3; ++c) {
            double e = (double)img[4 * p + c] - ref[4 * p + c];
            sum += e * e;
            diff = diff || e != 0.0;
        }
        changed += diff;
    }
    out->rmse = sqrt(sum / (3.0 * (double)n));
    out->changed = 100.0 * (double)changed / (double)n;
}

static int usage(const char *msg)
{
    fprintf(stderr, "bench_leaf_lod: %s\nusage: bench_leaf_lod [--quick] [--frames N] [--size S] "
                    "[--error-px E] [--sectors N]\n", msg);
    return 2;
}

int main(int argc, char **argv)
{
    bench_options o = {15, 512, 1, 0.5f};
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--quick") == 0) {
            o.frames = 3;
            o.size = 128;
        } else if (strcmp(a, "--frames") == 0 && val) {
            o.frames = atoi(val), ++i;
            if (o.frames < 1 || o.frames > MAX_FRAMES) return usage("--frames takes 1 to 101");
        } else if (strcmp(a, "--size") == 0 && val) {
            o.size = (uint32_t)atoi(val), ++i;
            if (o.size < 16 || o.size > 4096) return usage("--size takes 16 to 4096");
        } else if (strcmp(a, "--error-px") == 0 && val) {
            o.error_px = (float)atof(val), ++i;
            if (!(o.error_px > 0.0f && o.error_px <= 100.0f)) return usage("--error-px takes (0, 100]");
        } else if (strcmp(a, "--sectors") == 0 && val) {
            o.sectors = (uint32_t)atoi(val), ++i;
            if (o.sectors < 1 || o.sectors > XYL_FOLIAGE_MAX_SECTORS) return usage("--sectors takes 1 to 256");
        } else {
            return usage("unknown option or missing value");
        }
    }
    xyl_diag d = {0};
    xyl_foliage *f = default_foliage(o.sectors, &d);
    if (!f) {
        fprintf(stderr, "bench_leaf_lod: the default tree's foliage: %s\n", d.message);
        return 1;
    }
    xyl_gl_context *ctx = NULL;
    xyl_foliage_gl *gl = NULL;
    uint8_t *tex = malloc((size_t)XYL_LEAF_TEXTURE_WIDTH * XYL_LEAF_TEXTURE_HEIGHT * 4);
    size_t px = (size_t)o.size * o.size * 4;
    uint8_t *ref = malloc(px), *img = malloc(px);
    xyl_result r = tex && ref && img ? XYL_OK : XYL_ERR_OUT_OF_MEMORY;
    if (r == XYL_OK) r = xyl_gl_context_create_headless(NULL, &ctx, &d);
    if (r == XYL_OK) r = xyl_foliage_gl_create(NULL, &gl, &d);
    if (r == XYL_OK) {
        xyl_leaf_texture(tex, XYL_LEAF_TEXTURE_WIDTH, XYL_LEAF_TEXTURE_HEIGHT);
        r = xyl_foliage_gl_set_texture(gl, tex, XYL_LEAF_TEXTURE_WIDTH, XYL_LEAF_TEXTURE_HEIGHT, &d);
    }
    if (r == XYL_OK) r = xyl_foliage_gl_set_foliage(gl, f, &d);
    target t = {0, {0, 0}, o.size};
    if (r == XYL_OK) {
        glCreateRenderbuffers(2, t.rb);
        glNamedRenderbufferStorage(t.rb[0], GL_RGBA8, (GLsizei)o.size, (GLsizei)o.size);
        glNamedRenderbufferStorage(t.rb[1], GL_DEPTH_COMPONENT24, (GLsizei)o.size, (GLsizei)o.size);
        glCreateFramebuffers(1, &t.fbo);
        glNamedFramebufferRenderbuffer(t.fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, t.rb[0]);
        glNamedFramebufferRenderbuffer(t.fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.rb[1]);
        glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
        glViewport(0, 0, (GLsizei)o.size, (GLsizei)o.size);
        printf("device: %s; default tree, %zu leaves, %u sector(s), %u x %u px, budget %.3g px, "
               "median of %d frames\n", xyl_gl_context_renderer(ctx), f->original_count, o.sectors,
               o.size, o.size, (double)o.error_px, o.frames);
        printf("%-7s %-14s %8s %9s %8s %10s\n", "view", "mode", "leaves", "RMSE", "changed",
               "frame ms");
    }
    const float zooms[3] = {1.0f, 4.0f, 16.0f};
    const char *const views[3] = {"near", "middle", "far"};
    for (int vi = 0; r == XYL_OK && vi < 3; ++vi) {
        xyl_tess_camera cam = {0};
        view_camera(f, zooms[vi], &cam);
        xyl_foliage_gl_frame fr = {0};
        r = xyl_tess_camera_matrix(&cam, XYL_TESS_CLIP_GL, fr.view_proj, &d);
        fr.light_dir[0] = 0.4f, fr.light_dir[1] = 0.8f, fr.light_dir[2] = 0.45f;
        fr.color[0] = fr.color[1] = fr.color[2] = fr.color[3] = 1.0f;
        xyl_foliage_view v = {{cam.eye[0], cam.eye[1], cam.eye[2]}, cam.fovy, o.size, o.error_px};
        for (int m = 0; r == XYL_OK && m < 3; ++m) {
            run out = {0};
            r = run_mode(gl, f, (mode)m, &fr, &v, o.frames, m == MODE_FULL ? ref : img, o.size,
                         &out, &d);
            if (r != XYL_OK) break;
            if (m != MODE_FULL) compare(ref, img, o.size, &out);
            printf("%-7s %-14s %8zu %9.3f %7.2f%% %10.3f\n", views[vi], mode_names[m], out.drawn,
                   out.rmse, out.changed, out.frame_ms);
        }
    }
    if (t.fbo) {
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glDeleteFramebuffers(1, &t.fbo);
        glDeleteRenderbuffers(2, t.rb);
    }
    if (r != XYL_OK) fprintf(stderr, "bench_leaf_lod: %s: %s\n", xyl_result_string(r), d.message);
    xyl_foliage_gl_destroy(gl);
    xyl_gl_context_destroy(ctx);
    xyl_foliage_destroy(f);
    free(tex);
    free(ref);
    free(img);
    return r == XYL_OK ? 0 : 1;
}

/* foliage/'s GL 4.5 leaf renderer on a headless EGL context (llvmpipe where there is no GPU):
 * the clip-space corners the vertex shader computes against a CPU reference at every LOD of
 * real trees, the primitive count of a draw, the alpha test and the texture's orientation in
 * read-back pixels, bad input (with no GL call), and the caller's allocator. Without a usable
 * GL 4.5 context every test is skipped, and says why. */
#include <epoxy/gl.h>
#include <float.h>
#include <math.h>

#include "test_util.h"
#include "foliage_tree.h"
#include "foliage_gl_debug.h"
#include "foliage_internal.h"
#include "foliage_cut_check.h"
#include "tess_util.h"
#include <xylem/xyl_foliage_gl.h>
#include <xylem/xyl_tess_gl.h>

/* The GPU's corner, against the CPU's in double from the same packed record: each clip
 * coordinate within REL_BOUND of the sum of the magnitudes of the terms that make it
 * (sum_k |M_rk| (|centre_k| + |side_k| + |axis_k|) + |M_r3|): a few float roundings of the
 * corner and of the four products, whether or not the driver fuses them. */
#define REL_BOUND 1e-6

typedef struct suite {
    xyl_gl_context *ctx;
    xyl_foliage_gl *gl;
    char why[320]; /* why the tests are skipped; empty when they run */
} suite;

static int setup(void **state)
{
    suite *s = calloc(1, sizeof *s);
    if (!s) return -1;
    xyl_diag d = {0};
    if (xyl_gl_context_create_headless(NULL, &s->ctx, &d) != XYL_OK ||
        xyl_foliage_gl_create(NULL, &s->gl, &d) != XYL_OK) {
        snprintf(s->why, sizeof s->why, "no usable GL 4.5 context: %s", d.message);
        xyl_gl_context_destroy(s->ctx);
        s->ctx = NULL;
    }
    *state = s;
    return 0;
}

static int teardown(void **state)
{
    suite *s = *state;
    xyl_foliage_gl_destroy(s->gl);
    xyl_gl_context_destroy(s->ctx);
    free(s);
    return 0;
}

static suite *need_gl(void **state)
{
    suite *s = *state;
    if (s->why[0]) {
        print_message("skipped: %s\n", s->why);
        skip();
    }
    return s;
}

static void expect(xyl_result got, xyl_result want, const xyl_diag *d)
{
    if (got != want)
        fail_msg("expected %s, got %s (%s)", xyl_result_string(want), xyl_result_string(got),
                 d->message);
    if (want != XYL_OK) assert_true(strlen(d->message) > 0);
}

/* ---- trees and cameras ---------------------------------------------------------------------- */

static xyl_foliage *tree_foliage(const char *preset, uint32_t sectors)
{
    return ft_tree_foliage(preset, sectors);
}

/* A perspective camera framing the foliage's sphere from (azimuth, elevation). */
static void frame_of(const xyl_foliage *f, float azimuth, float elevation,
                     xyl_foliage_gl_frame *fr)
{
    float c[3] = {f->center.x, f->center.y, f->center.z}, r = f->radius;
    float lo[3] = {c[0] - r, c[1] - r, c[2] - r}, hi[3] = {c[0] + r, c[1] + r, c[2] + r};
    xyl_tess_camera cam;
    xyl_tess_camera_frame(lo, hi, azimuth, elevation, 0.8f, 1.0f, &cam);
    memset(fr, 0, sizeof *fr);
    assert_int_equal(xyl_tess_camera_matrix(&cam, XYL_TESS_CLIP_GL, fr->view_proj, NULL), XYL_OK);
    fr->light_dir[0] = 0.4f, fr->light_dir[1] = 0.8f, fr->light_dir[2] = 0.45f;
}

/* ---- 1. GPU = CPU --------------------------------------------------------------------------- */

typedef struct compare {
    const xyl_foliage *f;
    const xyl_foliage_gpu_leaf *records;
    const float *m; /* column-major */
    double worst;   /* largest error / scale seen */
} compare;

/* Is leaf k drawn at these LODs? */
static bool in_lod(const xyl_foliage *f, const uint32_t *lods, uint32_t k)
{
    for (uint32_t s = 0; s < f->sector_count; ++s) {
        const xyl_foliage_sector *sec = &f->sectors[s];
        const xyl_foliage_lod *l = &sec->lods[lods[s]];
        if (k >= sec->base && k < sec->base + l->a) return true;
        if (k >= sec->base + l->b && k < sec->base + l->b + l->c) return true;
    }
    return false;
}

static void check_vertex(compare *c, const xyl__foliage_captured *v)
{
    assert_true(v->leaf < c->f->leaf_count);
    assert_true(fabsf(v->st[0]) == 1.0f && fabsf(v->st[1]) == 1.0f);
    xyl_leaf l = xyl__foliage_unpack_gpu(&c->records[v->leaf]);
    const double ce[3] = {l.center.x, l.center.y, l.center.z};
    const double sd[3] = {l.side.x, l.side.y, l.side.z}, ax[3] = {l.axis.x, l.axis.y, l.axis.z};
    double p[3], mag[3];
    for (int k = 0; k < 3; ++k) {
        p[k] = ce[k] + v->st[0] * sd[k] + v->st[1] * ax[k];
        mag[k] = fabs(ce[k]) + fabs(sd[k]) + fabs(ax[k]);
    }
    for (int r = 0; r < 4; ++r) {
        double want = c->m[12 + r], scale = fabs(c->m[12 + r]);
        for (int k = 0; k < 3; ++k) {
            want += (double)c->m[4 * k + r] * p[k];
            scale += fabs((double)c->m[4 * k + r]) * mag[k];
        }
        double e = fabs((double)v->clip[r] - want) / scale;
        if (e > c->worst) c->worst = e;
        if (e > REL_BOUND)
            fail_msg("leaf %u corner (%g, %g) clip[%d]: GPU %.9g, CPU %.9g (%.3g of the scale)",
                     v->leaf, (double)v->st[0], (double)v->st[1], r, (double)v->clip[r], want, e);
    }
}

/* Captures the LODs, checks every vertex against the reference and that each drawn leaf shows
 * its four corners in exactly two triangles, and returns the leaves drawn. */
static uint64_t capture_and_compare(suite *s, compare *c, const xyl_foliage_gl_frame *fr,
                                    const uint32_t *lods, xyl__foliage_captured *buf,
                                    size_t capacity, uint8_t *seen)
{
    size_t count = 0;
    uint64_t generated = 0;
    xyl_diag d = {0};
    expect(xyl__foliage_gl_capture(s->gl, fr, lods, c->f->sector_count, buf, capacity, &count,
                                   &generated, &d), XYL_OK, &d);
    size_t want_leaves = 0;
    expect(xyl_foliage_gather(c->f, lods, c->f->sector_count, NULL, 0, &want_leaves, &d), XYL_OK,
           &d);
    assert_int_equal(generated, 2 * (uint64_t)want_leaves);
    assert_int_equal(count, 6 * want_leaves);
    memset(seen, 0, c->f->leaf_count);
    for (size_t i = 0; i < count; ++i) {
        const xyl__foliage_captured *v = &buf[i];
        check_vertex(c, v);
        assert_true(in_lod(c->f, lods, v->leaf));
        int corner = (v->st[0] > 0) | (v->st[1] > 0) << 1;
        seen[v->leaf] |= (uint8_t)(1u << corner);
    }
    uint64_t drawn = 0;
    for (size_t k = 0; k < c->f->leaf_count; ++k) {
        if (seen[k]) {
            assert_int_equal(seen[k], 15);
            ++drawn;
        }
    }
    assert_int_equal(drawn, want_leaves);
    return drawn;
}

/* All the LODs of each sector: step i draws LOD min(i, merged_count) of every sector. */
static void every_lod_matches(suite *s, xyl_foliage *f, uint32_t stride, double *worst)
{
    xyl_diag d = {0};
    expect(xyl_foliage_gl_set_foliage(s->gl, f, &d), XYL_OK, &d);
    xyl_foliage_gpu_leaf *records = malloc(f->leaf_count * sizeof *records);
    assert_non_null(records);
    assert_int_equal(xyl_foliage_pack_gpu(f->leaves, f->leaf_count, records, NULL), XYL_OK);
    xyl_foliage_gl_frame fr;
    frame_of(f, 0.7f, 0.3f, &fr);
    compare c = {f, records, fr.view_proj, 0.0};
    size_t capacity = 6 * f->original_count;
    xyl__foliage_captured *buf = malloc(capacity * sizeof *buf);
    uint8_t *seen = malloc(f->leaf_count);
    uint32_t lods[XYL_FOLIAGE_MAX_SECTORS];
    uint32_t top = 0;
    for (uint32_t k = 0; k < f->sector_count; ++k)
        top = f->sectors[k].merged_count > top ? f->sectors[k].merged_count : top;
    for (uint32_t i = 0;; i = i + stride > top && i < top ? top : i + stride) {
        for (uint32_t k = 0; k < f->sector_count; ++k)
            lods[k] = i < f->sectors[k].merged_count ? i : f->sectors[k].merged_count;
        capture_and_compare(s, &c, &fr, lods, buf, capacity, seen);
        if (i >= top) break;
    }
    if (c.worst > *worst) *worst = c.worst;
    free(seen);
    free(buf);
    free(records);
}

static void gpu_corners_match_the_cpu_reference_at_every_lod(void **state)
{
    suite *s = need_gl(state);
    double worst = 0.0;
    for (uint32_t sectors = 1; sectors <= 3; sectors += 2) { /* one chain, and three sectors */
        xyl_foliage *f = tree_foliage("faycal-leaves", sectors);
        every_lod_matches(s, f, 1, &worst);
        xyl_foliage_destroy(f);
    }
    /* The default tree (5103 leaves) in three sectors: every LOD of each sector (26 million
     * vertices, seconds on llvmpipe; every 1024th under the sanitizers). */
    xyl_foliage *f = tree_foliage(xyl_lsystem_default_preset(), 3);
    every_lod_matches(s, f, SANITIZED ? 1024 : 1, &worst);
    xyl_foliage_destroy(f);
    print_message("worst clip-space error: %.3g of the terms' magnitude (bound %.0e)\n", worst,
                  REL_BOUND);
}

/* ---- 2. pixels ------------------------------------------------------------------------------ */

#define SIDE 64

typedef struct own_target {
    GLuint fbo, rb[2];
} own_target;

static own_target target_create(void)
{
    own_target t;
    glCreateRenderbuffers(2, t.rb);
    glNamedRenderbufferStorage(t.rb[0], GL_RGBA8, SIDE, SIDE);
    glNamedRenderbufferStorage(t.rb[1], GL_DEPTH_COMPONENT24, SIDE, SIDE);
    glCreateFramebuffers(1, &t.fbo);
    glNamedFramebufferRenderbuffer(t.fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, t.rb[0]);
    glNamedFramebufferRenderbuffer(t.fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.rb[1]);
    assert_int_equal(glCheckNamedFramebufferStatus(t.fbo, GL_FRAMEBUFFER), GL_FRAMEBUFFER_COMPLETE);
    return t;
}

static void target_destroy(own_target *t)
{
    glDeleteFramebuffers(1, &t->fbo);
    glDeleteRenderbuffers(2, t->rb);
}

/* One leaf filling clip space: side +X, axis +Y, so s runs with the image's x and t up it. */
static xyl_foliage *square_leaf(void)
{
    xyl_leaf l = {0};
    l.normal = (xyl_vec3){0, 0, 1};
    l.side = (xyl_vec3){1, 0, 0};
    l.axis = (xyl_vec3){0, 1, 0};
    xyl_foliage_desc fd = {0};
    fd.leaves = &l;
    fd.leaf_count = 1;
    xyl_foliage *f = NULL;
    assert_int_equal(xyl_foliage_build(&fd, &f, NULL), XYL_OK);
    return f;
}

static const uint8_t background[4] = {10, 20, 200, 255};

/* The identity camera (clip = world) with a light towards -z (the viewer's side of the
 * square's front face, whose normal is +z: GL's clip space looks down +z) and a white tint. */
static xyl_foliage_gl_frame square_frame(void)
{
    xyl_foliage_gl_frame fr = {0};
    for (int k = 0; k < 4; ++k) fr.view_proj[5 * k] = 1.0f;
    fr.light_dir[2] = -1.0f;
    fr.color[0] = fr.color[1] = fr.color[2] = fr.color[3] = 1.0f;
    return fr;
}

/* Draws the leaf into the test's framebuffer; rgba bottom row first. */
static void draw_square(suite *s, const xyl_foliage_gl_frame *fr, uint8_t *rgba)
{
    xyl_diag d = {0};
    own_target t = target_create();
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    glViewport(0, 0, SIDE, SIDE);
    glClearColor(background[0] / 255.0f, background[1] / 255.0f, background[2] / 255.0f, 1.0f);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    uint32_t lod = 0;
    expect(xyl_foliage_gl_draw(s->gl, fr, &lod, 1, &d), XYL_OK, &d);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, SIDE, SIDE, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    target_destroy(&t);
}

static void draw_textured(suite *s, const uint8_t *tex, uint8_t *rgba)
{
    xyl_diag d = {0};
    expect(xyl_foliage_gl_set_texture(s->gl, tex, 16, 16, &d), XYL_OK, &d);
    xyl_foliage_gl_frame fr = square_frame();
    draw_square(s, &fr, rgba);
}

static bool is_background(const uint8_t *px)
{
    return memcmp(px, background, 3) == 0;
}

/* A 16 x 16 texture, opaque white but for the texels `clear` picks (row y from the top). */
static void half_clear(uint8_t *tex, bool (*clear)(int x, int y))
{
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            uint8_t *t = tex + 4 * (16 * y + x);
            t[0] = t[1] = t[2] = 255;
            t[3] = clear && clear(x, y) ? 0 : 255;
        }
}

static bool left_half(int x, int y) { return (void)y, x < 8; }
static bool top_half(int x, int y) { return (void)x, y < 8; }

static void alpha_test_discards_the_transparent_half(void **state)
{
    suite *s = need_gl(state);
    xyl_foliage *f = square_leaf();
    xyl_diag d = {0};
    expect(xyl_foliage_gl_set_foliage(s->gl, f, &d), XYL_OK, &d);
    uint8_t tex[16 * 16 * 4], *rgba = malloc(4 * SIDE * SIDE);
    /* control: all opaque covers the whole image */
    half_clear(tex, NULL);
    draw_textured(s, tex, rgba);
    for (int i = 0; i < SIDE * SIDE; ++i) assert_false(is_background(rgba + 4 * i));
    /* u < 0.5 transparent: the left half (s < 0) shows the background, the right the leaf */
    half_clear(tex, left_half);
    draw_textured(s, tex, rgba);
    for (int y = 0; y < SIDE; ++y)
        for (int x = 0; x < SIDE; ++x) {
            if (abs(2 * x + 1 - SIDE) < 8) continue; /* linear filtering at the edge */
            assert_int_equal(is_background(rgba + 4 * (SIDE * y + x)), x < SIDE / 2);
        }
    /* the texture's top rows (the tip end, v = 1) transparent: the top of the image is empty;
     * glReadPixels' rows run bottom up */
    half_clear(tex, top_half);
    draw_textured(s, tex, rgba);
    for (int y = 0; y < SIDE; ++y)
        for (int x = 0; x < SIDE; ++x) {
            if (abs(2 * y + 1 - SIDE) < 8) continue;
            assert_int_equal(is_background(rgba + 4 * (SIDE * y + x)), y >= SIDE / 2);
        }
    free(rgba);
    xyl_foliage_destroy(f);
}

/* Brightness (r + g + b) of the middle pixel. */
static int middle(const uint8_t *rgba)
{
    const uint8_t *p = rgba + 4 * (SIDE * (SIDE / 2) + SIDE / 2);
    return p[0] + p[1] + p[2];
}

/* Double-sided: the back face (seen through a matrix mirroring x, which reverses the winding)
 * with the light on its side is lit as the front face is with the light on its side; a face
 * lit from behind is darker than that, but brighter than with no translucency. */
static void both_faces_are_lit_and_light_shines_through(void **state)
{
    suite *s = need_gl(state);
    xyl_foliage *f = square_leaf();
    xyl_diag d = {0};
    expect(xyl_foliage_gl_set_foliage(s->gl, f, &d), XYL_OK, &d);
    uint8_t tex[16 * 16 * 4], *rgba = malloc(4 * SIDE * SIDE);
    half_clear(tex, NULL);
    expect(xyl_foliage_gl_set_texture(s->gl, tex, 16, 16, &d), XYL_OK, &d);
    xyl_foliage_gl_frame fr = square_frame();
    fr.light_dir[2] = 1.0f; /* along the front face's normal */
    draw_square(s, &fr, rgba);
    int front_lit = middle(rgba);
    fr.view_proj[0] = -1.0f; /* the back face, normal -z */
    fr.light_dir[2] = -1.0f;
    draw_square(s, &fr, rgba);
    int back_lit = middle(rgba);
    fr.light_dir[2] = 1.0f; /* the back face lit from behind */
    draw_square(s, &fr, rgba);
    int through = middle(rgba);
    fr.translucency = -1.0f;
    draw_square(s, &fr, rgba);
    int unlit = middle(rgba);
    print_message("front lit %d, back lit %d, lit from behind %d, without translucency %d\n",
                  front_lit, back_lit, through, unlit);
    assert_true(abs(front_lit - back_lit) <= 3);
    assert_true(through < front_lit - 30);
    assert_true(through > unlit + 30);
    assert_true(unlit > 0);
    free(rgba);
    xyl_foliage_destroy(f);
}

/* ---- 3. bad input --------------------------------------------------------------------------- */

static void expect_no_gl_call(xyl_result got, xyl_result want, const xyl_diag *d)
{
    expect(got, want, d);
    GLint prog = -1;
    glGetIntegerv(GL_CURRENT_PROGRAM, &prog);
    assert_int_equal(prog, 0); /* the renderer's program was never bound */
}

/* ---- 3. the per-leaf cut: GPU = CPU, and a valid cut ----------------------------------------- */

/* The GPU's cut for one eye against xyl_foliage_cut (foliage_cut_check.h). */
static size_t compare_cut(suite *s, const xyl_foliage *f, const xyl_foliage_view *v,
                          const xyl_foliage_gl_frame *fr, size_t *ties)
{
    xyl_diag d = {0};
    expect(xyl_foliage_gl_draw_adaptive(s->gl, fr, v, &d), XYL_OK, &d);
    size_t n_gpu = 0;
    expect(xyl_foliage_gl_last_cut(s->gl, NULL, 0, &n_gpu, &d), XYL_OK, &d);
    uint32_t *gpu = malloc((n_gpu + 1) * sizeof *gpu);
    assert_non_null(gpu);
    expect(xyl_foliage_gl_last_cut(s->gl, gpu, n_gpu, &n_gpu, &d), XYL_OK, &d);
    size_t n = cut_compare(f, v, gpu, n_gpu, ties);
    free(gpu);
    return n;
}

static void gpu_cut_equals_the_cpu_cut(void **state)
{
    suite *s = need_gl(state);
    own_target t = target_create();
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    glViewport(0, 0, SIDE, SIDE);
    for (uint32_t sectors = 1; sectors <= 4; sectors += 3) {
        xyl_foliage *f = tree_foliage(xyl_lsystem_default_preset(), sectors);
        xyl_diag d = {0};
        expect(xyl_foliage_gl_set_foliage(s->gl, f, &d), XYL_OK, &d);
        /* how often a merged leaf's error is below a child's (the cut does not need it) */
        size_t below = 0, merged = 0;
        for (size_t k = 0; k < f->leaf_count; ++k) {
            const xyl_leaf_link *l = &f->links[k];
            if (l->children[0] < 0) continue;
            ++merged;
            below += l->error < f->links[l->children[0]].error ||
                     l->error < f->links[l->children[1]].error;
        }
        xyl_foliage_gl_frame fr;
        frame_of(f, 0.7f, 0.3f, &fr);
        size_t ties = 0, first = 0, last = 0;
        for (int i = 0; i < CUT_DISTANCES; ++i)
            for (int b = 0; b < CUT_BUDGETS; ++b) {
                xyl_foliage_view v = cut_view(f, i, b);
                size_t n = compare_cut(s, f, &v, &fr, &ties);
                if (i == 0 && b == 0) first = n;
                last = n;
            }
        /* inside the crown every original; far away the roots of the forest */
        assert_int_equal(first, f->original_count);
        assert_int_equal(last, f->coarsest_count);
        print_message("%u sector(s): %zu leaves, %zu of %zu merged leaves with an error below a "
                      "child's, %zu leaves decided by a float tie\n",
                      sectors, f->leaf_count, below, merged, ties);
        xyl_foliage_destroy(f);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    target_destroy(&t);
}

static void adaptive_bad_input_gets_result_codes(void **state)
{
    (void)need_gl(state);
    xyl_diag d = {0};
    xyl_foliage_gl *fresh = NULL;
    expect(xyl_foliage_gl_create(NULL, &fresh, &d), XYL_OK, &d);
    xyl_foliage *f = tree_foliage("faycal-leaves", 1);
    xyl_foliage_gl_frame fr;
    frame_of(f, 0.3f, 0.2f, &fr);
    xyl_foliage_view v = {{0, 1, 30}, 0, 0, 0};
    own_target t = target_create();
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    glUseProgram(0);
    size_t n = 0;
    expect_no_gl_call(xyl_foliage_gl_draw_adaptive(fresh, &fr, &v, &d), XYL_ERR_INVALID_ARGUMENT,
                      &d);
    expect(xyl_foliage_gl_last_cut(fresh, NULL, 0, &n, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_gl_set_foliage(fresh, f, &d), XYL_OK, &d);
    glUseProgram(0);
    expect_no_gl_call(xyl_foliage_gl_draw_adaptive(NULL, &fr, &v, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect_no_gl_call(xyl_foliage_gl_draw_adaptive(fresh, NULL, &v, &d), XYL_ERR_INVALID_ARGUMENT,
                      &d);
    expect_no_gl_call(xyl_foliage_gl_draw_adaptive(fresh, &fr, NULL, &d), XYL_ERR_INVALID_ARGUMENT,
                      &d);
    xyl_foliage_view bad = v;
    bad.error_px = -1.0f;
    expect_no_gl_call(xyl_foliage_gl_draw_adaptive(fresh, &fr, &bad, &d), XYL_ERR_INVALID_ARGUMENT,
                      &d);
    bad = v;
    bad.fovy = 4.0f;
    expect_no_gl_call(xyl_foliage_gl_draw_adaptive(fresh, &fr, &bad, &d), XYL_ERR_INVALID_ARGUMENT,
                      &d);
    bad = v;
    bad.eye[1] = NAN;
    expect_no_gl_call(xyl_foliage_gl_draw_adaptive(fresh, &fr, &bad, &d), XYL_ERR_NON_FINITE, &d);
    xyl_foliage_gl_frame zero = {0};
    expect_no_gl_call(xyl_foliage_gl_draw_adaptive(fresh, &zero, &v, &d), XYL_ERR_INVALID_ARGUMENT,
                      &d);
    /* a read-back before any adaptive draw of this upload */
    expect(xyl_foliage_gl_last_cut(fresh, NULL, 0, &n, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_gl_draw_adaptive(fresh, &fr, &v, &d), XYL_OK, &d);
    expect(xyl_foliage_gl_last_cut(NULL, NULL, 0, &n, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_gl_last_cut(fresh, NULL, 0, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_gl_last_cut(fresh, NULL, 0, &n, &d), XYL_OK, &d);
    assert_true(n > 0);
    uint32_t one = 0;
    if (n > 1)
        expect(xyl_foliage_gl_last_cut(fresh, &one, 1, &n, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    target_destroy(&t);
    xyl_foliage_gl_destroy(fresh);
    xyl_foliage_destroy(f);
}

static void bad_input_gets_result_codes(void **state)
{
    (void)need_gl(state);
    xyl_diag d = {0};
    xyl_foliage_gl *fresh = NULL;
    expect(xyl_foliage_gl_create(NULL, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_gl_create(NULL, &fresh, &d), XYL_OK, &d);
    xyl_foliage *f = tree_foliage("faycal-leaves", 3);
    xyl_foliage_gl_frame fr;
    frame_of(f, 0.3f, 0.2f, &fr);
    uint32_t lods[3] = {0, 0, 0};
    own_target t = target_create(); /* the surfaceless default framebuffer draws nothing */
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    glUseProgram(0);
    /* nothing uploaded yet */
    expect_no_gl_call(xyl_foliage_gl_draw(fresh, &fr, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    /* set_foliage: NULL, zero leaves */
    expect(xyl_foliage_gl_set_foliage(NULL, f, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_gl_set_foliage(fresh, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_foliage_desc none = {0};
    xyl_foliage *empty = NULL;
    assert_int_equal(xyl_foliage_build(&none, &empty, NULL), XYL_OK);
    expect(xyl_foliage_gl_set_foliage(fresh, empty, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_foliage_destroy(empty);
    /* a table reaching outside the array */
    xyl_foliage bent = *f;
    xyl_foliage_sector sectors[3];
    memcpy(sectors, f->sectors, sizeof sectors);
    sectors[2].base = (uint32_t)f->leaf_count;
    bent.sectors = sectors;
    expect(xyl_foliage_gl_set_foliage(fresh, &bent, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_int_equal(d.index, 2);
    expect(xyl_foliage_gl_set_foliage(fresh, f, &d), XYL_OK, &d);
    /* draw: NULLs, LOD count and range, matrix, cutoff */
    glUseProgram(0);
    expect_no_gl_call(xyl_foliage_gl_draw(NULL, &fr, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect_no_gl_call(xyl_foliage_gl_draw(fresh, NULL, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect_no_gl_call(xyl_foliage_gl_draw(fresh, &fr, NULL, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect_no_gl_call(xyl_foliage_gl_draw(fresh, &fr, lods, 1, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    lods[1] = f->sectors[1].merged_count + 1;
    expect_no_gl_call(xyl_foliage_gl_draw(fresh, &fr, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_int_equal(d.index, 1);
    lods[1] = f->sectors[1].merged_count; /* the coarsest is fine */
    xyl_foliage_gl_frame bad = fr;
    bad.view_proj[7] = NAN;
    expect_no_gl_call(xyl_foliage_gl_draw(fresh, &bad, lods, 3, &d), XYL_ERR_NON_FINITE, &d);
    bad = fr;
    bad.view_proj[0] = INFINITY;
    expect_no_gl_call(xyl_foliage_gl_draw(fresh, &bad, lods, 3, &d), XYL_ERR_NON_FINITE, &d);
    memset(bad.view_proj, 0, sizeof bad.view_proj);
    expect_no_gl_call(xyl_foliage_gl_draw(fresh, &bad, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bad = fr;
    bad.light_dir[1] = NAN;
    expect_no_gl_call(xyl_foliage_gl_draw(fresh, &bad, lods, 3, &d), XYL_ERR_NON_FINITE, &d);
    bad = fr;
    bad.alpha_cutoff = 1.5f;
    expect_no_gl_call(xyl_foliage_gl_draw(fresh, &bad, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    /* and the good draw binds the program (so the checks above could fail) */
    expect(xyl_foliage_gl_draw(fresh, &fr, lods, 3, &d), XYL_OK, &d);
    GLint prog = 0;
    glGetIntegerv(GL_CURRENT_PROGRAM, &prog);
    assert_int_not_equal(prog, 0);
    glUseProgram(0);
    /* textures: NULL, sides of 0 and beyond the limit */
    uint8_t px[4] = {255, 255, 255, 255};
    expect(xyl_foliage_gl_set_texture(NULL, px, 1, 1, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_gl_set_texture(fresh, NULL, 1, 1, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_gl_set_texture(fresh, px, 0, 1, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_gl_set_texture(fresh, px, 1, XYL_FOLIAGE_GL_MAX_TEXTURE_SIDE + 1, &d),
           XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_gl_set_texture(fresh, px, 1, 1, &d), XYL_OK, &d);
    /* capture: its own NULLs */
    size_t count = 0;
    uint64_t gen = 0;
    expect(xyl__foliage_gl_capture(fresh, &fr, lods, 3, NULL, 4, &count, &gen, &d),
           XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl__foliage_gl_capture(fresh, &fr, lods, 3, NULL, 0, NULL, &gen, &d),
           XYL_ERR_INVALID_ARGUMENT, &d);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    target_destroy(&t);
    xyl_foliage_gl_destroy(fresh);
    xyl_foliage_gl_destroy(NULL);
    xyl_foliage_destroy(f);
}

static void create_without_a_context_is_unsupported(void **state)
{
    suite *s = need_gl(state);
    xyl_foliage_gl_destroy(s->gl);
    s->gl = NULL;
    xyl_gl_context_destroy(s->ctx);
    s->ctx = NULL;
    xyl_diag d = {0};
    xyl_foliage_gl *gl = NULL;
    expect(xyl_foliage_gl_create(NULL, &gl, &d), XYL_ERR_UNSUPPORTED, &d);
    assert_null(gl);
    assert_int_equal(xyl_gl_context_create_headless(NULL, &s->ctx, &d), XYL_OK);
    expect(xyl_foliage_gl_create(NULL, &s->gl, &d), XYL_OK, &d);
}

/* ---- 4. memory ------------------------------------------------------------------------------ */

/* The renderer's own memory (its record, the LOD tables, the packed records while uploading)
 * comes from the desc's allocator and all of it goes back; failing each allocation in turn is
 * XYL_ERR_OUT_OF_MEMORY with nothing left behind and the previous upload still drawn. */
static void renderer_allocates_through_the_callers_allocator(void **state)
{
    (void)need_gl(state);
    xyl_foliage *f = tree_foliage("faycal-leaves", 3), *one = square_leaf();
    xyl_foliage_gl_frame fr;
    frame_of(f, 0.3f, 0.2f, &fr);
    const uint32_t lods[3] = {1, 2, 3}, lod0 = 0;
    xyl_diag d = {0};
    own_target t = target_create();
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    size_t needed = 0;
    for (size_t fail_at = 1;; ++fail_at) {
        tu_counter c = {0, 0, 0, fail_at};
        xyl_foliage_gl_desc gd = {0};
        gd.alloc = tu_counting(&c);
        xyl_foliage_gl *gl = NULL;
        xyl_result r = xyl_foliage_gl_create(&gd, &gl, &d);
        if (r != XYL_OK) assert_null(gl);
        bool one_up = false;
        if (r == XYL_OK) r = xyl_foliage_gl_set_foliage(gl, one, &d);
        if (r == XYL_OK) {
            one_up = true;
            r = xyl_foliage_gl_set_foliage(gl, f, &d);
        }
        xyl_diag d2 = {0};
        if (r == XYL_OK) expect(xyl_foliage_gl_draw(gl, &fr, lods, 3, &d2), XYL_OK, &d2);
        else if (one_up) expect(xyl_foliage_gl_draw(gl, &fr, &lod0, 1, &d2), XYL_OK, &d2);
        xyl_foliage_gl_destroy(gl);
        assert_int_equal(c.allocs, c.frees);
        if (r == XYL_OK) {
            needed = fail_at - 1;
            break;
        }
        expect(r, XYL_ERR_OUT_OF_MEMORY, &d);
        assert_true(fail_at < 64);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    target_destroy(&t);
    print_message("%zu allocations from create to the second upload\n", needed);
    assert_true(needed >= 5); /* the record; per upload the packed records and two tables */
    xyl_foliage_destroy(one);
    xyl_foliage_destroy(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(gpu_corners_match_the_cpu_reference_at_every_lod),
        cmocka_unit_test(alpha_test_discards_the_transparent_half),
        cmocka_unit_test(both_faces_are_lit_and_light_shines_through),
        cmocka_unit_test(bad_input_gets_result_codes),
        cmocka_unit_test(gpu_cut_equals_the_cpu_cut),
        cmocka_unit_test(adaptive_bad_input_gets_result_codes),
        cmocka_unit_test(create_without_a_context_is_unsupported),
        cmocka_unit_test(renderer_allocates_through_the_callers_allocator),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

/* Transitions between levels of detail (docs/foliage.md, "Transitions"): the fade's band,
 * hysteresis and dither levels on the CPU; the screen-door dither splitting every pixel between
 * two draws on the stems', the leaves' and the billboard's renderers; and a camera dolly past
 * the switch from the whole tree (tessellated stems and leaves) to its billboard, whose frame-to-
 * frame image changes at the switch stay near those of ordinary frames with the cross-fade and
 * do not without it. On a headless EGL context (llvmpipe where there is no GPU); without a
 * usable GL 4.5 context the GPU tests are skipped, and say why. */
#include <epoxy/gl.h>
#include <math.h>

#include "test_util.h"
#include "foliage_tree.h"
#include "../shaders/xyl_dither.h"
#include <xylem/xyl_billboard_gl.h>
#include <xylem/xyl_foliage_gl.h>
#include <xylem/xyl_stems.h>
#include <xylem/xyl_tess_gl.h>

#define SIDE 160 /* pixels of a dolly frame */
#define FRAMES 128
/* The dolly's worst frame-to-frame change during the cross-fade, against the tree-alone dolly's
 * change at the same frame: at most this factor (measured on llvmpipe: 1.04 with the fade,
 * 1.83 at the hard switch's frame) */
#define FADE_FACTOR 1.5

static void expect(xyl_result got, xyl_result want, const xyl_diag *d)
{
    if (got != want)
        fail_msg("expected %s, got %s (%s)", xyl_result_string(want), xyl_result_string(got),
                 d->message);
    if (want != XYL_OK) assert_true(strlen(d->message) > 0);
}

/* ---- 1. the fade on the CPU ---------------------------------------------------------------- */

static xyl_fade_draws fade_at(const xyl_fade_desc *fd, double distance, xyl_fade_state *st)
{
    xyl_fade_draws out;
    xyl_diag d = {0};
    expect(xyl_fade_update(fd, distance, st, &out, &d), XYL_OK, &d);
    return out;
}

/* Through the band the far share grows from 0 to 1 in steps of the dither's levels, the two keep
 * ranges split [0, 1) between them, and only the level with a share is drawn. */
static void the_band_hands_over_in_dither_levels(void **state)
{
    (void)state;
    const xyl_fade_desc fd = {10.0, 20.0, 0.0};
    float last = -1.0f;
    for (int i = 0; i <= 300; ++i) {
        double dist = 5.0 + 0.05 * i;
        xyl_fade_state st = {0};
        xyl_fade_draws o = fade_at(&fd, dist, &st);
        double want = dist <= 10.0 ? 0.0 : dist >= 20.0 ? 1.0 : (dist - 10.0) / 10.0;
        assert_true(fabs(o.t - want) <= 0.5 / 64 + 1e-6);
        assert_float_equal(o.t * 64.0f, roundf(o.t * 64.0f), 1e-4);
        assert_true(o.t >= last);
        last = o.t;
        assert_true(o.near == (o.t < 1.0f) && o.far == (o.t > 0.0f));
        if (o.near && o.far) {
            assert_true(o.near_keep[0] == o.t && o.near_keep[1] == 1.0f);
            assert_true(o.far_keep[0] == 0.0f && o.far_keep[1] == o.t);
        } else {
            const float zero[2] = {0.0f, 0.0f};
            assert_memory_equal(o.near ? o.near_keep : o.far_keep, zero, sizeof zero);
        }
    }
}

/* The two ranges keep complementary pixels: each of the 64 thresholds once per 8 x 8 block,
 * and each pixel in exactly one range whatever t. */
static void the_dither_splits_every_pixel_once(void **state)
{
    (void)state;
    uint8_t seen[64] = {0};
    for (uint32_t y = 0; y < 8; ++y)
        for (uint32_t x = 0; x < 8; ++x) {
            float b = xyl_dither_threshold(x, y);
            int k = (int)(b * 64.0f);
            assert_float_equal(b, (k + 0.5f) / 64.0f, 1e-7);
            assert_int_equal(seen[k]++, 0);
            assert_float_equal(b, xyl_dither_threshold(x + 8, y + 16), 0.0);
        }
    /* spread evenly: the first 4 levels fall one in each 4 x 4 quadrant of the block */
    for (int q = 0; q < 4; ++q) {
        int hits = 0;
        for (uint32_t y = 0; y < 8; ++y)
            for (uint32_t x = 0; x < 8; ++x)
                hits += xyl_dither_threshold(x, y) < 4.0f / 64.0f &&
                        (x / 4) + 2 * (y / 4) == (uint32_t)q;
        assert_int_equal(hits, 1);
    }
}

/* A still camera gets the same draws every frame; one that jitters by less than the
 * hysteresis keeps its share; moving on past it, the share follows again. */
static void hysteresis_holds_a_jittering_camera(void **state)
{
    (void)state;
    const xyl_fade_desc fd = {10.0, 20.0, 0.5};
    xyl_fade_state st = {0};
    xyl_fade_draws first = fade_at(&fd, 14.0, &st);
    for (int i = 0; i < 100; ++i) {
        double jitter = 0.45 * sin(0.7 * i);
        xyl_fade_draws o = fade_at(&fd, 14.0 + jitter, &st);
        assert_memory_equal(&o, &first, sizeof o);
    }
    xyl_fade_draws on = fade_at(&fd, 16.0, &st);
    assert_true(on.t > first.t);
    /* backing off by less than the hysteresis keeps it; by more, follows */
    xyl_fade_draws held = fade_at(&fd, 15.6, &st);
    assert_float_equal(held.t, on.t, 0.0);
    xyl_fade_draws back = fade_at(&fd, 14.0, &st);
    assert_true(back.t < on.t);
    /* without hysteresis a camera at a level's edge still does not toggle between levels */
    const xyl_fade_desc none = {10.0, 20.0, 0.0};
    xyl_fade_state s2 = {0};
    double edge = 10.0 + 10.0 * (20.5 / 64.0); /* t on the rounding edge of levels 20 and 21 */
    xyl_fade_draws a = fade_at(&none, edge - 1e-3, &s2);
    for (int i = 0; i < 20; ++i) {
        xyl_fade_draws o = fade_at(&none, edge + (i % 2 ? 1e-3 : -1e-3), &s2);
        assert_float_equal(o.t, a.t, 0.0);
    }
}

static void fade_bad_input_gets_result_codes(void **state)
{
    (void)state;
    xyl_diag d = {0};
    xyl_fade_desc fd = {10.0, 20.0, 0.0};
    xyl_fade_state st = {0};
    xyl_fade_draws o;
    expect(xyl_fade_update(NULL, 1.0, &st, &o, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_fade_update(&fd, 1.0, NULL, &o, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_fade_update(&fd, 1.0, &st, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_fade_update(&fd, NAN, &st, &o, &d), XYL_ERR_NON_FINITE, &d);
    expect(xyl_fade_update(&fd, -1.0, &st, &o, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_fade_desc bad = {20.0, 10.0, 0.0};
    expect(xyl_fade_update(&bad, 1.0, &st, &o, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bad = (xyl_fade_desc){10.0, 10.0, 0.0};
    expect(xyl_fade_update(&bad, 1.0, &st, &o, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bad = (xyl_fade_desc){10.0, 20.0, -1.0};
    expect(xyl_fade_update(&bad, 1.0, &st, &o, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bad = (xyl_fade_desc){10.0, INFINITY, 0.0};
    expect(xyl_fade_update(&bad, 1.0, &st, &o, &d), XYL_ERR_NON_FINITE, &d);
    assert_false(st.primed); /* untouched */
}

/* ---- the GPU suite --------------------------------------------------------------------------- */

static const float scene_light[3] = {0.4f, 0.8f, 0.45f};

typedef struct suite {
    xyl_gl_context *ctx;
    char why[320];
    xyl_skeleton *sk;
    xyl_mesh *mesh;
    xyl_tess_patterns *patterns;
    xyl_tess_patches *patches;
    xyl_tess_batches *batches;
    xyl_tess_gl *stems;
    xyl_foliage *tree;
    xyl_foliage_gl *leaves;
    xyl_billboard_gl *billboard;
    float lo[3], hi[3];
    GLuint fbo, rb[2];
} suite;

/* The whole tree with this matrix, light, eye and dithers (NULL: every fragment): stems at
 * the levels a 0.5 px budget picks from the eye, leaves at the LOD it picks. */
static xyl_result draw_tree(suite *s, const float view_proj[16], const float light[3],
                            const float eye[3], const float *dither, xyl_diag *d)
{
    xyl_tess_view tv = {0};
    memcpy(tv.eye, eye, sizeof tv.eye);
    tv.viewport_height = SIDE;
    xyl_result r = xyl_tess_select(s->patches, s->patterns, &tv, s->batches, d);
    xyl_tess_frame sf = {0};
    memcpy(sf.view_proj, view_proj, sizeof sf.view_proj);
    memcpy(sf.light_dir, light, 3 * sizeof *light);
    sf.color[0] = 0.45f, sf.color[1] = 0.33f, sf.color[2] = 0.22f, sf.color[3] = 1.0f;
    if (dither) sf.dither = xyl_tess_dither(dither[0], dither[1]);
    if (r == XYL_OK) r = xyl_tess_gl_draw(s->stems, s->batches, &sf, XYL_TESS_PATH_INSTANCED, d);
    xyl_foliage_view fv = {{eye[0], eye[1], eye[2]}, 0.8f, SIDE, 0.5f};
    uint32_t lod[1];
    if (r == XYL_OK) r = xyl_foliage_pick(s->tree, &fv, lod, 1, d);
    xyl_foliage_gl_frame lf = {0};
    memcpy(lf.view_proj, view_proj, sizeof lf.view_proj);
    memcpy(lf.light_dir, light, sizeof lf.light_dir);
    if (dither) memcpy(lf.dither, dither, sizeof lf.dither);
    if (r == XYL_OK) r = xyl_foliage_gl_draw(s->leaves, &lf, lod, 1, d);
    return r;
}

/* The bake's callback: the tree seen from the bake camera (an orthographic matrix; the eye for
 * the level choice far off along its line of sight does not matter at a fine budget, so the
 * centre of the box stands for it at a tree's size away). */
static xyl_result bake_draw(void *user, const float view_proj[16], const float light[3],
                            xyl_diag *d)
{
    suite *s = user;
    float eye[3];
    for (int k = 0; k < 3; ++k)
        eye[k] = 0.5f * (s->lo[k] + s->hi[k]) + light[k] * (s->hi[1] - s->lo[1]);
    return draw_tree(s, view_proj, light, eye, NULL, d);
}

static int setup(void **state)
{
    suite *s = calloc(1, sizeof *s);
    if (!s) return -1;
    *state = s;
    xyl_diag d = {0};
    if (xyl_gl_context_create_headless(NULL, &s->ctx, &d) != XYL_OK) {
        snprintf(s->why, sizeof s->why, "no usable GL 4.5 context: %s", d.message);
        return 0;
    }
    s->sk = tu_grow(xyl_lsystem_preset_source(xyl_lsystem_default_preset()), NULL);
    if (xyl_stems_build(s->sk, NULL, &s->mesh, NULL, &d) ||
        xyl_tess_patterns_create(16, NULL, &s->patterns, &d) ||
        xyl_tess_patches_create(s->mesh, NULL, &s->patches, &d) ||
        xyl_tess_batches_create(NULL, &s->batches, &d) ||
        xyl_tess_gl_create(NULL, s->patterns, &s->stems, &d) ||
        xyl_tess_gl_set_patches(s->stems, s->patches, &d) ||
        xyl_foliage_gl_create(NULL, &s->leaves, &d))
        return fprintf(stderr, "setup: %s\n", d.message), -1;
    s->tree = ft_foliage_of(s->sk, 1);
    if (xyl_foliage_gl_set_foliage(s->leaves, s->tree, &d)) return -1;
    /* the box of stems and leaves */
    xyl_foliage_bounds(s->tree, s->lo, s->hi);
    for (size_t v = 0; v < s->mesh->vertex_count; ++v) {
        const float p[3] = {s->mesh->positions[v].x, s->mesh->positions[v].y,
                            s->mesh->positions[v].z};
        for (int k = 0; k < 3; ++k) {
            s->lo[k] = fminf(s->lo[k], p[k]);
            s->hi[k] = fmaxf(s->hi[k], p[k]);
        }
    }
    xyl_billboard_gl_desc bd = {0};
    bd.kind = XYL_BILLBOARD_CROSS;
    bd.planes = 4;
    bd.resolution = 256;
    memcpy(bd.light_dir, scene_light, sizeof bd.light_dir); /* baked under the scene's light */
    memcpy(bd.lo, s->lo, sizeof bd.lo);
    memcpy(bd.hi, s->hi, sizeof bd.hi);
    if (xyl_billboard_gl_bake(&bd, bake_draw, s, &s->billboard, &d))
        return fprintf(stderr, "bake: %s\n", d.message), -1;
    glCreateRenderbuffers(2, s->rb);
    glNamedRenderbufferStorage(s->rb[0], GL_RGBA8, SIDE, SIDE);
    glNamedRenderbufferStorage(s->rb[1], GL_DEPTH_COMPONENT24, SIDE, SIDE);
    glCreateFramebuffers(1, &s->fbo);
    glNamedFramebufferRenderbuffer(s->fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, s->rb[0]);
    glNamedFramebufferRenderbuffer(s->fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, s->rb[1]);
    return glCheckNamedFramebufferStatus(s->fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE ? 0
                                                                                            : -1;
}

static int teardown(void **state)
{
    suite *s = *state;
    if (s->ctx) {
        glDeleteFramebuffers(1, &s->fbo);
        glDeleteRenderbuffers(2, s->rb);
    }
    xyl_billboard_gl_destroy(s->billboard);
    xyl_foliage_gl_destroy(s->leaves);
    xyl_foliage_destroy(s->tree);
    xyl_tess_gl_destroy(s->stems);
    xyl_tess_batches_destroy(s->batches);
    xyl_tess_patches_destroy(s->patches);
    xyl_tess_patterns_destroy(s->patterns);
    xyl_mesh_destroy(s->mesh);
    xyl_skeleton_destroy(s->sk);
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

typedef struct shot {
    xyl_tess_camera cam;
    float view_proj[16], eye[3];
} shot;

/* The camera framing the tree from azimuth 30, elevation 15 degrees, zoomed to factor times the
 * framing distance. */
static shot shot_at(const suite *s, float factor)
{
    shot sh;
    xyl_tess_camera_frame(s->lo, s->hi, 0.52f, 0.26f, 0.8f, 1.0f, &sh.cam);
    xyl_tess_camera_zoom(&sh.cam, factor);
    assert_int_equal(xyl_tess_camera_matrix(&sh.cam, XYL_TESS_CLIP_GL, sh.view_proj, NULL), XYL_OK);
    memcpy(sh.eye, sh.cam.eye, sizeof sh.eye);
    return sh;
}

static double distance_of(const suite *s, const shot *sh)
{
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        double c = 0.5 * ((double)s->lo[k] + s->hi[k]) - sh->eye[k];
        d2 += c * c;
    }
    return sqrt(d2);
}

/* One frame: the tree with near_keep where near, the billboard with far_keep where far. */
static void render(suite *s, const shot *sh, const xyl_fade_draws *o, uint8_t *rgba)
{
    glBindFramebuffer(GL_FRAMEBUFFER, s->fbo);
    glViewport(0, 0, SIDE, SIDE);
    glClearColor(0.8f, 0.86f, 0.92f, 1.0f);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    xyl_diag d = {0};
    if (o->near)
        expect(draw_tree(s, sh->view_proj, scene_light, sh->eye, o->near_keep, &d), XYL_OK, &d);
    if (o->far) {
        xyl_billboard_gl_frame bf = {0};
        memcpy(bf.view_proj, sh->view_proj, sizeof bf.view_proj);
        memcpy(bf.eye, sh->eye, sizeof bf.eye);
        memcpy(bf.light_dir, scene_light, sizeof bf.light_dir);
        memcpy(bf.dither, o->far_keep, sizeof bf.dither);
        expect(xyl_billboard_gl_draw(s->billboard, &bf, &d), XYL_OK, &d);
    }
    glReadPixels(0, 0, SIDE, SIDE, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

static double rmse(const uint8_t *a, const uint8_t *b)
{
    double sum = 0.0;
    for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i)
        for (int c = 0; c < 3; ++c) {
            double e = ((double)a[4 * i + c] - b[4 * i + c]) / 255.0;
            sum += e * e;
        }
    return sqrt(sum / (3.0 * SIDE * SIDE));
}

static bool background(const uint8_t *px)
{
    return abs(px[0] - 204) <= 1 && abs(px[1] - 219) <= 1 && abs(px[2] - 235) <= 1;
}

/* Two draws of one level with the ranges [0, t) and [t, 1) cover the pixels one draw without
 * dither covers, each pixel once, each about its share; on the stems, the leaves and the
 * billboard alike. */
static void the_dither_splits_a_draw_between_two_ranges(void **state)
{
    suite *s = need_gl(state);
    shot sh = shot_at(s, 1.0f);
    uint8_t *all = malloc(4 * SIDE * SIDE), *a = malloc(4 * SIDE * SIDE),
            *b = malloc(4 * SIDE * SIDE);
    assert_true(all && a && b);
    for (int level = 0; level < 2; ++level) { /* the tree; the billboard */
        xyl_fade_draws o = {0};
        o.near = level == 0, o.far = level == 1;
        render(s, &sh, &o, all);
        const float t = 21.0f / 64.0f;
        float lower[2] = {0.0f, t}, upper[2] = {t, 1.0f};
        memcpy(level ? o.far_keep : o.near_keep, lower, sizeof lower);
        render(s, &sh, &o, a);
        memcpy(level ? o.far_keep : o.near_keep, upper, sizeof upper);
        render(s, &sh, &o, b);
        size_t covered = 0, in_a = 0, both = 0, neither = 0;
        for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i) {
            bool c = !background(all + 4 * i), ca = !background(a + 4 * i),
                 cb = !background(b + 4 * i);
            covered += c;
            in_a += ca;
            both += ca && cb;
            /* a covered pixel is covered by one of the halves, with the colour of the whole:
             * the dither only removes fragments */
            if (c && !ca && !cb) ++neither;
            if (ca) assert_memory_equal(a + 4 * i, all + 4 * i, 3);
            if (cb) assert_memory_equal(b + 4 * i, all + 4 * i, 3);
        }
        print_message("%s: %zu pixels covered, the lower range %zu (share %.3f, t %.3f), both "
                      "%zu, neither %zu\n",
                      level ? "billboard" : "tree", covered, in_a,
                      (double)in_a / (double)covered, (double)t, both, neither);
        assert_true(covered > 500);
        assert_int_equal(both, 0);
        /* a pixel whose front surface is discarded may show what lies behind it: only where
         * the halves do not cover it together is it neither's */
        assert_true(neither <= covered / 50);
        assert_true(fabs((double)in_a / (double)covered - t) < 0.05);
    }
    free(all);
    free(a);
    free(b);
}

/* The dolly: the camera backs off from 2 to 4.5 framing distances in FRAMES geometric steps,
 * three times: with the tree alone (the ordinary frames), handing over to its billboard with
 * the cross-fade between 2.5 and 3.5 framing distances, and with a hard switch at 3. At each
 * frame of a hand-over, its change from the frame before (RMSE of RGB) is compared with the
 * tree-alone dolly's change at the same frame. */
static void a_dolly_past_the_billboard_switch_does_not_pop(void **state)
{
    suite *s = need_gl(state);
    shot base = shot_at(s, 1.0f);
    double unit = distance_of(s, &base);
    const xyl_fade_desc passes[3] = {{1e6 * unit, 2e6 * unit, 0.0},
                                     {2.5 * unit, 3.5 * unit, 0.02 * unit},
                                     {3.0 * unit, 3.0 * unit * (1.0 + 1e-9), 0.0}};
    uint8_t *prev = malloc(4 * SIDE * SIDE), *cur = malloc(4 * SIDE * SIDE);
    assert_true(prev && cur);
    double change[3][FRAMES];
    bool handing[3][FRAMES];
    for (int pass = 0; pass < 3; ++pass) {
        xyl_fade_state st = {0};
        float last_t = 0.0f;
        for (int i = 0; i < FRAMES; ++i) {
            float factor = 2.0f * powf(4.5f / 2.0f, (float)i / (FRAMES - 1));
            shot sh = shot_at(s, factor);
            xyl_fade_draws o = fade_at(&passes[pass], distance_of(s, &sh), &st);
            render(s, &sh, &o, cur);
            change[pass][i] = i ? rmse(prev, cur) : 0.0;
            handing[pass][i] = i && o.t != last_t;
            last_t = o.t;
            uint8_t *swap = prev;
            prev = cur;
            cur = swap;
        }
    }
    double worst[3] = {0.0, 0.0, 0.0};
    int frames[3] = {0, 0, 0};
    for (int pass = 1; pass < 3; ++pass)
        for (int i = 1; i < FRAMES; ++i) {
            assert_false(handing[0][i]);
            if (!handing[pass][i]) continue;
            ++frames[pass];
            worst[pass] = fmax(worst[pass], change[pass][i] / change[0][i]);
        }
    print_message("dolly of %d frames: the cross-fade's %d frames change at most %.2f x the "
                  "tree alone's, the hard switch's frame %.2f x\n",
                  FRAMES, frames[1], worst[1], worst[2]);
    assert_true(frames[1] >= 5 && frames[2] == 1);
    assert_true(worst[1] <= FADE_FACTOR);
    assert_true(worst[2] > FADE_FACTOR); /* the test sees a pop where there is one */
    free(prev);
    free(cur);
}

/* A still camera in the band draws the same picture frame after frame. */
static void a_still_camera_in_the_band_never_flickers(void **state)
{
    suite *s = need_gl(state);
    shot base = shot_at(s, 1.0f);
    double unit = distance_of(s, &base);
    const xyl_fade_desc fd = {2.5 * unit, 3.5 * unit, 0.02 * unit};
    shot sh = shot_at(s, 3.0f);
    xyl_fade_state st = {0};
    uint8_t *first = malloc(4 * SIDE * SIDE), *again = malloc(4 * SIDE * SIDE);
    assert_true(first && again);
    xyl_fade_draws o = fade_at(&fd, distance_of(s, &sh), &st);
    assert_true(o.near && o.far);
    render(s, &sh, &o, first);
    for (int i = 0; i < 5; ++i) {
        o = fade_at(&fd, distance_of(s, &sh), &st);
        render(s, &sh, &o, again);
        assert_memory_equal(first, again, 4 * SIDE * SIDE);
    }
    free(first);
    free(again);
}

static void dither_bad_input_gets_result_codes(void **state)
{
    suite *s = need_gl(state);
    shot sh = shot_at(s, 1.0f);
    xyl_diag d = {0};
    const float bad[][2] = {{0.5f, 0.5f}, {0.6f, 0.4f}, {-0.1f, 0.5f}, {0.2f, 1.5f}};
    uint32_t lod = 0;
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        xyl_foliage_gl_frame lf = {0};
        memcpy(lf.view_proj, sh.view_proj, sizeof lf.view_proj);
        memcpy(lf.dither, bad[i], sizeof lf.dither);
        expect(xyl_foliage_gl_draw(s->leaves, &lf, &lod, 1, &d), XYL_ERR_INVALID_ARGUMENT, &d);
        xyl_billboard_gl_frame bf = {0};
        memcpy(bf.view_proj, sh.view_proj, sizeof bf.view_proj);
        memcpy(bf.dither, bad[i], sizeof bf.dither);
        expect(xyl_billboard_gl_draw(s->billboard, &bf, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    }
    xyl_foliage_gl_frame lf = {0};
    memcpy(lf.view_proj, sh.view_proj, sizeof lf.view_proj);
    lf.dither[1] = NAN;
    expect(xyl_foliage_gl_draw(s->leaves, &lf, &lod, 1, &d), XYL_ERR_NON_FINITE, &d);
    /* the stems' packing clamps and rounds; (0, 0) stays every fragment */
    assert_int_equal(xyl_tess_dither(0.0f, 0.0f), 0u);
    assert_int_equal(xyl_tess_dither(0.0f, 1.0f), 0xffff0000u);
    assert_int_equal(xyl_tess_dither(-3.0f, 7.0f), 0xffff0000u);
    assert_int_equal(xyl_tess_dither(NAN, 0.5f), 32768u << 16);
}

int main(void)
{
    const struct CMUnitTest cpu[] = {
        cmocka_unit_test(the_band_hands_over_in_dither_levels),
        cmocka_unit_test(the_dither_splits_every_pixel_once),
        cmocka_unit_test(hysteresis_holds_a_jittering_camera),
        cmocka_unit_test(fade_bad_input_gets_result_codes),
    };
    const struct CMUnitTest gpu[] = {
        cmocka_unit_test(the_dither_splits_a_draw_between_two_ranges),
        cmocka_unit_test(a_dolly_past_the_billboard_switch_does_not_pop),
        cmocka_unit_test(a_still_camera_in_the_band_never_flickers),
        cmocka_unit_test(dither_bad_input_gets_result_codes),
    };
    int failed = cmocka_run_group_tests_name("fade", cpu, NULL, NULL);
    return failed + cmocka_run_group_tests_name("transitions on GL", gpu, setup, teardown);
}

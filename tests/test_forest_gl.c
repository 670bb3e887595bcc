/* foliage/'s forest (xyl_forest_gl.h, the instance record and grid of xyl_foliage.h) on a
 * headless EGL context (llvmpipe where there is no GPU): the 16-byte record's round trip, the
 * grid, the LOD choice against a CPU reference of the documented rule, hysteresis, a small
 * forest's picture against each instance drawn on its own by xyl_foliage_gl and
 * xyl_billboard_gl, and bad input. Without a usable GL 4.5 context the GL tests are skipped,
 * and say why. */
#include <epoxy/gl.h>
#include <math.h>

#include "test_util.h"
#include "foliage_tree.h"
#include <xylem/xyl_billboard_gl.h>
#include <xylem/xyl_foliage_gl.h>
#include <xylem/xyl_forest_gl.h>
#include <xylem/xyl_tess_gl.h>

#define SIDE 256
/* A forest's picture against its instances drawn one by one (same leaves, same LODs): the share
 * of pixels whose channels differ by more than 16/255 (edge pixels where placing a corner by
 * the instance in the shader and by a model matrix round differently). Measured on llvmpipe:
 * at most 2e-5 (one or two pixels); the instances turned the wrong way round: 0.033. */
#define MAX_DIFFERING_SHARE 0.002

typedef struct suite {
    xyl_gl_context *ctx;
    xyl_foliage *tree;
    float lo[3], hi[3];
    char why[320];
} suite;

static void expect(xyl_result got, xyl_result want, const xyl_diag *d)
{
    if (got != want)
        fail_msg("expected %s, got %s (%s)", xyl_result_string(want), xyl_result_string(got),
                 d->message);
    if (want != XYL_OK) assert_true(strlen(d->message) > 0);
}

static xyl_foliage *tree_foliage(const char *preset)
{
    return ft_tree_foliage(preset, 1);
}

static int setup(void **state)
{
    suite *s = calloc(1, sizeof *s);
    if (!s) return -1;
    xyl_diag d = {0};
    *state = s;
    if (xyl_gl_context_create_headless(NULL, &s->ctx, &d) != XYL_OK) {
        snprintf(s->why, sizeof s->why, "no usable GL 4.5 context: %s", d.message);
        s->ctx = NULL;
        return 0;
    }
    s->tree = tree_foliage("abop-2.8-ternary");
    for (int k = 0; k < 3; ++k) s->lo[k] = INFINITY, s->hi[k] = -INFINITY;
    xyl_foliage_bounds(s->tree, s->lo, s->hi);
    return 0;
}

static int teardown(void **state)
{
    suite *s = *state;
    xyl_foliage_destroy(s->tree);
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

/* ---- the record and the grid (no GL) ---------------------------------------------------- */

static void instance_packs_into_16_bytes_and_round_trips(void **state)
{
    (void)state;
    assert_int_equal(sizeof(xyl_forest_instance), 16);
    const float rotations[5] = {0.0f, 1.0f, -2.5f, 6.2f, 100.0f};
    const float scales[4] = {1.0f / 64.0f, 0.8f, 1.0f, 4.0f};
    const uint32_t lods[3] = {0, 15, XYL_FOREST_LOD_BILLBOARD};
    xyl_diag d = {0};
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 4; ++j)
            for (int k = 0; k < 3; ++k) {
                xyl_forest_instance_values v = {{-1234.5f, 2.25f, 1e5f}, rotations[i], scales[j],
                                                (uint32_t)(i * 13 + j) % 64, lods[k]};
                xyl_forest_instance in;
                expect(xyl_forest_instance_pack(&v, &in, &d), XYL_OK, &d);
                xyl_forest_instance_values back;
                xyl_forest_instance_unpack(&in, &back);
                assert_memory_equal(back.position, v.position, sizeof v.position);
                double da = fmod((double)back.rotation - v.rotation, 6.283185307179586);
                if (da > 3.141592653589793) da -= 6.283185307179586;
                if (da < -3.141592653589793) da += 6.283185307179586;
                assert_true(fabs(da) <= 3.141592653589793 / 1024.0 + 1e-5);
                assert_true(back.rotation >= 0.0f && back.rotation < 6.2832f);
                assert_true(fabs((double)back.scale - v.scale) <= 1.0 / 128.0 + 1e-7);
                assert_int_equal(back.species, v.species);
                assert_int_equal(back.lod, v.lod);
            }
}

static void instance_pack_refuses_what_does_not_fit(void **state)
{
    (void)state;
    xyl_diag d = {0};
    xyl_forest_instance in = {{7, 7, 7}, 0xdeadbeefu}, keep = in;
    xyl_forest_instance_values v = {{0, 0, 0}, 0, 1, 0, 0};
    v.scale = 0.0f;
    expect(xyl_forest_instance_pack(&v, &in, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    v.scale = 4.5f;
    expect(xyl_forest_instance_pack(&v, &in, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    v.scale = 1.0f, v.species = 64;
    expect(xyl_forest_instance_pack(&v, &in, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    v.species = 0, v.lod = 16;
    expect(xyl_forest_instance_pack(&v, &in, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    v.lod = 0, v.position[1] = NAN;
    expect(xyl_forest_instance_pack(&v, &in, &d), XYL_ERR_NON_FINITE, &d);
    expect(xyl_forest_instance_pack(NULL, &in, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_memory_equal(&in, &keep, sizeof in);
}

static void grid_is_seeded_jittered_and_bounded(void **state)
{
    (void)state;
    enum { N = 1000 };
    xyl_forest_instance *a = malloc(N * sizeof *a), *b = malloc(N * sizeof *b);
    assert_true(a && b);
    xyl_forest_grid_desc gd = {0};
    gd.count = N, gd.spacing = 10.0f, gd.jitter = 0.5f, gd.seed = 3, gd.species_count = 3;
    gd.scale_min = 0.5f, gd.scale_max = 2.0f;
    xyl_diag d = {0};
    expect(xyl_forest_grid(&gd, a, N, &d), XYL_OK, &d);
    expect(xyl_forest_grid(&gd, b, N, &d), XYL_OK, &d);
    assert_memory_equal(a, b, N * sizeof *a);
    uint32_t seen_species = 0;
    for (int i = 0; i < N; ++i) { /* 32 x 32 grid centred on the origin */
        xyl_forest_instance_values v;
        xyl_forest_instance_unpack(&a[i], &v);
        double gx = -155.0 + 10.0 * (i % 32), gz = -155.0 + 10.0 * (i / 32);
        assert_true(fabs(v.position[0] - gx) <= 2.5 + 1e-3 && fabs(v.position[2] - gz) <= 2.5 + 1e-3);
        assert_true(v.position[1] == 0.0f && v.lod == 0 && v.species < 3);
        assert_true(v.scale >= 0.5f - 1.0f / 128.0f && v.scale <= 2.0f + 1.0f / 128.0f);
        seen_species |= 1u << v.species;
    }
    assert_int_equal(seen_species, 7);
    gd.seed = 4;
    expect(xyl_forest_grid(&gd, b, N, &d), XYL_OK, &d);
    assert_true(memcmp(a, b, N * sizeof *a) != 0);
    gd.count = 0;
    expect(xyl_forest_grid(&gd, a, N, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    gd.count = (uint64_t)1 << 40;
    expect(xyl_forest_grid(&gd, a, N, &d), XYL_ERR_LIMIT_EXCEEDED, &d);
    gd.count = N + 1;
    expect(xyl_forest_grid(&gd, a, N, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    gd.count = N, gd.spacing = 0.0f;
    expect(xyl_forest_grid(&gd, a, N, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    gd.spacing = INFINITY;
    expect(xyl_forest_grid(&gd, a, N, &d), XYL_ERR_NON_FINITE, &d);
    free(a);
    free(b);
}

/* ---- the choice ----------------------------------------------------------------------------- */

static xyl_forest_gl *make_forest(const suite *s, float hysteresis, xyl_billboard_gl *bb)
{
    xyl_forest_gl_desc fd = {0};
    fd.hysteresis = hysteresis;
    xyl_forest_gl *f = NULL;
    xyl_diag d = {0};
    expect(xyl_forest_gl_create(&fd, &f, &d), XYL_OK, &d);
    xyl_forest_gl_species_desc sd = {0};
    sd.foliage = s->tree;
    sd.billboard = bb;
    uint32_t index = 99;
    expect(xyl_forest_gl_add_species(f, &sd, &index, &d), XYL_OK, &d);
    assert_int_equal(index, 0);
    return f;
}

static void camera_frame(const float eye[3], const float target[3], xyl_forest_gl_frame *fr)
{
    xyl_tess_camera cam = {0};
    memcpy(cam.eye, eye, sizeof cam.eye);
    memcpy(cam.target, target, sizeof cam.target);
    cam.fovy = 0.8f;
    cam.aspect = 1.0f;
    float dx = eye[0] - target[0], dy = eye[1] - target[1], dz = eye[2] - target[2];
    float dist = sqrtf(dx * dx + dy * dy + dz * dz);
    cam.near_plane = 0.02f * dist;
    cam.far_plane = 20.0f * dist;
    xyl_diag d = {0};
    expect(xyl_tess_camera_matrix(&cam, XYL_TESS_CLIP_GL, fr->view_proj, &d), XYL_OK, &d);
    memcpy(fr->eye, eye, sizeof fr->eye);
    fr->fovy = 0.8f;
    fr->viewport_height = SIDE;
}

/* The documented rule in double: the coarsest level k with
 * error_k <= per_distance * (|eye - centre| / scale - radius). */
static uint32_t reference_level(const xyl_forest_gl_species_info *info,
                                const xyl_forest_instance *in, const xyl_forest_gl_frame *fr,
                                double *margin)
{
    xyl_forest_instance_values v;
    xyl_forest_instance_unpack(in, &v);
    double per = fr->error_px * 2.0 * tan(0.5 * fr->fovy) / fr->viewport_height;
    double c[3] = {v.position[0], v.position[1] + (double)info->center_y * v.scale, v.position[2]};
    double dx = fr->eye[0] - c[0], dy = fr->eye[1] - c[1], dz = fr->eye[2] - c[2];
    double dn = sqrt(dx * dx + dy * dy + dz * dz) / v.scale - info->radius;
    uint32_t lv = 0;
    *margin = INFINITY;
    for (uint32_t k = 1; k < info->level_count; ++k) {
        double t = info->level_error[k] / per;
        *margin = fmin(*margin, fabs(dn - t) / fmax(t, 1.0));
        if (t <= dn) lv = k;
    }
    return lv;
}

/* Without hysteresis every instance's level is the rule's (a relative margin of 1e-4 around
 * each threshold is left to float rounding), whatever level it came from; the per-level counts
 * add up to the instances when nothing is culled. */
static void lod_choice_matches_the_cpu_rule(void **state)
{
    suite *s = need_gl(state);
    xyl_forest_gl *f = make_forest(s, -1.0f, NULL);
    enum { N = 2000 };
    xyl_forest_instance *in = malloc(N * sizeof *in);
    assert_non_null(in);
    xyl_forest_grid_desc gd = {0};
    gd.count = N, gd.spacing = 900.0f, gd.jitter = 0.9f, gd.seed = 11;
    gd.scale_min = 0.5f, gd.scale_max = 2.0f;
    xyl_diag d = {0};
    expect(xyl_forest_grid(&gd, in, N, &d), XYL_OK, &d);
    for (int i = 0; i < N; ++i) in[i].bits = (in[i].bits & ~255u) | (uint32_t)(i % 14);
    xyl_forest_gl_species_info info;
    expect(xyl_forest_gl_species(f, 0, &info, &d), XYL_OK, &d);
    assert_true(info.level_count >= 4);
    for (int i = 0; i < N; ++i) in[i].bits = (in[i].bits & ~255u) | (uint32_t)(i % info.level_count);
    expect(xyl_forest_gl_set_instances(f, in, N, &d), XYL_OK, &d);
    xyl_forest_gl_frame fr = {0};
    const float eye[3] = {-30000.0f, 3000.0f, -25000.0f}, target[3] = {0, 0, 0};
    camera_frame(eye, target, &fr);
    fr.error_px = 2.0f;
    fr.mode = XYL_FOREST_LEAF_LEVELS;
    fr.no_cull = true;
    xyl_forest_gl_stats st;
    expect(xyl_forest_gl_choose(f, &fr, &st, &d), XYL_OK, &d);
    size_t n = 0;
    const xyl_forest_instance *got = xyl_forest_gl_instances(f, &n);
    assert_int_equal(n, N);
    uint64_t per_level[XYL_FOREST_MAX_LEVELS] = {0}, sum = 0;
    uint32_t distinct = 0;
    for (int i = 0; i < N; ++i) {
        double margin;
        uint32_t want = reference_level(&info, &got[i], &fr, &margin);
        uint32_t have = got[i].bits & 255u;
        if (have != want && margin > 1e-4)
            fail_msg("instance %d: level %u, the rule says %u", i, have, want);
        distinct |= 1u << have;
        per_level[have]++;
    }
    for (uint32_t k = 0; k < info.level_count; ++k) {
        assert_int_equal(st.per_level[k], per_level[k]);
        sum += st.per_level[k];
    }
    assert_int_equal(sum, N);
    assert_int_equal(st.visible, N);
    assert_int_equal(st.bytes_per_instance, 16);
    assert_true(__builtin_popcount(distinct) >= 3); /* the view spans several levels */
    for (int i = 0; i < N; ++i) /* only the LOD bits change */
        assert_int_equal(got[i].bits >> 8, in[i].bits >> 8);
    free(in);
    xyl_forest_gl_destroy(f);
}

/* One instance, the eye on a line away from it. Inside the band between level 1's threshold
 * and 1.1 times it, a still camera keeps level 0 if it came from 0 and level 1 if it came from
 * 1, frame after frame; a dolly out across the whole range switches each time to a coarser
 * level only (never back), a dolly in only to finer ones, and a camera shaking by 2% around a
 * threshold switches at most once. */
static uint32_t level_at(xyl_forest_gl *f, xyl_forest_gl_frame *fr, double dist, double cy)
{
    const float eye[3] = {(float)dist, (float)cy, 0.0f}, target[3] = {0.0f, (float)cy, 1.0f};
    float keep = fr->error_px;
    camera_frame(eye, target, fr);
    fr->error_px = keep;
    xyl_diag d = {0};
    expect(xyl_forest_gl_choose(f, fr, NULL, &d), XYL_OK, &d);
    size_t n = 0;
    return xyl_forest_gl_instances(f, &n)[0].bits & 255u;
}

static void hysteresis_keeps_a_still_camera_and_switches_once(void **state)
{
    suite *s = need_gl(state);
    xyl_forest_gl *f = make_forest(s, 0.1f, NULL);
    xyl_forest_gl_species_info info;
    xyl_diag d = {0};
    expect(xyl_forest_gl_species(f, 0, &info, &d), XYL_OK, &d);
    xyl_forest_instance in = {{0, 0, 0}, 0u | 63u << 24}; /* scale 1, species 0, level 0 */
    expect(xyl_forest_gl_set_instances(f, &in, 1, &d), XYL_OK, &d);
    xyl_forest_gl_frame fr = {0};
    fr.error_px = 1.0f;
    fr.mode = XYL_FOREST_LEAF_LEVELS;
    fr.no_cull = true;
    double per = 2.0 * tan(0.4) / SIDE, r = info.radius, cy = info.center_y;
    double t1 = info.level_error[1] / per;
    double band = r + 1.05 * t1; /* the eye's distance from the axis point, inside the band */
    for (int frame = 0; frame < 3; ++frame) assert_int_equal(level_at(f, &fr, band, cy), 0);
    in.bits |= 1u;
    expect(xyl_forest_gl_set_instances(f, &in, 1, &d), XYL_OK, &d);
    for (int frame = 0; frame < 3; ++frame) assert_int_equal(level_at(f, &fr, band, cy), 1);
    /* dolly out, then in */
    double far = r + 1.5 * info.level_error[info.level_count - 1] / per;
    uint32_t prev = level_at(f, &fr, r * 0.5, cy), switches = 0;
    assert_int_equal(prev, 0);
    for (int step = 1; step <= 400; ++step) {
        uint32_t lv = level_at(f, &fr, r * 0.5 + (far - r * 0.5) * step / 400.0, cy);
        assert_true(lv >= prev);
        switches += lv != prev;
        prev = lv;
    }
    assert_int_equal(prev, info.level_count - 1);
    assert_true(switches >= 1 && switches <= info.level_count - 1);
    for (int step = 399; step >= 0; --step) {
        uint32_t lv = level_at(f, &fr, r * 0.5 + (far - r * 0.5) * step / 400.0, cy);
        assert_true(lv <= prev);
        prev = lv;
    }
    assert_int_equal(prev, 0);
    /* shaking around level 1's threshold */
    switches = 0;
    prev = level_at(f, &fr, r + t1, cy);
    for (int step = 0; step < 50; ++step) {
        uint32_t lv = level_at(f, &fr, r + t1 * (step % 2 ? 1.02 : 0.98), cy);
        switches += lv != prev;
        prev = lv;
    }
    assert_true(switches <= 1);
    xyl_forest_gl_destroy(f);
}

/* The frustum test keeps every instance whose sphere reaches into the frustum (the exact
 * six-plane test, in double), and culls most of those behind the camera: one instance at 3000
 * places around the eye, each chosen alone. */
static void culling_keeps_every_instance_in_view(void **state)
{
    suite *s = need_gl(state);
    xyl_forest_gl *f = make_forest(s, 0.0f, NULL);
    xyl_forest_gl_species_info info;
    xyl_diag d = {0};
    expect(xyl_forest_gl_species(f, 0, &info, &d), XYL_OK, &d);
    xyl_forest_gl_frame fr = {0};
    const float eye[3] = {100.0f, 700.0f, -300.0f}, target[3] = {9000.0f, 200.0f, 2500.0f};
    camera_frame(eye, target, &fr);
    fr.error_px = 1.0f;
    size_t kept = 0, inside = 0, behind = 0, behind_kept = 0;
    uint64_t state_rng = 99;
    for (int i = 0; i < 3000; ++i) {
        state_rng = state_rng * 6364136223846793005ull + 1442695040888963407ull;
        double u = (double)(state_rng >> 11) / 9007199254740992.0;
        state_rng = state_rng * 6364136223846793005ull + 1442695040888963407ull;
        double w = (double)(state_rng >> 11) / 9007199254740992.0;
        xyl_forest_instance_values v = {{(float)(eye[0] + 40000.0 * (u - 0.5)), 0.0f,
                                         (float)(eye[2] + 40000.0 * (w - 0.5))},
                                        (float)(6.0 * u), 0.5f + (float)w, 0, 0};
        xyl_forest_instance in;
        expect(xyl_forest_instance_pack(&v, &in, &d), XYL_OK, &d);
        xyl_forest_instance_unpack(&in, &v);
        expect(xyl_forest_gl_set_instances(f, &in, 1, &d), XYL_OK, &d);
        xyl_forest_gl_stats st;
        expect(xyl_forest_gl_choose(f, &fr, &st, &d), XYL_OK, &d);
        double c[3] = {v.position[0], v.position[1] + (double)info.center_y * v.scale,
                       v.position[2]}, r = (double)info.radius * v.scale;
        bool in_view = true;
        for (int k = 0; k < 6; ++k) {
            double pl[4], len = 0.0;
            for (int j = 0; j < 4; ++j)
                pl[j] = (double)fr.view_proj[4 * j + 3] + (k % 2 ? -1.0 : 1.0) * fr.view_proj[4 * j + k / 2];
            for (int j = 0; j < 3; ++j) len += pl[j] * pl[j];
            len = sqrt(len);
            in_view = in_view && (pl[0] * c[0] + pl[1] * c[1] + pl[2] * c[2] + pl[3]) / len >= -r;
        }
        double fwd = (c[0] - eye[0]) * (target[0] - eye[0]) + (c[2] - eye[2]) * (target[2] - eye[2]);
        if (in_view && st.visible != 1) fail_msg("instance %d in view was culled", i);
        kept += st.visible, inside += in_view;
        if (fwd < 0.0 && !in_view) behind++, behind_kept += st.visible;
    }
    print_message("%zu kept, %zu in the frustum, %zu of %zu behind the eye kept\n", kept, inside,
                  behind_kept, behind);
    assert_true(inside > 100 && behind > 1000);
    assert_true(behind_kept * 20 < behind); /* under 5% */
    xyl_forest_gl_destroy(f);
}

/* ---- pictures ------------------------------------------------------------------------------- */

typedef struct target {
    GLuint rb[2], fbo;
} target;

static void target_begin(target *t)
{
    glCreateRenderbuffers(2, t->rb);
    glNamedRenderbufferStorage(t->rb[0], GL_RGBA8, SIDE, SIDE);
    glNamedRenderbufferStorage(t->rb[1], GL_DEPTH_COMPONENT24, SIDE, SIDE);
    glCreateFramebuffers(1, &t->fbo);
    glNamedFramebufferRenderbuffer(t->fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, t->rb[0]);
    glNamedFramebufferRenderbuffer(t->fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t->rb[1]);
    assert_int_equal(glCheckNamedFramebufferStatus(t->fbo, GL_FRAMEBUFFER), GL_FRAMEBUFFER_COMPLETE);
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    glViewport(0, 0, SIDE, SIDE);
    glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

static void target_end(target *t, uint8_t *rgba)
{
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, SIDE, SIDE, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &t->fbo);
    glDeleteRenderbuffers(2, t->rb);
}

/* The instance's model matrix (column-major): turn about +Y, scale, move. */
static void model_of(const xyl_forest_instance_values *v, float m[16])
{
    float c = cosf(v->rotation), s = sinf(v->rotation), k = v->scale;
    const float mm[16] = {k * c, 0, -k * s, 0, 0, k, 0, 0, k * s, 0, k * c, 0,
                          v->position[0], v->position[1], v->position[2], 1};
    memcpy(m, mm, sizeof mm);
}

static void mul(const float a[16], const float b[16], float out[16])
{
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            float t = 0.0f;
            for (int k = 0; k < 4; ++k) t += a[k * 4 + r] * b[c * 4 + k];
            out[c * 4 + r] = t;
        }
}

/* The world light and eye in the instance's own coordinates. */
static void to_model(const xyl_forest_instance_values *v, const float world_light[3],
                     const float world_eye[3], float light[3], float eye[3])
{
    float c = cosf(v->rotation), s = sinf(v->rotation);
    light[0] = c * world_light[0] - s * world_light[2];
    light[1] = world_light[1];
    light[2] = s * world_light[0] + c * world_light[2];
    float p[3];
    for (int k = 0; k < 3; ++k) p[k] = (world_eye[k] - v->position[k]) / v->scale;
    eye[0] = c * p[0] - s * p[2];
    eye[1] = p[1];
    eye[2] = s * p[0] + c * p[2];
}

static double differing_share(const uint8_t *a, const uint8_t *b, size_t *covered)
{
    size_t differ = 0;
    *covered = 0;
    for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i) {
        bool bad = false;
        for (int k = 0; k < 4; ++k) bad |= abs(a[4 * i + k] - b[4 * i + k]) > 16;
        differ += bad;
        *covered += a[4 * i + 3] > 0;
    }
    return (double)differ / ((double)SIDE * SIDE);
}

/* Level k's single-sector LOD, as the header defines the levels. */
static uint32_t level_lod(const xyl_foliage *f, const xyl_forest_gl_species_info *info, uint32_t k)
{
    const xyl_foliage_sector *sec = &f->sectors[0];
    if (k + 1 == info->level_count && k > 0) return sec->merged_count;
    uint64_t n = sec->original_count, keep = (n + ((uint64_t)1 << k) - 1) >> k;
    uint64_t lod = n - (keep ? keep : 1);
    return lod > sec->merged_count ? sec->merged_count : (uint32_t)lod;
}

static xyl_result bake_leaves(void *user, const float view_proj[16], const float light[3],
                              xyl_diag *d)
{
    xyl_foliage_gl *leaves = user;
    xyl_foliage_gl_frame fr = {0};
    memcpy(fr.view_proj, view_proj, sizeof fr.view_proj);
    memcpy(fr.light_dir, light, sizeof fr.light_dir);
    const uint32_t lod0[1] = {0};
    return xyl_foliage_gl_draw(leaves, &fr, lod0, 1, d);
}

/* A 3 x 3 forest drawn by xyl_forest_gl against each instance drawn alone with a model matrix
 * (xyl_foliage_gl_draw at the instance's chosen level, xyl_billboard_gl_draw for a billboard):
 * at full detail, at the levels a 6 px budget picks (several levels in one picture), as
 * cross billboards from far away, and as octahedral impostors (one quad each, relit and
 * parallax-corrected in the instance's frame). At most MAX_DIFFERING_SHARE of the pixels differ (measured
 * on llvmpipe: printed), and the forest covers a real share of the picture. */
static void forest_picture_matches_instances_drawn_alone(void **state)
{
    suite *s = need_gl(state);
    xyl_diag d = {0};
    xyl_foliage_gl *leaves = NULL;
    expect(xyl_foliage_gl_create(NULL, &leaves, &d), XYL_OK, &d);
    expect(xyl_foliage_gl_set_foliage(leaves, s->tree, &d), XYL_OK, &d);
    xyl_billboard_gl_desc bd = {0};
    bd.kind = XYL_BILLBOARD_CROSS;
    bd.planes = 3;
    bd.resolution = 256;
    memcpy(bd.lo, s->lo, sizeof bd.lo);
    memcpy(bd.hi, s->hi, sizeof bd.hi);
    xyl_billboard_gl *bb = NULL;
    expect(xyl_billboard_gl_bake(&bd, bake_leaves, leaves, &bb, &d), XYL_OK, &d);
    xyl_forest_gl *f = make_forest(s, 0.0f, bb);
    xyl_forest_gl_species_info info;
    expect(xyl_forest_gl_species(f, 0, &info, &d), XYL_OK, &d);
    /* a second forest with an octahedral impostor as its far kind */
    xyl_billboard_gl_desc od = bd;
    od.kind = XYL_BILLBOARD_OCTAHEDRAL, od.planes = 0, od.grid = 8, od.resolution = 512;
    xyl_billboard_gl *oct = NULL;
    expect(xyl_billboard_gl_bake(&od, bake_leaves, leaves, &oct, &d), XYL_OK, &d);
    xyl_forest_gl *fo = make_forest(s, 0.0f, oct);
    xyl_forest_instance in[9];
    xyl_forest_grid_desc gd = {0};
    gd.count = 9, gd.spacing = 1.1f * (s->hi[0] - s->lo[0]), gd.jitter = 0.5f, gd.seed = 5;
    gd.scale_min = 0.7f, gd.scale_max = 1.3f;
    expect(xyl_forest_grid(&gd, in, 9, &d), XYL_OK, &d);
    expect(xyl_forest_gl_set_instances(f, in, 9, &d), XYL_OK, &d);
    expect(xyl_forest_gl_set_instances(fo, in, 9, &d), XYL_OK, &d);
    const struct { xyl_forest_mode mode; float error_px, distance; } cases[4] = {
        {XYL_FOREST_FULL, 1.0f, 3.0f}, {XYL_FOREST_LEAF_LEVELS, 6.0f, 3.0f},
        {XYL_FOREST_LOD, 2000.0f, 2.0f}, {XYL_FOREST_LOD, 2000.0f, 1.2f}};
    uint8_t *a = malloc(4 * SIDE * SIDE), *b = malloc(4 * SIDE * SIDE);
    assert_true(a && b);
    const float light[3] = {0.42f, 0.78f, 0.46f};
    for (int c = 0; c < 4; ++c) {
        xyl_forest_gl *forest = c == 3 ? fo : f;
        xyl_billboard_gl *far = c == 3 ? oct : bb;
        float ext = gd.spacing * 3.0f * cases[c].distance;
        const float eye[3] = {0.6f * ext, 0.45f * ext, 0.8f * ext};
        const float tgt[3] = {0.0f, 0.5f * (s->lo[1] + s->hi[1]), 0.0f};
        xyl_forest_gl_frame fr = {0};
        camera_frame(eye, tgt, &fr);
        fr.error_px = cases[c].error_px;
        fr.mode = cases[c].mode;
        memcpy(fr.light_dir, light, sizeof light);
        target t;
        target_begin(&t);
        xyl_forest_gl_stats st;
        expect(xyl_forest_gl_draw(forest, &fr, &st, &d), XYL_OK, &d);
        target_end(&t, a);
        size_t n = 0;
        const xyl_forest_instance *got = xyl_forest_gl_instances(forest, &n);
        uint32_t levels = 0;
        target_begin(&t);
        for (size_t i = 0; i < n; ++i) {
            xyl_forest_instance_values v;
            xyl_forest_instance_unpack(&got[i], &v);
            levels |= v.lod == XYL_FOREST_LOD_BILLBOARD ? 1u << 31 : 1u << v.lod;
            float m[16], vp[16], ml[3], me[3];
            model_of(&v, m);
            mul(fr.view_proj, m, vp);
            to_model(&v, light, eye, ml, me);
            if (v.lod == XYL_FOREST_LOD_BILLBOARD) {
                xyl_billboard_gl_frame bf = {0};
                memcpy(bf.view_proj, vp, sizeof vp);
                memcpy(bf.eye, me, sizeof me);
                memcpy(bf.light_dir, ml, sizeof ml);
                expect(xyl_billboard_gl_draw(far, &bf, &d), XYL_OK, &d);
            } else {
                xyl_foliage_gl_frame lf = {0};
                memcpy(lf.view_proj, vp, sizeof vp);
                memcpy(lf.light_dir, ml, sizeof ml);
                const uint32_t lod[1] = {level_lod(s->tree, &info, v.lod)};
                expect(xyl_foliage_gl_draw(leaves, &lf, lod, 1, &d), XYL_OK, &d);
            }
        }
        target_end(&t, b);
        size_t covered = 0;
        double share = differing_share(a, b, &covered);
        print_message("case %d: %.5f of the pixels differ, %zu covered, levels 0x%x, %llu draws\n",
                      c, share, covered, levels, (unsigned long long)st.draws);
        assert_true(share <= MAX_DIFFERING_SHARE);
        assert_true(covered > (size_t)SIDE * SIDE / 50);
        if (c == 1) assert_true(__builtin_popcount(levels) >= 2);
        if (c >= 2) assert_int_equal(levels, 1u << 31);
        if (c == 3) assert_int_equal(st.triangles, 2 * 9);
    }
    free(a);
    free(b);
    xyl_forest_gl_destroy(f);
    xyl_forest_gl_destroy(fo);
    xyl_billboard_gl_destroy(bb);
    xyl_billboard_gl_destroy(oct);
    xyl_foliage_gl_destroy(leaves);
}

/* A species with stems: in full mode every visible instance draws its base mesh (the stats
 * count its triangles), the stems add pixels the leaves alone do not cover, and a stem_width
 * larger than every level's error keeps the stems at every level while one under level 1's
 * error keeps them at level 0 only. */
static void stems_are_drawn_where_the_trunk_is_wide_enough(void **state)
{
    suite *s = need_gl(state);
    xyl_skeleton *sk = tu_grow(xyl_lsystem_preset_source("abop-2.8-ternary"), NULL);
    xyl_mesh *stems = NULL;
    xyl_diag d = {0};
    expect(xyl_stems_build(sk, NULL, &stems, NULL, &d), XYL_OK, &d);
    xyl_skeleton_destroy(sk);
    xyl_forest_gl *f = NULL;
    expect(xyl_forest_gl_create(NULL, &f, &d), XYL_OK, &d);
    xyl_forest_gl_species_desc sd = {0};
    sd.foliage = s->tree;
    uint32_t bare = 0, with = 0, wide = 0;
    expect(xyl_forest_gl_add_species(f, &sd, &bare, &d), XYL_OK, &d);
    sd.stems = stems;
    expect(xyl_forest_gl_add_species(f, &sd, &with, &d), XYL_OK, &d);
    xyl_forest_gl_species_info info;
    expect(xyl_forest_gl_species(f, with, &info, &d), XYL_OK, &d);
    assert_int_equal(info.stem_triangles, stems->tri_view_count);
    assert_int_equal(info.stem_levels, info.level_count);
    sd.stem_width = 0.5f * info.level_error[1];
    expect(xyl_forest_gl_add_species(f, &sd, &wide, &d), XYL_OK, &d);
    expect(xyl_forest_gl_species(f, wide, &info, &d), XYL_OK, &d);
    assert_int_equal(info.stem_levels, 1);
    uint8_t *img[2] = {malloc(4 * SIDE * SIDE), malloc(4 * SIDE * SIDE)};
    assert_true(img[0] && img[1]);
    size_t covered[2];
    for (int k = 0; k < 2; ++k) {
        xyl_forest_instance in = {{0, 0, 0}, (k ? with : bare) << 8 | 63u << 24};
        expect(xyl_forest_gl_set_instances(f, &in, 1, &d), XYL_OK, &d);
        const float eye[3] = {0.0f, 0.5f * (s->lo[1] + s->hi[1]), 2.5f * (s->hi[1] - s->lo[1])};
        const float tgt[3] = {0.0f, 0.5f * (s->lo[1] + s->hi[1]), 0.0f};
        xyl_forest_gl_frame fr = {0};
        camera_frame(eye, tgt, &fr);
        fr.error_px = 1.0f;
        fr.mode = XYL_FOREST_FULL;
        target t;
        target_begin(&t);
        xyl_forest_gl_stats st;
        expect(xyl_forest_gl_draw(f, &fr, &st, &d), XYL_OK, &d);
        target_end(&t, img[k]);
        assert_int_equal(st.with_stems, (uint64_t)k);
        assert_int_equal(st.triangles, 2 * s->tree->original_count + (k ? stems->tri_view_count : 0));
        assert_int_equal(st.draws, (uint64_t)(1 + k));
        covered[k] = 0;
        for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i) covered[k] += img[k][4 * i + 3] > 0;
    }
    print_message("covered: leaves %zu, leaves and stems %zu\n", covered[0], covered[1]);
    assert_true(covered[1] > covered[0] + 50);
    free(img[0]);
    free(img[1]);
    xyl_forest_gl_destroy(f);
    xyl_mesh_destroy(stems);
}

/* ---- per-leaf instances ------------------------------------------------------------------- */


/* Every instance of a 3 x 3 forest with its own cut (per_leaf 9) draws the picture of each
 * instance drawn alone by xyl_foliage_gl_draw_adaptive with its model matrix and the eye in
 * its frame, and the stats count the cuts' leaves as xyl_foliage_gl_last_cut reads them; with
 * per_leaf 4 the four instances nearest the eye get cuts and the others keep their levels. */
static void per_leaf_instances_draw_their_own_cut(void **state)
{
    suite *s = need_gl(state);
    xyl_diag d = {0};
    xyl_foliage_gl *leaves = NULL;
    expect(xyl_foliage_gl_create(NULL, &leaves, &d), XYL_OK, &d);
    expect(xyl_foliage_gl_set_foliage(leaves, s->tree, &d), XYL_OK, &d);
    xyl_forest_gl *f = make_forest(s, 0.0f, NULL);
    xyl_forest_instance in[9];
    xyl_forest_grid_desc gd = {0};
    gd.count = 9, gd.spacing = 1.1f * (s->hi[0] - s->lo[0]), gd.jitter = 0.5f, gd.seed = 5;
    gd.scale_min = 0.7f, gd.scale_max = 1.3f;
    expect(xyl_forest_grid(&gd, in, 9, &d), XYL_OK, &d);
    expect(xyl_forest_gl_set_instances(f, in, 9, &d), XYL_OK, &d);
    float ext = gd.spacing * 3.0f * 1.5f;
    const float eye[3] = {0.6f * ext, 0.45f * ext, 0.8f * ext};
    const float tgt[3] = {0.0f, 0.5f * (s->lo[1] + s->hi[1]), 0.0f};
    const float light[3] = {0.42f, 0.78f, 0.46f};
    xyl_forest_gl_frame fr = {0};
    camera_frame(eye, tgt, &fr);
    fr.error_px = 3.0f;
    fr.mode = XYL_FOREST_LEAF_LEVELS;
    fr.per_leaf = 9;
    memcpy(fr.light_dir, light, sizeof light);
    uint8_t *a = malloc(4 * SIDE * SIDE), *b = malloc(4 * SIDE * SIDE);
    assert_true(a && b);
    target t;
    target_begin(&t);
    xyl_forest_gl_stats st;
    expect(xyl_forest_gl_draw(f, &fr, &st, &d), XYL_OK, &d);
    target_end(&t, a);
    assert_int_equal(st.per_leaf, 9);
    assert_int_equal(st.visible, 9);
    uint64_t level_sum = 0;
    for (int k = 0; k <= XYL_FOREST_MAX_LEVELS; ++k) level_sum += st.per_level[k];
    assert_int_equal(level_sum, 0);
    uint64_t cut_leaves = 0;
    target_begin(&t);
    for (int i = 0; i < 9; ++i) {
        xyl_forest_instance_values v;
        xyl_forest_instance_unpack(&in[i], &v);
        float m[16], vp[16], ml[3], me[3];
        model_of(&v, m);
        mul(fr.view_proj, m, vp);
        to_model(&v, light, eye, ml, me);
        xyl_foliage_gl_frame lf = {0};
        memcpy(lf.view_proj, vp, sizeof vp);
        memcpy(lf.light_dir, ml, sizeof ml);
        xyl_foliage_view view = {{me[0], me[1], me[2]}, fr.fovy, fr.viewport_height, fr.error_px};
        expect(xyl_foliage_gl_draw_adaptive(leaves, &lf, &view, &d), XYL_OK, &d);
        size_t n = 0;
        expect(xyl_foliage_gl_last_cut(leaves, NULL, 0, &n, &d), XYL_OK, &d);
        cut_leaves += n;
    }
    target_end(&t, b);
    size_t covered = 0;
    double share = differing_share(a, b, &covered);
    print_message("9 per-leaf instances: %llu leaves (the cuts drawn alone: %llu), %.5f of the "
                  "pixels differ, %zu covered\n", (unsigned long long)st.leaves,
                  (unsigned long long)cut_leaves, share, covered);
    assert_true(st.leaves == cut_leaves);
    assert_true(share <= MAX_DIFFERING_SHARE);
    assert_true(covered > (size_t)SIDE * SIDE / 50);
    /* four of them: the rest at their levels */
    fr.per_leaf = 4;
    target_begin(&t);
    expect(xyl_forest_gl_draw(f, &fr, &st, &d), XYL_OK, &d);
    target_end(&t, b);
    level_sum = 0;
    for (int k = 0; k <= XYL_FOREST_MAX_LEVELS; ++k) level_sum += st.per_level[k];
    assert_int_equal(st.per_leaf, 4);
    assert_int_equal(level_sum, 5);
    /* with a fade, a per-leaf instance leaves both of its buckets: the levels hold the others,
     * the fading ones twice */
    fr.fade = 2.0f;
    fr.per_leaf = 2;
    target_begin(&t);
    expect(xyl_forest_gl_draw(f, &fr, &st, &d), XYL_OK, &d);
    target_end(&t, b);
    level_sum = 0;
    for (int k = 0; k <= XYL_FOREST_MAX_LEVELS; ++k) level_sum += st.per_level[k];
    print_message("fade 2, 2 per-leaf: %llu fading, levels hold %llu\n",
                  (unsigned long long)st.faded, (unsigned long long)level_sum);
    assert_int_equal(st.visible, 9);
    assert_int_equal(st.per_leaf, 2);
    assert_int_equal(level_sum, 7 + st.faded);
    fr.fade = 0.0f;
    fr.per_leaf = XYL_FOREST_MAX_PER_LEAF + 1;
    expect(xyl_forest_gl_draw(f, &fr, &st, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    free(a);
    free(b);
    xyl_forest_gl_destroy(f);
    xyl_foliage_gl_destroy(leaves);
}

/* ---- cross-fades ----------------------------------------------------------------------------- */

static double rmse(const uint8_t *a, const uint8_t *b)
{
    double sum = 0.0;
    for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i)
        for (int k = 0; k < 3; ++k) {
            double e = (double)a[4 * i + k] - b[4 * i + k];
            sum += e * e;
        }
    return sqrt(sum / (3.0 * SIDE * SIDE));
}

typedef struct fade_rig {
    xyl_foliage_gl *leaves;
    xyl_billboard_gl *bb;
    xyl_forest_gl *forest;
    xyl_forest_gl_species_info info;
    float spacing, target[3];
} fade_rig;

/* A 3 x 3 forest of the tree with stems-free leaves and a baked cross billboard, no
 * hysteresis (so a hard switch happens exactly at each threshold). */
static void fade_rig_make(const suite *s, fade_rig *r)
{
    xyl_diag d = {0};
    memset(r, 0, sizeof *r);
    expect(xyl_foliage_gl_create(NULL, &r->leaves, &d), XYL_OK, &d);
    expect(xyl_foliage_gl_set_foliage(r->leaves, s->tree, &d), XYL_OK, &d);
    xyl_billboard_gl_desc bd = {0};
    bd.kind = XYL_BILLBOARD_CROSS;
    bd.planes = 3;
    bd.resolution = 256;
    memcpy(bd.lo, s->lo, sizeof bd.lo);
    memcpy(bd.hi, s->hi, sizeof bd.hi);
    expect(xyl_billboard_gl_bake(&bd, bake_leaves, r->leaves, &r->bb, &d), XYL_OK, &d);
    r->forest = make_forest(s, -1.0f, r->bb);
    expect(xyl_forest_gl_species(r->forest, 0, &r->info, &d), XYL_OK, &d);
    xyl_forest_instance in[9];
    xyl_forest_grid_desc gd = {0};
    r->spacing = 1.1f * (s->hi[0] - s->lo[0]);
    gd.count = 9, gd.spacing = r->spacing, gd.jitter = 0.5f, gd.seed = 5;
    gd.scale_min = 0.7f, gd.scale_max = 1.3f;
    expect(xyl_forest_grid(&gd, in, 9, &d), XYL_OK, &d);
    expect(xyl_forest_gl_set_instances(r->forest, in, 9, &d), XYL_OK, &d);
    r->target[1] = 0.5f * (s->lo[1] + s->hi[1]);
}

static void fade_rig_free(fade_rig *r)
{
    xyl_forest_gl_destroy(r->forest);
    xyl_billboard_gl_destroy(r->bb);
    xyl_foliage_gl_destroy(r->leaves);
}

/* The eye at factor times the forest's width from its middle; the budget puts the middle
 * tree's billboard switch at 4 widths, its leaf levels' switches nearer. */
static void fade_frame(const fade_rig *r, float factor, xyl_forest_mode mode, float fade,
                       xyl_forest_gl_frame *fr)
{
    float ext = 3.0f * r->spacing * factor;
    const float eye[3] = {0.6f * ext, r->target[1] + 0.3f * ext, 0.75f * ext};
    memset(fr, 0, sizeof *fr);
    camera_frame(eye, r->target, fr);
    double per_px = 2.0 * tan(0.4) / SIDE, at = 4.0 * 3.0 * r->spacing;
    fr->error_px = (float)(r->info.billboard_error / ((at - r->info.radius) * per_px));
    fr->mode = mode;
    fr->fade = fade;
    const float light[3] = {0.42f, 0.78f, 0.46f};
    memcpy(fr->light_dir, light, sizeof light);
}

/* What a frame chose: each instance's level and the stats' counts, to see a switch happen. */
static uint64_t choice_key(const xyl_forest_gl *f, const xyl_forest_gl_stats *st)
{
    size_t n = 0;
    const xyl_forest_instance *in = xyl_forest_gl_instances(f, &n);
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < n; ++i) h = (h ^ (in[i].bits & 255u)) * 1099511628211ull;
    return h ^ st->faded;
}

/* The forest dolly: the camera backs off from 1.5 to 9 forest widths in FADE_FRAMES geometric
 * steps, three times: at full detail (the ordinary frames, nothing switches), with hard
 * switches (no hysteresis, no fade) and with the cross-fade over half of each switch distance.
 * Each frame where something switches (a level, or a share inside a band) has its change from
 * the frame before (RMSE of RGB) compared with the full-detail dolly's change at the same
 * frame; the worst ratio of the fade must stay under FADE_FACTOR, and the hard switches' must
 * not (the test sees a pop where there is one). */
#define FADE_FRAMES 96
/* measured on llvmpipe: 0.77 with the fade, 1.56 with hard switches */
#define FADE_FACTOR 1.2

static void a_forest_dolly_cross_fades_without_popping(void **state)
{
    suite *s = need_gl(state);
    fade_rig r;
    fade_rig_make(s, &r);
    uint8_t *prev = malloc(4 * SIDE * SIDE), *cur = malloc(4 * SIDE * SIDE);
    assert_true(prev && cur);
    static double change[3][FADE_FRAMES];
    static bool switching[3][FADE_FRAMES];
    const xyl_forest_mode modes[3] = {XYL_FOREST_FULL, XYL_FOREST_LOD, XYL_FOREST_LOD};
    const float fades[3] = {0.0f, 0.0f, 0.5f};
    uint64_t twice = 0, billboards = 0;
    xyl_diag d = {0};
    for (int pass = 0; pass < 3; ++pass) {
        uint64_t last = 0;
        for (int i = 0; i < FADE_FRAMES; ++i) {
            float factor = 1.5f * powf(9.0f / 1.5f, (float)i / (FADE_FRAMES - 1));
            xyl_forest_gl_frame fr;
            fade_frame(&r, factor, modes[pass], fades[pass], &fr);
            target t;
            target_begin(&t);
            xyl_forest_gl_stats st;
            expect(xyl_forest_gl_draw(r.forest, &fr, &st, &d), XYL_OK, &d);
            target_end(&t, cur);
            uint64_t key = choice_key(r.forest, &st);
            change[pass][i] = i ? rmse(prev, cur) : 0.0;
            switching[pass][i] = i && (key != last || st.faded);
            last = key;
            if (pass == 2) {
                twice += st.faded;
                billboards += st.per_level[XYL_FOREST_MAX_LEVELS];
                assert_int_equal(st.visible, 9);
            }
            uint8_t *swap = prev;
            prev = cur;
            cur = swap;
        }
    }
    double worst[3] = {0.0, 0.0, 0.0};
    int frames[3] = {0, 0, 0};
    for (int pass = 1; pass < 3; ++pass)
        for (int i = 1; i < FADE_FRAMES; ++i) {
            assert_false(switching[0][i]);
            if (!switching[pass][i]) continue;
            ++frames[pass];
            worst[pass] = fmax(worst[pass], change[pass][i] / fmax(change[0][i], 0.05));
        }
    print_message("forest dolly of %d frames: the cross-fade's %d switching frames change at "
                  "most %.2f x the full-detail dolly's, the hard switches' %d frames %.2f x; "
                  "%llu instance-frames drawn twice, %llu as billboards\n",
                  FADE_FRAMES, frames[2], worst[2], frames[1], worst[1],
                  (unsigned long long)twice, (unsigned long long)billboards);
    assert_true(frames[1] >= 3 && frames[2] >= 10 && twice > 0 && billboards > 0);
    assert_true(worst[2] <= FADE_FACTOR);
    assert_true(worst[1] > FADE_FACTOR);
    free(prev);
    free(cur);
    fade_rig_free(&r);
}

/* Inside a band, a still camera draws the same picture frame after frame, the two copies of
 * an instance split its pixels (the faded picture covers what the finer level alone covers or
 * the coarser one does, nothing more), and the stats count the instance at both levels. */
static void a_still_camera_in_a_forest_fade_never_flickers(void **state)
{
    suite *s = need_gl(state);
    fade_rig r;
    fade_rig_make(s, &r);
    uint8_t *a = malloc(4 * SIDE * SIDE), *b = malloc(4 * SIDE * SIDE);
    assert_true(a && b);
    xyl_diag d = {0};
    bool found = false;
    for (int i = 0; i < 60 && !found; ++i) {
        xyl_forest_gl_frame fr;
        fade_frame(&r, 3.0f + 0.05f * (float)i, XYL_FOREST_LOD, 0.5f, &fr);
        xyl_forest_gl_stats st;
        expect(xyl_forest_gl_choose(r.forest, &fr, &st, &d), XYL_OK, &d);
        if (!st.faded) continue;
        found = true;
        uint64_t sum = 0;
        for (int k = 0; k <= XYL_FOREST_MAX_LEVELS; ++k) sum += st.per_level[k];
        assert_int_equal(sum, st.visible + st.faded);
        for (int frame = 0; frame < 4; ++frame) {
            target t;
            target_begin(&t);
            xyl_forest_gl_stats again;
            expect(xyl_forest_gl_draw(r.forest, &fr, &again, &d), XYL_OK, &d);
            target_end(&t, frame ? b : a);
            assert_int_equal(again.faded, st.faded);
            assert_memory_equal(again.per_level, st.per_level, sizeof st.per_level);
            if (frame) assert_memory_equal(a, b, 4 * SIDE * SIDE);
        }
        print_message("still camera at %.2f widths: %llu of 9 instances fading, the same "
                      "picture 4 frames running\n",
                      3.0 + 0.05 * i, (unsigned long long)st.faded);
    }
    assert_true(found);
    /* a fade outside its range is refused */
    xyl_forest_gl_frame fr;
    fade_frame(&r, 3.0f, XYL_FOREST_LOD, -0.1f, &fr);
    expect(xyl_forest_gl_draw(r.forest, &fr, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    fr.fade = XYL_FOREST_MAX_FADE * 2.0f;
    expect(xyl_forest_gl_choose(r.forest, &fr, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    fr.fade = NAN;
    expect(xyl_forest_gl_draw(r.forest, &fr, NULL, &d), XYL_ERR_NON_FINITE, &d);
    free(a);
    free(b);
    fade_rig_free(&r);
}

/* ---- bad input -------------------------------------------------------------------------------- */

static void bad_input_gets_result_codes(void **state)
{
    suite *s = need_gl(state);
    xyl_diag d = {0};
    xyl_forest_gl *f = NULL;
    expect(xyl_forest_gl_create(NULL, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_forest_gl_desc fd = {0};
    fd.max_instances = (uint64_t)1 << 40;
    expect(xyl_forest_gl_create(&fd, &f, &d), XYL_ERR_LIMIT_EXCEEDED, &d);
    fd.max_instances = 100, fd.hysteresis = 2.0f;
    expect(xyl_forest_gl_create(&fd, &f, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    fd.hysteresis = NAN;
    expect(xyl_forest_gl_create(&fd, &f, &d), XYL_ERR_NON_FINITE, &d);
    assert_null(f);
    fd.hysteresis = 0.0f;
    expect(xyl_forest_gl_create(&fd, &f, &d), XYL_OK, &d);

    /* species */
    uint32_t index = 0;
    xyl_forest_gl_species_desc sd = {0};
    expect(xyl_forest_gl_add_species(f, &sd, &index, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_forest_gl_add_species(NULL, &sd, &index, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_foliage_desc empty_desc = {0};
    xyl_foliage *empty = NULL;
    expect(xyl_foliage_build(&empty_desc, &empty, &d), XYL_OK, &d);
    sd.foliage = empty;
    expect(xyl_forest_gl_add_species(f, &sd, &index, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_non_null(strstr(d.message, "no leaves"));
    sd.foliage = s->tree;
    sd.billboard_error = -1.0f;
    expect(xyl_forest_gl_add_species(f, &sd, &index, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    sd.billboard_error = 0.0f, sd.stem_width = NAN;
    expect(xyl_forest_gl_add_species(f, &sd, &index, &d), XYL_ERR_NON_FINITE, &d);
    sd.stem_width = 0.0f;
    expect(xyl_forest_gl_add_species(f, &sd, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_forest_gl_add_species(f, &sd, &index, &d), XYL_OK, &d);
    xyl_forest_gl_species_info info;
    expect(xyl_forest_gl_species(f, 1, &info, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_forest_gl_species(f, 0, &info, &d), XYL_OK, &d);

    /* instances */
    xyl_forest_instance in[101];
    xyl_forest_grid_desc gd = {0};
    gd.count = 101, gd.spacing = 1000.0f;
    expect(xyl_forest_grid(&gd, in, 101, &d), XYL_OK, &d);
    expect(xyl_forest_gl_set_instances(f, in, 0, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_non_null(strstr(d.message, "0 instances"));
    expect(xyl_forest_gl_set_instances(f, NULL, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_forest_gl_set_instances(NULL, in, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_forest_gl_set_instances(f, in, 101, &d), XYL_ERR_LIMIT_EXCEEDED, &d);
    in[7].bits = (in[7].bits & ~255u) | info.level_count; /* one past the last level */
    expect(xyl_forest_gl_set_instances(f, in, 100, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_int_equal(d.index, 7);
    in[7].bits |= 255u; /* a billboard, but the species has none */
    expect(xyl_forest_gl_set_instances(f, in, 100, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_non_null(strstr(d.message, "no billboard"));
    in[7].bits &= ~255u;
    in[8].bits |= 1u << 8; /* species 1 was never added */
    expect(xyl_forest_gl_set_instances(f, in, 100, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    in[8].bits &= ~(63u << 8);
    in[9].position[0] = INFINITY;
    expect(xyl_forest_gl_set_instances(f, in, 100, &d), XYL_ERR_NON_FINITE, &d);
    in[9].position[0] = 0.0f;

    /* frames */
    xyl_forest_gl_frame fr = {0};
    const float eye[3] = {5000, 2000, 5000}, tgt[3] = {0, 0, 0};
    camera_frame(eye, tgt, &fr);
    fr.error_px = 1.0f;
    expect(xyl_forest_gl_draw(f, &fr, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d); /* no instances */
    expect(xyl_forest_gl_set_instances(f, in, 100, &d), XYL_OK, &d);
    fr.error_px = 0.0f;
    expect(xyl_forest_gl_draw(f, &fr, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_non_null(strstr(d.message, "budget"));
    fr.error_px = -1.0f;
    expect(xyl_forest_gl_choose(f, &fr, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    fr.error_px = NAN;
    expect(xyl_forest_gl_draw(f, &fr, NULL, &d), XYL_ERR_NON_FINITE, &d);
    fr.error_px = 1.0f, fr.mode = (xyl_forest_mode)7;
    expect(xyl_forest_gl_draw(f, &fr, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    fr.mode = XYL_FOREST_LOD, fr.alpha_cutoff = 2.0f;
    expect(xyl_forest_gl_draw(f, &fr, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    fr.alpha_cutoff = 0.0f;
    xyl_forest_gl_frame zero = fr;
    memset(zero.view_proj, 0, sizeof zero.view_proj);
    expect(xyl_forest_gl_draw(f, &zero, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_forest_gl_draw(f, NULL, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_forest_gl_draw(NULL, &fr, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_forest_gl_set_texture(f, NULL, 1, 1, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    const uint8_t px[4] = {255, 255, 255, 255};
    expect(xyl_forest_gl_set_texture(f, px, 0, 1, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    size_t n = 1;
    assert_null(xyl_forest_gl_instances(NULL, &n));
    assert_int_equal(n, 0);
    /* a good frame still draws after all that */
    target t;
    target_begin(&t);
    xyl_forest_gl_stats st;
    expect(xyl_forest_gl_draw(f, &fr, &st, &d), XYL_OK, &d);
    uint8_t *rgba = malloc(4 * SIDE * SIDE);
    assert_non_null(rgba);
    target_end(&t, rgba);
    free(rgba);
    assert_int_equal(st.instances, 100);
    xyl_foliage_destroy(empty);
    xyl_forest_gl_destroy(f);
    xyl_forest_gl_destroy(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(instance_packs_into_16_bytes_and_round_trips),
        cmocka_unit_test(instance_pack_refuses_what_does_not_fit),
        cmocka_unit_test(grid_is_seeded_jittered_and_bounded),
        cmocka_unit_test(lod_choice_matches_the_cpu_rule),
        cmocka_unit_test(hysteresis_keeps_a_still_camera_and_switches_once),
        cmocka_unit_test(culling_keeps_every_instance_in_view),
        cmocka_unit_test(forest_picture_matches_instances_drawn_alone),
        cmocka_unit_test(stems_are_drawn_where_the_trunk_is_wide_enough),
        cmocka_unit_test(per_leaf_instances_draw_their_own_cut),
        cmocka_unit_test(a_forest_dolly_cross_fades_without_popping),
        cmocka_unit_test(a_still_camera_in_a_forest_fade_never_flickers),
        cmocka_unit_test(bad_input_gets_result_codes),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

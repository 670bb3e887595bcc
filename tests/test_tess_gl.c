/* tessellate/'s OpenGL 4.5 backend on a headless EGL context (llvmpipe where there is no GPU):
 * GPU-evaluated vertices against the CPU reference on both paths, no cracks under adaptive
 * levels (with a negative control), bad input, and a plausible rendered image. */
#include <epoxy/gl.h>
#include <float.h>
#include <math.h>

#include "test_util.h"
#include "tess_debug.h"
#include "tess_util.h"
#include <xylem/xyl_tess_gl.h>
#include <xylem/xyl_tessellate.h>

#define PI 3.14159265358979323846

/* Under AddressSanitizer the CPU reference and llvmpipe's tessellator (whose output arrays grow
 * by realloc, which ASan always copies to fresh pages) run 20-50x slower: the GPU = CPU matrix
 * then stops at level 3, and the hardware path (5.7 of its 7.5 minutes there) is captured on
 * the mixed quad / triangle mesh only, with one variant, so the sanitizer suite stays within
 * minutes. Release runs the full matrix (SANITIZED: test_util.h). */
#define MAX_LEVEL 16u /* adaptive views stay under it; keeps llvmpipe captures small */
#define SIDE 256u

static const xyl_tess_variant variants[] = {XYL_TESS_PN, XYL_TESS_ROUNDED, XYL_TESS_CIRCLE,
                                             XYL_TESS_ARC};
static const char *const variant_names[] = {"pn", "rounded", "circle", "arc"};

typedef struct suite {
    xyl_gl_context *ctx;
    xyl_tess_patterns *pat;
    xyl_tess_gl *gl;
} suite;

static int setup(void **state)
{
    suite *s = calloc(1, sizeof *s);
    xyl_diag d = {0};
    if (!s || xyl_gl_context_create_headless(NULL, &s->ctx, &d) != XYL_OK ||
        xyl_tess_patterns_create(MAX_LEVEL, NULL, &s->pat, &d) != XYL_OK ||
        xyl_tess_gl_create(NULL, s->pat, &s->gl, &d) != XYL_OK) {
        print_error("setup failed: %s\n", d.message);
        return -1;
    }
    *state = s;
    return 0;
}

static int teardown(void **state)
{
    suite *s = *state;
    xyl_tess_gl_destroy(s->gl);
    xyl_tess_patterns_destroy(s->pat);
    xyl_gl_context_destroy(s->ctx);
    free(s);
    return 0;
}

static void expect(xyl_result got, xyl_result want, const xyl_diag *d)
{
    if (got != want)
        fail_msg("expected %s, got %s (%s)", xyl_result_string(want), xyl_result_string(got),
                 d->message);
    if (want != XYL_OK) assert_true(strlen(d->message) > 0);
}

/* ---- meshes and views ----------------------------------------------------------------------- */

static xyl_mesh *skel_mesh(const char *name, uint32_t sides)
{
    char path[512];
    snprintf(path, sizeof path, "%s/stems/%s", XYL_TEST_DATA, name);
    xyl_skeleton *sk = NULL;
    xyl_diag d = {0};
    expect(xyl_skeleton_read_file(path, NULL, &sk, &d), XYL_OK, &d);
    xyl_stems_desc sd = {0};
    sd.sides = sides;
    xyl_mesh *m = NULL;
    expect(xyl_stems_build(sk, &sd, &m, NULL, &d), XYL_OK, &d);
    xyl_skeleton_destroy(sk);
    return m;
}

static xyl_tess_patches *patches_of(const xyl_mesh *m)
{
    xyl_tess_patches *tp = NULL;
    assert_int_equal(xyl_tess_patches_create(m, NULL, &tp, NULL), XYL_OK);
    return tp;
}

/* Records that carry the arc variant's axes: every variant evaluates them (the others ignore
 * the axes), so one upload serves the four. */
static xyl_tess_patches *arc_patches_of(const xyl_mesh *m)
{
    xyl_tess_patches_desc pd = {0};
    pd.variant = XYL_TESS_ARC;
    xyl_tess_patches *tp = NULL;
    assert_int_equal(xyl_tess_patches_create(m, &pd, &tp, NULL), XYL_OK);
    return tp;
}

/* A camera framing the mesh's bounds from (azimuth, elevation), moved towards their centre by
 * `zoom` (1: the whole box in view), and the frame uniforms that go with it. */
static void make_view(const xyl_mesh *m, float azimuth, float elevation, float zoom,
                      xyl_tess_camera *cam, xyl_tess_frame *frame)
{
    float lo[3], hi[3];
    xyl_mesh_bounds(m, lo, hi);
    xyl_tess_camera_frame(lo, hi, azimuth, elevation, 0.8f, 1.0f, cam);
    for (int k = 0; k < 3; ++k)
        cam->eye[k] = cam->target[k] + zoom * (cam->eye[k] - cam->target[k]);
    cam->near_plane *= zoom;
    memset(frame, 0, sizeof *frame);
    assert_int_equal(xyl_tess_camera_matrix(cam, XYL_TESS_CLIP_GL, frame->view_proj, NULL), XYL_OK);
    const float light[3] = {0.4f, 0.8f, 0.45f};
    float l = sqrtf(light[0] * light[0] + light[1] * light[1] + light[2] * light[2]);
    for (int k = 0; k < 3; ++k) frame->light_dir[k] = light[k] / l;
    frame->color[0] = 0.55f; frame->color[1] = 0.42f; frame->color[2] = 0.3f; frame->color[3] = 1;
    frame->line_color[1] = 1.0f; frame->line_color[3] = 1.0f;
}

/* ---- 1. context ----------------------------------------------------------------------------- */

static void headless_context_is_gl45_core_with_a_renderer(void **state)
{
    suite *s = *state;
    assert_true(epoxy_is_desktop_gl());
    assert_true(epoxy_gl_version() >= 45);
    GLint profile = 0;
    glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    assert_true(profile & GL_CONTEXT_CORE_PROFILE_BIT);
    const char *name = xyl_gl_context_renderer(s->ctx);
    assert_true(strlen(name) > 0);
    assert_string_equal(name, (const char *)glGetString(GL_RENDERER));
    print_message("GL %s, %s\n", (const char *)glGetString(GL_VERSION), name);
}

/* ---- 2. GPU = CPU --------------------------------------------------------------------------- */

/* Triangles GL's tessellator emits for one patch (equal spacing, inner level l, outer levels
 * le[e] <= l): a ring between each outer side and the inner side of l - 2 segments (le + l - 2
 * triangles), around the uniform inner tessellation of level l - 2. */
static uint64_t uniform_triangles(uint32_t kind, uint32_t n)
{
    if (kind == XYL_TESS_KIND_QUAD) return 2ull * n * n;
    if (n <= 1) return n;
    return 6ull * n - 6 + uniform_triangles(kind, n - 2);
}

static uint64_t hardware_triangles(const xyl_tess_instance *in)
{
    if (in->level == 1) return in->kind == XYL_TESS_KIND_QUAD ? 2 : 1;
    uint64_t t = uniform_triangles(in->kind, in->level - 2);
    for (uint32_t e = 0; e < in->kind; ++e)
        t += ((in->edge_levels >> (8 * e)) & 0xffu) + in->level - 2;
    return t;
}

typedef struct deviation {
    double pos, nrm;
} deviation;

static void compare_one(const xyl_tess_patches *tp, xyl_tess_variant v, bool hw,
                        const xyl__tess_captured *c, uint32_t edge_levels, deviation *worst,
                        size_t slot)
{
    float pos[3], nrm[3];
    const xyl_tess_patch *rec = &tp->records[c->patch];
    if (hw)
        xyl__tess_reference_hardware(rec, v, c->coord, edge_levels, pos, nrm);
    else
        xyl_tess_eval_lattice(rec, v, (uint32_t)c->coord[2], edge_levels, (uint32_t)c->coord[0],
                              (uint32_t)c->coord[1], pos, nrm);
    double dp = 0.0, dn = 0.0;
    for (int k = 0; k < 3; ++k) {
        dp = fmax(dp, fabs((double)c->position[k] - pos[k]));
        dn = fmax(dn, fabs((double)c->normal[k] - nrm[k]));
    }
    if (!(dp <= 1e-5 * tp->size) || !(dn <= 1e-4))
        fail_msg("%s %s vertex %zu (patch %u, coord %g %g %g): position off by %g (size %g), "
                 "normal by %g", hw ? "hardware" : "instanced", variant_names[v], slot, c->patch,
                 c->coord[0], c->coord[1], c->coord[2], dp, tp->size, dn);
    worst->pos = fmax(worst->pos, dp / tp->size);
    worst->nrm = fmax(worst->nrm, dn);
}

/* The tessellator emits a vertex once per triangle that uses it (about six times). A repeat,
 * bit-identical to a vertex already compared with the reference, needs no reference of its
 * own: that keeps the suite's time reasonable under the sanitizers, where the CPU reference
 * dominates. */
typedef struct seen_table {
    uint32_t *slots; /* 1 + index of the first vertex with a (patch, coord), 0: empty */
    size_t mask;
} seen_table;

static seen_table seen_create(size_t count)
{
    seen_table t;
    size_t cap = 16;
    while (cap < 2 * count) cap *= 2;
    t.slots = calloc(cap, sizeof *t.slots);
    t.mask = cap - 1;
    assert_non_null(t.slots);
    return t;
}

static bool same_key(const xyl__tess_captured *a, const xyl__tess_captured *b)
{
    return a->patch == b->patch && memcmp(a->coord, b->coord, sizeof a->coord) == 0;
}

/* True when cap[k] repeats an earlier vertex exactly, key and value. */
static bool seen_repeats(seen_table *t, const xyl__tess_captured *cap, size_t k)
{
    uint32_t w[4];
    memcpy(w, cap[k].coord, sizeof cap[k].coord);
    w[3] = cap[k].patch;
    uint64_t h = 1469598103934665603ull;
    for (int i = 0; i < 4; ++i) h = (h ^ w[i]) * 1099511628211ull;
    for (size_t at = (size_t)h & t->mask;; at = (at + 1) & t->mask) {
        if (!t->slots[at]) {
            t->slots[at] = (uint32_t)k + 1;
            return false;
        }
        const xyl__tess_captured *first = &cap[t->slots[at] - 1];
        if (same_key(first, &cap[k]))
            return memcmp(first->position, cap[k].position, sizeof first->position) == 0 &&
                   memcmp(first->normal, cap[k].normal, sizeof first->normal) == 0;
    }
}

static void check_capture(suite *s, const xyl_tess_patches *tp, const xyl_tess_batches *b,
                          xyl_tess_variant v, xyl_tess_path path, deviation *worst)
{
    bool hw = path == XYL_TESS_PATH_HARDWARE;
    size_t count = 0;
    xyl_diag d = {0};
    /* count first (capacity 0), then fill */
    expect(xyl__tess_gl_capture(s->gl, b, v, path, NULL, 0, &count, &d), XYL_OK, &d);
    xyl__tess_captured *cap = malloc((count ? count : 1) * sizeof *cap);
    size_t again = 0;
    expect(xyl__tess_gl_capture(s->gl, b, v, path, cap, count, &again, &d), XYL_OK, &d);
    assert_int_equal(again, count);
    uint32_t *inst_of = malloc(tp->count * sizeof *inst_of);
    for (size_t p = 0; p < tp->count; ++p) inst_of[p] = UINT32_MAX;
    uint64_t expect = 0;
    for (size_t i = 0; i < b->instance_count; ++i) {
        inst_of[b->instances[i].patch] = (uint32_t)i;
        expect += hw ? 3 * hardware_triangles(&b->instances[i]) : 0;
    }
    if (hw) { /* every patch tessellated once: no patch drawn twice in place of another */
        size_t *per = calloc(tp->count, sizeof *per);
        for (size_t k = 0; k < count; ++k) per[cap[k].patch < tp->count ? cap[k].patch : 0]++;
        for (size_t i = 0; i < b->instance_count; ++i) {
            const xyl_tess_instance *in = &b->instances[i];
            if (per[in->patch] != 3 * hardware_triangles(in)) {
                fail_msg("patch %u (kind %u, level %u, edges %08x, instance %zu of %zu): %zu "
                         "triangles captured, %llu expected", in->patch, in->kind, in->level,
                         in->edge_levels, i, b->instance_count, per[in->patch] / 3,
                         (unsigned long long)hardware_triangles(in));
            }
        }
        free(per);
    }
    assert_int_equal(count, hw ? expect : b->vertices);
    seen_table seen = seen_create(count);
    for (size_t k = 0; k < count; ++k) {
        const xyl__tess_captured *c = &cap[k];
        if (c->patch >= tp->count || inst_of[c->patch] == UINT32_MAX)
            fail_msg("captured vertex %zu names patch %u of %zu", k, c->patch, tp->count);
        if (!seen_repeats(&seen, cap, k))
            compare_one(tp, v, hw, c, b->instances[inst_of[c->patch]].edge_levels, worst, k);
    }
    free(seen.slots);
    free(inst_of);
    free(cap);
}

static void gpu_vertices_match_the_cpu_reference_on_both_paths(void **state)
{
    suite *s = *state;
    const struct { uint32_t sides; xyl_subdivision sub; } meshes[] = {
        {3, XYL_SUBDIVIDE_NONE}, {4, XYL_SUBDIVIDE_NONE}, {4, XYL_SUBDIVIDE_CATMARK}};
    deviation worst[2] = {{0, 0}, {0, 0}};
    xyl_tess_batches *b = tu_batches_create();
    for (size_t mi = 0; mi < 3; ++mi) {
        xyl_mesh *m = tu_tree_mesh(0, meshes[mi].sides, meshes[mi].sub);
        xyl_tess_patches *tp = arc_patches_of(m);
        if (mi == 0) assert_true(tp->quad_count > 0 && tp->quad_count < tp->count); /* mixed */
        assert_int_equal(xyl_tess_gl_set_patches(s->gl, tp, NULL), XYL_OK);
        /* 0: adaptive. The Catmull-Clark mesh has 4x the patches; at level 8 its capture would
         * pass llvmpipe's 128 MiB storage block limit (XYL_ERR_LIMIT_EXCEEDED) and take most of
         * the suite's time, so it stops at level 3 (the cap of its adaptive view too). */
        const uint32_t fixed[] = {1, 3, 8, 0};
        uint32_t cap = meshes[mi].sub || SANITIZED ? 3 : 8;
        uint32_t adaptive_max = meshes[mi].sub ? 3 : SANITIZED ? 4 : 8;
        for (size_t li = 0; li < 4; ++li) {
            if (fixed[li] > cap) continue;
            xyl_tess_view view = {0};
            view.fixed_level = fixed[li];
            view.eye[0] = 0.3f * tp->size; view.eye[1] = 0.2f * tp->size;
            view.max_level = adaptive_max;
            assert_int_equal(xyl_tess_select(tp, s->pat, &view, b, NULL), XYL_OK);
            if (!fixed[li]) assert_true(b->cmd_count >= 3);
            for (size_t vi = 0; vi < XYL_TESS_VARIANT_COUNT; ++vi)
                for (int path = 0; path < 2; ++path) {
                    bool hw_sampled = path == 0 || !SANITIZED || (mi == 0 && vi == 0);
                    if (hw_sampled)
                        check_capture(s, tp, b, variants[vi], (xyl_tess_path)path, &worst[path]);
                }
        }
        xyl_tess_patches_destroy(tp);
        xyl_mesh_destroy(m);
    }
    print_message("worst GPU - CPU: instanced %.3g x size (position), %.3g (normal); "
                  "hardware %.3g x size, %.3g\n", worst[0].pos, worst[0].nrm, worst[1].pos,
                  worst[1].nrm);
    xyl_tess_batches_destroy(b);
}

/* ---- 3. cracks ------------------------------------------------------------------------------ */

static size_t count_pixels(const uint8_t *rgba, size_t n, const uint8_t want[4], bool equal)
{
    size_t c = 0;
    for (size_t i = 0; i < n; ++i) c += (memcmp(rgba + 4 * i, want, 4) == 0) == equal;
    return c;
}

static const uint8_t red[4] = {255, 0, 0, 255};

/* Red pixels over six views for one path, at one fixed level or (0) adaptive levels; breaks
 * the shared edges first when asked. */
static size_t red_over_views(suite *s, const xyl_mesh *m, const xyl_tess_patches *tp,
                             xyl_tess_path path, uint32_t fixed_level, bool break_edges,
                             uint8_t *rgba)
{
    const float az[6] = {0.3f, 1.9f, 3.5f, 5.0f, 0.8f, 2.6f};
    const float el[6] = {0.25f, 0.1f, 0.35f, -0.1f, 1.35f, -1.35f};
    xyl_tess_batches *b = tu_batches_create();
    size_t total = 0;
    for (int i = 0; i < 6; ++i) {
        xyl_tess_camera cam;
        xyl_tess_frame frame;
        make_view(m, az[i], el[i], 0.45f, &cam, &frame);
        frame.flags = XYL__TESS_FLAG_BACKFACES;
        xyl_tess_view view = {0};
        memcpy(view.eye, cam.eye, sizeof view.eye);
        view.fovy = cam.fovy;
        view.viewport_height = SIDE;
        view.error_px = 0.05f; /* a small budget: levels vary from 1 to MAX_LEVEL */
        view.fixed_level = fixed_level;
        assert_int_equal(xyl_tess_select(tp, s->pat, &view, b, NULL), XYL_OK);
        if (!fixed_level) assert_true(b->cmd_count >= 3);
        /* every other instance: all its edges at its own level, so an edge it shares with a
         * coarser neighbour gets points the neighbour lacks */
        tu_batches broken = {0};
        const xyl_tess_batches *drawn = b;
        if (break_edges) {
            tu_batches_copy(b, &broken);
            for (size_t k = 0; k < b->instance_count; k += 2)
                broken.instances[k].edge_levels = broken.instances[k].level * 0x01010101u;
            drawn = &broken.view;
        }
        xyl_tess_image_desc img = {0};
        img.width = img.height = SIDE;
        xyl_diag d = {0};
        assert_int_equal(xyl_tess_gl_render_rgba(s->gl, drawn, &frame, path, &img, rgba, &d),
                         XYL_OK);
        tu_batches_free(&broken);
        total += count_pixels(rgba, (size_t)SIDE * SIDE, red, true);
    }
    xyl_tess_batches_destroy(b);
    return total;
}

/* The mesh must be one whose refined surface shows no back face without a hole, so that red
 * means a crack: the default tree does not qualify (at a uniform level 8, where shared edges
 * cannot crack, a few of its PN branches still fold and show red pixels), nor does a skeleton
 * whose tubes intersect (binary_depth7: cousins cross). This uses the eight-spoke fork of the
 * stem mesher's test data (free of intersections), checked at a uniform level first. */
static void adaptive_levels_show_no_back_faces_through_cracks(void **state)
{
    suite *s = *state;
    uint8_t *rgba = malloc(4u * SIDE * SIDE);
    for (uint32_t sides = 3; sides <= 4; ++sides) {
        xyl_mesh *m = skel_mesh("spokes_8.skel", sides);
        xyl_tess_patches *tp = patches_of(m);
        assert_int_equal(xyl_tess_gl_set_patches(s->gl, tp, NULL), XYL_OK);
        for (int path = 0; path < 2; ++path) {
            xyl_tess_path p = (xyl_tess_path)path;
            size_t uniform = red_over_views(s, m, tp, p, 8, false, rgba);
            size_t clean = red_over_views(s, m, tp, p, 0, false, rgba);
            size_t broken = red_over_views(s, m, tp, p, 0, true, rgba);
            print_message("k = %u, %s: %zu red pixels at level 8, %zu adaptive, %zu with "
                          "mismatched edge levels\n", sides, path ? "hardware" : "instanced",
                          uniform, clean, broken);
            assert_int_equal(uniform, 0);
            assert_int_equal(clean, 0);
            assert_true(broken > 0); /* the check can fail */
        }
        xyl_tess_patches_destroy(tp);
        xyl_mesh_destroy(m);
    }
    free(rgba);
}

/* ---- 4. bad input --------------------------------------------------------------------------- */

static void bad_draw_arguments_get_result_codes(suite *s, const xyl_tess_batches *b,
                                                const xyl_tess_frame *f, xyl_diag *d)
{
    expect(xyl_tess_gl_draw(NULL, b, f, XYL_TESS_PATH_INSTANCED, d), XYL_ERR_INVALID_ARGUMENT, d);
    expect(xyl_tess_gl_draw(s->gl, NULL, f, XYL_TESS_PATH_INSTANCED, d), XYL_ERR_INVALID_ARGUMENT, d);
    expect(xyl_tess_gl_draw(s->gl, b, NULL, XYL_TESS_PATH_INSTANCED, d), XYL_ERR_INVALID_ARGUMENT, d);
    expect(xyl_tess_gl_draw(s->gl, b, f, (xyl_tess_path)7, d), XYL_ERR_INVALID_ARGUMENT, d);
    xyl_tess_frame bad = *f;
    bad.variant = 9;
    expect(xyl_tess_gl_draw(s->gl, b, &bad, XYL_TESS_PATH_INSTANCED, d), XYL_ERR_INVALID_ARGUMENT, d);
    size_t n = 0;
    xyl__tess_captured one;
    expect(xyl__tess_gl_capture(s->gl, b, XYL_TESS_PN, XYL_TESS_PATH_INSTANCED, NULL, 0, NULL, d),
           XYL_ERR_INVALID_ARGUMENT, d);
    expect(xyl__tess_gl_capture(s->gl, b, XYL_TESS_PN, XYL_TESS_PATH_INSTANCED, NULL, 5, &n, d),
           XYL_ERR_INVALID_ARGUMENT, d);
    expect(xyl__tess_gl_capture(s->gl, b, (xyl_tess_variant)XYL_TESS_VARIANT_COUNT,
                                XYL_TESS_PATH_HARDWARE, &one, 1, &n, d),
           XYL_ERR_INVALID_ARGUMENT, d);
    expect(xyl_tess_gl_set_patches(s->gl, NULL, d), XYL_ERR_INVALID_ARGUMENT, d);
    expect(xyl_tess_gl_set_patches(NULL, NULL, d), XYL_ERR_INVALID_ARGUMENT, d);
}

/* Every entry point that takes batches refuses ones the renderer cannot draw, on both paths,
 * and leaves its outputs alone. */
static void refuse_batches(suite *s, const xyl_tess_batches *b, const xyl_tess_frame *f,
                           uint8_t *rgba, xyl_diag *d)
{
    xyl_tess_image_desc img = {0};
    img.width = img.height = 16;
    for (int path = 0; path < 2; ++path) {
        xyl_tess_path p = (xyl_tess_path)path;
        memset(rgba, 0xab, 4 * 16 * 16);
        expect(xyl_tess_gl_draw(s->gl, b, f, p, d), XYL_ERR_INVALID_ARGUMENT, d);
        expect(xyl_tess_gl_render_rgba(s->gl, b, f, p, &img, rgba, d), XYL_ERR_INVALID_ARGUMENT, d);
        assert_int_equal(rgba[0], 0xab);
        assert_int_equal(rgba[4 * 16 * 16 - 1], 0xab);
        size_t n = 12345;
        xyl__tess_captured c;
        expect(xyl__tess_gl_capture(s->gl, b, XYL_TESS_PN, p, &c, 1, &n, d), XYL_ERR_INVALID_ARGUMENT, d);
        assert_int_equal(n, 12345);
    }
}

static void bad_images_get_result_codes(suite *s, const xyl_tess_batches *b,
                                        const xyl_tess_frame *f, xyl_diag *d)
{
    uint8_t *rgba = malloc(4u * 512 * 512);
    xyl_tess_image_desc img = {0};
    img.width = 9000; img.height = 16;
    expect(xyl_tess_gl_render_rgba(s->gl, b, f, XYL_TESS_PATH_INSTANCED, &img, rgba, d),
           XYL_ERR_INVALID_ARGUMENT, d);
    img.width = 16; img.height = 9000;
    expect(xyl_tess_gl_render_rgba(s->gl, b, f, XYL_TESS_PATH_INSTANCED, &img, rgba, d),
           XYL_ERR_INVALID_ARGUMENT, d);
    img.height = 16;
    img.background[2] = NAN;
    expect(xyl_tess_gl_render_rgba(s->gl, b, f, XYL_TESS_PATH_INSTANCED, &img, rgba, d),
           XYL_ERR_NON_FINITE, d);
    img.background[2] = 0.0f;
    img.samples = 1000;
    expect(xyl_tess_gl_render_rgba(s->gl, b, f, XYL_TESS_PATH_INSTANCED, &img, rgba, d),
           XYL_ERR_UNSUPPORTED, d);
    expect(xyl_tess_gl_render_rgba(s->gl, b, f, XYL_TESS_PATH_INSTANCED, &img, NULL, d),
           XYL_ERR_INVALID_ARGUMENT, d);
    /* zero-filled sizes are the documented default, 512 x 512 */
    img.samples = 0;
    img.width = img.height = 0;
    expect(xyl_tess_gl_render_rgba(s->gl, b, f, XYL_TESS_PATH_INSTANCED, &img, rgba, d), XYL_OK, d);
    expect(xyl_tess_gl_render_rgba(s->gl, b, f, XYL_TESS_PATH_HARDWARE, NULL, rgba, d), XYL_OK, d);
    free(rgba);
}

static void bad_input_gets_result_codes(void **state)
{
    suite *s = *state;
    xyl_diag d = {0};
    expect(xyl_gl_context_create_headless(NULL, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_tess_gl *none = (xyl_tess_gl *)(uintptr_t)1;
    expect(xyl_tess_gl_create(NULL, NULL, &none, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_tess_gl_create(NULL, s->pat, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_ptr_equal(none, (xyl_tess_gl *)(uintptr_t)1);
    assert_true(xyl_tess_gl_last_gpu_ms(NULL) < 0.0);
    xyl_tess_gl_destroy(NULL);
    xyl_gl_context_destroy(NULL);

    xyl_mesh *m = tu_tree_mesh(0, 3, XYL_SUBDIVIDE_NONE);
    xyl_tess_patches *tp = patches_of(m);
    xyl_tess_camera cam;
    xyl_tess_frame f;
    make_view(m, 0.5f, 0.2f, 1.0f, &cam, &f);
    xyl_tess_view view = {0};
    view.fixed_level = 2;
    xyl_tess_batches *b = tu_batches_create();
    assert_int_equal(xyl_tess_select(tp, s->pat, &view, b, NULL), XYL_OK);
    assert_int_equal(xyl_tess_gl_set_patches(s->gl, tp, &d), XYL_OK);
    bad_draw_arguments_get_result_codes(s, b, &f, &d);
    bad_images_get_result_codes(s, b, &f, &d);

    uint8_t *rgba = malloc(4 * 16 * 16);
    /* batches that reference patches beyond the uploaded set */
    xyl_tess_patches half = *tp;
    half.count = tp->count / 2;
    half.quad_count = half.quad_count < half.count ? half.quad_count : half.count;
    assert_int_equal(xyl_tess_gl_set_patches(s->gl, &half, &d), XYL_OK);
    refuse_batches(s, b, &f, rgba, &d);
    assert_int_equal(xyl_tess_gl_set_patches(s->gl, tp, &d), XYL_OK);
    /* a level above the renderer's patterns (MAX_LEVEL) */
    xyl_tess_patterns *big = NULL;
    assert_int_equal(xyl_tess_patterns_create(MAX_LEVEL + 4, NULL, &big, NULL), XYL_OK);
    view.fixed_level = MAX_LEVEL + 1;
    xyl_tess_batches *high = tu_batches_create();
    assert_int_equal(xyl_tess_select(tp, big, &view, high, NULL), XYL_OK);
    refuse_batches(s, high, &f, rgba, &d);
    /* an instance whose edge level is above its patch level, or a command that lies */
    tu_batches edited;
    tu_batches_copy(b, &edited);
    edited.instances[0].edge_levels |= 0xffu;
    refuse_batches(s, &edited.view, &f, rgba, &d);
    edited.instances[0] = b->instances[0];
    edited.cmds[0].index_count += 3;
    refuse_batches(s, &edited.view, &f, rgba, &d);
    tu_batches_free(&edited);
    expect(xyl_tess_gl_draw(s->gl, b, &f, XYL_TESS_PATH_INSTANCED, &d),
           XYL_ERR_UNSUPPORTED, &d); /* valid, but a surfaceless context has no framebuffer */

    free(rgba);
    xyl_tess_batches_destroy(high);
    xyl_tess_patterns_destroy(big);
    xyl_tess_batches_destroy(b);
    xyl_tess_patches_destroy(tp);
    xyl_mesh_destroy(m);
}

/* Without a current context the renderer says so instead of crashing in the driver. */
static void create_without_a_context_is_unsupported(void **state)
{
    suite *s = *state;
    xyl_tess_gl_destroy(s->gl);
    s->gl = NULL;
    xyl_gl_context_destroy(s->ctx);
    s->ctx = NULL;
    xyl_diag d = {0};
    xyl_tess_gl *gl = NULL;
    expect(xyl_tess_gl_create(NULL, s->pat, &gl, &d), XYL_ERR_UNSUPPORTED, &d);
    assert_null(gl);
    /* and a context made again afterwards works */
    assert_int_equal(xyl_gl_context_create_headless(NULL, &s->ctx, &d), XYL_OK);
    assert_int_equal(xyl_tess_gl_create(NULL, s->pat, &s->gl, &d), XYL_OK);
}

/* ---- 5. rendering --------------------------------------------------------------------------- */

static const uint8_t transparent[4] = {0, 0, 0, 0};

/* The same frame through xyl_tess_gl_draw into the test's own framebuffer. */
static void draw_into_own_framebuffer(suite *s, const xyl_tess_batches *b, const xyl_tess_frame *f,
                                      xyl_tess_path path, uint8_t *rgba)
{
    GLuint fbo, rb[2];
    glCreateRenderbuffers(2, rb);
    glNamedRenderbufferStorage(rb[0], GL_RGBA8, SIDE, SIDE);
    glNamedRenderbufferStorage(rb[1], GL_DEPTH_COMPONENT24, SIDE, SIDE);
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferRenderbuffer(fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    glNamedFramebufferRenderbuffer(fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, SIDE, SIDE);
    glClearColor(0, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    xyl_diag d = {0};
    expect(xyl_tess_gl_draw(s->gl, b, f, path, &d), XYL_OK, &d);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, SIDE, SIDE, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    assert_int_equal(glGetError(), GL_NO_ERROR);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &fbo);
    glDeleteRenderbuffers(2, rb);
}

/* render_rgba's image is top row first; a framebuffer read is bottom row first. */
static bool same_but_flipped(const uint8_t *top_first, const uint8_t *bottom_first)
{
    for (uint32_t y = 0; y < SIDE; ++y)
        if (memcmp(top_first + 4u * SIDE * y, bottom_first + 4u * SIDE * (SIDE - 1 - y), 4u * SIDE))
            return false;
    return true;
}

static void render_path(suite *s, const xyl_tess_batches *b, xyl_tess_frame *f, xyl_tess_path path,
                        uint8_t *plain, uint8_t *other)
{
    xyl_tess_image_desc img = {0};
    img.width = img.height = SIDE;
    xyl_diag d = {0};
    expect(xyl_tess_gl_render_rgba(s->gl, b, f, path, &img, plain, &d), XYL_OK, &d);
    double ms = xyl_tess_gl_last_gpu_ms(s->gl);
    size_t n = (size_t)SIDE * SIDE, covered = count_pixels(plain, n, transparent, false);
    print_message("%s: %.1f %% covered, %.2f ms GPU\n", path ? "hardware" : "instanced",
                  100.0 * (double)covered / (double)n, ms);
    assert_true(covered > n / 50);
    assert_true(ms >= 0.0);
    /* the tree stands upright: more of it in the lower half than in the top rows */
    assert_true(count_pixels(plain + 4 * n / 2, n / 2, transparent, false) >
                count_pixels(plain, n / 8, transparent, false));
    img.wireframe = true;
    expect(xyl_tess_gl_render_rgba(s->gl, b, f, path, &img, other, &d), XYL_OK, &d);
    const uint8_t green[4] = {0, 255, 0, 255};
    size_t lines = count_pixels(other, n, green, true);
    assert_true(lines > 0 && memcmp(plain, other, 4 * n) != 0);
    assert_int_equal(count_pixels(plain, n, green, true), 0);
    img.wireframe = false;
    img.samples = 4;
    expect(xyl_tess_gl_render_rgba(s->gl, b, f, path, &img, other, &d), XYL_OK, &d);
    size_t msaa = count_pixels(other, n, transparent, false);
    print_message("%s: %zu pixels covered with 4x MSAA, %zu without\n",
                  path ? "hardware" : "instanced", msaa, covered);
    assert_true(msaa > covered * 9 / 10 && msaa < covered * 3);
    draw_into_own_framebuffer(s, b, f, path, other);
    assert_true(same_but_flipped(plain, other));
}

static void default_tree_renders_with_coverage_and_wireframe(void **state)
{
    suite *s = *state;
    xyl_mesh *m = tu_tree_mesh(0, 4, XYL_SUBDIVIDE_NONE);
    xyl_tess_patches *tp = patches_of(m);
    assert_int_equal(xyl_tess_gl_set_patches(s->gl, tp, NULL), XYL_OK);
    xyl_tess_camera cam;
    xyl_tess_frame f;
    make_view(m, 0.6f, 0.15f, 1.0f, &cam, &f);
    xyl_tess_view view = {0};
    memcpy(view.eye, cam.eye, sizeof view.eye);
    view.viewport_height = SIDE;
    xyl_tess_batches *b = tu_batches_create();
    assert_int_equal(xyl_tess_select(tp, s->pat, &view, b, NULL), XYL_OK);
    uint8_t *plain = malloc(4u * SIDE * SIDE), *other = malloc(4u * SIDE * SIDE);
    for (int path = 0; path < 2; ++path) render_path(s, b, &f, (xyl_tess_path)path, plain, other);
    free(plain);
    free(other);
    xyl_tess_batches_destroy(b);
    xyl_tess_patches_destroy(tp);
    xyl_mesh_destroy(m);
}

/* The renderer's own memory (pattern and patch tables, staging for a render) comes from the
 * allocator in its desc, and all of it goes back on destroy; a refusing allocator is
 * XYL_ERR_OUT_OF_MEMORY, with nothing left behind. */
static void renderer_allocates_through_the_callers_allocator(void **state)
{
    suite *s = *state;
    xyl_mesh *m = tu_tree_mesh(0, 4, XYL_SUBDIVIDE_NONE);
    xyl_tess_patches *tp = patches_of(m);
    tu_counting_alloc counted = {0, 0, false};
    xyl_tess_gl_desc gd = {0};
    gd.alloc = tu_counting_allocator(&counted);
    xyl_tess_gl *gl = NULL;
    xyl_diag d = {0};
    expect(xyl_tess_gl_create(&gd, s->pat, &gl, &d), XYL_OK, &d);
    expect(xyl_tess_gl_set_patches(gl, tp, &d), XYL_OK, &d);
    xyl_tess_camera cam;
    xyl_tess_frame f;
    make_view(m, 0.6f, 0.15f, 1.0f, &cam, &f);
    xyl_tess_view view = {0};
    memcpy(view.eye, cam.eye, sizeof view.eye);
    view.viewport_height = SIDE;
    xyl_tess_batches *b = tu_batches_create();
    expect(xyl_tess_select(tp, s->pat, &view, b, &d), XYL_OK, &d);
    xyl_tess_image_desc img = {0};
    img.width = img.height = 64;
    uint8_t *rgba = malloc(4u * 64 * 64);
    expect(xyl_tess_gl_render_rgba(gl, b, &f, XYL_TESS_PATH_INSTANCED, &img, rgba, &d), XYL_OK, &d);
    assert_true(counted.calls >= 3);
    xyl_tess_gl_destroy(gl);
    assert_int_equal(counted.live, 0);
    counted.refuse = true;
    gl = NULL;
    expect(xyl_tess_gl_create(&gd, s->pat, &gl, &d), XYL_ERR_OUT_OF_MEMORY, &d);
    assert_null(gl);
    assert_int_equal(counted.live, 0);
    tu_counting_alloc ctx_count = {0, 0, false};
    xyl_allocator ca = tu_counting_allocator(&ctx_count);
    xyl_gl_context *other = NULL;
    ctx_count.refuse = true;
    expect(xyl_gl_context_create_headless(&ca, &other, &d), XYL_ERR_OUT_OF_MEMORY, &d);
    assert_null(other);
    free(rgba);
    xyl_tess_batches_destroy(b);
    xyl_tess_patches_destroy(tp);
    xyl_mesh_destroy(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(headless_context_is_gl45_core_with_a_renderer),
        cmocka_unit_test(gpu_vertices_match_the_cpu_reference_on_both_paths),
        cmocka_unit_test(adaptive_levels_show_no_back_faces_through_cracks),
        cmocka_unit_test(default_tree_renders_with_coverage_and_wireframe),
        cmocka_unit_test(bad_input_gets_result_codes),
        cmocka_unit_test(create_without_a_context_is_unsupported),
        cmocka_unit_test(renderer_allocates_through_the_callers_allocator),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

/* tessellate/ Vulkan backend (instanced path) on whatever driver the machine has (lavapipe in
 * CI), always with the Khronos validation layer: captured vertices against the CPU reference,
 * crack-freedom and winding seen through back faces, render sanity, the caller's allocator,
 * draws recorded into an application's own device, pass and command buffers (equal to the
 * offscreen render), bad input. Every test ends with no validation message. */
#include <math.h>

#include "test_util.h"
#include "tess_util.h"
#include "vk_internal.h" /* the device handle, to provoke the layer directly; capture */
#include <xylem/xyl_tess_vk.h>

static const xyl_tess_variant variants[] = {XYL_TESS_PN, XYL_TESS_ROUNDED, XYL_TESS_CIRCLE,
                                             XYL_TESS_ARC};
static const char *const variant_names[] = {"pn", "rounded", "circle", "arc"};

static xyl_tess_vk *open_vk(const xyl_tess_patterns *pat)
{
    xyl_tess_vk_desc vd = {0};
    vd.validation = true;
    xyl_tess_vk *vk = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_tess_vk_create(&vd, pat, &vk, &d);
    if (r != XYL_OK) fail_msg("xyl_tess_vk_create: %s: %s", xyl_result_string(r), d.message);
    return vk;
}

/* Every test ends here: the validation layer reported nothing. */
static void close_vk(xyl_tess_vk *vk)
{
    uint32_t n = xyl_tess_vk_validation_messages(vk);
    if (n != 0) {
        char first[XYL_DIAG_MESSAGE_SIZE];
        snprintf(first, sizeof first, "%s", xyl_tess_vk_first_message(vk));
        xyl_tess_vk_destroy(vk);
        fail_msg("%u validation messages, the first: %s", n, first);
    }
    xyl_tess_vk_destroy(vk);
}

static void expect_ok(xyl_result r, const xyl_diag *d, const char *what)
{
    if (r != XYL_OK) fail_msg("%s: %s: %s", what, xyl_result_string(r), d->message);
}

/* ---- device -------------------------------------------------------------------------------- */

static void device_reports_a_name_and_validation_is_active(void **state)
{
    (void)state;
    xyl_tess_patterns *pat = NULL;
    assert_int_equal(xyl_tess_patterns_create(4, NULL, &pat, NULL), XYL_OK);
    xyl_tess_vk *vk = open_vk(pat);
    const char *name = xyl_tess_vk_device_name(vk);
    assert_true(strlen(name) > 0);
    printf("device: %s\n", name);
    assert_int_equal(xyl_tess_vk_validation_messages(vk), 0);
    assert_string_equal(xyl_tess_vk_first_message(vk), "");
    /* A zero-sized buffer breaks a valid-usage rule: the layer must report it (and, having
     * found it invalid, not pass the call down). */
    VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    VkBuffer b = VK_NULL_HANDLE;
    VkResult r = vkCreateBuffer(vk->device, &bi, NULL, &b);
    if (r == VK_SUCCESS && b) vkDestroyBuffer(vk->device, b, NULL);
    assert_true(xyl_tess_vk_validation_messages(vk) >= 1);
    assert_non_null(strstr(xyl_tess_vk_first_message(vk), "VUID-VkBufferCreateInfo-size"));
    printf("the layer reported: %.100s...\n", xyl_tess_vk_first_message(vk));
    xyl_tess_vk_destroy(vk); /* the provoked message is the point here */
    /* Naming the device picks it; a name no device has is refused. */
    xyl_tess_vk_desc vd = {0};
    vd.validation = true;
    vd.device_name = "no such device";
    xyl_tess_vk *none = (xyl_tess_vk *)(uintptr_t)1;
    xyl_diag d = {0};
    assert_int_equal(xyl_tess_vk_create(&vd, pat, &none, &d), XYL_ERR_UNSUPPORTED);
    assert_ptr_equal(none, (xyl_tess_vk *)(uintptr_t)1);
    assert_non_null(strstr(d.message, "no such device"));
    xyl_tess_patterns_destroy(pat);
}

/* ---- GPU = CPU ----------------------------------------------------------------------------- */

typedef struct deviation {
    double pos, nrm;
} deviation;

static void compare_capture(xyl_tess_vk *vk, const xyl_tess_patches *tp,
                            const xyl_tess_batches *b, xyl_tess_variant variant, deviation *worst)
{
    size_t n = (size_t)b->vertices, count = 0;
    xyl__tess_captured *cap = calloc(n ? n : 1, sizeof *cap);
    uint32_t *edge_levels = calloc(tp->count, sizeof *edge_levels);
    assert_true(cap && edge_levels);
    for (size_t i = 0; i < b->instance_count; ++i)
        edge_levels[b->instances[i].patch] = b->instances[i].edge_levels;
    xyl_diag d = {0};
    expect_ok(xyl__tess_vk_capture(vk, b, variant, cap, n, &count, &d), &d, "capture");
    assert_int_equal(count, b->vertices);
    const double tol_pos = 1e-5 * tp->size, tol_nrm = 1e-4;
    for (size_t v = 0; v < n; ++v) {
        const xyl__tess_captured *c = &cap[v];
        assert_true(c->patch < tp->count);
        float p[3], nr[3];
        xyl_tess_eval_lattice(&tp->records[c->patch], variant, (uint32_t)c->coord[2],
                              edge_levels[c->patch], (uint32_t)c->coord[0], (uint32_t)c->coord[1],
                              p, nr);
        for (int k = 0; k < 3; ++k) {
            double dp = fabs((double)c->position[k] - p[k]);
            double dn = fabs((double)c->normal[k] - nr[k]);
            worst->pos = fmax(worst->pos, dp);
            worst->nrm = fmax(worst->nrm, dn);
            if (!(dp <= tol_pos) || !(dn <= tol_nrm))
                fail_msg("vertex %zu (patch %u, i %g j %g level %g) axis %d: GPU %g / %g, CPU "
                         "%g / %g", v, c->patch, c->coord[0], c->coord[1], c->coord[2], k,
                         c->position[k], c->normal[k], p[k], nr[k]);
        }
    }
    free(edge_levels);
    free(cap);
}

/* A camera near the trunk, so that levels vary from patch to patch. */
static void close_view(const xyl_tess_patches *tp, const float lo[3], const float hi[3],
                       xyl_tess_view *v)
{
    memset(v, 0, sizeof *v);
    v->eye[0] = 0.5f * (lo[0] + hi[0]) + 0.15f * tp->size;
    v->eye[1] = lo[1] + 0.3f * (hi[1] - lo[1]);
    v->eye[2] = 0.5f * (lo[2] + hi[2]) + 0.1f * tp->size;
    v->max_level = 16;
}

static void capture_matches_cpu_reference(void **state)
{
    (void)state;
    xyl_tess_patterns *pat = NULL;
    assert_int_equal(xyl_tess_patterns_create(0, NULL, &pat, NULL), XYL_OK);
    xyl_tess_vk *vk = open_vk(pat);
    const uint32_t sides[] = {3, 4}, fixed[] = {1, 3, 8, 0};
    for (size_t si = 0; si < 2; ++si) {
        xyl_mesh *m = tu_tree_mesh(0, sides[si], XYL_SUBDIVIDE_NONE);
        float lo[3], hi[3];
        xyl_mesh_bounds(m, lo, hi);
        for (size_t vi = 0; vi < XYL_TESS_VARIANT_COUNT; ++vi) {
            xyl_tess_patches_desc pd = {0};
            pd.variant = variants[vi];
            xyl_tess_patches *tp = NULL;
            assert_int_equal(xyl_tess_patches_create(m, &pd, &tp, NULL), XYL_OK);
            xyl_diag d = {0};
            expect_ok(xyl_tess_vk_set_patches(vk, tp, &d), &d, "set_patches");
            xyl_tess_batches *b = tu_batches_create();
            for (size_t li = 0; li < 4; ++li) {
                xyl_tess_view view;
                close_view(tp, lo, hi, &view);
                view.fixed_level = fixed[li];
                assert_int_equal(xyl_tess_select(tp, pat, &view, b, NULL), XYL_OK);
                if (!fixed[li]) assert_true(b->cmd_count >= 3);
                deviation worst = {0, 0};
                compare_capture(vk, tp, b, variants[vi], &worst);
                char level[16];
                snprintf(level, sizeof level, fixed[li] ? "%u" : "adaptive", fixed[li]);
                printf("k %u %-7s level %-8s %2zu cmds %8llu vertices: worst |dp| %.3g "
                       "(%.3g of size), |dn| %.3g\n",
                       sides[si], variant_names[vi], level, b->cmd_count,
                       (unsigned long long)b->vertices, worst.pos,
                       worst.pos / tp->size, worst.nrm);
            }
            xyl_tess_batches_destroy(b);
            xyl_tess_patches_destroy(tp);
        }
        printf("k %u: %zu quads, %zu triangles\n", sides[si], m->quad_count, m->triangle_count);
        xyl_mesh_destroy(m);
    }
    close_vk(vk);
    xyl_tess_patterns_destroy(pat);
}

/* ---- rendering ----------------------------------------------------------------------------- */

typedef struct scene {
    xyl_mesh *mesh;
    xyl_tess_patches *patches;
    xyl_tess_patterns *patterns;
    xyl_tess_batches *batches;
    float lo[3], hi[3];
    xyl_tess_vk *vk;
} scene;

static void scene_open(scene *s, uint32_t sides, uint32_t depth)
{
    memset(s, 0, sizeof *s);
    s->mesh = tu_tree_mesh(depth, sides, XYL_SUBDIVIDE_NONE);
    xyl_mesh_bounds(s->mesh, s->lo, s->hi);
    assert_int_equal(xyl_tess_patterns_create(0, NULL, &s->patterns, NULL), XYL_OK);
    assert_int_equal(xyl_tess_patches_create(s->mesh, NULL, &s->patches, NULL), XYL_OK);
    s->batches = tu_batches_create();
    s->vk = open_vk(s->patterns);
    xyl_diag d = {0};
    expect_ok(xyl_tess_vk_set_patches(s->vk, s->patches, &d), &d, "set_patches");
}

static void scene_close(scene *s)
{
    close_vk(s->vk);
    xyl_tess_batches_destroy(s->batches);
    xyl_tess_patches_destroy(s->patches);
    xyl_tess_patterns_destroy(s->patterns);
    xyl_mesh_destroy(s->mesh);
}

/* The frame and adaptive batches for a view of the whole tree from (azimuth, elevation);
 * zoom < 1 moves the camera closer to the tree's centre. */
static void scene_view(scene *s, float azimuth, float elevation, float zoom, uint32_t size,
                       uint32_t flags, xyl_tess_frame *f)
{
    xyl_tess_camera cam;
    xyl_tess_camera_frame(s->lo, s->hi, azimuth, elevation, 0.8f, 1.0f, &cam);
    for (int k = 0; k < 3; ++k) cam.eye[k] = cam.target[k] + zoom * (cam.eye[k] - cam.target[k]);
    cam.near_plane *= zoom;
    memset(f, 0, sizeof *f);
    assert_int_equal(xyl_tess_camera_matrix(&cam, XYL_TESS_CLIP_VULKAN, f->view_proj, NULL),
                     XYL_OK);
    const float light[3] = {0.4f, 0.8f, 0.45f};
    float l = sqrtf(light[0] * light[0] + light[1] * light[1] + light[2] * light[2]);
    for (int k = 0; k < 3; ++k) f->light_dir[k] = light[k] / l;
    f->color[0] = 0.45f; f->color[1] = 0.32f; f->color[2] = 0.2f; f->color[3] = 1.0f;
    f->line_color[1] = 1.0f; f->line_color[3] = 1.0f;
    f->variant = XYL_TESS_PN;
    f->flags = flags;
    xyl_tess_view v = {0};
    memcpy(v.eye, cam.eye, sizeof v.eye);
    v.fovy = cam.fovy;
    v.viewport_height = size;
    v.max_level = 16;
    assert_int_equal(xyl_tess_select(s->patches, s->patterns, &v, s->batches, NULL), XYL_OK);
}

static uint8_t *render(scene *s, const xyl_tess_batches *b, const xyl_tess_frame *f,
                       uint32_t size, bool wireframe, uint32_t samples)
{
    xyl_tess_image_desc img = {0};
    img.width = size;
    img.height = size;
    img.wireframe = wireframe;
    img.samples = samples;
    uint8_t *rgba = malloc(4u * size * size);
    assert_non_null(rgba);
    xyl_diag d = {0};
    expect_ok(xyl_tess_vk_render_rgba(s->vk, b, f, &img, rgba, &d), &d, "render");
    return rgba;
}

typedef struct pixel_counts {
    size_t covered, red;
} pixel_counts;

static pixel_counts count_pixels(const uint8_t *rgba, uint32_t size)
{
    pixel_counts c = {0, 0};
    for (size_t p = 0; p < (size_t)size * size; ++p) {
        const uint8_t *px = rgba + 4 * p;
        if (px[3] != 0) ++c.covered; /* the background is transparent */
        if (px[0] == 255 && px[1] == 0 && px[2] == 0 && px[3] == 255) ++c.red;
    }
    return c;
}

/* A crack opened by a T-junction is a sliver along a patch edge: red pixels next to red pixels.
 * A lone red pixel is a depth tie on a contour, where a back face meets the front face it folds
 * under at equal depth (any z-buffer shows a few; they appear at fixed levels too, where no
 * crack is possible). */
static size_t crack_pixels(const uint8_t *rgba, uint32_t size)
{
#define RED(x, y) (memcmp(rgba + 4 * ((size_t)(y) * size + (x)), "\xff\0\0\xff", 4) == 0)
    size_t n = 0;
    for (uint32_t y = 1; y + 1 < size; ++y)
        for (uint32_t x = 1; x + 1 < size; ++x)
            n += RED(x, y) && (RED(x + 1, y) || RED(x - 1, y) || RED(x, y + 1) || RED(x, y - 1));
#undef RED
    return n;
}

/* Back faces are pure red and nothing is culled: on a closed surface a back face shows only
 * through a crack. The mesh is the default grammar grown to depth 3 (27 branches): the full
 * default tree self-intersects (xyl_mesh_self_intersections: 538 pairs at k = 3, 129 at k = 4)
 * and its PN surface folds into view at fixed levels, where no crack is possible; the depth-3
 * mesh has no self-intersection at k = 3 (quads and triangles) or k = 4. Negative control: half
 * the instances get their own level on every edge instead of the shared edge level, which opens
 * T-junctions along the edges to lower-level neighbours. */
static void adaptive_levels_show_no_cracks(void **state)
{
    (void)state;
    const uint32_t size = 256;
    for (uint32_t sides = 3; sides <= 4; ++sides) {
        scene s;
        scene_open(&s, sides, 3);
        size_t red = 0, corrupted_red = 0, corrupted_cracks = 0;
        for (int view = 0; view < 8; ++view) {
            float az = 1.6f * (float)(view / 2), el = view % 2 ? 0.5f : -0.1f;
            xyl_tess_frame f;
            scene_view(&s, az, el, 0.35f, size, XYL__TESS_FLAG_BACKFACES, &f);
            uint8_t *rgba = render(&s, s.batches, &f, size, false, 1);
            pixel_counts c = count_pixels(rgba, size);
            size_t cracks = crack_pixels(rgba, size);
            free(rgba);
            tu_batches broken;
            tu_batches_copy(s.batches, &broken);
            for (size_t i = 0; i < broken.view.instance_count; i += 2) {
                xyl_tess_instance *in = &broken.instances[i];
                in->edge_levels = 0;
                for (uint32_t e = 0; e < in->kind; ++e)
                    in->edge_levels |= in->level << (XYL_TESS_EDGE_LEVEL_BITS * e);
            }
            rgba = render(&s, &broken.view, &f, size, false, 1);
            tu_batches_free(&broken);
            pixel_counts cc = count_pixels(rgba, size);
            size_t ccracks = crack_pixels(rgba, size);
            free(rgba);
            printf("k %u view %d: %2zu cmds, %6llu triangles, %5zu covered, %2zu red, %zu in "
                   "cracks; corrupted: %3zu red, %2zu in cracks\n",
                   sides, view, s.batches->cmd_count, (unsigned long long)s.batches->triangles,
                   c.covered, c.red, cracks, cc.red, ccracks);
            assert_true(c.covered > 0 && s.batches->cmd_count >= 2);
            assert_int_equal(cracks, 0);
            red += c.red;
            corrupted_red += cc.red;
            corrupted_cracks += ccracks;
        }
        /* the test sees cracks when there are some */
        assert_true(corrupted_cracks > 0);
        assert_true(corrupted_red > 4 * red + 10);
        scene_close(&s);
    }
}

static void renders_cover_the_tree_with_lit_front_faces(void **state)
{
    (void)state;
    const uint32_t size = 256;
    scene s;
    scene_open(&s, 4, 0);
    xyl_tess_frame f;
    scene_view(&s, 0.6f, 0.2f, 1.0f, size, 0, &f);
    uint8_t *plain = render(&s, s.batches, &f, size, false, 1);
    pixel_counts c = count_pixels(plain, size);
    double gpu_ms = xyl_tess_vk_last_gpu_ms(s.vk);
    printf("%zu of %u pixels covered, GPU %.3f ms\n", c.covered, size * size, gpu_ms);
    assert_true((double)c.covered > 0.02 * size * size);
    assert_true(gpu_ms >= 0.0);
    assert_int_equal(c.red, 0);
    /* the wireframe overlay changes pixels */
    uint8_t *wire = render(&s, s.batches, &f, size, true, 1);
    size_t changed = 0;
    for (size_t p = 0; p < 4u * size * size; p += 4) changed += memcmp(plain + p, wire + p, 4) != 0;
    printf("wireframe changed %zu pixels\n", changed);
    assert_true(changed > c.covered / 20);
    /* with nothing culled and back faces red, what is seen is the outside: front faces */
    f.flags = XYL__TESS_FLAG_BACKFACES;
    uint8_t *back = render(&s, s.batches, &f, size, false, 1);
    pixel_counts cb = count_pixels(back, size);
    printf("back-face view: %zu covered, %zu red\n", cb.covered, cb.red);
    assert_true(cb.covered == c.covered && cb.red * 100 < cb.covered);
    /* the transitions' dither: the ranges [0, t) and [t, 1) split the covered pixels, none in
     * both, each pixel's colour the undithered one but where the surface in front was discarded
     * and one behind it shows */
    f.dither = xyl_tess_dither(0.0f, 0.25f);
    uint8_t *low = render(&s, s.batches, &f, size, false, 1);
    f.dither = xyl_tess_dither(0.25f, 1.0f);
    uint8_t *high = render(&s, s.batches, &f, size, false, 1);
    f.dither = 0;
    size_t in_low = 0, in_both = 0, behind = 0;
    for (size_t p = 0; p < 4u * size * size; p += 4) {
        bool l = low[p + 3] != 0, h = high[p + 3] != 0;
        in_low += l;
        in_both += l && h;
        behind += (plain[p + 3] != 0 && !l && !h) || (l && memcmp(low + p, plain + p, 4)) ||
                  (h && memcmp(high + p, plain + p, 4));
    }
    printf("dither: %zu of %zu covered pixels in [0, 0.25), %zu in both, %zu show what lies "
           "behind\n",
           in_low, c.covered, in_both, behind);
    assert_true(in_both <= behind);
    assert_true(behind <= c.covered / 50);
    assert_true(fabs((double)in_low / (double)c.covered - 0.25) < 0.05);
    free(low);
    free(high);
    /* 4x MSAA resolves to about the same coverage */
    f.flags = 0;
    uint8_t *msaa = render(&s, s.batches, &f, size, false, 4);
    pixel_counts cm = count_pixels(msaa, size);
    printf("4x MSAA: %zu covered\n", cm.covered);
    assert_true(cm.covered >= c.covered * 9 / 10);
    free(plain);
    free(wire);
    free(back);
    free(msaa);
    scene_close(&s);
}

/* ---- bad input ----------------------------------------------------------------------------- */

static void bad_render_calls(scene *s, const xyl_tess_frame *f)
{
    xyl_diag d = {0};
    xyl_tess_image_desc img = {0};
    uint8_t *rgba = malloc(4u * 512 * 512);
    assert_non_null(rgba);
    assert_int_equal(xyl_tess_vk_render_rgba(NULL, s->batches, f, &img, rgba, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, NULL, f, &img, rgba, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, s->batches, NULL, &img, rgba, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, s->batches, f, NULL, rgba, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, s->batches, f, &img, NULL, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    /* size 0 is the documented default, 512 x 512 */
    expect_ok(xyl_tess_vk_render_rgba(s->vk, s->batches, f, &img, rgba, &d), &d, "512 x 512");
    img.width = 9000;
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, s->batches, f, &img, rgba, &d),
                     XYL_ERR_LIMIT_EXCEEDED);
    img.width = 64;
    img.height = 8193;
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, s->batches, f, &img, rgba, &d),
                     XYL_ERR_LIMIT_EXCEEDED);
    img.height = 64;
    img.samples = 3;
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, s->batches, f, &img, rgba, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    img.samples = 1;
    xyl_tess_frame bad = *f;
    bad.variant = 9;
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, s->batches, &bad, &img, rgba, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    bad = *f;
    bad.view_proj[5] = NAN;
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, s->batches, &bad, &img, rgba, &d),
                     XYL_ERR_NON_FINITE);
    free(rgba);
}

/* Batches that do not match the uploaded patches or the patterns: each exact code, no draw. */
static void bad_batches(scene *s, const xyl_tess_frame *f)
{
    xyl_diag d = {0};
    xyl_tess_image_desc img = {0};
    img.width = img.height = 64;
    uint8_t rgba[4 * 64 * 64];
    size_t count = 0;
    tu_batches e; /* a copy the test may break */
    tu_batches_copy(s->batches, &e);
    const xyl_tess_batches *b = &e.view;
    xyl_tess_instance keep = b->instances[0];
    e.instances[0].patch = (uint32_t)s->patches->count; /* one past the uploaded set */
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, b, f, &img, rgba, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(d.index, 0);
    assert_int_equal(xyl__tess_vk_capture(s->vk, b, XYL_TESS_PN, NULL, 0, &count, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    e.instances[0] = keep;
    e.instances[0].level = 65; /* above the patterns' 64 */
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, b, f, &img, rgba, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    e.instances[0] = keep;
    e.cmds[0].instance_count += 1u << 20; /* past the instance records */
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, b, f, &img, rgba, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    e.cmds[0].instance_count -= 1u << 20;
    e.cmds[0].first_index += 3; /* not its pattern */
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, b, f, &img, rgba, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    e.cmds[0].first_index -= 3;
    /* the patches uploaded are fewer than the batches name */
    xyl_tess_patches few = *s->patches;
    few.count = 10;
    expect_ok(xyl_tess_vk_set_patches(s->vk, &few, &d), &d, "set 10 patches");
    assert_int_equal(xyl_tess_vk_render_rgba(s->vk, b, f, &img, rgba, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(d.message, "10 uploaded"));
    expect_ok(xyl_tess_vk_set_patches(s->vk, s->patches, &d), &d, "set all patches");
    expect_ok(xyl_tess_vk_render_rgba(s->vk, b, f, &img, rgba, &d), &d, "render after errors");
    /* a patch drawn twice has no single capture slot */
    xyl_tess_instance second = b->instances[1];
    e.instances[1].patch = b->instances[0].patch;
    assert_int_equal(xyl__tess_vk_capture(s->vk, b, XYL_TESS_PN, NULL, 0, &count, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    e.instances[1] = second;
    assert_int_equal(xyl__tess_vk_capture(s->vk, b, (xyl_tess_variant)5, NULL, 0, &count, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl__tess_vk_capture(s->vk, b, XYL_TESS_PN, NULL, 0, NULL, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl__tess_vk_capture(s->vk, b, XYL_TESS_PN, NULL, 5, &count, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    expect_ok(xyl__tess_vk_capture(s->vk, b, XYL_TESS_PN, NULL, 0, &count, &d), &d, "count only");
    assert_int_equal(count, b->vertices);
    tu_batches_free(&e);
}

static void bad_input_gets_exact_codes(void **state)
{
    (void)state;
    scene s;
    scene_open(&s, 4, 0);
    xyl_tess_frame f;
    scene_view(&s, 0.0f, 0.0f, 1.0f, 64, 0, &f);
    xyl_diag d = {0};
    /* create */
    xyl_tess_vk *vk = (xyl_tess_vk *)(uintptr_t)1;
    assert_int_equal(xyl_tess_vk_create(NULL, NULL, &vk, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_tess_vk_create(NULL, s.patterns, NULL, &d), XYL_ERR_INVALID_ARGUMENT);
    xyl_tess_patterns broken = *s.patterns;
    broken.ranges[1][5].first_index = (uint32_t)broken.index_count; /* leaves the indices */
    assert_int_equal(xyl_tess_vk_create(NULL, &broken, &vk, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(d.index, 5);
    broken = *s.patterns;
    broken.max_level = 0;
    assert_int_equal(xyl_tess_vk_create(NULL, &broken, &vk, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_ptr_equal(vk, (xyl_tess_vk *)(uintptr_t)1);
    /* patches */
    assert_int_equal(xyl_tess_vk_set_patches(NULL, s.patches, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_tess_vk_set_patches(s.vk, NULL, &d), XYL_ERR_INVALID_ARGUMENT);
    xyl_tess_patches no_records = *s.patches;
    no_records.records = NULL;
    assert_int_equal(xyl_tess_vk_set_patches(s.vk, &no_records, &d), XYL_ERR_INVALID_ARGUMENT);
    /* queries on NULL */
    assert_string_equal(xyl_tess_vk_device_name(NULL), "");
    assert_true(xyl_tess_vk_last_gpu_ms(NULL) < 0.0);
    assert_int_equal(xyl_tess_vk_validation_messages(NULL), 0);
    xyl_tess_vk_destroy(NULL);
    bad_render_calls(&s, &f);
    bad_batches(&s, &f);
    scene_close(&s);
}

/* Every host allocation of a context on the library's device goes through desc.alloc: the
 * library's own blocks and, as VkAllocationCallbacks, Vulkan's (the loader's, the layer's and
 * the driver's: hundreds, where the library makes a handful). (Failures injected deeper than the
 * first allocation would test the driver's out-of-memory paths more than the library's: lavapipe
 * in Mesa 22.3 crashes in one of them.) */
static void own_device_allocates_through_the_callers_allocator(void **state)
{
    (void)state;
    scene s;
    scene_open(&s, 4, 0);
    tu_counting_alloc counted = {0, 0, true};
    xyl_tess_vk_desc vd = {0};
    vd.validation = true;
    vd.alloc = tu_counting_allocator(&counted);
    xyl_tess_vk *vk = (xyl_tess_vk *)(uintptr_t)1;
    xyl_diag d = {0};
    assert_int_equal(xyl_tess_vk_create(&vd, s.patterns, &vk, &d), XYL_ERR_OUT_OF_MEMORY);
    assert_ptr_equal(vk, (xyl_tess_vk *)(uintptr_t)1);
    counted.refuse = false;
    expect_ok(xyl_tess_vk_create(&vd, s.patterns, &vk, &d), &d, "create");
    expect_ok(xyl_tess_vk_set_patches(vk, s.patches, &d), &d, "set_patches");
    xyl_tess_frame f;
    scene_view(&s, 0.6f, 0.2f, 1.0f, 64, 0, &f);
    xyl_tess_image_desc img = {0};
    img.width = img.height = 64;
    img.wireframe = true;
    uint8_t *rgba = malloc(4u * 64 * 64);
    assert_non_null(rgba);
    expect_ok(xyl_tess_vk_render_rgba(vk, s.batches, &f, &img, rgba, &d), &d, "render");
    free(rgba);
    printf("%zu allocations through the caller's allocator, %zu live before destroy\n",
           counted.calls, counted.live);
    assert_true(counted.calls > 100);
    close_vk(vk);
    assert_int_equal(counted.live, 0);
    scene_close(&s);
}

/* ---- the caller's own device --------------------------------------------------------------- */

/* What an application has: its instance (validation on, its own messenger), device, queue,
 * command pool, render pass and targets. Nothing here comes from the library. */
typedef struct app {
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    uint32_t messages;
    char first[XYL_DIAG_MESSAGE_SIZE];
    VkPhysicalDevice physical;
    VkPhysicalDeviceFeatures features; /* enabled */
    bool dynamic_rendering;
    VkDevice device;
    uint32_t family;
    VkQueue queue;
    VkCommandPool pool;
    VkRenderPass pass;
} app;

typedef struct app_target {
    VkImage image[2]; /* colour, depth */
    VkDeviceMemory memory[3];
    VkImageView view[2];
    VkFramebuffer framebuffer;
    VkBuffer readback;
    void *pixels;
} app_target;

#define APP_SIDE 192u
#define APP_COLOR VK_FORMAT_R8G8B8A8_UNORM
#define APP_DEPTH VK_FORMAT_D32_SFLOAT

static VKAPI_ATTR VkBool32 VKAPI_CALL app_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                  VkDebugUtilsMessageTypeFlagsEXT types,
                                                  const VkDebugUtilsMessengerCallbackDataEXT *data,
                                                  void *user)
{
    (void)severity, (void)types; /* the messenger asks for warnings and errors only */
    app *a = user;
    if (a->messages++ == 0) snprintf(a->first, sizeof a->first, "%s", data->pMessage);
    return VK_FALSE;
}

static void vk_ok(VkResult r, const char *what)
{
    if (r != VK_SUCCESS) fail_msg("%s: VkResult %d", what, (int)r);
}

static void app_instance(app *a)
{
    uint32_t version = VK_API_VERSION_1_2;
    vk_ok(vkEnumerateInstanceVersion(&version), "vkEnumerateInstanceVersion");
    VkApplicationInfo ai = {.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO};
    ai.apiVersion = version >= VK_API_VERSION_1_3 ? VK_API_VERSION_1_3 : VK_API_VERSION_1_2;
    VkDebugUtilsMessengerCreateInfoEXT mi = {
        .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                         VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    mi.pfnUserCallback = app_message;
    mi.pUserData = a;
    const char *layer = "VK_LAYER_KHRONOS_validation", *ext = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    VkInstanceCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ci.pNext = &mi;
    ci.pApplicationInfo = &ai;
    ci.enabledLayerCount = 1;
    ci.ppEnabledLayerNames = &layer;
    ci.enabledExtensionCount = 1;
    ci.ppEnabledExtensionNames = &ext;
    vk_ok(vkCreateInstance(&ci, NULL, &a->instance), "vkCreateInstance");
    PFN_vkCreateDebugUtilsMessengerEXT create = (PFN_vkCreateDebugUtilsMessengerEXT)
        vkGetInstanceProcAddr(a->instance, "vkCreateDebugUtilsMessengerEXT");
    assert_non_null(create);
    vk_ok(create(a->instance, &mi, NULL, &a->messenger), "vkCreateDebugUtilsMessengerEXT");
    a->dynamic_rendering = ai.apiVersion >= VK_API_VERSION_1_3;
}

/* The first device with a graphics queue; the features the library can use, and dynamic
 * rendering where the device has Vulkan 1.3. */
static void app_device(app *a)
{
    uint32_t n = 1;
    VkResult r = vkEnumeratePhysicalDevices(a->instance, &n, &a->physical);
    assert_true((r == VK_SUCCESS || r == VK_INCOMPLETE) && n == 1);
    VkPhysicalDeviceProperties props;
    vkGetPhysicalDeviceProperties(a->physical, &props);
    a->dynamic_rendering = a->dynamic_rendering && props.apiVersion >= VK_API_VERSION_1_3;
    VkQueueFamilyProperties q[8];
    uint32_t nq = 8;
    vkGetPhysicalDeviceQueueFamilyProperties(a->physical, &nq, q);
    for (a->family = 0; a->family < nq; ++a->family)
        if (q[a->family].queueFlags & VK_QUEUE_GRAPHICS_BIT) break;
    assert_true(a->family < nq);
    VkPhysicalDeviceFeatures have;
    vkGetPhysicalDeviceFeatures(a->physical, &have);
    memset(&a->features, 0, sizeof a->features);
    a->features.drawIndirectFirstInstance = VK_TRUE;
    a->features.multiDrawIndirect = have.multiDrawIndirect;
    a->features.fillModeNonSolid = have.fillModeNonSolid;
    assert_true(have.drawIndirectFirstInstance && have.fillModeNonSolid);
    VkPhysicalDeviceVulkan13Features v13 = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    v13.dynamicRendering = VK_TRUE;
    float priority = 1.0f;
    VkDeviceQueueCreateInfo qi = {.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qi.queueFamilyIndex = a->family;
    qi.queueCount = 1;
    qi.pQueuePriorities = &priority;
    VkDeviceCreateInfo di = {.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    di.pNext = a->dynamic_rendering ? &v13 : NULL;
    di.queueCreateInfoCount = 1;
    di.pQueueCreateInfos = &qi;
    di.pEnabledFeatures = &a->features;
    vk_ok(vkCreateDevice(a->physical, &di, NULL, &a->device), "vkCreateDevice");
    vkGetDeviceQueue(a->device, a->family, 0, &a->queue);
    VkCommandPoolCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT; /* recorded again per context */
    pi.queueFamilyIndex = a->family;
    vk_ok(vkCreateCommandPool(a->device, &pi, NULL, &a->pool), "vkCreateCommandPool");
}

/* Colour cleared and stored, then read back by a copy; depth cleared. */
static void app_render_pass(app *a)
{
    VkAttachmentDescription att[2] = {{0}, {0}};
    att[0].format = APP_COLOR;
    att[0].finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    att[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    att[1].format = APP_DEPTH;
    att[1].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    att[1].storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    for (int k = 0; k < 2; ++k) {
        att[k].samples = VK_SAMPLE_COUNT_1_BIT;
        att[k].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        att[k].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        att[k].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    }
    VkAttachmentReference color = {0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth = {1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub = {0};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.colorAttachmentCount = 1;
    sub.pColorAttachments = &color;
    sub.pDepthStencilAttachment = &depth;
    VkSubpassDependency dep = {0, VK_SUBPASS_EXTERNAL,
                               VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                               VK_PIPELINE_STAGE_TRANSFER_BIT,
                               VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT,
                               0};
    VkRenderPassCreateInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    ri.attachmentCount = 2;
    ri.pAttachments = att;
    ri.subpassCount = 1;
    ri.pSubpasses = &sub;
    ri.dependencyCount = 1;
    ri.pDependencies = &dep;
    vk_ok(vkCreateRenderPass(a->device, &ri, NULL, &a->pass), "vkCreateRenderPass");
}

static void app_open(app *a)
{
    memset(a, 0, sizeof *a);
    app_instance(a);
    app_device(a);
    app_render_pass(a);
}

/* Every test on the caller's device ends with no message from its own messenger. */
static void app_close(app *a)
{
    vkDestroyRenderPass(a->device, a->pass, NULL);
    vkDestroyCommandPool(a->device, a->pool, NULL);
    vkDestroyDevice(a->device, NULL);
    PFN_vkDestroyDebugUtilsMessengerEXT destroy = (PFN_vkDestroyDebugUtilsMessengerEXT)
        vkGetInstanceProcAddr(a->instance, "vkDestroyDebugUtilsMessengerEXT");
    destroy(a->instance, a->messenger, NULL);
    vkDestroyInstance(a->instance, NULL);
    if (a->messages) fail_msg("%u validation messages, the first: %s", a->messages, a->first);
}

static VkDeviceMemory app_memory(const app *a, VkMemoryRequirements req,
                                 VkMemoryPropertyFlags need)
{
    VkPhysicalDeviceMemoryProperties mp;
    vkGetPhysicalDeviceMemoryProperties(a->physical, &mp);
    uint32_t type = 0;
    while (type < mp.memoryTypeCount && (!(req.memoryTypeBits & (1u << type)) ||
                                         (mp.memoryTypes[type].propertyFlags & need) != need))
        ++type;
    assert_true(type < mp.memoryTypeCount);
    VkMemoryAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = type;
    VkDeviceMemory m;
    vk_ok(vkAllocateMemory(a->device, &ai, NULL, &m), "vkAllocateMemory");
    return m;
}

static void app_target_open(const app *a, app_target *t)
{
    memset(t, 0, sizeof *t);
    const VkFormat formats[2] = {APP_COLOR, APP_DEPTH};
    const VkImageUsageFlags usage[2] = {
        VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
        VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT};
    for (int k = 0; k < 2; ++k) {
        VkImageCreateInfo ii = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
        ii.imageType = VK_IMAGE_TYPE_2D;
        ii.format = formats[k];
        ii.extent = (VkExtent3D){APP_SIDE, APP_SIDE, 1};
        ii.mipLevels = ii.arrayLayers = 1;
        ii.samples = VK_SAMPLE_COUNT_1_BIT;
        ii.usage = usage[k];
        vk_ok(vkCreateImage(a->device, &ii, NULL, &t->image[k]), "vkCreateImage");
        VkMemoryRequirements req;
        vkGetImageMemoryRequirements(a->device, t->image[k], &req);
        t->memory[k] = app_memory(a, req, 0);
        vk_ok(vkBindImageMemory(a->device, t->image[k], t->memory[k], 0), "vkBindImageMemory");
        VkImageViewCreateInfo vi = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
        vi.image = t->image[k];
        vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
        vi.format = formats[k];
        vi.subresourceRange.aspectMask = k ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
        vi.subresourceRange.levelCount = vi.subresourceRange.layerCount = 1;
        vk_ok(vkCreateImageView(a->device, &vi, NULL, &t->view[k]), "vkCreateImageView");
    }
    VkFramebufferCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fi.renderPass = a->pass;
    fi.attachmentCount = 2;
    fi.pAttachments = t->view;
    fi.width = fi.height = APP_SIDE;
    fi.layers = 1;
    vk_ok(vkCreateFramebuffer(a->device, &fi, NULL, &t->framebuffer), "vkCreateFramebuffer");
    VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = 4u * APP_SIDE * APP_SIDE;
    bi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    vk_ok(vkCreateBuffer(a->device, &bi, NULL, &t->readback), "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(a->device, t->readback, &req);
    t->memory[2] = app_memory(a, req, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                          VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    vk_ok(vkBindBufferMemory(a->device, t->readback, t->memory[2], 0), "vkBindBufferMemory");
    vk_ok(vkMapMemory(a->device, t->memory[2], 0, VK_WHOLE_SIZE, 0, &t->pixels), "vkMapMemory");
}

static void app_target_close(const app *a, app_target *t)
{
    vkDestroyFramebuffer(a->device, t->framebuffer, NULL);
    vkDestroyBuffer(a->device, t->readback, NULL);
    for (int k = 0; k < 2; ++k) {
        vkDestroyImageView(a->device, t->view[k], NULL);
        vkDestroyImage(a->device, t->image[k], NULL);
    }
    for (int k = 0; k < 3; ++k) vkFreeMemory(a->device, t->memory[k], NULL);
}

static void image_barrier(VkCommandBuffer cb, VkImage image, VkImageAspectFlags aspect,
                          VkImageLayout from, VkImageLayout to, VkPipelineStageFlags src_stage,
                          VkAccessFlags src, VkPipelineStageFlags dst_stage, VkAccessFlags dst)
{
    VkImageMemoryBarrier b = {.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.srcAccessMask = src;
    b.dstAccessMask = dst;
    b.oldLayout = from;
    b.newLayout = to;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = image;
    b.subresourceRange.aspectMask = aspect;
    b.subresourceRange.levelCount = b.subresourceRange.layerCount = 1;
    vkCmdPipelineBarrier(cb, src_stage, dst_stage, 0, 0, NULL, 0, NULL, 1, &b);
}

/* Dynamic rendering: the attachments' layouts are the application's to set. */
static void begin_dynamic(VkCommandBuffer cb, const app_target *t)
{
    const VkPipelineStageFlags frag_tests = VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                                            VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    image_barrier(cb, t->image[0], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                  VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0,
                  VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                  VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT);
    image_barrier(cb, t->image[1], VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                  VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0,
                  frag_tests, VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                                  VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT);
    VkRenderingAttachmentInfo color = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    color.imageView = t->view[0];
    color.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    color.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    VkRenderingAttachmentInfo depth = color;
    depth.imageView = t->view[1];
    depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
    depth.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    depth.clearValue.depthStencil.depth = 1.0f;
    VkRenderingInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDERING_INFO};
    ri.renderArea.extent = (VkExtent2D){APP_SIDE, APP_SIDE};
    ri.layerCount = 1;
    ri.colorAttachmentCount = 1;
    ri.pColorAttachments = &color;
    ri.pDepthAttachment = &depth;
    vkCmdBeginRendering(cb, &ri);
}

static void end_dynamic(VkCommandBuffer cb, const app_target *t)
{
    vkCmdEndRendering(cb);
    image_barrier(cb, t->image[0], VK_IMAGE_ASPECT_COLOR_BIT,
                  VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                  VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                  VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                  VK_ACCESS_TRANSFER_READ_BIT);
}

/* The application's frame: clear, the library's draws in the pass (or dynamic rendering
 * instance), a copy of the colour image to host memory. */
static void app_record(const app *a, VkCommandBuffer cb, const app_target *t, bool dynamic,
                       xyl_tess_vk *vk, uint32_t frame_index, const xyl_tess_batches *b,
                       const xyl_tess_frame *f)
{
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    vk_ok(vkBeginCommandBuffer(cb, &bi), "vkBeginCommandBuffer");
    if (dynamic) {
        begin_dynamic(cb, t);
    } else {
        VkClearValue clear[2];
        memset(clear, 0, sizeof clear);
        clear[1].depthStencil.depth = 1.0f;
        VkRenderPassBeginInfo rb = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
        rb.renderPass = a->pass;
        rb.framebuffer = t->framebuffer;
        rb.renderArea.extent = (VkExtent2D){APP_SIDE, APP_SIDE};
        rb.clearValueCount = 2;
        rb.pClearValues = clear;
        vkCmdBeginRenderPass(cb, &rb, VK_SUBPASS_CONTENTS_INLINE);
    }
    VkViewport vp = {0.0f, 0.0f, (float)APP_SIDE, (float)APP_SIDE, 0.0f, 1.0f};
    VkRect2D sc = {{0, 0}, {APP_SIDE, APP_SIDE}};
    vkCmdSetViewport(cb, 0, 1, &vp);
    vkCmdSetScissor(cb, 0, 1, &sc);
    xyl_diag d = {0};
    expect_ok(xyl_tess_vk_cmd_draw(vk, cb, frame_index, b, f, &d), &d, "cmd_draw");
    if (dynamic) end_dynamic(cb, t);
    else vkCmdEndRenderPass(cb);
    VkBufferImageCopy copy = {0};
    copy.imageSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    copy.imageSubresource.layerCount = 1;
    copy.imageExtent = (VkExtent3D){APP_SIDE, APP_SIDE, 1};
    vkCmdCopyImageToBuffer(cb, t->image[0], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, t->readback, 1,
                           &copy);
    VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1,
                         &mb, 0, NULL, 0, NULL);
    vk_ok(vkEndCommandBuffer(cb), "vkEndCommandBuffer");
}

static void app_submit_wait(const app *a, const VkCommandBuffer *cbs, uint32_t n)
{
    VkFenceCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    vk_ok(vkCreateFence(a->device, &fi, NULL, &fence), "vkCreateFence");
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = n;
    si.pCommandBuffers = cbs;
    vk_ok(vkQueueSubmit(a->queue, 1, &si, fence), "vkQueueSubmit");
    vk_ok(vkWaitForFences(a->device, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
    vkDestroyFence(a->device, fence, NULL);
}

/* The context for the application's device, pass or dynamic rendering, with its queue. */
static xyl_tess_vk *app_context(const app *a, bool dynamic, const xyl_tess_patterns *pat,
                                const xyl_tess_patches *tp, const xyl_allocator *alloc)
{
    xyl_tess_vk_device_desc dd = {0};
    dd.physical_device = a->physical;
    dd.device = a->device;
    dd.enabled_features = &a->features;
    if (dynamic) {
        dd.color_format = APP_COLOR;
        dd.depth_format = APP_DEPTH;
    } else {
        dd.render_pass = a->pass;
    }
    dd.queue = a->queue;
    dd.queue_family = a->family;
    if (alloc) dd.alloc = *alloc;
    xyl_tess_vk *vk = NULL;
    xyl_diag d = {0};
    expect_ok(xyl_tess_vk_create_for_device(&dd, pat, &vk, &d), &d, "create_for_device");
    expect_ok(xyl_tess_vk_set_patches(vk, tp, &d), &d, "set_patches");
    return vk;
}

static size_t differing_pixels(const uint8_t *a, const uint8_t *b)
{
    size_t n = 0;
    for (size_t p = 0; p < (size_t)APP_SIDE * APP_SIDE; ++p)
        n += memcmp(a + 4 * p, b + 4 * p, 4) != 0;
    return n;
}

/* The offscreen render of the same frame by `vk` (wireframe as an image option there). */
static uint8_t *offscreen(xyl_tess_vk *vk, const xyl_tess_batches *b, const xyl_tess_frame *f)
{
    xyl_tess_image_desc img = {0};
    img.width = img.height = APP_SIDE;
    img.wireframe = (f->flags & XYL_TESS_FLAG_WIREFRAME) != 0;
    xyl_tess_frame plain = *f;
    plain.flags &= ~XYL_TESS_FLAG_WIREFRAME;
    uint8_t *rgba = malloc(4u * APP_SIDE * APP_SIDE);
    assert_non_null(rgba);
    xyl_diag d = {0};
    expect_ok(xyl_tess_vk_render_rgba(vk, b, &plain, &img, rgba, &d), &d, "render_rgba");
    return rgba;
}

/* Two frames in flight, recorded before either is submitted and submitted together: frame 0
 * from one view, frame 1 from another with the wireframe overlay, both selected into the same
 * batches object (its arrays change between the two recordings: what a draw reads was copied
 * into its frame's slot when it was recorded). Each application image equals, pixel for pixel,
 * xyl_tess_vk_render_rgba of the same frame on the library's own device and on the
 * application's; then the same through dynamic rendering. Both instances report nothing. */
static void draws_on_the_callers_device_equal_the_offscreen_render(void **state)
{
    (void)state;
    app a;
    app_open(&a);
    scene s;
    scene_open(&s, 4, 0); /* s.vk: the library's own device, validation on */
    tu_counting_alloc counted = {0, 0, false};
    xyl_allocator alloc = tu_counting_allocator(&counted);
    app_target t[2];
    app_target_open(&a, &t[0]);
    app_target_open(&a, &t[1]);
    VkCommandBuffer cbs[2];
    VkCommandBufferAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = a.pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 2;
    vk_ok(vkAllocateCommandBuffers(a.device, &ai, cbs), "vkAllocateCommandBuffers");
    for (int dynamic = 0; dynamic <= (int)a.dynamic_rendering; ++dynamic) {
        xyl_tess_vk *vk = app_context(&a, dynamic != 0, s.patterns, s.patches, &alloc);
        xyl_tess_frame f[2];
        scene_view(&s, 0.6f, 0.2f, 1.0f, APP_SIDE, 0, &f[0]);
        app_record(&a, cbs[0], &t[0], dynamic, vk, 0, s.batches, &f[0]);
        scene_view(&s, 2.2f, -0.1f, 0.6f, APP_SIDE, XYL_TESS_FLAG_WIREFRAME, &f[1]);
        app_record(&a, cbs[1], &t[1], dynamic, vk, 1, s.batches, &f[1]);
        app_submit_wait(&a, cbs, 2);
        for (int i = 1; i >= 0; --i) { /* frame 1's batches are selected; then frame 0's */
            if (i == 0) scene_view(&s, 0.6f, 0.2f, 1.0f, APP_SIDE, 0, &f[0]);
            uint8_t *own = offscreen(s.vk, s.batches, &f[i]);
            uint8_t *same_device = offscreen(vk, s.batches, &f[i]);
            pixel_counts c = count_pixels(t[i].pixels, APP_SIDE);
            size_t off_own = differing_pixels(t[i].pixels, own);
            size_t off_same = differing_pixels(t[i].pixels, same_device);
            printf("%s, frame %d: %zu pixels covered; %zu differ from render_rgba on the "
                   "library's device, %zu on the application's\n",
                   dynamic ? "dynamic rendering" : "render pass", i, c.covered, off_own,
                   off_same);
            assert_true(c.covered > APP_SIDE * APP_SIDE / 50);
            assert_int_equal(off_own, 0);
            assert_int_equal(off_same, 0);
            free(own);
            free(same_device);
        }
        xyl_tess_vk_destroy(vk);
        assert_int_equal(counted.live, 0);
    }
    printf("the caller's allocator saw %zu allocations\n", counted.calls);
    assert_true(counted.calls > 0);
    vkFreeCommandBuffers(a.device, a.pool, 2, cbs);
    app_target_close(&a, &t[0]);
    app_target_close(&a, &t[1]);
    scene_close(&s);
    app_close(&a);
}

/* Arguments a context on the caller's device refuses, each with its exact code. */
static void device_contexts_refuse_bad_input(void **state)
{
    (void)state;
    app a;
    app_open(&a);
    xyl_tess_patterns *pat = NULL;
    assert_int_equal(xyl_tess_patterns_create(4, NULL, &pat, NULL), XYL_OK);
    xyl_tess_vk_device_desc dd = {0};
    dd.physical_device = a.physical;
    dd.device = a.device;
    dd.render_pass = a.pass;
    xyl_tess_vk *vk = (xyl_tess_vk *)(uintptr_t)1;
    xyl_diag d = {0};
    assert_int_equal(xyl_tess_vk_create_for_device(NULL, pat, &vk, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_tess_vk_create_for_device(&dd, NULL, &vk, &d), XYL_ERR_INVALID_ARGUMENT);
    xyl_tess_vk_device_desc bad = dd;
    bad.device = VK_NULL_HANDLE;
    assert_int_equal(xyl_tess_vk_create_for_device(&bad, pat, &vk, &d), XYL_ERR_INVALID_ARGUMENT);
    bad = dd;
    bad.render_pass = VK_NULL_HANDLE; /* and no colour format for dynamic rendering */
    assert_int_equal(xyl_tess_vk_create_for_device(&bad, pat, &vk, &d), XYL_ERR_INVALID_ARGUMENT);
    bad = dd;
    bad.frames_in_flight = 17;
    assert_int_equal(xyl_tess_vk_create_for_device(&bad, pat, &vk, &d), XYL_ERR_INVALID_ARGUMENT);
    bad = dd;
    bad.samples = (VkSampleCountFlagBits)3;
    assert_int_equal(xyl_tess_vk_create_for_device(&bad, pat, &vk, &d), XYL_ERR_INVALID_ARGUMENT);
    bad = dd;
    VkPhysicalDeviceFeatures none = {0};
    bad.enabled_features = &none;
    assert_int_equal(xyl_tess_vk_create_for_device(&bad, pat, &vk, &d), XYL_ERR_UNSUPPORTED);
    assert_non_null(strstr(d.message, "drawIndirectFirstInstance"));
    bad = dd;
    bad.queue = a.queue;
    bad.queue_family = 99;
    assert_int_equal(xyl_tess_vk_create_for_device(&bad, pat, &vk, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_ptr_equal(vk, (xyl_tess_vk *)(uintptr_t)1);
    /* default features (drawIndirectFirstInstance alone), no queue: draws, no offscreen render,
     * no wireframe */
    expect_ok(xyl_tess_vk_create_for_device(&dd, pat, &vk, &d), &d, "create_for_device");
    xyl_tess_batches *b = tu_batches_create();
    xyl_tess_frame f = {0};
    for (int k = 0; k < 4; ++k) f.view_proj[5 * k] = 1.0f;
    xyl_tess_image_desc img = {0};
    uint8_t px[4];
    assert_int_equal(xyl_tess_vk_render_rgba(vk, b, &f, &img, px, &d), XYL_ERR_UNSUPPORTED);
    VkCommandBuffer cb;
    VkCommandBufferAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = a.pool;
    ai.commandBufferCount = 1;
    vk_ok(vkAllocateCommandBuffers(a.device, &ai, &cb), "vkAllocateCommandBuffers");
    assert_int_equal(xyl_tess_vk_cmd_draw(vk, VK_NULL_HANDLE, 0, b, &f, &d),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_tess_vk_cmd_draw(vk, cb, 2, b, &f, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(d.message, "2 frames in flight"));
    assert_int_equal(xyl_tess_vk_cmd_draw(vk, cb, 0, NULL, &f, &d), XYL_ERR_INVALID_ARGUMENT);
    f.flags = XYL_TESS_FLAG_WIREFRAME;
    assert_int_equal(xyl_tess_vk_cmd_draw(vk, cb, 0, b, &f, &d), XYL_ERR_UNSUPPORTED);
    f.flags = 0;
    f.view_proj[3] = INFINITY;
    assert_int_equal(xyl_tess_vk_cmd_draw(vk, cb, 0, b, &f, &d), XYL_ERR_NON_FINITE);
    f.view_proj[3] = 0.0f;
    /* a context on the library's own device has no pass of the caller's */
    xyl_tess_vk *own = NULL;
    expect_ok(xyl_tess_vk_create(NULL, pat, &own, &d), &d, "create");
    assert_int_equal(xyl_tess_vk_cmd_draw(own, cb, 0, b, &f, &d), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_tess_vk_validation_messages(vk), 0);
    xyl_tess_vk_destroy(own);
    vkFreeCommandBuffers(a.device, a.pool, 1, &cb);
    xyl_tess_batches_destroy(b);
    xyl_tess_vk_destroy(vk);
    xyl_tess_patterns_destroy(pat);
    app_close(&a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(device_reports_a_name_and_validation_is_active),
        cmocka_unit_test(capture_matches_cpu_reference),
        cmocka_unit_test(adaptive_levels_show_no_cracks),
        cmocka_unit_test(renders_cover_the_tree_with_lit_front_faces),
        cmocka_unit_test(bad_input_gets_exact_codes),
        cmocka_unit_test(own_device_allocates_through_the_callers_allocator),
        cmocka_unit_test(draws_on_the_callers_device_equal_the_offscreen_render),
        cmocka_unit_test(device_contexts_refuse_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

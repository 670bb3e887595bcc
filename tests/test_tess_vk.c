/* tessellate/ Vulkan backend (instanced path) on whatever driver the machine has (lavapipe in
 * CI), always with the Khronos validation layer: captured vertices against the CPU reference,
 * crack-freedom and winding seen through back faces, render sanity, bad input. Every test ends
 * with no validation message. */
#include <math.h>

#include "test_util.h"
#include "tess_util.h"
#include "vk_internal.h" /* the device handle, to provoke the layer directly; capture */
#include <xylem/xyl_tess_vk.h>

static const xyl_tess_variant variants[] = {XYL_TESS_PN, XYL_TESS_ROUNDED, XYL_TESS_CIRCLE};
static const char *const variant_names[] = {"pn", "rounded", "circle"};

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
        for (size_t vi = 0; vi < 3; ++vi) {
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
                       sides[si], variant_names[vi], level, b->cmd_count, (unsigned long long)b->vertices, worst.pos,
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(device_reports_a_name_and_validation_is_active),
        cmocka_unit_test(capture_matches_cpu_reference),
        cmocka_unit_test(adaptive_levels_show_no_cracks),
        cmocka_unit_test(renders_cover_the_tree_with_lit_front_faces),
        cmocka_unit_test(bad_input_gets_exact_codes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

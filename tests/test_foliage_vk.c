/* foliage/'s Vulkan leaf renderer on the application's own device (lavapipe where there is no
 * GPU), always with the Khronos validation layer: the clip-space corners the vertex shader
 * computes against a CPU reference and the records each LOD reaches, the alpha test, the
 * texture's orientation and double-sided lighting in read-back pixels, bad input (with no
 * Vulkan call), and the caller's allocator. Every test ends with no validation message. Without
 * a Vulkan 1.2 device or the validation layer every test is skipped, and says why. */
#include <float.h>
#include <math.h>

#include "test_util.h"
#include "foliage_tree.h"
#include "foliage_internal.h"
#include "foliage_cut_check.h"
#include "foliage_vk_debug.h"
#include "../shaders/xyl_dither.h"
#include "tess_util.h"
#include <xylem/xyl_foliage_vk.h>

/* The bound of test_foliage_gl: each clip coordinate within REL_BOUND of the sum of the
 * magnitudes of the terms that make it. */
#define REL_BOUND 1e-6
#define SIDE 64u
#define COLOR_FORMAT VK_FORMAT_R8G8B8A8_UNORM
#define DEPTH_FORMAT VK_FORMAT_D32_SFLOAT

#include "vk_test_app.h"

typedef struct suite {
    app a;
    xyl_foliage_vk *vk;
    char why[320]; /* why the tests are skipped; empty when they run */
} suite;

static void expect(xyl_result got, xyl_result want, const xyl_diag *d)
{
    if (got != want)
        fail_msg("expected %s, got %s (%s)", xyl_result_string(want), xyl_result_string(got),
                 d->message);
    if (want != XYL_OK) assert_true(strlen(d->message) > 0);
}

static xyl_foliage_vk_desc app_desc(const app *a)
{
    xyl_foliage_vk_desc d = {0};
    d.physical_device = a->physical;
    d.device = a->device;
    d.queue = a->queue;
    d.queue_family = a->family;
    d.render_pass = a->pass;
    d.enabled_features = &a->features;
    return d;
}

static int setup(void **state)
{
    suite *s = calloc(1, sizeof *s);
    if (!s) return -1;
    *state = s;
    VkResult r = make_instance(&s->a);
    if (r != VK_SUCCESS) {
        snprintf(s->why, sizeof s->why,
                 "no Vulkan instance with the validation layer (VkResult %d)", (int)r);
        return 0;
    }
    if (!make_device(&s->a, true, s->why, sizeof s->why)) return 0;
    make_pass(&s->a);
    make_target(&s->a);
    xyl_foliage_vk_desc d = app_desc(&s->a);
    xyl_diag diag = {0};
    if (xyl_foliage_vk_create(&d, &s->vk, &diag) != XYL_OK)
        snprintf(s->why, sizeof s->why, "the leaf renderer: %s", diag.message);
    return 0;
}

static int teardown(void **state)
{
    suite *s = *state;
    app *a = &s->a;
    xyl_foliage_vk_destroy(s->vk);
    close_app(a);
    uint32_t messages = a->messages;
    free(s);
    return messages ? -1 : 0; /* a message at teardown fails the group */
}

static suite *need_vk(void **state)
{
    suite *s = *state;
    if (s->why[0]) {
        print_message("skipped: %s\n", s->why);
        skip();
    }
    return s;
}

/* Every test ends here: the validation layer reported nothing. */
static void no_messages(const suite *s)
{
    if (s->a.messages)
        fail_msg("%u validation messages, the first: %s", s->a.messages, s->a.first);
}

/* ---- trees and cameras ---------------------------------------------------------------------- */

static xyl_foliage *tree_foliage(const char *preset, uint32_t sectors)
{
    return ft_tree_foliage(preset, sectors);
}

/* A perspective camera framing the foliage's sphere, in Vulkan's clip convention. */
static void frame_of(const xyl_foliage *f, float azimuth, float elevation,
                     xyl_foliage_vk_frame *fr)
{
    float c[3] = {f->center.x, f->center.y, f->center.z}, r = f->radius;
    float lo[3] = {c[0] - r, c[1] - r, c[2] - r}, hi[3] = {c[0] + r, c[1] + r, c[2] + r};
    xyl_tess_camera cam;
    xyl_tess_camera_frame(lo, hi, azimuth, elevation, 0.8f, 1.0f, &cam);
    memset(fr, 0, sizeof *fr);
    assert_int_equal(xyl_tess_camera_matrix(&cam, XYL_TESS_CLIP_VULKAN, fr->view_proj, NULL),
                     XYL_OK);
    fr->light_dir[0] = 0.4f, fr->light_dir[1] = 0.8f, fr->light_dir[2] = 0.45f;
}

/* ---- 1. GPU = CPU --------------------------------------------------------------------------- */

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

/* Corner `corner` of record `leaf` against the CPU's clip coordinates in double; the largest
 * error relative to the terms' magnitude. */
static double check_corner(const xyl_foliage_gpu_leaf *rec, const float *m,
                           const xyl__foliage_vk_captured *v, uint32_t leaf, int corner)
{
    assert_int_equal(v->leaf, leaf);
    assert_true(v->st[0] == ((corner & 1) ? 1.0f : -1.0f));
    assert_true(v->st[1] == ((corner & 2) ? 1.0f : -1.0f));
    xyl_leaf l = xyl__foliage_unpack_gpu(rec);
    const double ce[3] = {l.center.x, l.center.y, l.center.z};
    const double sd[3] = {l.side.x, l.side.y, l.side.z}, ax[3] = {l.axis.x, l.axis.y, l.axis.z};
    double p[3], mag[3], worst = 0.0;
    for (int k = 0; k < 3; ++k) {
        p[k] = ce[k] + v->st[0] * sd[k] + v->st[1] * ax[k];
        mag[k] = fabs(ce[k]) + fabs(sd[k]) + fabs(ax[k]);
    }
    for (int r = 0; r < 4; ++r) {
        double want = m[12 + r], scale = fabs(m[12 + r]);
        for (int k = 0; k < 3; ++k) {
            want += (double)m[4 * k + r] * p[k];
            scale += fabs((double)m[4 * k + r]) * mag[k];
        }
        double e = fabs((double)v->clip[r] - want) / scale;
        if (e > worst) worst = e;
        if (e > REL_BOUND)
            fail_msg("leaf %u corner %d clip[%d]: GPU %.9g, CPU %.9g (%.3g of the scale)", leaf,
                     corner, r, (double)v->clip[r], want, e);
    }
    return worst;
}

/* Captures the LODs: each record of the LODs' ranges has its four corners, equal to the CPU's,
 * and no other record was reached. Returns the worst relative error. */
static double capture_and_compare(suite *s, const xyl_foliage *f,
                                  const xyl_foliage_gpu_leaf *records,
                                  const xyl_foliage_vk_frame *fr, const uint32_t *lods,
                                  xyl__foliage_vk_captured *buf)
{
    xyl_diag d = {0};
    expect(xyl__foliage_vk_capture(s->vk, fr, lods, f->sector_count, buf, 4 * f->leaf_count, &d),
           XYL_OK, &d);
    size_t want_leaves = 0;
    expect(xyl_foliage_gather(f, lods, f->sector_count, NULL, 0, &want_leaves, &d), XYL_OK, &d);
    size_t drawn = 0;
    double worst = 0.0;
    for (uint32_t k = 0; k < f->leaf_count; ++k) {
        bool want = in_lod(f, lods, k);
        drawn += want;
        for (int c = 0; c < 4; ++c) {
            const xyl__foliage_vk_captured *v = &buf[4 * k + c];
            if (!want) {
                if (v->leaf != UINT32_MAX) fail_msg("record %u is outside the LODs but drawn", k);
                continue;
            }
            double e = check_corner(&records[k], fr->view_proj, v, k, c);
            if (e > worst) worst = e;
        }
    }
    assert_int_equal(drawn, want_leaves);
    return worst;
}

/* Step i draws LOD min(i, merged_count) of every sector, i = 0, stride, 2 stride, ..., top. */
static void every_lod_matches(suite *s, xyl_foliage *f, uint32_t stride, double *worst)
{
    xyl_diag d = {0};
    expect(xyl_foliage_vk_set_foliage(s->vk, f, &d), XYL_OK, &d);
    xyl_foliage_gpu_leaf *records = malloc(f->leaf_count * sizeof *records);
    assert_non_null(records);
    assert_int_equal(xyl_foliage_pack_gpu(f->leaves, f->leaf_count, records, NULL), XYL_OK);
    xyl_foliage_vk_frame fr;
    frame_of(f, 0.7f, 0.3f, &fr);
    xyl__foliage_vk_captured *buf = malloc(4 * f->leaf_count * sizeof *buf);
    assert_non_null(buf);
    uint32_t lods[XYL_FOLIAGE_MAX_SECTORS], top = 0;
    for (uint32_t k = 0; k < f->sector_count; ++k)
        top = f->sectors[k].merged_count > top ? f->sectors[k].merged_count : top;
    for (uint32_t i = 0;; i = i + stride > top && i < top ? top : i + stride) {
        for (uint32_t k = 0; k < f->sector_count; ++k)
            lods[k] = i < f->sectors[k].merged_count ? i : f->sectors[k].merged_count;
        double e = capture_and_compare(s, f, records, &fr, lods, buf);
        if (e > *worst) *worst = e;
        if (i >= top) break;
    }
    free(buf);
    free(records);
}

static void gpu_corners_match_the_cpu_reference_per_lod(void **state)
{
    suite *s = need_vk(state);
    double worst = 0.0;
    for (uint32_t sectors = 1; sectors <= 3; sectors += 2) { /* one chain, and three sectors */
        xyl_foliage *f = tree_foliage("faycal-leaves", sectors);
        every_lod_matches(s, f, 1, &worst);
        xyl_foliage_destroy(f);
    }
    /* The default tree (5103 leaves) in three sectors: every LOD of each sector (seconds on
     * lavapipe; every 1021st under the sanitizers) */
    xyl_foliage *f = tree_foliage(xyl_lsystem_default_preset(), 3);
    every_lod_matches(s, f, SANITIZED ? 1021 : 1, &worst);
    xyl_foliage_destroy(f);
    print_message("worst clip-space error: %.3g of the terms' magnitude (bound %.0e)\n", worst,
                  REL_BOUND);
    no_messages(s);
}

/* ---- 2. pixels ------------------------------------------------------------------------------ */

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

/* test_foliage_gl's identity camera in Vulkan's convention (y flipped, as
 * XYL_TESS_CLIP_VULKAN flips it): the square fills the image, its axis (+y, the texture's tip
 * end) up, its front face (+z) towards the viewer. Light towards -z, white tint. */
static xyl_foliage_vk_frame square_frame(void)
{
    xyl_foliage_vk_frame fr = {0};
    for (int k = 0; k < 4; ++k) fr.view_proj[5 * k] = 1.0f;
    fr.view_proj[5] = -1.0f;
    fr.light_dir[2] = -1.0f;
    fr.color[0] = fr.color[1] = fr.color[2] = fr.color[3] = 1.0f;
    return fr;
}

/* The application's frame: clear, vk's leaves at lods (in the render pass, or with dynamic
 * rendering), or with lods NULL the per-leaf cut for view `cut` (the compute pass before the
 * render pass, its indirect draw inside), a copy of the colour image; rgba top row first. */
static void draw_any(suite *s, xyl_foliage_vk *vk, bool dynamic, const xyl_foliage_vk_frame *fr,
                     const uint32_t *lods, size_t lod_count, const xyl_foliage_view *cut,
                     uint8_t *rgba)
{
    app *a = &s->a;
    VkCommandBuffer cb;
    VkCommandBufferAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = a->pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    vk_ok(vkAllocateCommandBuffers(a->device, &ai, &cb), "vkAllocateCommandBuffers");
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    vk_ok(vkBeginCommandBuffer(cb, &bi), "vkBeginCommandBuffer");
    xyl_diag d = {0};
    if (!lods) expect(xyl_foliage_vk_cmd_cut(vk, cb, cut, &d), XYL_OK, &d);
    VkClearValue clear[2];
    memset(clear, 0, sizeof clear);
    for (int k = 0; k < 3; ++k) clear[0].color.float32[k] = background[k] / 255.0f;
    clear[0].color.float32[3] = 1.0f;
    clear[1].depthStencil.depth = 1.0f;
    if (dynamic) {
        begin_dynamic(a, cb, clear);
    } else {
        VkRenderPassBeginInfo rb = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
        rb.renderPass = a->pass;
        rb.framebuffer = a->framebuffer;
        rb.renderArea.extent = (VkExtent2D){SIDE, SIDE};
        rb.clearValueCount = 2;
        rb.pClearValues = clear;
        vkCmdBeginRenderPass(cb, &rb, VK_SUBPASS_CONTENTS_INLINE);
    }
    VkViewport vp = {0.0f, 0.0f, (float)SIDE, (float)SIDE, 0.0f, 1.0f};
    VkRect2D sc = {{0, 0}, {SIDE, SIDE}};
    vkCmdSetViewport(cb, 0, 1, &vp);
    vkCmdSetScissor(cb, 0, 1, &sc);
    if (lods) expect(xyl_foliage_vk_cmd_draw(vk, cb, fr, lods, lod_count, &d), XYL_OK, &d);
    else expect(xyl_foliage_vk_cmd_draw_cut(vk, cb, fr, &d), XYL_OK, &d);
    if (dynamic) end_dynamic(a, cb);
    else vkCmdEndRenderPass(cb);
    VkBufferImageCopy copy = {0};
    copy.imageSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    copy.imageSubresource.layerCount = 1;
    copy.imageExtent = (VkExtent3D){SIDE, SIDE, 1};
    vkCmdCopyImageToBuffer(cb, a->image[0], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, a->readback, 1,
                           &copy);
    VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb,
                         0, NULL, 0, NULL);
    vk_ok(vkEndCommandBuffer(cb), "vkEndCommandBuffer");
    VkFenceCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    vk_ok(vkCreateFence(a->device, &fi, NULL, &fence), "vkCreateFence");
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cb;
    vk_ok(vkQueueSubmit(a->queue, 1, &si, fence), "vkQueueSubmit");
    vk_ok(vkWaitForFences(a->device, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
    vkDestroyFence(a->device, fence, NULL);
    vkFreeCommandBuffers(a->device, a->pool, 1, &cb);
    memcpy(rgba, a->pixels, 4u * SIDE * SIDE);
}

static void draw_frame(suite *s, xyl_foliage_vk *vk, bool dynamic, const xyl_foliage_vk_frame *fr,
                       const uint32_t *lods, size_t lod_count, uint8_t *rgba)
{
    draw_any(s, vk, dynamic, fr, lods, lod_count, NULL, rgba);
}

static void draw_square(suite *s, const xyl_foliage_vk_frame *fr, uint8_t *rgba)
{
    uint32_t lod = 0;
    draw_frame(s, s->vk, false, fr, &lod, 1, rgba);
}

static void draw_textured(suite *s, const uint8_t *tex, uint8_t *rgba)
{
    xyl_diag d = {0};
    expect(xyl_foliage_vk_set_texture(s->vk, tex, 16, 16, &d), XYL_OK, &d);
    xyl_foliage_vk_frame fr = square_frame();
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
    suite *s = need_vk(state);
    xyl_foliage *f = square_leaf();
    xyl_diag d = {0};
    expect(xyl_foliage_vk_set_foliage(s->vk, f, &d), XYL_OK, &d);
    uint8_t tex[16 * 16 * 4], *rgba = malloc(4 * SIDE * SIDE);
    /* control: all opaque covers the whole image */
    half_clear(tex, NULL);
    draw_textured(s, tex, rgba);
    for (unsigned i = 0; i < SIDE * SIDE; ++i) assert_false(is_background(rgba + 4 * i));
    /* u < 0.5 transparent: the left half shows the background, the right the leaf */
    half_clear(tex, left_half);
    draw_textured(s, tex, rgba);
    for (int y = 0; y < (int)SIDE; ++y)
        for (int x = 0; x < (int)SIDE; ++x) {
            if (abs(2 * x + 1 - (int)SIDE) < 8) continue; /* linear filtering at the edge */
            assert_int_equal(is_background(rgba + 4 * (SIDE * y + x)), x < (int)SIDE / 2);
        }
    /* the texture's top rows (the tip end, v = 1) transparent: the image's top rows (the
     * first read back) are empty */
    half_clear(tex, top_half);
    draw_textured(s, tex, rgba);
    for (int y = 0; y < (int)SIDE; ++y)
        for (int x = 0; x < (int)SIDE; ++x) {
            if (abs(2 * y + 1 - (int)SIDE) < 8) continue;
            assert_int_equal(is_background(rgba + 4 * (SIDE * y + x)), y < (int)SIDE / 2);
        }
    free(rgba);
    xyl_foliage_destroy(f);
    no_messages(s);
}

/* The dither's keep ranges [0, t) and [t, 1) split the full-screen leaf between two draws:
 * each pixel in one, as the threshold of xyl_dither.h says (y counted from the top in Vulkan's
 * framebuffer, as gl_FragCoord counts it there). */
static void the_dither_splits_the_leaf_between_two_ranges(void **state)
{
    suite *s = need_vk(state);
    xyl_foliage *f = square_leaf();
    xyl_diag d = {0};
    expect(xyl_foliage_vk_set_foliage(s->vk, f, &d), XYL_OK, &d);
    uint8_t tex[16 * 16 * 4], *a = malloc(4 * SIDE * SIDE), *b = malloc(4 * SIDE * SIDE);
    assert_true(a && b);
    half_clear(tex, NULL);
    expect(xyl_foliage_vk_set_texture(s->vk, tex, 16, 16, &d), XYL_OK, &d);
    const float t = 37.0f / 64.0f;
    xyl_foliage_vk_frame fr = square_frame();
    fr.dither[0] = 0.0f, fr.dither[1] = t;
    draw_square(s, &fr, a);
    fr.dither[0] = t, fr.dither[1] = 1.0f;
    draw_square(s, &fr, b);
    size_t in_a = 0;
    for (uint32_t y = 0; y < SIDE; ++y)
        for (uint32_t x = 0; x < SIDE; ++x) {
            size_t at = 4 * (SIDE * y + x);
            bool ca = !is_background(a + at), cb = !is_background(b + at);
            assert_true(ca != cb);
            assert_int_equal(ca, xyl_dither_threshold(x, y) < t);
            in_a += ca;
        }
    assert_int_equal(in_a, SIDE * SIDE * 37 / 64);
    fr.dither[0] = 0.5f; /* an empty range is refused */
    fr.dither[1] = 0.5f;
    uint32_t lod = 0;
    expect(xyl_foliage_vk_cmd_draw(s->vk, (VkCommandBuffer)(uintptr_t)16, &fr, &lod, 1, &d),
           XYL_ERR_INVALID_ARGUMENT, &d);
    free(a);
    free(b);
    xyl_foliage_destroy(f);
    no_messages(s);
}

static int middle(const uint8_t *rgba)
{
    const uint8_t *p = rgba + 4 * (SIDE * (SIDE / 2) + SIDE / 2);
    return p[0] + p[1] + p[2];
}

/* test_foliage_gl's lighting test, with the same thresholds: the back face (x mirrored) lit on
 * its side as the front on its; light from behind shines through, less than in front. So
 * gl_FrontFacing agrees with GL under the y-flipped matrix. */
static void both_faces_are_lit_and_light_shines_through(void **state)
{
    suite *s = need_vk(state);
    xyl_foliage *f = square_leaf();
    xyl_diag d = {0};
    expect(xyl_foliage_vk_set_foliage(s->vk, f, &d), XYL_OK, &d);
    uint8_t tex[16 * 16 * 4], *rgba = malloc(4 * SIDE * SIDE);
    half_clear(tex, NULL);
    expect(xyl_foliage_vk_set_texture(s->vk, tex, 16, 16, &d), XYL_OK, &d);
    xyl_foliage_vk_frame fr = square_frame();
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
    no_messages(s);
}

/* A renderer made for dynamic rendering (formats, no render pass) draws the tree into the same
 * images exactly as the render pass renderer does, pixel for pixel; and the picture has leaves
 * (not only the background). Skipped without Vulkan 1.3 on instance and device. */
static void dynamic_rendering_draws_what_the_render_pass_draws(void **state)
{
    suite *s = need_vk(state);
    if (!s->a.dynamic_rendering) {
        print_message("skipped: no Vulkan 1.3 dynamic rendering\n");
        skip();
    }
    xyl_foliage_vk_desc dd = app_desc(&s->a);
    dd.render_pass = VK_NULL_HANDLE;
    dd.color_format = COLOR_FORMAT;
    dd.depth_format = DEPTH_FORMAT;
    xyl_foliage_vk *dyn = NULL;
    xyl_diag d = {0};
    expect(xyl_foliage_vk_create(&dd, &dyn, &d), XYL_OK, &d);
    xyl_foliage *f = tree_foliage("faycal-leaves", 3);
    expect(xyl_foliage_vk_set_foliage(s->vk, f, &d), XYL_OK, &d);
    expect(xyl_foliage_vk_set_foliage(dyn, f, &d), XYL_OK, &d);
    uint8_t tex[16 * 16 * 4];
    half_clear(tex, left_half);
    expect(xyl_foliage_vk_set_texture(s->vk, tex, 16, 16, &d), XYL_OK, &d);
    expect(xyl_foliage_vk_set_texture(dyn, tex, 16, 16, &d), XYL_OK, &d);
    xyl_foliage_vk_frame fr;
    frame_of(f, 0.7f, 0.3f, &fr);
    const uint32_t lods[3] = {0, 3, 9};
    uint8_t *pass = malloc(4 * SIDE * SIDE), *dynamic = malloc(4 * SIDE * SIDE);
    draw_frame(s, s->vk, false, &fr, lods, 3, pass);
    draw_frame(s, dyn, true, &fr, lods, 3, dynamic);
    size_t leaf = 0;
    for (unsigned i = 0; i < SIDE * SIDE; ++i) leaf += !is_background(pass + 4 * i);
    print_message("%zu of %u pixels show leaves\n", leaf, SIDE * SIDE);
    assert_true(leaf > 50);
    assert_memory_equal(pass, dynamic, 4 * SIDE * SIDE);
    free(pass);
    free(dynamic);
    xyl_foliage_vk_destroy(dyn);
    xyl_foliage_destroy(f);
    no_messages(s);
}

/* ---- 3. the per-leaf cut: GPU = CPU, and what it draws --------------------------------------- */

/* The cut for each view of foliage_cut_check.h against xyl_foliage_cut (equal but for float
 * ties, a valid cut), drawn through the list: with the eye inside the crown it keeps every
 * original and draws the image of LOD 0; far away it keeps the forest's roots. */
static void gpu_cut_equals_the_cpu_cut(void **state)
{
    suite *s = need_vk(state);
    uint8_t *cut_px = malloc(4 * SIDE * SIDE), *lod_px = malloc(4 * SIDE * SIDE);
    assert_true(cut_px && lod_px);
    for (uint32_t sectors = 1; sectors <= 4; sectors += 3) {
        xyl_foliage *f = tree_foliage(xyl_lsystem_default_preset(), sectors);
        xyl_diag d = {0};
        expect(xyl_foliage_vk_set_foliage(s->vk, f, &d), XYL_OK, &d);
        xyl_foliage_vk_frame fr;
        frame_of(f, 0.7f, 0.3f, &fr);
        size_t ties = 0, first = 0, last = 0, pixels = 0, full = 0;
        uint32_t *gpu = malloc(f->leaf_count * sizeof *gpu), lods[4] = {0, 0, 0, 0};
        assert_non_null(gpu);
        draw_frame(s, s->vk, false, &fr, lods, f->sector_count, lod_px);
        for (unsigned p = 0; p < SIDE * SIDE; ++p) full += !is_background(lod_px + 4 * p);
        assert_true(full > 200);
        for (int i = 0; i < CUT_DISTANCES; ++i)
            for (int b = 0; b < CUT_BUDGETS; ++b) {
                xyl_foliage_view v = cut_view(f, i, b);
                draw_any(s, s->vk, false, &fr, NULL, 0, &v, cut_px);
                size_t n_gpu = 0;
                expect(xyl_foliage_vk_last_cut(s->vk, gpu, f->leaf_count, &n_gpu, &d), XYL_OK,
                       &d);
                size_t n = cut_compare(f, &v, gpu, n_gpu, &ties);
                if (i == 0 && b == 0) first = n;
                last = n;
                /* a coarser cut keeps the crown's cover (merged leaves are larger); a draw that
                 * took the first n_gpu records instead of the listed ones would not */
                size_t leaf = 0;
                for (unsigned p = 0; p < SIDE * SIDE; ++p) leaf += !is_background(cut_px + 4 * p);
                assert_true(10 * leaf >= 9 * full);
                if (i != 0) continue;
                /* inside the crown: the records of LOD 0, so its pixels, but where two leaves
                 * meet at one depth in another order */
                size_t differ = 0;
                for (unsigned p = 0; p < SIDE * SIDE; ++p)
                    differ += memcmp(cut_px + 4 * p, lod_px + 4 * p, 4) != 0;
                assert_true(differ <= SIDE * SIDE / 1000);
                pixels += differ;
            }
        assert_int_equal(first, f->original_count);
        assert_int_equal(last, f->coarsest_count);
        print_message("%u sector(s): %zu leaves, %zu decided by a float tie, %zu pixels differ "
                      "from the two-range draws\n",
                      sectors, f->leaf_count, ties, pixels);
        free(gpu);
        xyl_foliage_destroy(f);
    }
    free(cut_px);
    free(lod_px);
    no_messages(s);
}

static void cut_bad_input_gets_result_codes(void **state)
{
    suite *s = need_vk(state);
    xyl_diag d = {0};
    xyl_foliage_vk *vk = NULL;
    xyl_foliage_vk_desc good = app_desc(&s->a);
    expect(xyl_foliage_vk_create(&good, &vk, &d), XYL_OK, &d);
    VkCommandBuffer poison = (VkCommandBuffer)(uintptr_t)16; /* refused before any call */
    xyl_foliage *f = tree_foliage("faycal-leaves", 3);
    xyl_foliage_vk_frame fr;
    frame_of(f, 0.3f, 0.2f, &fr);
    xyl_foliage_view v = cut_view(f, 3, 1);
    size_t n = 0;
    /* nothing uploaded */
    expect(xyl_foliage_vk_cmd_cut(vk, poison, &v, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_cmd_draw_cut(vk, poison, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_last_cut(vk, NULL, 0, &n, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_set_foliage(vk, f, &d), XYL_OK, &d);
    /* NULLs */
    expect(xyl_foliage_vk_cmd_cut(NULL, poison, &v, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_cmd_cut(vk, VK_NULL_HANDLE, &v, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_cmd_cut(vk, poison, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_cmd_draw_cut(NULL, poison, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_cmd_draw_cut(vk, VK_NULL_HANDLE, &fr, &d), XYL_ERR_INVALID_ARGUMENT,
           &d);
    expect(xyl_foliage_vk_cmd_draw_cut(vk, poison, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_last_cut(NULL, NULL, 0, &n, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_last_cut(vk, NULL, 0, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    /* a draw or a read-back before any cut of this upload */
    expect(xyl_foliage_vk_cmd_draw_cut(vk, poison, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_last_cut(vk, NULL, 0, &n, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    /* the view's bad values, as xyl_foliage_pick refuses them */
    xyl_foliage_view bad = v;
    bad.error_px = -1.0f;
    expect(xyl_foliage_vk_cmd_cut(vk, poison, &bad, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bad = v;
    bad.fovy = 4.0f;
    expect(xyl_foliage_vk_cmd_cut(vk, poison, &bad, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bad = v;
    bad.eye[1] = NAN;
    expect(xyl_foliage_vk_cmd_cut(vk, poison, &bad, &d), XYL_ERR_NON_FINITE, &d);
    /* a cut that ran; then the frame's bad values and too small an output */
    uint8_t *px = malloc(4 * SIDE * SIDE);
    assert_non_null(px);
    draw_any(s, vk, false, &fr, NULL, 0, &v, px);
    free(px);
    expect(xyl_foliage_vk_last_cut(vk, NULL, 0, &n, &d), XYL_OK, &d);
    assert_true(n > 1 && n < f->leaf_count);
    uint32_t one = 0;
    expect(xyl_foliage_vk_last_cut(vk, &one, 1, &n, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_foliage_vk_frame badf = fr;
    badf.view_proj[3] = INFINITY;
    expect(xyl_foliage_vk_cmd_draw_cut(vk, poison, &badf, &d), XYL_ERR_NON_FINITE, &d);
    badf = fr;
    badf.alpha_cutoff = 3.0f;
    expect(xyl_foliage_vk_cmd_draw_cut(vk, poison, &badf, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    /* a new upload forgets the cut */
    expect(xyl_foliage_vk_set_foliage(vk, f, &d), XYL_OK, &d);
    expect(xyl_foliage_vk_cmd_draw_cut(vk, poison, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_foliage_vk_destroy(vk);
    xyl_foliage_destroy(f);
    no_messages(s);
}

/* ---- 4. bad input --------------------------------------------------------------------------- */

static void bad_input_gets_result_codes(void **state)
{
    suite *s = need_vk(state);
    xyl_diag d = {0};
    xyl_foliage_vk *vk = NULL;
    /* create: NULLs and missing handles, no pass and no formats, a bad sample count */
    xyl_foliage_vk_desc good = app_desc(&s->a), bad = good;
    expect(xyl_foliage_vk_create(NULL, &vk, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_create(&good, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bad.device = VK_NULL_HANDLE;
    expect(xyl_foliage_vk_create(&bad, &vk, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bad = good;
    bad.queue = VK_NULL_HANDLE;
    expect(xyl_foliage_vk_create(&bad, &vk, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bad = good;
    bad.render_pass = VK_NULL_HANDLE;
    expect(xyl_foliage_vk_create(&bad, &vk, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bad = good;
    bad.samples = (VkSampleCountFlagBits)3;
    expect(xyl_foliage_vk_create(&bad, &vk, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bad = good;
    bad.queue_family = 99;
    expect(xyl_foliage_vk_create(&bad, &vk, &d), XYL_ERR_UNSUPPORTED, &d);
    assert_null(vk);
    expect(xyl_foliage_vk_create(&good, &vk, &d), XYL_OK, &d);

    /* Draws get a command buffer that is not one: any Vulkan call with it would crash, so
     * every refusal below is made before the first call. */
    VkCommandBuffer poison = (VkCommandBuffer)(uintptr_t)16;
    xyl_foliage *f = tree_foliage("faycal-leaves", 3);
    xyl_foliage_vk_frame fr;
    frame_of(f, 0.3f, 0.2f, &fr);
    uint32_t lods[3] = {0, 0, 0};
    expect(xyl_foliage_vk_cmd_draw(vk, poison, &fr, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_set_foliage(NULL, f, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_set_foliage(vk, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_foliage_desc none = {0};
    xyl_foliage *empty = NULL;
    assert_int_equal(xyl_foliage_build(&none, &empty, NULL), XYL_OK);
    expect(xyl_foliage_vk_set_foliage(vk, empty, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_foliage_destroy(empty);
    xyl_foliage bent = *f;
    xyl_foliage_sector sectors[3];
    memcpy(sectors, f->sectors, sizeof sectors);
    sectors[2].base = (uint32_t)f->leaf_count;
    bent.sectors = sectors;
    expect(xyl_foliage_vk_set_foliage(vk, &bent, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_int_equal(d.index, 2);
    expect(xyl_foliage_vk_set_foliage(vk, f, &d), XYL_OK, &d);
    expect(xyl_foliage_vk_cmd_draw(NULL, poison, &fr, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_cmd_draw(vk, VK_NULL_HANDLE, &fr, lods, 3, &d),
           XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_cmd_draw(vk, poison, NULL, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_cmd_draw(vk, poison, &fr, NULL, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_cmd_draw(vk, poison, &fr, lods, 1, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    lods[1] = f->sectors[1].merged_count + 1;
    expect(xyl_foliage_vk_cmd_draw(vk, poison, &fr, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_int_equal(d.index, 1);
    lods[1] = f->sectors[1].merged_count;
    xyl_foliage_vk_frame badf = fr;
    badf.view_proj[7] = NAN;
    expect(xyl_foliage_vk_cmd_draw(vk, poison, &badf, lods, 3, &d), XYL_ERR_NON_FINITE, &d);
    memset(badf.view_proj, 0, sizeof badf.view_proj);
    expect(xyl_foliage_vk_cmd_draw(vk, poison, &badf, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    badf = fr;
    badf.color[2] = INFINITY;
    expect(xyl_foliage_vk_cmd_draw(vk, poison, &badf, lods, 3, &d), XYL_ERR_NON_FINITE, &d);
    badf = fr;
    badf.alpha_cutoff = -0.5f;
    expect(xyl_foliage_vk_cmd_draw(vk, poison, &badf, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    badf = fr;
    badf.translucency = 2.0f;
    expect(xyl_foliage_vk_cmd_draw(vk, poison, &badf, lods, 3, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    /* textures */
    uint8_t px[4] = {255, 255, 255, 255};
    expect(xyl_foliage_vk_set_texture(NULL, px, 1, 1, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_set_texture(vk, NULL, 1, 1, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_set_texture(vk, px, 1, 0, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_set_texture(vk, px, XYL_FOLIAGE_VK_MAX_TEXTURE_SIDE + 1, 1, &d),
           XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_foliage_vk_set_texture(vk, px, 1, 1, &d), XYL_OK, &d);
    /* capture: too small an output */
    xyl__foliage_vk_captured one[4];
    expect(xyl__foliage_vk_capture(vk, &fr, lods, 3, one, 4, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl__foliage_vk_capture(vk, &fr, lods, 3, NULL, 0, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_foliage_vk_destroy(vk);
    xyl_foliage_vk_destroy(NULL);
    xyl_foliage_destroy(f);
    no_messages(s);
}

/* ---- 5. memory ------------------------------------------------------------------------------ */

/* Every host allocation of the renderer goes through the desc's allocator: its own blocks and,
 * as VkAllocationCallbacks, the driver's (and the layer's) for its objects; all of them come
 * back. Refusing the first one fails create with nothing made; refusing each of set_foliage's
 * own (two tables, the packed records and the cut's nodes, made before any Vulkan call) is
 * XYL_ERR_OUT_OF_MEMORY with the previous upload still drawn. (Failures injected into the
 * driver's allocations would test lavapipe's out-of-memory paths, not xylem's; test_tess_vk
 * says why it stops there too.) */
static void renderer_allocates_through_the_callers_allocator(void **state)
{
    suite *s = need_vk(state);
    xyl_foliage *f = tree_foliage("faycal-leaves", 3), *one = square_leaf();
    xyl_diag d = {0};
    tu_counter c = {0, 0, 0, 1};
    xyl_foliage_vk_desc vd = app_desc(&s->a);
    vd.alloc = tu_counting(&c);
    xyl_foliage_vk *vk = (xyl_foliage_vk *)(uintptr_t)1;
    expect(xyl_foliage_vk_create(&vd, &vk, &d), XYL_ERR_OUT_OF_MEMORY, &d);
    assert_ptr_equal(vk, (xyl_foliage_vk *)(uintptr_t)1);
    assert_int_equal(c.allocs, c.frees);
    c.fail_at = 0;
    expect(xyl_foliage_vk_create(&vd, &vk, &d), XYL_OK, &d);
    size_t at_create = c.allocs;
    expect(xyl_foliage_vk_set_foliage(vk, one, &d), XYL_OK, &d);
    xyl_foliage_vk_frame fr;
    frame_of(f, 0.3f, 0.2f, &fr);
    const uint32_t lod0 = 0;
    xyl__foliage_vk_captured got[4];
    for (size_t k = 1; k <= 4; ++k) {
        c.fail_at = c.attempts + k;
        expect(xyl_foliage_vk_set_foliage(vk, f, &d), XYL_ERR_OUT_OF_MEMORY, &d);
        memset(got, 0, sizeof got);
        expect(xyl__foliage_vk_capture(vk, &fr, &lod0, 1, got, 4, &d), XYL_OK, &d);
        for (int corner = 0; corner < 4; ++corner) assert_int_equal(got[corner].leaf, 0);
    }
    c.fail_at = 0;
    expect(xyl_foliage_vk_set_foliage(vk, f, &d), XYL_OK, &d);
    xyl_foliage_vk_destroy(vk);
    print_message("%zu allocations through the caller's allocator (%zu by create)\n", c.allocs,
                  at_create);
    assert_true(at_create > 10); /* the driver's too: the renderer itself makes one */
    assert_int_equal(c.allocs, c.frees);
    xyl_foliage_destroy(one);
    xyl_foliage_destroy(f);
    no_messages(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(gpu_corners_match_the_cpu_reference_per_lod),
        cmocka_unit_test(alpha_test_discards_the_transparent_half),
        cmocka_unit_test(the_dither_splits_the_leaf_between_two_ranges),
        cmocka_unit_test(both_faces_are_lit_and_light_shines_through),
        cmocka_unit_test(dynamic_rendering_draws_what_the_render_pass_draws),
        cmocka_unit_test(gpu_cut_equals_the_cpu_cut),
        cmocka_unit_test(cut_bad_input_gets_result_codes),
        cmocka_unit_test(bad_input_gets_result_codes),
        cmocka_unit_test(renderer_allocates_through_the_callers_allocator),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

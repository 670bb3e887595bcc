/* foliage/'s Vulkan tree billboards (xyl_billboard_vk.h) against the GL ones
 * (xyl_billboard_gl.h) on the same tree of leaves, baked through xyl_foliage_vk and
 * xyl_foliage_gl: each baked view's read-back, each kind's picture from the same camera, the
 * impostor's error against the tree over the 20 dodecahedron views, the dither's split, the
 * forest's instanced draw, and bad input. Vulkan runs with the Khronos validation layer on
 * (lavapipe where there is no GPU) and every test ends with no validation message. Without a
 * Vulkan 1.2 device with the layer, or a GL 4.5 context, every test is skipped, and says why. */
#include <epoxy/gl.h>
#include <math.h>

#include "test_util.h"
#include "foliage_tree.h"
#include <xylem/xyl_billboard_gl.h>
#include <xylem/xyl_billboard_vk.h>
#include <xylem/xyl_foliage_gl.h>
#include <xylem/xyl_foliage_vk.h>
#include <xylem/xyl_tess_gl.h>

#define SIDE 128u /* texels of a baked view and pixels of a test picture */
#define COLOR_FORMAT VK_FORMAT_R8G8B8A8_UNORM
#define DEPTH_FORMAT VK_FORMAT_D32_SFLOAT

/* Tolerances of Vulkan against GL (measured on lavapipe and llvmpipe, see each test). */
#define VIEW_COVERAGE_SHARE 0.01 /* texels whose coverage differs, of all */
#define VIEW_COLOUR_RMSE 0.02    /* colour where both cover, RGB in [0, 1] */
#define VIEW_NORMAL_RMSE 0.05    /* normal map where both cover */
#define PICTURE_COLOUR_RMSE 0.03 /* 4 x 4 blocks' mean colour */
#define PICTURE_COVERAGE_RMSE 0.08
#define IMPOSTOR_ERROR_GAP 0.01  /* mean colour RMSE against the tree, Vulkan minus GL */

#include "vk_test_app.h"

typedef struct suite {
    app a;
    xyl_gl_context *ctx;
    xyl_foliage_gl *gl_leaves;
    xyl_foliage_vk *vk_leaves;
    xyl_foliage *tree;
    uint32_t lods[64];
    float lo[3], hi[3];
    xyl_result fail_with; /* what the Vulkan bake callback returns */
    char why[320];
} suite;

static void expect(xyl_result got, xyl_result want, const xyl_diag *d)
{
    if (got != want)
        fail_msg("expected %s, got %s (%s)", xyl_result_string(want), xyl_result_string(got),
                 d->message);
    if (want != XYL_OK) assert_true(strlen(d->message) > 0);
}

/* ---- suite ---------------------------------------------------------------------------------- */

static int setup(void **state)
{
    suite *s = calloc(1, sizeof *s);
    if (!s) return -1;
    *state = s;
    xyl_diag d = {0};
    VkResult vr = make_instance(&s->a);
    if (vr != VK_SUCCESS) {
        snprintf(s->why, sizeof s->why,
                 "no Vulkan instance with the validation layer (VkResult %d)", (int)vr);
        return 0;
    }
    if (!make_device(&s->a, false, s->why, sizeof s->why)) return 0;
    make_pass(&s->a);
    make_target(&s->a);
    if (xyl_gl_context_create_headless(NULL, &s->ctx, &d) != XYL_OK ||
        xyl_foliage_gl_create(NULL, &s->gl_leaves, &d) != XYL_OK) {
        snprintf(s->why, sizeof s->why, "no usable GL 4.5 context: %s", d.message);
        return 0;
    }
    xyl_foliage_vk_desc ld = {0};
    ld.physical_device = s->a.physical;
    ld.device = s->a.device;
    ld.queue = s->a.queue;
    ld.queue_family = s->a.family;
    ld.render_pass = s->a.pass;
    ld.enabled_features = &s->a.features;
    if (xyl_foliage_vk_create(&ld, &s->vk_leaves, &d) != XYL_OK) {
        snprintf(s->why, sizeof s->why, "the Vulkan leaf renderer: %s", d.message);
        return 0;
    }
    s->tree = ft_tree_foliage("abop-2.8-ternary", 1);
    if (!s->tree || xyl_foliage_gl_set_foliage(s->gl_leaves, s->tree, &d) != XYL_OK ||
        xyl_foliage_vk_set_foliage(s->vk_leaves, s->tree, &d) != XYL_OK)
        return -1;
    for (int k = 0; k < 3; ++k) s->lo[k] = INFINITY, s->hi[k] = -INFINITY;
    for (size_t i = 0; i < s->tree->leaf_count; ++i) {
        const xyl_leaf *l = &s->tree->leaves[i];
        const float c[3] = {l->center.x, l->center.y, l->center.z};
        const float e[3] = {fabsf(l->side.x) + fabsf(l->axis.x),
                            fabsf(l->side.y) + fabsf(l->axis.y),
                            fabsf(l->side.z) + fabsf(l->axis.z)};
        for (int k = 0; k < 3; ++k) {
            s->lo[k] = fminf(s->lo[k], c[k] - e[k]);
            s->hi[k] = fmaxf(s->hi[k], c[k] + e[k]);
        }
    }
    return 0;
}

static int teardown(void **state)
{
    suite *s = *state;
    xyl_foliage_gl_destroy(s->gl_leaves);
    xyl_gl_context_destroy(s->ctx);
    xyl_foliage_vk_destroy(s->vk_leaves);
    xyl_foliage_destroy(s->tree);
    close_app(&s->a);
    uint32_t messages = s->a.messages;
    free(s);
    return messages ? -1 : 0;
}

static suite *need_both(void **state)
{
    suite *s = *state;
    if (s->why[0]) {
        print_message("skipped: %s\n", s->why);
        skip();
    }
    s->fail_with = XYL_OK;
    return s;
}

static void no_messages(const suite *s)
{
    if (s->a.messages)
        fail_msg("%u validation messages, the first: %s", s->a.messages, s->a.first);
}

/* ---- bakes ---------------------------------------------------------------------------------- */

static xyl_result gl_draw_leaves(void *user, const float view_proj[16], const float light[3],
                                 xyl_diag *d)
{
    suite *s = user;
    xyl_foliage_gl_frame fr = {0};
    memcpy(fr.view_proj, view_proj, sizeof fr.view_proj);
    memcpy(fr.light_dir, light, sizeof fr.light_dir);
    return xyl_foliage_gl_draw(s->gl_leaves, &fr, s->lods, s->tree->sector_count, d);
}

static xyl_result vk_draw_leaves(void *user, VkCommandBuffer cmd, VkRenderPass pass,
                                 const float view_proj[16], const float light[3], xyl_diag *d)
{
    suite *s = user;
    assert_non_null(pass);
    if (s->fail_with != XYL_OK) {
        snprintf(d->message, sizeof d->message, "the test's draw fails");
        return s->fail_with;
    }
    xyl_foliage_vk_frame fr = {0};
    memcpy(fr.view_proj, view_proj, sizeof fr.view_proj);
    memcpy(fr.light_dir, light, sizeof fr.light_dir);
    return xyl_foliage_vk_cmd_draw(s->vk_leaves, cmd, &fr, s->lods, s->tree->sector_count, d);
}

typedef struct kind_case {
    xyl_billboard_kind kind;
    uint32_t planes, grid;
    const char *name;
} kind_case;

static const kind_case kinds[4] = {{XYL_BILLBOARD_SPHERICAL, 0, 0, "spherical"},
                                   {XYL_BILLBOARD_CYLINDRICAL, 0, 0, "cylindrical"},
                                   {XYL_BILLBOARD_CROSS, 4, 0, "cross"},
                                   {XYL_BILLBOARD_OCTAHEDRAL, 0, 4, "octahedral"}};

static xyl_billboard_vk_desc vk_desc(const suite *s, const kind_case *k)
{
    xyl_billboard_vk_desc bd = {0};
    bd.physical_device = s->a.physical;
    bd.device = s->a.device;
    bd.queue = s->a.queue;
    bd.queue_family = s->a.family;
    bd.render_pass = s->a.pass;
    bd.enabled_features = &s->a.features;
    bd.kind = k->kind;
    bd.planes = k->planes;
    bd.grid = k->grid;
    bd.resolution = SIDE;
    memcpy(bd.lo, s->lo, sizeof bd.lo);
    memcpy(bd.hi, s->hi, sizeof bd.hi);
    bd.light_dir[0] = 0.3f, bd.light_dir[1] = 0.8f, bd.light_dir[2] = 0.5f;
    return bd;
}

static xyl_billboard_gl_desc gl_desc(const suite *s, const kind_case *k)
{
    xyl_billboard_gl_desc bd = {0};
    bd.kind = k->kind;
    bd.planes = k->planes;
    bd.grid = k->grid;
    bd.resolution = SIDE;
    memcpy(bd.lo, s->lo, sizeof bd.lo);
    memcpy(bd.hi, s->hi, sizeof bd.hi);
    bd.light_dir[0] = 0.3f, bd.light_dir[1] = 0.8f, bd.light_dir[2] = 0.5f;
    return bd;
}

static void bake_both(suite *s, const kind_case *k, xyl_billboard_gl **gl, xyl_billboard_vk **vk)
{
    xyl_diag d = {0};
    xyl_billboard_gl_desc gd = gl_desc(s, k);
    xyl_billboard_vk_desc vd = vk_desc(s, k);
    expect(xyl_billboard_gl_bake(&gd, gl_draw_leaves, s, gl, &d), XYL_OK, &d);
    expect(xyl_billboard_vk_bake(&vd, vk_draw_leaves, s, vk, &d), XYL_OK, &d);
    assert_int_equal(xyl_billboard_gl_view_count(*gl), xyl_billboard_vk_view_count(*vk));
}

/* ---- pictures ------------------------------------------------------------------------------- */

/* What a picture shows: the tree (bb NULL) or a billboard, from a camera. */
typedef struct shot {
    xyl_tess_camera cam;
    float light[3];
    float dither[2];
    xyl_billboard_gl *gl;
    xyl_billboard_vk *vk;
    bool tree;
    /* the forest's instanced draw instead of cmd_draw: instances [first, first + count) */
    bool instances;
    uint32_t first, count;
    /* multisampled: 4 samples resolved (GL: a blit; Vulkan: the msaa pass below), cleared to
     * the opaque background */
    bool msaa;
    VkRenderPass pass;
    VkFramebuffer framebuffer;
    bool dynamic; /* Vulkan: dynamic rendering into the application's images */
} shot;

static const float msaa_background[4] = {0.85f, 0.9f, 0.95f, 1.0f};

/* A SIDE x SIDE GL picture, top row first, cleared to 0. */
static void gl_picture(suite *s, const shot *p, uint8_t *rgba)
{
    GLuint rb[3], fbo[2];
    GLsizei samples = p->msaa ? 4 : 0;
    glCreateRenderbuffers(3, rb);
    glNamedRenderbufferStorageMultisample(rb[0], samples, GL_RGBA8, SIDE, SIDE);
    glNamedRenderbufferStorageMultisample(rb[1], samples, GL_DEPTH_COMPONENT32F, SIDE, SIDE);
    glNamedRenderbufferStorage(rb[2], GL_RGBA8, SIDE, SIDE);
    glCreateFramebuffers(2, fbo);
    glNamedFramebufferRenderbuffer(fbo[0], GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    glNamedFramebufferRenderbuffer(fbo[0], GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
    glNamedFramebufferRenderbuffer(fbo[1], GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[2]);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo[0]);
    glViewport(0, 0, SIDE, SIDE);
    const float *bg = msaa_background;
    if (p->msaa) glClearColor(bg[0], bg[1], bg[2], bg[3]);
    else glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    xyl_diag d = {0};
    float m[16];
    expect(xyl_tess_camera_matrix(&p->cam, XYL_TESS_CLIP_GL, m, &d), XYL_OK, &d);
    if (p->tree) {
        expect(gl_draw_leaves(s, m, p->light, &d), XYL_OK, &d);
    } else {
        xyl_billboard_gl_frame fr = {0};
        memcpy(fr.view_proj, m, sizeof m);
        memcpy(fr.eye, p->cam.eye, sizeof fr.eye);
        memcpy(fr.light_dir, p->light, sizeof fr.light_dir);
        memcpy(fr.dither, p->dither, sizeof fr.dither);
        expect(xyl_billboard_gl_draw(p->gl, &fr, &d), XYL_OK, &d);
    }
    glBlitNamedFramebuffer(fbo[0], fbo[1], 0, 0, SIDE, SIDE, 0, 0, SIDE, SIDE,
                           GL_COLOR_BUFFER_BIT, GL_NEAREST); /* the resolve */
    glBindFramebuffer(GL_FRAMEBUFFER, fbo[1]);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    uint8_t *tmp = malloc(4 * SIDE * SIDE);
    assert_non_null(tmp);
    glReadPixels(0, 0, SIDE, SIDE, GL_RGBA, GL_UNSIGNED_BYTE, tmp);
    for (uint32_t y = 0; y < SIDE; ++y)
        memcpy(rgba + 4 * y * SIDE, tmp + 4 * (SIDE - 1 - y) * SIDE, 4 * SIDE);
    free(tmp);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(2, fbo);
    glDeleteRenderbuffers(3, rb);
}

/* The same on Vulkan: the application's pass, the frame recorded into its command buffer. */
static void vk_picture(suite *s, const shot *p, uint8_t *rgba)
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
    VkClearValue clear[3];
    memset(clear, 0, sizeof clear);
    if (p->msaa) memcpy(clear[0].color.float32, msaa_background, sizeof msaa_background);
    clear[1].depthStencil.depth = 1.0f;
    VkRenderPassBeginInfo rb = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rb.renderPass = p->msaa ? p->pass : a->pass;
    rb.framebuffer = p->msaa ? p->framebuffer : a->framebuffer;
    rb.renderArea.extent = (VkExtent2D){SIDE, SIDE};
    rb.clearValueCount = p->msaa ? 3 : 2;
    rb.pClearValues = clear;
    if (p->dynamic) begin_dynamic(a, cb, clear);
    else vkCmdBeginRenderPass(cb, &rb, VK_SUBPASS_CONTENTS_INLINE);
    VkViewport vp = {0.0f, 0.0f, (float)SIDE, (float)SIDE, 0.0f, 1.0f};
    VkRect2D sc = {{0, 0}, {SIDE, SIDE}};
    vkCmdSetViewport(cb, 0, 1, &vp);
    vkCmdSetScissor(cb, 0, 1, &sc);
    xyl_diag d = {0};
    float m[16];
    expect(xyl_tess_camera_matrix(&p->cam, XYL_TESS_CLIP_VULKAN, m, &d), XYL_OK, &d);
    if (p->tree) {
        expect(vk_draw_leaves(s, cb, a->pass, m, p->light, &d), XYL_OK, &d);
    } else {
        xyl_billboard_vk_frame fr = {0};
        memcpy(fr.view_proj, m, sizeof m);
        memcpy(fr.eye, p->cam.eye, sizeof fr.eye);
        memcpy(fr.light_dir, p->light, sizeof fr.light_dir);
        memcpy(fr.dither, p->dither, sizeof fr.dither);
        if (p->instances)
            expect(xyl_billboard_vk_cmd_draw_instances(p->vk, cb, &fr, p->first, p->count, &d),
                   XYL_OK, &d);
        else
            expect(xyl_billboard_vk_cmd_draw(p->vk, cb, &fr, &d), XYL_OK, &d);
    }
    if (p->dynamic) end_dynamic(a, cb);
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

/* XYL_TEST_PNG_DIR set: the picture as a PNG there, to look at. */
static void keep_png(const char *name, const uint8_t *rgba)
{
    const char *dir = getenv("XYL_TEST_PNG_DIR");
    if (!dir) return;
    char path[512];
    snprintf(path, sizeof path, "%s/%s.ppm", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f) return;
    fprintf(f, "P6\n%u %u\n255\n", SIDE, SIDE);
    for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i) fwrite(rgba + 4 * i, 1, 3, f);
    fclose(f);
}

/* 4 x 4 blocks, over those either picture covers: RMSE of mean colour and of covered share. */
static void block_rmse(const uint8_t *a, const uint8_t *b, double *colour, double *coverage,
                       size_t *covered)
{
    double sc = 0.0, sv = 0.0;
    size_t blocks = 0, px = 0;
    for (uint32_t by = 0; by < SIDE / 4; ++by)
        for (uint32_t bx = 0; bx < SIDE / 4; ++bx) {
            double ca[3] = {0}, cb[3] = {0}, va = 0.0, vb = 0.0;
            for (uint32_t y = 4 * by; y < 4 * by + 4; ++y)
                for (uint32_t x = 4 * bx; x < 4 * bx + 4; ++x) {
                    size_t i = (size_t)y * SIDE + x;
                    for (int k = 0; k < 3; ++k)
                        ca[k] += a[4 * i + k] / 255.0 / 16.0, cb[k] += b[4 * i + k] / 255.0 / 16.0;
                    va += a[4 * i + 3] > 0 ? 1.0 / 16.0 : 0.0;
                    vb += b[4 * i + 3] > 0 ? 1.0 / 16.0 : 0.0;
                    px += a[4 * i + 3] > 0;
                }
            if (va == 0.0 && vb == 0.0) continue;
            ++blocks;
            for (int k = 0; k < 3; ++k) sc += (ca[k] - cb[k]) * (ca[k] - cb[k]);
            sv += (va - vb) * (va - vb);
        }
    *colour = blocks ? sqrt(sc / (3.0 * (double)blocks)) : 0.0;
    *coverage = blocks ? sqrt(sv / (double)blocks) : 0.0;
    *covered = px;
}

static void frame_camera(const suite *s, float azimuth, float elevation, shot *p)
{
    xyl_tess_camera_frame(s->lo, s->hi, azimuth, elevation, 0.8f, 1.0f, &p->cam);
    xyl_tess_camera_zoom(&p->cam, 0.4f); /* the framing leaves the tree a fifth of the width */
    p->light[0] = 0.3f, p->light[1] = 0.8f, p->light[2] = 0.5f;
}

/* ---- tests ---------------------------------------------------------------------------------- */

/* Every baked view of every kind read back from Vulkan is GL's: the coverage differs in at
 * most VIEW_COVERAGE_SHARE of the texels (edges where the two rasterisers round differently),
 * the colour and normal maps where both cover within VIEW_COLOUR_RMSE and VIEW_NORMAL_RMSE
 * (RGB in [0, 1]), and the views are not empty (over 1% covered). */
static void baked_views_read_back_as_on_gl(void **state)
{
    suite *s = need_both(state);
    uint8_t *g = malloc(4 * SIDE * SIDE), *v = malloc(4 * SIDE * SIDE);
    assert_true(g && v);
    for (int k = 0; k < 4; ++k) {
        xyl_billboard_gl *gl = NULL;
        xyl_billboard_vk *vk = NULL;
        bake_both(s, &kinds[k], &gl, &vk);
        double worst[3] = {0.0, 0.0, 0.0};
        for (uint32_t view = 0; view < xyl_billboard_vk_view_count(vk); ++view)
            for (int normal = 0; normal < 2; ++normal) {
                xyl_diag d = {0};
                expect(xyl_billboard_gl_read_view(gl, view, normal, g, &d), XYL_OK, &d);
                expect(xyl_billboard_vk_read_view(vk, view, normal, v, &d), XYL_OK, &d);
                size_t differ = 0, both = 0, covered = 0;
                double sum = 0.0;
                for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i) {
                    bool a, b;
                    if (!normal) a = g[4 * i + 3] > 127, b = v[4 * i + 3] > 127;
                    else a = g[4 * i + 2] != 255 || g[4 * i + 3] != 128,
                         b = v[4 * i + 2] != 255 || v[4 * i + 3] != 128;
                    covered += a;
                    differ += a != b;
                    if (!(a && b)) continue;
                    ++both;
                    for (int c = 0; c < 3; ++c) {
                        double e = (g[4 * i + c] - v[4 * i + c]) / 255.0;
                        sum += e * e;
                    }
                }
                if (!normal) {
                    assert_true(covered > SIDE * SIDE / 100);
                    worst[0] = fmax(worst[0], (double)differ / (SIDE * SIDE));
                }
                double rmse = both ? sqrt(sum / (3.0 * (double)both)) : 0.0;
                worst[1 + normal] = fmax(worst[1 + normal], rmse);
                if (view == 0 && !normal) {
                    char name[64];
                    snprintf(name, sizeof name, "view0_%s_gl", kinds[k].name);
                    keep_png(name, g);
                    snprintf(name, sizeof name, "view0_%s_vk", kinds[k].name);
                    keep_png(name, v);
                }
            }
        print_message("%s: %u views, worst coverage difference %.4f, colour RMSE %.4f, "
                      "normal RMSE %.4f\n", kinds[k].name, xyl_billboard_vk_view_count(vk),
                      worst[0], worst[1], worst[2]);
        assert_true(worst[0] <= VIEW_COVERAGE_SHARE);
        assert_true(worst[1] <= VIEW_COLOUR_RMSE);
        assert_true(worst[2] <= VIEW_NORMAL_RMSE);
        xyl_billboard_gl_destroy(gl);
        xyl_billboard_vk_destroy(vk);
    }
    free(g);
    free(v);
    no_messages(s);
}

/* Each kind drawn on Vulkan from the same camera as on GL (30 degrees round, 20 up, the
 * bake's light) is GL's picture within PICTURE_COLOUR_RMSE and PICTURE_COVERAGE_RMSE in 4 x 4
 * blocks; both pictures against the tree itself are further apart than that, so the
 * comparison can fail. */
static void each_kind_draws_as_on_gl(void **state)
{
    suite *s = need_both(state);
    uint8_t *g = malloc(4 * SIDE * SIDE), *v = malloc(4 * SIDE * SIDE),
            *t = malloc(4 * SIDE * SIDE);
    assert_true(g && v && t);
    shot p = {0};
    frame_camera(s, 0.52f, 0.35f, &p);
    p.tree = true;
    vk_picture(s, &p, t);
    keep_png("tree_vk", t);
    p.tree = false;
    for (int k = 0; k < 4; ++k) {
        bake_both(s, &kinds[k], &p.gl, &p.vk);
        gl_picture(s, &p, g);
        vk_picture(s, &p, v);
        char name[64];
        snprintf(name, sizeof name, "draw_%s_gl", kinds[k].name);
        keep_png(name, g);
        snprintf(name, sizeof name, "draw_%s_vk", kinds[k].name);
        keep_png(name, v);
        double colour, coverage, tree_colour, tree_coverage;
        size_t covered, tree_covered;
        block_rmse(g, v, &colour, &coverage, &covered);
        block_rmse(t, v, &tree_colour, &tree_coverage, &tree_covered);
        print_message("%s: against GL colour RMSE %.4f, coverage RMSE %.4f (%zu px); against "
                      "the tree %.4f, %.4f\n", kinds[k].name, colour, coverage, covered,
                      tree_colour, tree_coverage);
        assert_true(covered > SIDE * SIDE / 50);
        assert_true(colour <= PICTURE_COLOUR_RMSE);
        assert_true(coverage <= PICTURE_COVERAGE_RMSE);
        assert_true(tree_coverage > coverage);
        xyl_billboard_gl_destroy(p.gl);
        xyl_billboard_vk_destroy(p.vk);
    }
    free(g);
    free(v);
    free(t);
    no_messages(s);
}

/* --billboard-error's measure: colour RMSE over all pixels against the tree's picture. */
static double colour_rmse(const uint8_t *a, const uint8_t *b)
{
    double sum = 0.0;
    for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i)
        for (int k = 0; k < 3; ++k) {
            double e = (a[4 * i + k] - b[4 * i + k]) / 255.0;
            sum += e * e;
        }
    return sqrt(sum / (3.0 * SIDE * SIDE));
}

/* The octahedral impostor (grid 8) against the tree from the 20 vertices of a dodecahedron, as
 * xylem render --billboard-error measures it: the mean colour RMSE on Vulkan within
 * IMPOSTOR_ERROR_GAP of GL's. */
static void impostor_error_is_gls(void **state)
{
    suite *s = need_both(state);
    const kind_case k = {XYL_BILLBOARD_OCTAHEDRAL, 0, 8, "octahedral"};
    shot p = {0};
    bake_both(s, &k, &p.gl, &p.vk);
    const double phi = 1.6180339887498949, ip = 1.0 / phi;
    double dirs[20][3];
    int n = 0;
    for (int i = 0; i < 8; ++i)
        dirs[n][0] = i & 1 ? -1 : 1, dirs[n][1] = i & 2 ? -1 : 1, dirs[n][2] = i & 4 ? -1 : 1, ++n;
    for (int i = 0; i < 4; ++i) {
        double s1 = i & 1 ? -1 : 1, s2 = i & 2 ? -1 : 1;
        dirs[n][0] = 0, dirs[n][1] = s1 * ip, dirs[n][2] = s2 * phi, ++n;
        dirs[n][0] = s1 * ip, dirs[n][1] = s2 * phi, dirs[n][2] = 0, ++n;
        dirs[n][0] = s1 * phi, dirs[n][1] = 0, dirs[n][2] = s2 * ip, ++n;
    }
    uint8_t *pic[4];
    for (int i = 0; i < 4; ++i) assert_non_null(pic[i] = malloc(4 * SIDE * SIDE));
    double sum_gl = 0.0, sum_vk = 0.0;
    for (int v = 0; v < 20; ++v) {
        double *d = dirs[v], len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        frame_camera(s, (float)atan2(d[0], d[2]), (float)asin(d[1] / len), &p);
        p.tree = true;
        gl_picture(s, &p, pic[0]);
        vk_picture(s, &p, pic[1]);
        p.tree = false;
        gl_picture(s, &p, pic[2]);
        vk_picture(s, &p, pic[3]);
        sum_gl += colour_rmse(pic[0], pic[2]);
        sum_vk += colour_rmse(pic[1], pic[3]);
        if (v == 0) {
            keep_png("impostor_tree_vk", pic[1]);
            keep_png("impostor_vk", pic[3]);
        }
    }
    print_message("impostor, grid 8, %u x %u, 20 views: mean colour RMSE GL %.4f, Vulkan %.4f\n",
                  SIDE, SIDE, sum_gl / 20.0, sum_vk / 20.0);
    assert_true(sum_vk > 0.0);
    assert_true(fabs(sum_vk - sum_gl) / 20.0 <= IMPOSTOR_ERROR_GAP);
    for (int i = 0; i < 4; ++i) free(pic[i]);
    xyl_billboard_gl_destroy(p.gl);
    xyl_billboard_vk_destroy(p.vk);
    no_messages(s);
}

/* Two complementary keep ranges [0, t) and [t, 1) split the billboard's pixels: no pixel in
 * both, none of the full draw's in neither, and each keeps its share of them (within 0.03:
 * the 8 x 8 pattern over a silhouette), for the cross and the impostor. */
static void dither_ranges_split_the_pixels(void **state)
{
    suite *s = need_both(state);
    uint8_t *full = malloc(4 * SIDE * SIDE), *lo = malloc(4 * SIDE * SIDE),
            *hi = malloc(4 * SIDE * SIDE);
    assert_true(full && lo && hi);
    for (int k = 2; k < 4; ++k) {
        shot p = {0};
        bake_both(s, &kinds[k], &p.gl, &p.vk);
        frame_camera(s, 0.3f, 0.2f, &p);
        vk_picture(s, &p, full);
        const float t = 0.375f;
        p.dither[0] = 0.0f, p.dither[1] = t;
        vk_picture(s, &p, lo);
        p.dither[0] = t, p.dither[1] = 1.0f;
        vk_picture(s, &p, hi);
        size_t n_full = 0, n_lo = 0, n_both = 0, n_lost = 0;
        for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i) {
            bool f = full[4 * i + 3] > 0, a = lo[4 * i + 3] > 0, b = hi[4 * i + 3] > 0;
            n_full += f;
            n_lo += a;
            n_both += a && b;
            n_lost += f && !a && !b;
        }
        double share = (double)n_lo / (double)n_full;
        print_message("%s: %zu pixels, [0, %.3f) keeps %.3f of them, %zu in both, %zu in "
                      "neither\n", kinds[k].name, n_full, (double)t, share, n_both, n_lost);
        assert_true(n_full > SIDE * SIDE / 50);
        assert_int_equal(n_both, 0);
        assert_int_equal(n_lost, 0);
        assert_true(fabs(share - t) < 0.03);
        xyl_billboard_gl_destroy(p.gl);
        xyl_billboard_vk_destroy(p.vk);
    }
    free(full);
    free(lo);
    free(hi);
    no_messages(s);
}

/* The forest's instanced draw: an instance at the origin, unturned, at scale 1 draws exactly
 * the billboard's own picture; one moved by a fifth of the box along +X, seen from a camera
 * moved the same way, draws that picture again (within 0.01 colour and 0.03 coverage RMSE in
 * 4 x 4 blocks: the same quads through other float sums), while the same instance from the
 * unmoved camera is another picture; one turned by 45 degrees and twice as large, seen from
 * the camera turned and scaled the same way, draws it again too. */
static void instances_place_the_billboard(void **state)
{
    suite *s = need_both(state);
    shot p = {0};
    bake_both(s, &kinds[2], &p.gl, &p.vk);
    float dx = 0.2f * (s->hi[0] - s->lo[0]);
    xyl_forest_instance inst[2];
    xyl_forest_instance_values iv = {{0.0f, 0.0f, 0.0f}, 0.0f, 1.0f, 0, XYL_FOREST_LOD_BILLBOARD};
    xyl_diag d = {0};
    expect(xyl_forest_instance_pack(&iv, &inst[0], &d), XYL_OK, &d);
    iv.position[0] = dx;
    expect(xyl_forest_instance_pack(&iv, &inst[1], &d), XYL_OK, &d);
    /* the caller's buffer */
    app *a = &s->a;
    VkBuffer buf;
    VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = sizeof inst;
    bi.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    vk_ok(vkCreateBuffer(a->device, &bi, NULL, &buf), "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(a->device, buf, &req);
    VkDeviceMemory mem = memory_for(a, req, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                                VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    vk_ok(vkBindBufferMemory(a->device, buf, mem, 0), "vkBindBufferMemory");
    void *map;
    vk_ok(vkMapMemory(a->device, mem, 0, VK_WHOLE_SIZE, 0, &map), "vkMapMemory");
    memcpy(map, inst, sizeof inst);
    vkUnmapMemory(a->device, mem);
    expect(xyl_billboard_vk_set_instances(p.vk, buf, sizeof inst, &d), XYL_OK, &d);
    uint8_t *own = malloc(4 * SIDE * SIDE), *at0 = malloc(4 * SIDE * SIDE),
            *at1 = malloc(4 * SIDE * SIDE), *moved = malloc(4 * SIDE * SIDE);
    assert_true(own && at0 && at1 && moved);
    frame_camera(s, 0.4f, 0.3f, &p);
    vk_picture(s, &p, own);
    p.instances = true, p.first = 0, p.count = 1;
    vk_picture(s, &p, at0);
    p.first = 1;
    vk_picture(s, &p, at1); /* the moved instance from the unmoved camera */
    p.cam.eye[0] += dx, p.cam.target[0] += dx;
    vk_picture(s, &p, moved);
    keep_png("instance_0", at0);
    keep_png("instance_1_moved_camera", moved);
    double colour, coverage, other_colour, other_coverage;
    size_t covered, other_covered;
    block_rmse(own, moved, &colour, &coverage, &covered);
    block_rmse(own, at1, &other_colour, &other_coverage, &other_covered);
    print_message("instance moved with the camera: colour RMSE %.4f, coverage RMSE %.4f; "
                  "from the unmoved camera %.4f, %.4f\n", colour, coverage, other_colour,
                  other_coverage);
    assert_memory_equal(own, at0, 4 * SIDE * SIDE);
    assert_true(covered > SIDE * SIDE / 50);
    assert_true(colour <= 0.01 && coverage <= 0.03);
    assert_true(other_coverage > 3.0 * coverage + 0.05);
    /* turned by 45 degrees (128 of 1024 steps) and twice as large, seen from the camera turned
     * and scaled the same way about the base point: the billboard's own picture again */
    iv.position[0] = 0.0f, iv.rotation = 3.14159265358979f / 4.0f, iv.scale = 2.0f;
    expect(xyl_forest_instance_pack(&iv, &inst[1], &d), XYL_OK, &d);
    vk_ok(vkMapMemory(a->device, mem, 0, VK_WHOLE_SIZE, 0, &map), "vkMapMemory");
    memcpy(map, inst, sizeof inst);
    vkUnmapMemory(a->device, mem);
    frame_camera(s, 0.4f, 0.3f, &p);
    const float c = cosf(iv.rotation), sn = sinf(iv.rotation);
    float *pts[2] = {p.cam.eye, p.cam.target};
    for (int k = 0; k < 2; ++k) {
        float x = pts[k][0], z = pts[k][2];
        pts[k][0] = 2.0f * (c * x + sn * z), pts[k][1] *= 2.0f, pts[k][2] = 2.0f * (-sn * x + c * z);
    }
    p.cam.near_plane *= 2.0f, p.cam.far_plane *= 2.0f;
    vk_picture(s, &p, moved);
    keep_png("instance_turned_scaled", moved);
    block_rmse(own, moved, &colour, &coverage, &covered);
    print_message("instance turned and scaled with the camera: colour RMSE %.4f, coverage RMSE "
                  "%.4f\n", colour, coverage);
    assert_true(colour <= 0.01 && coverage <= 0.03);
    /* runs outside the bound instances, and no instances on an impostor */
    xyl_billboard_vk_frame fr = {0};
    fr.view_proj[0] = 1.0f;
    VkCommandBuffer cb = (VkCommandBuffer)(uintptr_t)1; /* refused before any Vulkan call */
    expect(xyl_billboard_vk_cmd_draw_instances(p.vk, cb, &fr, 1, 2, &d), XYL_ERR_INVALID_ARGUMENT,
           &d);
    expect(xyl_billboard_vk_cmd_draw_instances(p.vk, cb, &fr, 0, 0, &d), XYL_ERR_INVALID_ARGUMENT,
           &d);
    expect(xyl_billboard_vk_set_instances(p.vk, buf, 24, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_vk_set_instances(p.vk, VK_NULL_HANDLE, 32, &d), XYL_ERR_INVALID_ARGUMENT,
           &d);
    free(own);
    free(at0);
    free(at1);
    free(moved);
    xyl_billboard_gl_destroy(p.gl);
    xyl_billboard_vk_destroy(p.vk);
    vkDestroyBuffer(a->device, buf, NULL);
    vkFreeMemory(a->device, mem, NULL);
    no_messages(s);
}

/* A 4-sample pass resolving into the application's colour image (left in TRANSFER_SRC for
 * the copy), with its own multisampled colour and depth. */
typedef struct msaa_target {
    VkRenderPass pass;
    VkImage image[2];
    VkDeviceMemory memory[2];
    VkImageView view[2];
    VkFramebuffer framebuffer;
} msaa_target;

static void msaa_make(app *a, msaa_target *m)
{
    VkAttachmentDescription att[3];
    memset(att, 0, sizeof att);
    const VkFormat formats[3] = {COLOR_FORMAT, DEPTH_FORMAT, COLOR_FORMAT};
    for (int k = 0; k < 3; ++k) {
        att[k].format = formats[k];
        att[k].samples = k == 2 ? VK_SAMPLE_COUNT_1_BIT : VK_SAMPLE_COUNT_4_BIT;
        att[k].loadOp = k == 2 ? VK_ATTACHMENT_LOAD_OP_DONT_CARE : VK_ATTACHMENT_LOAD_OP_CLEAR;
        att[k].storeOp = k == 2 ? VK_ATTACHMENT_STORE_OP_STORE : VK_ATTACHMENT_STORE_OP_DONT_CARE;
        att[k].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        att[k].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        att[k].finalLayout = k == 1 ? VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL
                             : k == 2 ? VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
                                      : VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    }
    VkAttachmentReference color = {0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth = {1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkAttachmentReference resolve = {2, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub = {0};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.colorAttachmentCount = 1;
    sub.pColorAttachments = &color;
    sub.pResolveAttachments = &resolve;
    sub.pDepthStencilAttachment = &depth;
    VkSubpassDependency dep = {0, VK_SUBPASS_EXTERNAL,
                               VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                               VK_PIPELINE_STAGE_TRANSFER_BIT,
                               VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT,
                               0};
    VkRenderPassCreateInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    ri.attachmentCount = 3;
    ri.pAttachments = att;
    ri.subpassCount = 1;
    ri.pSubpasses = &sub;
    ri.dependencyCount = 1;
    ri.pDependencies = &dep;
    vk_ok(vkCreateRenderPass(a->device, &ri, NULL, &m->pass), "vkCreateRenderPass");
    for (int k = 0; k < 2; ++k) {
        VkImageCreateInfo ii = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
        ii.imageType = VK_IMAGE_TYPE_2D;
        ii.format = formats[k];
        ii.extent = (VkExtent3D){SIDE, SIDE, 1};
        ii.mipLevels = ii.arrayLayers = 1;
        ii.samples = VK_SAMPLE_COUNT_4_BIT;
        ii.usage = k ? VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT
                     : VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
        vk_ok(vkCreateImage(a->device, &ii, NULL, &m->image[k]), "vkCreateImage");
        VkMemoryRequirements req;
        vkGetImageMemoryRequirements(a->device, m->image[k], &req);
        m->memory[k] = memory_for(a, req, 0);
        vk_ok(vkBindImageMemory(a->device, m->image[k], m->memory[k], 0), "vkBindImageMemory");
        VkImageViewCreateInfo vi = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
        vi.image = m->image[k];
        vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
        vi.format = formats[k];
        vi.subresourceRange.aspectMask = k ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
        vi.subresourceRange.levelCount = vi.subresourceRange.layerCount = 1;
        vk_ok(vkCreateImageView(a->device, &vi, NULL, &m->view[k]), "vkCreateImageView");
    }
    VkImageView views[3] = {m->view[0], m->view[1], a->view[0]};
    VkFramebufferCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fi.renderPass = m->pass;
    fi.attachmentCount = 3;
    fi.pAttachments = views;
    fi.width = fi.height = SIDE;
    fi.layers = 1;
    vk_ok(vkCreateFramebuffer(a->device, &fi, NULL, &m->framebuffer), "vkCreateFramebuffer");
}

static void msaa_free(app *a, msaa_target *m)
{
    vkDestroyFramebuffer(a->device, m->framebuffer, NULL);
    for (int k = 0; k < 2; ++k) {
        vkDestroyImageView(a->device, m->view[k], NULL);
        vkDestroyImage(a->device, m->image[k], NULL);
        vkFreeMemory(a->device, m->memory[k], NULL);
    }
    vkDestroyRenderPass(a->device, m->pass, NULL);
}

/* Into 4 samples the billboard's filtered coverage goes to alpha-to-coverage: each kind drawn
 * into a multisampled Vulkan pass (resolved) is GL's multisampled picture (alpha-to-coverage
 * and alpha-to-one there) within MSAA_COLOUR_RMSE over every pixel, against an opaque
 * background; the bake itself stays single-sampled. */
#define MSAA_COLOUR_RMSE 0.02
static void multisampled_draws_as_on_gl(void **state)
{
    suite *s = need_both(state);
    msaa_target m;
    memset(&m, 0, sizeof m);
    msaa_make(&s->a, &m);
    uint8_t *g = malloc(4 * SIDE * SIDE), *v = malloc(4 * SIDE * SIDE);
    assert_true(g && v);
    for (int k = 0; k < 4; ++k) {
        xyl_diag d = {0};
        shot p = {0};
        xyl_billboard_gl_desc gd = gl_desc(s, &kinds[k]);
        xyl_billboard_vk_desc vd = vk_desc(s, &kinds[k]);
        vd.render_pass = m.pass;
        vd.samples = VK_SAMPLE_COUNT_4_BIT;
        expect(xyl_billboard_gl_bake(&gd, gl_draw_leaves, s, &p.gl, &d), XYL_OK, &d);
        expect(xyl_billboard_vk_bake(&vd, vk_draw_leaves, s, &p.vk, &d), XYL_OK, &d);
        frame_camera(s, 0.52f, 0.35f, &p);
        p.msaa = true, p.pass = m.pass, p.framebuffer = m.framebuffer;
        gl_picture(s, &p, g);
        vk_picture(s, &p, v);
        char name[64];
        snprintf(name, sizeof name, "msaa_%s_gl", kinds[k].name);
        keep_png(name, g);
        snprintf(name, sizeof name, "msaa_%s_vk", kinds[k].name);
        keep_png(name, v);
        double rmse = colour_rmse(g, v);
        size_t shown = 0;
        for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i)
            shown += abs(v[4 * i + 1] - (int)lrintf(msaa_background[1] * 255.0f)) > 8;
        print_message("%s, 4 samples: colour RMSE against GL %.4f, %zu pixels off the "
                      "background\n", kinds[k].name, rmse, shown);
        assert_true(shown > SIDE * SIDE / 50);
        assert_true(rmse <= MSAA_COLOUR_RMSE);
        xyl_billboard_gl_destroy(p.gl);
        xyl_billboard_vk_destroy(p.vk);
    }
    free(g);
    free(v);
    msaa_free(&s->a, &m);
    no_messages(s);
}

/* A billboard made for dynamic rendering (Vulkan 1.3: no render pass, the colour and depth
 * formats) draws, inside vkCmdBeginRendering on the application's images, the picture the
 * render pass's billboard draws, byte for byte. */
static void dynamic_rendering_draws_what_the_pass_draws(void **state)
{
    suite *s = need_both(state);
    if (!s->a.dynamic_rendering) {
        print_message("skipped: no Vulkan 1.3 dynamic rendering\n");
        skip();
    }
    uint8_t *pass = malloc(4 * SIDE * SIDE), *dyn = malloc(4 * SIDE * SIDE);
    assert_true(pass && dyn);
    for (int k = 2; k < 4; ++k) {
        xyl_diag d = {0};
        shot p = {0};
        xyl_billboard_vk_desc vd = vk_desc(s, &kinds[k]);
        expect(xyl_billboard_vk_bake(&vd, vk_draw_leaves, s, &p.vk, &d), XYL_OK, &d);
        frame_camera(s, 0.52f, 0.35f, &p);
        vk_picture(s, &p, pass);
        xyl_billboard_vk_destroy(p.vk);
        vd.render_pass = VK_NULL_HANDLE;
        vd.color_format = COLOR_FORMAT;
        vd.depth_format = DEPTH_FORMAT;
        expect(xyl_billboard_vk_bake(&vd, vk_draw_leaves, s, &p.vk, &d), XYL_OK, &d);
        p.dynamic = true;
        vk_picture(s, &p, dyn);
        size_t covered = 0;
        for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i) covered += dyn[4 * i + 3] > 0;
        print_message("%s: %zu pixels covered with dynamic rendering\n", kinds[k].name, covered);
        assert_true(covered > SIDE * SIDE / 50);
        assert_memory_equal(pass, dyn, 4 * SIDE * SIDE);
        xyl_billboard_vk_destroy(p.vk);
    }
    free(pass);
    free(dyn);
    no_messages(s);
}

static void bad_input_gets_result_codes(void **state)
{
    suite *s = need_both(state);
    xyl_diag d = {0};
    xyl_billboard_vk *bb = NULL;
    xyl_billboard_vk_desc good = vk_desc(s, &kinds[2]);
    xyl_billboard_vk_desc bd = good;
    expect(xyl_billboard_vk_bake(NULL, vk_draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_vk_bake(&bd, NULL, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd.device = VK_NULL_HANDLE;
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd = good, bd.render_pass = VK_NULL_HANDLE;
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd = good, bd.samples = (VkSampleCountFlagBits)3;
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd = good, bd.kind = (xyl_billboard_kind)7;
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_non_null(strstr(d.message, "kind"));
    bd = good, bd.planes = 9;
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd = good, bd.resolution = 4;
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd = good, bd.grid = 4; /* a grid on a cross */
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd = vk_desc(s, &kinds[3]), bd.grid = 33;
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd = vk_desc(s, &kinds[3]), bd.grid = 32, bd.resolution = 1024; /* a 32768-texel atlas */
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd = good, bd.hi[1] = bd.lo[1];
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd = good, bd.lo[0] = NAN;
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_NON_FINITE, &d);
    bd = good, bd.light_dir[2] = INFINITY;
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_NON_FINITE, &d);
    bd = good, bd.queue_family = 99;
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_UNSUPPORTED, &d);
    assert_null(bb);
    /* the callback's error comes back as it is, and nothing is left */
    s->fail_with = XYL_ERR_LIMIT_EXCEEDED;
    expect(xyl_billboard_vk_bake(&good, vk_draw_leaves, s, &bb, &d), XYL_ERR_LIMIT_EXCEEDED, &d);
    assert_null(bb);
    s->fail_with = XYL_OK;
    expect(xyl_billboard_vk_bake(&good, vk_draw_leaves, s, &bb, &d), XYL_OK, &d);
    uint8_t *rgba = malloc(4 * SIDE * SIDE);
    assert_non_null(rgba);
    expect(xyl_billboard_vk_read_view(bb, 4, false, rgba, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_vk_read_view(NULL, 0, false, rgba, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_vk_read_view(bb, 0, false, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    free(rgba);
    /* draws refused before any Vulkan call: the command buffer is never touched */
    VkCommandBuffer cb = (VkCommandBuffer)(uintptr_t)1;
    xyl_billboard_vk_frame fr = {0};
    expect(xyl_billboard_vk_cmd_draw(bb, cb, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    fr.view_proj[0] = 1.0f;
    expect(xyl_billboard_vk_cmd_draw(NULL, cb, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_vk_cmd_draw(bb, VK_NULL_HANDLE, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_vk_cmd_draw(bb, cb, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    fr.view_proj[5] = NAN;
    expect(xyl_billboard_vk_cmd_draw(bb, cb, &fr, &d), XYL_ERR_NON_FINITE, &d);
    fr.view_proj[5] = 1.0f, fr.alpha_cutoff = 2.0f;
    expect(xyl_billboard_vk_cmd_draw(bb, cb, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    fr.alpha_cutoff = 0.0f, fr.dither[0] = 0.6f, fr.dither[1] = 0.2f;
    expect(xyl_billboard_vk_cmd_draw(bb, cb, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    fr.dither[1] = 0.8f, fr.eye[1] = INFINITY;
    expect(xyl_billboard_vk_cmd_draw(bb, cb, &fr, &d), XYL_ERR_NON_FINITE, &d);
    fr.eye[1] = 0.0f;
    expect(xyl_billboard_vk_cmd_draw_instances(bb, cb, &fr, 0, 1, &d), XYL_ERR_INVALID_ARGUMENT,
           &d); /* no instances bound */
    assert_int_equal(xyl_billboard_vk_view_count(NULL), 0);
    assert_int_equal(xyl_billboard_vk_view_count(bb), 4);
    xyl_billboard_vk_destroy(bb);
    xyl_billboard_vk_destroy(NULL);
    /* an impostor has no instanced draw */
    bd = vk_desc(s, &kinds[3]);
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_OK, &d);
    VkBuffer any = (VkBuffer)(uintptr_t)1;
    expect(xyl_billboard_vk_set_instances(bb, any, 32, &d), XYL_ERR_UNSUPPORTED, &d);
    xyl_billboard_vk_destroy(bb);
    no_messages(s);
}

/* Every host allocation of a bake, the driver's included, goes through the caller's
 * allocator: a failure at any of the first 12 allocations, or at every 8th up to the 44th,
 * is XYL_ERR_OUT_OF_MEMORY with nothing left allocated (nor on the device: the validation layer reports objects left at the end),
 * and a billboard baked and destroyed frees all it took. */
static void bake_allocates_through_the_callers_allocator(void **state)
{
    suite *s = need_both(state);
    xyl_diag d = {0};
    tu_counter c = {0, 0, 0, 0};
    xyl_billboard_vk_desc bd = vk_desc(s, &kinds[2]);
    bd.alloc = tu_counting(&c);
    xyl_billboard_vk *bb = NULL;
    expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_OK, &d);
    size_t total = c.attempts;
    xyl_billboard_vk_destroy(bb);
    print_message("%zu allocations through the caller's allocator\n", c.allocs);
    assert_true(c.allocs > 10); /* the driver's too */
    assert_int_equal(c.allocs, c.frees);
    s->a.expect_oom = true;
    /* the first 12, then every 8th up to the 44th: the device checks, shader modules, layouts,
     * images. Not later: lavapipe (Mesa 22) itself fails on its own out-of-memory paths, with
     * libc's free() on a block of the caller's allocator at the 52nd of 446 (a pipeline), and
     * in vkCmdPipelineBarrier after a failed allocation while recording at the 137th */
    for (size_t i = 1; i <= 16; ++i) {
        size_t k = i <= 12 ? i : 12 + 8 * (i - 12);
        c = (tu_counter){0, 0, 0, k};
        if (getenv("XYL_TEST_VK_VERBOSE")) fprintf(stderr, "failing allocation %zu of %zu\n", k, total);
        bb = (xyl_billboard_vk *)(uintptr_t)1;
        expect(xyl_billboard_vk_bake(&bd, vk_draw_leaves, s, &bb, &d), XYL_ERR_OUT_OF_MEMORY,
               &d);
        assert_ptr_equal(bb, (xyl_billboard_vk *)(uintptr_t)1);
        assert_int_equal(c.allocs, c.frees);
    }
    s->a.expect_oom = false;
    print_message("%u reports of the injected failures\n", s->a.oom_messages);
    assert_true(total > 44);
    no_messages(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(baked_views_read_back_as_on_gl),
        cmocka_unit_test(each_kind_draws_as_on_gl),
        cmocka_unit_test(impostor_error_is_gls),
        cmocka_unit_test(dither_ranges_split_the_pixels),
        cmocka_unit_test(instances_place_the_billboard),
        cmocka_unit_test(multisampled_draws_as_on_gl),
        cmocka_unit_test(dynamic_rendering_draws_what_the_pass_draws),
        cmocka_unit_test(bad_input_gets_result_codes),
        cmocka_unit_test(bake_allocates_through_the_callers_allocator),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

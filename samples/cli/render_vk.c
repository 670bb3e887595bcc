/* The CLI as a Vulkan application: its instance, device, render pass and target, with xylem's
 * stems and leaves recorded into its command buffer between its own begin and end of the pass
 * (render_vk.h). */
#include "render_vk.h"

#include <stdio.h>
#include <string.h>

#include <time.h>

#include <xylem/xyl_billboard_vk.h>
#include <xylem/xyl_foliage_vk.h>
#include <xylem/xyl_tess_vk.h>

#define COLOR_FORMAT VK_FORMAT_R8G8B8A8_UNORM
#define DEPTH_FORMAT VK_FORMAT_D32_SFLOAT

typedef struct app {
    VkInstance instance;
    VkPhysicalDevice physical;
    VkPhysicalDeviceFeatures features;
    VkDevice device;
    uint32_t family;
    VkQueue queue;
    VkCommandPool pool;
    VkRenderPass pass;
    VkImage image[3];          /* colour, depth, resolve (with samples > 1) */
    VkDeviceMemory memory[4];  /* and the readback buffer's */
    VkImageView view[3];
    VkFramebuffer framebuffer;
    VkBuffer readback;
    VkQueryPool timer;   /* two timestamps around the pass; none where the queue lacks them */
    double tick_ns;
    uint32_t width, height;
    VkSampleCountFlagBits samples;
} app;

static xyl_result fail(xyl_diag *d, VkResult r, const char *what)
{
    snprintf(d->message, sizeof d->message, "%s failed (VkResult %d)", what, (int)r);
    return r == VK_ERROR_OUT_OF_HOST_MEMORY || r == VK_ERROR_OUT_OF_DEVICE_MEMORY
               ? XYL_ERR_OUT_OF_MEMORY
               : XYL_ERR_UNSUPPORTED;
}

#define TRY(call, what)                                                                        \
    do {                                                                                       \
        VkResult vr_ = (call);                                                                 \
        if (vr_ != VK_SUCCESS) return fail(d, vr_, what);                                      \
    } while (0)

/* The first Vulkan 1.2 device with a graphics queue and drawIndirectFirstInstance. */
static xyl_result open_device(app *a, char *name, xyl_diag *d)
{
    VkApplicationInfo ai = {.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO};
    ai.pApplicationName = "xylem";
    ai.apiVersion = VK_API_VERSION_1_2;
    VkInstanceCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ci.pApplicationInfo = &ai;
    TRY(vkCreateInstance(&ci, NULL, &a->instance), "vkCreateInstance");
    VkPhysicalDevice devs[8];
    uint32_t n = 8;
    VkResult vr = vkEnumeratePhysicalDevices(a->instance, &n, devs);
    if (vr != VK_SUCCESS && vr != VK_INCOMPLETE) return fail(d, vr, "vkEnumeratePhysicalDevices");
    for (uint32_t i = 0; i < n && !a->physical; ++i) {
        VkPhysicalDeviceProperties p;
        VkPhysicalDeviceFeatures f;
        vkGetPhysicalDeviceProperties(devs[i], &p);
        vkGetPhysicalDeviceFeatures(devs[i], &f);
        VkQueueFamilyProperties q[16];
        uint32_t nq = 16;
        vkGetPhysicalDeviceQueueFamilyProperties(devs[i], &nq, q);
        uint32_t fam = 0;
        while (fam < nq && !(q[fam].queueFlags & VK_QUEUE_GRAPHICS_BIT)) ++fam;
        if (p.apiVersion < VK_API_VERSION_1_2 || !f.drawIndirectFirstInstance || fam == nq)
            continue;
        a->physical = devs[i];
        a->family = fam;
        if (q[fam].timestampValidBits > 0) a->tick_ns = p.limits.timestampPeriod;
        snprintf(name, 256, "%s", p.deviceName);
        a->features.drawIndirectFirstInstance = VK_TRUE;
        a->features.multiDrawIndirect = f.multiDrawIndirect;
        a->features.fillModeNonSolid = f.fillModeNonSolid;
        a->features.alphaToOne = f.alphaToOne; /* the billboard's alpha-to-coverage */
    }
    if (!a->physical) {
        snprintf(d->message, sizeof d->message,
                 "no Vulkan 1.2 device with a graphics queue and drawIndirectFirstInstance");
        return XYL_ERR_UNSUPPORTED;
    }
    float priority = 1.0f;
    VkDeviceQueueCreateInfo qi = {.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qi.queueFamilyIndex = a->family;
    qi.queueCount = 1;
    qi.pQueuePriorities = &priority;
    VkDeviceCreateInfo di = {.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    di.queueCreateInfoCount = 1;
    di.pQueueCreateInfos = &qi;
    di.pEnabledFeatures = &a->features;
    TRY(vkCreateDevice(a->physical, &di, NULL, &a->device), "vkCreateDevice");
    vkGetDeviceQueue(a->device, a->family, 0, &a->queue);
    VkCommandPoolCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pi.queueFamilyIndex = a->family;
    TRY(vkCreateCommandPool(a->device, &pi, NULL, &a->pool), "vkCreateCommandPool");
    if (a->tick_ns > 0.0) {
        VkQueryPoolCreateInfo qp = {.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
        qp.queryType = VK_QUERY_TYPE_TIMESTAMP;
        qp.queryCount = 2;
        TRY(vkCreateQueryPool(a->device, &qp, NULL, &a->timer), "vkCreateQueryPool");
    }
    return XYL_OK;
}

/* Colour and depth cleared; with samples the colour resolves into a third attachment. The image
 * read back ends in TRANSFER_SRC layout. */
static xyl_result make_pass(app *a, xyl_diag *d)
{
    bool msaa = a->samples != VK_SAMPLE_COUNT_1_BIT;
    VkAttachmentDescription att[3];
    memset(att, 0, sizeof att);
    const VkFormat formats[3] = {COLOR_FORMAT, DEPTH_FORMAT, COLOR_FORMAT};
    for (int k = 0; k < 3; ++k) {
        att[k].format = formats[k];
        att[k].samples = k == 2 ? VK_SAMPLE_COUNT_1_BIT : a->samples;
        att[k].loadOp = k == 2 ? VK_ATTACHMENT_LOAD_OP_DONT_CARE : VK_ATTACHMENT_LOAD_OP_CLEAR;
        att[k].storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        att[k].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        att[k].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        att[k].finalLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    }
    att[1].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    VkAttachmentDescription *shown = msaa ? &att[2] : &att[0];
    shown->storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    shown->finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    VkAttachmentReference color = {0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth = {1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkAttachmentReference resolve = {2, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub = {0};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.colorAttachmentCount = 1;
    sub.pColorAttachments = &color;
    sub.pResolveAttachments = msaa ? &resolve : NULL;
    sub.pDepthStencilAttachment = &depth;
    VkSubpassDependency dep = {0, VK_SUBPASS_EXTERNAL,
                               VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                               VK_PIPELINE_STAGE_TRANSFER_BIT,
                               VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT,
                               0};
    VkRenderPassCreateInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    ri.attachmentCount = msaa ? 3 : 2;
    ri.pAttachments = att;
    ri.subpassCount = 1;
    ri.pSubpasses = &sub;
    ri.dependencyCount = 1;
    ri.pDependencies = &dep;
    TRY(vkCreateRenderPass(a->device, &ri, NULL, &a->pass), "vkCreateRenderPass");
    return XYL_OK;
}

static xyl_result memory_for(const app *a, VkMemoryRequirements req, VkMemoryPropertyFlags need,
                             VkDeviceMemory *out, xyl_diag *d)
{
    VkPhysicalDeviceMemoryProperties mp;
    vkGetPhysicalDeviceMemoryProperties(a->physical, &mp);
    uint32_t type = 0;
    while (type < mp.memoryTypeCount && (!(req.memoryTypeBits & (1u << type)) ||
                                         (mp.memoryTypes[type].propertyFlags & need) != need))
        ++type;
    if (type == mp.memoryTypeCount) {
        snprintf(d->message, sizeof d->message, "no fitting Vulkan memory type");
        return XYL_ERR_UNSUPPORTED;
    }
    VkMemoryAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = type;
    TRY(vkAllocateMemory(a->device, &ai, NULL, out), "vkAllocateMemory");
    return XYL_OK;
}

static xyl_result make_image(app *a, int k, xyl_diag *d)
{
    const VkFormat format = k == 1 ? DEPTH_FORMAT : COLOR_FORMAT;
    bool shown = k == (a->samples != VK_SAMPLE_COUNT_1_BIT ? 2 : 0);
    VkImageCreateInfo ii = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ii.imageType = VK_IMAGE_TYPE_2D;
    ii.format = format;
    ii.extent = (VkExtent3D){a->width, a->height, 1};
    ii.mipLevels = ii.arrayLayers = 1;
    ii.samples = k == 2 ? VK_SAMPLE_COUNT_1_BIT : a->samples;
    ii.usage = (k == 1 ? VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT
                       : VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT) |
               (shown ? VK_IMAGE_USAGE_TRANSFER_SRC_BIT : 0);
    TRY(vkCreateImage(a->device, &ii, NULL, &a->image[k]), "vkCreateImage");
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(a->device, a->image[k], &req);
    xyl_result r = memory_for(a, req, 0, &a->memory[k], d);
    if (r != XYL_OK) return r;
    TRY(vkBindImageMemory(a->device, a->image[k], a->memory[k], 0), "vkBindImageMemory");
    VkImageViewCreateInfo vi = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = a->image[k];
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = format;
    vi.subresourceRange.aspectMask = k == 1 ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
    vi.subresourceRange.levelCount = vi.subresourceRange.layerCount = 1;
    TRY(vkCreateImageView(a->device, &vi, NULL, &a->view[k]), "vkCreateImageView");
    return XYL_OK;
}

static xyl_result make_target(app *a, xyl_diag *d)
{
    int images = a->samples != VK_SAMPLE_COUNT_1_BIT ? 3 : 2;
    xyl_result r = XYL_OK;
    for (int k = 0; k < images && r == XYL_OK; ++k) r = make_image(a, k, d);
    if (r != XYL_OK) return r;
    VkFramebufferCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fi.renderPass = a->pass;
    fi.attachmentCount = (uint32_t)images;
    fi.pAttachments = a->view;
    fi.width = a->width;
    fi.height = a->height;
    fi.layers = 1;
    TRY(vkCreateFramebuffer(a->device, &fi, NULL, &a->framebuffer), "vkCreateFramebuffer");
    VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = 4u * (VkDeviceSize)a->width * a->height;
    bi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    TRY(vkCreateBuffer(a->device, &bi, NULL, &a->readback), "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(a->device, a->readback, &req);
    r = memory_for(a, req, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                               VK_MEMORY_PROPERTY_HOST_COHERENT_BIT, &a->memory[3], d);
    if (r != XYL_OK) return r;
    TRY(vkBindBufferMemory(a->device, a->readback, a->memory[3], 0), "vkBindBufferMemory");
    return XYL_OK;
}

static void close_app(app *a)
{
    if (a->device) {
        vkDeviceWaitIdle(a->device);
        if (a->readback) vkDestroyBuffer(a->device, a->readback, NULL);
        if (a->framebuffer) vkDestroyFramebuffer(a->device, a->framebuffer, NULL);
        for (int k = 0; k < 3; ++k) {
            if (a->view[k]) vkDestroyImageView(a->device, a->view[k], NULL);
            if (a->image[k]) vkDestroyImage(a->device, a->image[k], NULL);
        }
        for (int k = 0; k < 4; ++k)
            if (a->memory[k]) vkFreeMemory(a->device, a->memory[k], NULL);
        if (a->pass) vkDestroyRenderPass(a->device, a->pass, NULL);
        if (a->timer) vkDestroyQueryPool(a->device, a->timer, NULL);
        if (a->pool) vkDestroyCommandPool(a->device, a->pool, NULL);
        vkDestroyDevice(a->device, NULL);
    }
    if (a->instance) vkDestroyInstance(a->instance, NULL);
}

/* Records stems then leaves with this matrix and light into cb, inside a render pass. */
static xyl_result record_tree(VkCommandBuffer cb, xyl_tess_vk *stems, xyl_foliage_vk *leaves,
                              const xyl_cli_vk_tree *t, const float view_proj[16],
                              const float light[3], bool wireframe, xyl_diag *d)
{
    xyl_tess_frame sf = t->frame;
    memcpy(sf.view_proj, view_proj, sizeof sf.view_proj);
    memcpy(sf.light_dir, light, 3 * sizeof *light);
    if (wireframe) sf.flags |= XYL_TESS_FLAG_WIREFRAME;
    xyl_result r = xyl_tess_vk_cmd_draw(stems, cb, 0, t->batches, &sf, d);
    xyl_foliage_vk_frame lf = {0};
    memcpy(lf.view_proj, view_proj, sizeof lf.view_proj);
    memcpy(lf.light_dir, light, sizeof lf.light_dir);
    lf.color[0] = lf.color[1] = lf.color[2] = lf.color[3] = 1.0f; /* the texture's own */
    if (r == XYL_OK && t->lods)
        r = xyl_foliage_vk_cmd_draw(leaves, cb, &lf, t->lods, t->foliage->sector_count, d);
    else if (r == XYL_OK)
        r = xyl_foliage_vk_cmd_draw_cut(leaves, cb, &lf, d);
    return r;
}

/* The frame: the pass, stems then leaves (or the billboard), the copy of the shown image to
 * host memory. */
static xyl_result record(const app *a, VkCommandBuffer cb, xyl_tess_vk *stems,
                         xyl_foliage_vk *leaves, xyl_billboard_vk *bb, const xyl_cli_vk_tree *t,
                         xyl_diag *d)
{
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    TRY(vkBeginCommandBuffer(cb, &bi), "vkBeginCommandBuffer");
    if (a->timer) {
        vkCmdResetQueryPool(cb, a->timer, 0, 2);
        vkCmdWriteTimestamp(cb, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, a->timer, 0);
    }
    xyl_result r = XYL_OK;
    if (!bb && !t->lods) r = xyl_foliage_vk_cmd_cut(leaves, cb, t->cut_view, d); /* outside */
    VkClearValue clear[3];
    memset(clear, 0, sizeof clear);
    memcpy(clear[0].color.float32, t->image->background, sizeof clear[0].color.float32);
    clear[1].depthStencil.depth = 1.0f;
    VkRenderPassBeginInfo rb = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rb.renderPass = a->pass;
    rb.framebuffer = a->framebuffer;
    rb.renderArea.extent = (VkExtent2D){a->width, a->height};
    rb.clearValueCount = 3;
    rb.pClearValues = clear;
    vkCmdBeginRenderPass(cb, &rb, VK_SUBPASS_CONTENTS_INLINE);
    VkViewport vp = {0.0f, 0.0f, (float)a->width, (float)a->height, 0.0f, 1.0f};
    VkRect2D sc = {{0, 0}, {a->width, a->height}};
    vkCmdSetViewport(cb, 0, 1, &vp);
    vkCmdSetScissor(cb, 0, 1, &sc);
    if (r == XYL_OK && bb) {
        xyl_billboard_vk_frame bf = {0};
        memcpy(bf.view_proj, t->frame.view_proj, sizeof bf.view_proj);
        memcpy(bf.eye, t->billboard->eye, sizeof bf.eye);
        memcpy(bf.light_dir, t->frame.light_dir, sizeof bf.light_dir);
        r = xyl_billboard_vk_cmd_draw(bb, cb, &bf, d);
    } else if (r == XYL_OK) {
        r = record_tree(cb, stems, leaves, t, t->frame.view_proj, t->frame.light_dir,
                        t->image->wireframe, d);
    }
    vkCmdEndRenderPass(cb);
    if (a->timer) vkCmdWriteTimestamp(cb, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, a->timer, 1);
    VkBufferImageCopy copy = {0};
    copy.imageSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    copy.imageSubresource.layerCount = 1;
    copy.imageExtent = (VkExtent3D){a->width, a->height, 1};
    VkImage shown = a->image[a->samples != VK_SAMPLE_COUNT_1_BIT ? 2 : 0];
    vkCmdCopyImageToBuffer(cb, shown, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, a->readback, 1, &copy);
    VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb,
                         0, NULL, 0, NULL);
    VkResult vr = vkEndCommandBuffer(cb);
    if (r == XYL_OK && vr != VK_SUCCESS) r = fail(d, vr, "vkEndCommandBuffer");
    return r;
}

static xyl_result submit_and_read(const app *a, VkCommandBuffer cb, uint8_t *rgba,
                                  double *gpu_ms, xyl_diag *d)
{
    VkFenceCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    TRY(vkCreateFence(a->device, &fi, NULL, &fence), "vkCreateFence");
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cb;
    VkResult vr = vkQueueSubmit(a->queue, 1, &si, fence);
    if (vr == VK_SUCCESS) vr = vkWaitForFences(a->device, 1, &fence, VK_TRUE, UINT64_MAX);
    vkDestroyFence(a->device, fence, NULL);
    if (vr != VK_SUCCESS) return fail(d, vr, "submitting the frame");
    void *map = NULL;
    TRY(vkMapMemory(a->device, a->memory[3], 0, VK_WHOLE_SIZE, 0, &map), "vkMapMemory");
    memcpy(rgba, map, 4u * (size_t)a->width * a->height);
    vkUnmapMemory(a->device, a->memory[3]);
    uint64_t ticks[2];
    *gpu_ms = -1.0;
    if (a->timer && vkGetQueryPoolResults(a->device, a->timer, 0, 2, sizeof ticks, ticks,
                                          sizeof ticks[0], VK_QUERY_RESULT_64_BIT) == VK_SUCCESS)
        *gpu_ms = (double)(ticks[1] - ticks[0]) * a->tick_ns * 1e-6;
    return XYL_OK;
}

/* Stems and leaves renderers for this pass and sample count, the species uploaded. */
static xyl_result make_renderers(const app *a, const xyl_cli_vk_tree *t, VkRenderPass pass,
                                 VkSampleCountFlagBits samples, xyl_tess_vk **stems,
                                 xyl_foliage_vk **leaves, xyl_diag *d)
{
    xyl_tess_vk_device_desc sd = {0};
    sd.physical_device = a->physical;
    sd.device = a->device;
    sd.enabled_features = &a->features;
    sd.render_pass = pass;
    sd.samples = samples;
    sd.frames_in_flight = 1;
    xyl_foliage_vk_desc ld = {0};
    ld.physical_device = a->physical;
    ld.device = a->device;
    ld.queue = a->queue;
    ld.queue_family = a->family;
    ld.render_pass = pass;
    ld.samples = samples;
    ld.enabled_features = &a->features;
    xyl_result r = xyl_tess_vk_create_for_device(&sd, t->patterns, stems, d);
    if (r == XYL_OK) r = xyl_tess_vk_set_patches(*stems, t->patches, d);
    if (r == XYL_OK) r = xyl_foliage_vk_create(&ld, leaves, d);
    if (r == XYL_OK) r = xyl_foliage_vk_set_foliage(*leaves, t->foliage, d);
    if (r == XYL_OK)
        r = xyl_foliage_vk_set_texture(*leaves, t->leaf_texture, t->texture_width,
                                       t->texture_height, d);
    return r;
}

/* The billboard's bake: the tree drawn by renderers made, at the first view, for the bake's
 * own pass (one sample; the frame's may have more). */
typedef struct bake_tree {
    const app *a;
    const xyl_cli_vk_tree *t;
    xyl_tess_vk *stems;
    xyl_foliage_vk *leaves;
} bake_tree;

static xyl_result bake_draw(void *user, VkCommandBuffer cb, VkRenderPass pass,
                            const float view_proj[16], const float light[3], xyl_diag *d)
{
    bake_tree *b = user;
    xyl_result r = XYL_OK;
    if (!b->stems)
        r = make_renderers(b->a, b->t, pass, VK_SAMPLE_COUNT_1_BIT, &b->stems, &b->leaves, d);
    if (r == XYL_OK) r = record_tree(cb, b->stems, b->leaves, b->t, view_proj, light, false, d);
    return r;
}

static double seconds(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static xyl_result bake(const app *a, const xyl_cli_vk_tree *t, xyl_billboard_vk **bb,
                       xyl_diag *d)
{
    xyl_cli_vk_billboard *in = t->billboard;
    xyl_billboard_vk_desc bd = {0};
    bd.physical_device = a->physical;
    bd.device = a->device;
    bd.queue = a->queue;
    bd.queue_family = a->family;
    bd.render_pass = a->pass;
    bd.samples = a->samples;
    bd.enabled_features = &a->features;
    bd.kind = (xyl_billboard_kind)in->kind;
    bd.planes = in->planes;
    bd.grid = in->grid;
    bd.resolution = in->resolution;
    memcpy(bd.lo, in->lo, sizeof bd.lo);
    memcpy(bd.hi, in->hi, sizeof bd.hi);
    memcpy(bd.light_dir, t->frame.light_dir, sizeof bd.light_dir); /* the scene's light */
    bake_tree b = {a, t, NULL, NULL};
    double t0 = seconds();
    xyl_result r = xyl_billboard_vk_bake(&bd, bake_draw, &b, bb, d);
    in->bake_ms = (seconds() - t0) * 1e3;
    in->views = xyl_billboard_vk_view_count(*bb);
    vkDeviceWaitIdle(a->device);
    xyl_foliage_vk_destroy(b.leaves);
    xyl_tess_vk_destroy(b.stems);
    return r;
}

static xyl_result draw(app *a, const xyl_cli_vk_tree *t, uint8_t *rgba, double *gpu_ms,
                       xyl_diag *d)
{
    xyl_tess_vk *stems = NULL;
    xyl_foliage_vk *leaves = NULL;
    xyl_billboard_vk *bb = NULL;
    VkCommandBuffer cb = VK_NULL_HANDLE;
    xyl_result r = t->billboard ? bake(a, t, &bb, d)
                                : make_renderers(a, t, a->pass, a->samples, &stems, &leaves, d);
    if (r == XYL_OK) {
        VkCommandBufferAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        ai.commandPool = a->pool;
        ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
        ai.commandBufferCount = 1;
        VkResult vr = vkAllocateCommandBuffers(a->device, &ai, &cb);
        if (vr != VK_SUCCESS) r = fail(d, vr, "vkAllocateCommandBuffers");
    }
    if (r == XYL_OK) r = record(a, cb, stems, leaves, bb, t, d);
    if (r == XYL_OK) r = submit_and_read(a, cb, rgba, gpu_ms, d);
    if (r == XYL_OK && !bb && !t->lods)
        r = xyl_foliage_vk_last_cut(leaves, NULL, 0, t->cut_leaves, d);
    vkDeviceWaitIdle(a->device);
    if (cb) vkFreeCommandBuffers(a->device, a->pool, 1, &cb);
    xyl_billboard_vk_destroy(bb);
    xyl_foliage_vk_destroy(leaves);
    xyl_tess_vk_destroy(stems);
    return r;
}

xyl_result xyl_cli_render_vk_tree(const xyl_cli_vk_tree *t, uint8_t *rgba, char *device_name,
                                  double *gpu_ms, xyl_diag *d)
{
    app a;
    memset(&a, 0, sizeof a);
    a.width = t->image->width;
    a.height = t->image->height;
    a.samples = t->image->samples > 1 ? (VkSampleCountFlagBits)t->image->samples
                                      : VK_SAMPLE_COUNT_1_BIT;
    xyl_result r = open_device(&a, device_name, d);
    if (r == XYL_OK) {
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(a.physical, &p);
        VkSampleCountFlags offered =
            p.limits.framebufferColorSampleCounts & p.limits.framebufferDepthSampleCounts;
        if (!(offered & a.samples)) {
            snprintf(d->message, sizeof d->message, "%u samples asked, %.64s does not offer them",
                     (unsigned)a.samples, p.deviceName);
            r = XYL_ERR_UNSUPPORTED;
        }
    }
    if (r == XYL_OK) r = make_pass(&a, d);
    if (r == XYL_OK) r = make_target(&a, d);
    if (r == XYL_OK) r = draw(&a, t, rgba, gpu_ms, d);
    close_app(&a);
    return r;
}

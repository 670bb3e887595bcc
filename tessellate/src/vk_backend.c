/* The Vulkan 1.2 backend of tessellate/ (instanced path): the public calls, input checks and
 * command recording. Setup lives in vk_setup.c, passes and pipelines in vk_pipeline.c. Every call
 * records one command buffer, submits it and waits, so buffers are simply rewritten per call. */
#include <math.h>
#include <string.h>

#include "vk_internal.h"

#define BUF_VERTEX VK_BUFFER_USAGE_VERTEX_BUFFER_BIT
#define BUF_STORAGE VK_BUFFER_USAGE_STORAGE_BUFFER_BIT

static const xyl_tess_pattern_range *range_of(const xyl_tess_vk *vk, uint32_t kind,
                                              uint32_t level)
{
    return &vk->ranges[kind == XYL_TESS_KIND_QUAD ? 0 : 1][level];
}

/* ---- patterns ------------------------------------------------------------------------------ */

/* The draws index the pattern buffers with these ranges, so a caller-made patterns struct is
 * checked to stay inside its arrays before anything reaches the GPU. */
static bool range_ok(const xyl_tess_patterns *p, const xyl_tess_pattern_range *r, uint32_t level)
{
    if ((uint64_t)r->first_vertex + r->vertex_count > p->vertex_count ||
        (uint64_t)r->first_index + r->index_count > p->index_count || r->index_count % 3 != 0)
        return false;
    for (uint32_t k = 0; k < r->index_count; ++k)
        if (p->indices[r->first_index + k] >= r->vertex_count) return false;
    for (uint32_t v = 0; v < r->vertex_count; ++v) {
        uint32_t pk = p->vertices[r->first_vertex + v];
        if ((pk & 0xffu) > level || ((pk >> XYL_TESS_PATTERN_SHIFT_J) & 0xffu) > level ||
            (pk >> XYL_TESS_PATTERN_SHIFT_LOCAL) >= r->vertex_count)
            return false;
    }
    return true;
}

static xyl_result check_patterns(const xyl_tess_patterns *p, xyl_diag *diag)
{
    if (p->max_level < 1 || p->max_level > XYL_TESS_MAX_LEVEL || !p->vertices || !p->indices ||
        p->vertex_count > UINT32_MAX || p->index_count > UINT32_MAX)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "patterns: max level %u, arrays or sizes out of range", p->max_level);
    for (int k = 0; k < 2; ++k)
        for (uint32_t l = 1; l <= p->max_level; ++l)
            if (!range_ok(p, &p->ranges[k][l], l))
                return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, l,
                                 "patterns: the %s pattern of level %u leaves its arrays",
                                 k ? "triangle" : "quad", l);
    return XYL_OK;
}

static xyl_result upload_patterns(xyl_tess_vk *vk, const xyl_tess_patterns *p, xyl_diag *diag)
{
    xyl_result r = xyl__vk_buffer_reserve(vk, &vk->pattern_vertices,
                                          p->vertex_count * sizeof(uint32_t), BUF_VERTEX, diag);
    if (r == XYL_OK)
        r = xyl__vk_buffer_reserve(vk, &vk->pattern_indices, p->index_count * sizeof(uint32_t),
                                   VK_BUFFER_USAGE_INDEX_BUFFER_BIT, diag);
    if (r != XYL_OK) return r;
    memcpy(vk->pattern_vertices.map, p->vertices, p->vertex_count * sizeof(uint32_t));
    memcpy(vk->pattern_indices.map, p->indices, p->index_count * sizeof(uint32_t));
    memcpy(vk->ranges, p->ranges, sizeof vk->ranges);
    vk->max_level = p->max_level;
    vk->lattice = vk->pattern_vertices.map;
    return XYL_OK;
}

/* ---- create / destroy ---------------------------------------------------------------------- */

static xyl_result create_all(xyl_tess_vk *vk, const xyl_tess_vk_desc *desc,
                             const xyl_tess_patterns *patterns, xyl_diag *diag)
{
    xyl_result r = xyl__vk_create_instance(vk, desc && desc->validation, diag);
    if (r == XYL_OK) r = xyl__vk_pick_device(vk, desc ? desc->device_name : NULL, diag);
    if (r == XYL_OK) r = xyl__vk_create_device(vk, diag);
    if (r == XYL_OK) r = xyl__vk_create_pipelines(vk, diag);
    if (r == XYL_OK) r = upload_patterns(vk, patterns, diag);
    VkDeviceSize align = vk->props.limits.minUniformBufferOffsetAlignment;
    if (align < 1) align = 1;
    vk->frame_stride = (sizeof(xyl_tess_frame) + align - 1) / align * align;
    return r;
}

xyl_result xyl_tess_vk_create(const xyl_tess_vk_desc *desc, const xyl_tess_patterns *patterns,
                              xyl_tess_vk **out, xyl_diag *diag)
{
    if (!patterns || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "patterns and out are required");
    xyl_result r = check_patterns(patterns, diag);
    if (r != XYL_OK) return r;
    xyl_tess_vk *vk = xyl__calloc(NULL, 1, sizeof *vk);
    if (!vk) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    vk->gpu_ms = -1.0;
    r = create_all(vk, desc, patterns, diag);
    if (r != XYL_OK) {
        xyl_tess_vk_destroy(vk);
        return r;
    }
    *out = vk;
    xyl__diag_ok(diag);
    return XYL_OK;
}

static void destroy_buffers(xyl_tess_vk *vk)
{
    xyl__vk_buffer *all[] = {&vk->pattern_vertices, &vk->pattern_indices, &vk->patches,
                             &vk->instances, &vk->cmds, &vk->frame, &vk->capture_out,
                             &vk->offsets, &vk->readback};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; ++i) xyl__vk_buffer_destroy(vk, all[i]);
}

void xyl_tess_vk_destroy(xyl_tess_vk *vk)
{
    if (!vk) return;
    if (vk->device) {
        vkDeviceWaitIdle(vk->device); /* nothing may be in flight; every call waits anyway */
        xyl__vk_target_destroy(vk, &vk->target);
        xyl__vk_destroy_pipelines(vk);
        destroy_buffers(vk);
        if (vk->queries) vkDestroyQueryPool(vk->device, vk->queries, NULL);
        if (vk->fence) vkDestroyFence(vk->device, vk->fence, NULL);
        if (vk->pool) vkDestroyCommandPool(vk->device, vk->pool, NULL);
        vkDestroyDevice(vk->device, NULL);
    }
    if (vk->messenger) vk->destroy_messenger(vk->instance, vk->messenger, NULL);
    if (vk->instance) vkDestroyInstance(vk->instance, NULL);
    xyl__free(NULL, vk->patch_kinds);
    xyl__free(NULL, vk);
}

const char *xyl_tess_vk_device_name(const xyl_tess_vk *vk)
{
    return vk ? vk->device_name : "";
}

double xyl_tess_vk_last_gpu_ms(const xyl_tess_vk *vk)
{
    return vk ? vk->gpu_ms : -1.0;
}

uint32_t xyl_tess_vk_validation_messages(const xyl_tess_vk *vk)
{
    return vk ? vk->messages.count : 0;
}

const char *xyl_tess_vk_first_message(const xyl_tess_vk *vk)
{
    return vk ? vk->messages.first : "";
}

/* ---- patches ------------------------------------------------------------------------------- */

static xyl_result check_usable(const xyl_tess_vk *vk, xyl_diag *diag)
{
    if (vk->lost)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: the device was lost; destroy and recreate the backend");
    return XYL_OK;
}

xyl_result xyl_tess_vk_set_patches(xyl_tess_vk *vk, const xyl_tess_patches *patches,
                                   xyl_diag *diag)
{
    if (!vk || !patches || (patches->count && !patches->records))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "vk and patches (with records) are required");
    xyl_result r = check_usable(vk, diag);
    if (r != XYL_OK) return r;
    if (patches->count > vk->props.limits.maxStorageBufferRange / sizeof(xyl_tess_patch))
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu patches exceed the device's storage buffer range of %u bytes",
                         patches->count, vk->props.limits.maxStorageBufferRange);
    uint8_t *kinds = xyl__alloc_array(NULL, patches->count, 1);
    if (!kinds) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    /* The old patches are dropped first: a failed upload leaves none rather than stale ones. */
    xyl__free(NULL, vk->patch_kinds);
    vk->patch_kinds = NULL;
    vk->patch_count = 0;
    r = xyl__vk_buffer_reserve(vk, &vk->patches, patches->count * sizeof(xyl_tess_patch),
                               BUF_STORAGE, diag);
    if (r != XYL_OK) {
        xyl__free(NULL, kinds);
        return r;
    }
    for (size_t i = 0; i < patches->count; ++i)
        kinds[i] = (uint8_t)xyl_tess_patch_kind(&patches->records[i]);
    if (patches->count)
        memcpy(vk->patches.map, patches->records, patches->count * sizeof(xyl_tess_patch));
    vk->patch_kinds = kinds;
    vk->patch_count = patches->count;
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- batches ------------------------------------------------------------------------------- */

static bool instance_ok(const xyl_tess_vk *vk, const xyl_tess_instance *in)
{
    if (in->patch >= vk->patch_count || in->level < 1 || in->level > vk->max_level ||
        in->kind != vk->patch_kinds[in->patch])
        return false;
    for (uint32_t e = 0; e < in->kind; ++e) {
        uint32_t le = (in->edge_levels >> (XYL_TESS_EDGE_LEVEL_BITS * e)) & 0xffu;
        if (le < 1 || le > in->level) return false;
    }
    return true;
}

/* A command draws its batch's pattern over instance records of that (kind, level); all commands
 * together draw each record at most once (so checking them costs one pass over the records). */
static xyl_result check_cmd(const xyl_tess_vk *vk, const xyl_tess_batches *b, size_t c,
                            uint64_t *drawn, xyl_diag *diag)
{
    const xyl_tess_draw_cmd *cmd = &b->cmds[c];
    xyl_tess_batch bt = b->batches[c];
    const char *why = NULL;
    if ((bt.kind != XYL_TESS_KIND_QUAD && bt.kind != XYL_TESS_KIND_TRIANGLE) || bt.level < 1 ||
        bt.level > vk->max_level)
        why = "draws a kind or level the patterns lack";
    const xyl_tess_pattern_range *r = why ? NULL : range_of(vk, bt.kind, bt.level);
    if (r && (cmd->index_count != r->index_count || cmd->first_index != r->first_index ||
              cmd->base_vertex != (int32_t)r->first_vertex))
        why = "does not draw its batch's pattern";
    else if (r && ((uint64_t)cmd->base_instance + cmd->instance_count > b->instance_count ||
                   (*drawn += cmd->instance_count) > b->instance_count))
        why = "draws instance records beyond the batches' or more than once";
    for (uint32_t i = 0; !why && i < cmd->instance_count; ++i) {
        const xyl_tess_instance *in = &b->instances[cmd->base_instance + i];
        if (in->kind != bt.kind || in->level != bt.level) why = "draws a record of another level";
    }
    if (!why) return XYL_OK;
    return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)c, "draw command %zu %s", c,
                     why);
}

static xyl_result check_batches(const xyl_tess_vk *vk, const xyl_tess_batches *b, xyl_diag *diag)
{
    if ((b->instance_count && !b->instances) || (b->cmd_count && (!b->cmds || !b->batches)) ||
        b->instance_count > UINT32_MAX || b->cmd_count > UINT32_MAX)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "batches: missing arrays or counts out of range");
    for (size_t i = 0; i < b->instance_count; ++i)
        if (!instance_ok(vk, &b->instances[i]))
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)i,
                             "instance %zu (patch %u, level %u) does not match the %zu uploaded "
                             "patches or the patterns (max level %u)",
                             i, b->instances[i].patch, b->instances[i].level, vk->patch_count,
                             vk->max_level);
    uint64_t drawn = 0;
    for (size_t c = 0; c < b->cmd_count; ++c) {
        xyl_result r = check_cmd(vk, b, c, &drawn, diag);
        if (r != XYL_OK) return r;
    }
    return XYL_OK;
}

static xyl_result upload_batches(xyl_tess_vk *vk, const xyl_tess_batches *b, xyl_diag *diag)
{
    xyl_result r = xyl__vk_buffer_reserve(vk, &vk->instances,
                                          b->instance_count * sizeof(xyl_tess_instance),
                                          BUF_VERTEX, diag);
    if (r == XYL_OK)
        r = xyl__vk_buffer_reserve(vk, &vk->cmds, b->cmd_count * sizeof(xyl_tess_draw_cmd),
                                   VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, diag);
    if (r != XYL_OK) return r;
    if (b->instance_count)
        memcpy(vk->instances.map, b->instances, b->instance_count * sizeof(xyl_tess_instance));
    if (b->cmd_count) memcpy(vk->cmds.map, b->cmds, b->cmd_count * sizeof(xyl_tess_draw_cmd));
    return XYL_OK;
}

/* ---- recording ----------------------------------------------------------------------------- */

static void buffer_info(VkDescriptorBufferInfo *bi, const xyl__vk_buffer *b, VkDeviceSize range)
{
    bi->buffer = b->buffer;
    bi->offset = 0;
    bi->range = range;
}

/* Every buffer of the set exists (reserved before), possibly re-created since the last call. */
static void update_set(xyl_tess_vk *vk)
{
    VkDescriptorBufferInfo bi[4];
    buffer_info(&bi[0], &vk->patches, VK_WHOLE_SIZE);
    buffer_info(&bi[1], &vk->frame, sizeof(xyl_tess_frame));
    buffer_info(&bi[2], &vk->capture_out, VK_WHOLE_SIZE);
    buffer_info(&bi[3], &vk->offsets, VK_WHOLE_SIZE);
    VkWriteDescriptorSet w[4];
    for (uint32_t k = 0; k < 4; ++k) {
        VkWriteDescriptorSet wk = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        wk.dstSet = vk->set;
        wk.dstBinding = k; /* XYL_TESS_BINDING_PATCHES .. XYL_TESS_BINDING_OFFSETS */
        wk.descriptorCount = 1;
        wk.descriptorType = k == XYL_TESS_BINDING_FRAME ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC
                                                        : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        wk.pBufferInfo = &bi[k];
        w[k] = wk;
    }
    vkUpdateDescriptorSets(vk->device, 4, w, 0, NULL);
}

/* The buffers every pipeline's set names, so that the set is complete for either path. */
static xyl_result reserve_common(xyl_tess_vk *vk, xyl_diag *diag)
{
    xyl_result r = xyl__vk_buffer_reserve(vk, &vk->patches, 0, BUF_STORAGE, diag);
    if (r == XYL_OK)
        r = xyl__vk_buffer_reserve(vk, &vk->frame, 2 * vk->frame_stride,
                                   VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, diag);
    if (r == XYL_OK) r = xyl__vk_buffer_reserve(vk, &vk->capture_out, 0, BUF_STORAGE, diag);
    if (r == XYL_OK) r = xyl__vk_buffer_reserve(vk, &vk->offsets, 0, BUF_STORAGE, diag);
    return r;
}

static void bind_geometry(xyl_tess_vk *vk, VkPipeline pipeline, uint32_t frame_copy)
{
    VkCommandBuffer cb = vk->cmd;
    uint32_t offset = (uint32_t)(frame_copy * vk->frame_stride);
    vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
    vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, vk->layout, 0, 1, &vk->set, 1,
                            &offset);
    VkBuffer vbs[2] = {vk->pattern_vertices.buffer, vk->instances.buffer};
    VkDeviceSize offs[2] = {0, 0};
    vkCmdBindVertexBuffers(cb, 0, 2, vbs, offs);
    vkCmdBindIndexBuffer(cb, vk->pattern_indices.buffer, 0, VK_INDEX_TYPE_UINT32);
}

static void draw_batches(xyl_tess_vk *vk, size_t cmd_count)
{
    const uint32_t stride = sizeof(xyl_tess_draw_cmd);
    if (cmd_count == 0) return;
    if (vk->features.multiDrawIndirect && cmd_count <= vk->props.limits.maxDrawIndirectCount) {
        vkCmdDrawIndexedIndirect(vk->cmd, vk->cmds.buffer, 0, (uint32_t)cmd_count, stride);
        return;
    }
    for (size_t c = 0; c < cmd_count; ++c)
        vkCmdDrawIndexedIndirect(vk->cmd, vk->cmds.buffer, c * stride, 1, stride);
}

static void set_viewport(VkCommandBuffer cb, uint32_t width, uint32_t height)
{
    VkViewport vp = {0.0f, 0.0f, (float)width, (float)height, 0.0f, 1.0f};
    VkRect2D sc = {{0, 0}, {width, height}};
    vkCmdSetViewport(cb, 0, 1, &vp);
    vkCmdSetScissor(cb, 0, 1, &sc);
}

static void host_barrier(VkCommandBuffer cb, VkPipelineStageFlags stage, VkAccessFlags access)
{
    VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = access;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cb, stage, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, NULL, 0, NULL);
}

static xyl_result begin(xyl_tess_vk *vk, xyl_diag *diag)
{
    VkResult r = vkResetCommandBuffer(vk->cmd, 0);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkResetCommandBuffer");
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    r = vkBeginCommandBuffer(vk->cmd, &bi);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkBeginCommandBuffer");
}

static xyl_result end_and_submit(xyl_tess_vk *vk, xyl_diag *diag)
{
    VkResult r = vkEndCommandBuffer(vk->cmd);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkEndCommandBuffer");
    return xyl__vk_submit_wait(vk, diag);
}

/* ---- render -------------------------------------------------------------------------------- */

typedef struct render_params {
    uint32_t width, height;
    VkSampleCountFlagBits samples;
    bool wireframe, backfaces;
    float background[4];
} render_params;

static void record_pass(xyl_tess_vk *vk, const render_params *p, size_t cmd_count)
{
    VkCommandBuffer cb = vk->cmd;
    const xyl__vk_target *t = &vk->target;
    VkClearValue clear[3];
    memset(clear, 0, sizeof clear);
    memcpy(clear[0].color.float32, p->background, sizeof p->background);
    clear[1].depthStencil.depth = 1.0f;
    VkRenderPassBeginInfo rb = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rb.renderPass = t->pass;
    rb.framebuffer = t->framebuffer;
    rb.renderArea.extent.width = p->width;
    rb.renderArea.extent.height = p->height;
    rb.clearValueCount = p->samples != VK_SAMPLE_COUNT_1_BIT ? 3 : 2;
    rb.pClearValues = clear;
    vkCmdBeginRenderPass(cb, &rb, VK_SUBPASS_CONTENTS_INLINE);
    set_viewport(cb, p->width, p->height);
    bind_geometry(vk, t->fill[p->backfaces], 0);
    draw_batches(vk, cmd_count);
    if (p->wireframe) {
        bind_geometry(vk, t->line[p->backfaces], 1);
        draw_batches(vk, cmd_count);
    }
    vkCmdEndRenderPass(cb);
}

static void record_readback(xyl_tess_vk *vk, const render_params *p)
{
    const xyl__vk_target *t = &vk->target;
    VkBufferImageCopy copy = {0};
    copy.imageSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    copy.imageSubresource.layerCount = 1;
    copy.imageExtent.width = p->width;
    copy.imageExtent.height = p->height;
    copy.imageExtent.depth = 1;
    VkImage src = p->samples != VK_SAMPLE_COUNT_1_BIT ? t->resolve.image : t->color.image;
    vkCmdCopyImageToBuffer(vk->cmd, src, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                           vk->readback.buffer, 1, &copy);
    host_barrier(vk->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
}

static xyl_result record_render(xyl_tess_vk *vk, const render_params *p, size_t cmd_count,
                                xyl_diag *diag)
{
    xyl_result r = begin(vk, diag);
    if (r != XYL_OK) return r;
    if (vk->queries) {
        vkCmdResetQueryPool(vk->cmd, vk->queries, 0, 2);
        vkCmdWriteTimestamp(vk->cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, vk->queries, 0);
    }
    record_pass(vk, p, cmd_count);
    if (vk->queries)
        vkCmdWriteTimestamp(vk->cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, vk->queries, 1);
    record_readback(vk, p);
    return end_and_submit(vk, diag);
}

static void read_gpu_time(xyl_tess_vk *vk)
{
    vk->gpu_ms = -1.0;
    uint64_t ts[2];
    if (!vk->queries ||
        vkGetQueryPoolResults(vk->device, vk->queries, 0, 2, sizeof ts, ts, sizeof ts[0],
                              VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) != VK_SUCCESS)
        return;
    uint64_t mask = vk->timestamp_bits >= 64 ? UINT64_MAX : (1ull << vk->timestamp_bits) - 1u;
    uint64_t ticks = (ts[1] - ts[0]) & mask; /* the counter may wrap within its valid bits */
    vk->gpu_ms = (double)ticks * (double)vk->props.limits.timestampPeriod * 1e-6;
}

static uint32_t image_size(uint32_t v)
{
    return v ? v : 512u;
}

static xyl_result check_samples(const xyl_tess_vk *vk, uint32_t samples,
                                VkSampleCountFlagBits *out, xyl_diag *diag)
{
    uint32_t s = samples ? samples : 1u;
    if (s > 64 || (s & (s - 1u)) != 0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "image: %u samples is not a power of two up to 64", s);
    VkSampleCountFlags have = vk->props.limits.framebufferColorSampleCounts &
                              vk->props.limits.framebufferDepthSampleCounts;
    if (!(have & s))
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: %s offers no %u-sample colour + depth target", vk->device_name,
                         s);
    *out = (VkSampleCountFlagBits)s;
    return XYL_OK;
}

static xyl_result check_image(const xyl_tess_vk *vk, const xyl_tess_image_desc *img,
                              render_params *p, xyl_diag *diag)
{
    p->width = image_size(img->width);
    p->height = image_size(img->height);
    if (p->width > XYL__VK_MAX_IMAGE || p->height > XYL__VK_MAX_IMAGE)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "image: %u x %u exceeds the limit of %u pixels each way", p->width,
                         p->height, XYL__VK_MAX_IMAGE);
    const VkPhysicalDeviceLimits *lim = &vk->props.limits;
    if (p->width > lim->maxFramebufferWidth || p->height > lim->maxFramebufferHeight ||
        p->width > lim->maxImageDimension2D || p->height > lim->maxImageDimension2D)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: %s has no %u x %u framebuffer", vk->device_name, p->width,
                         p->height);
    p->wireframe = img->wireframe;
    if (p->wireframe && !vk->features.fillModeNonSolid)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: wireframe needs the fillModeNonSolid feature, which %s lacks",
                         vk->device_name);
    for (int k = 0; k < 4; ++k) {
        float c = img->background[k];
        p->background[k] = isfinite(c) ? (c < 0.0f ? 0.0f : c > 1.0f ? 1.0f : c) : 0.0f;
    }
    return check_samples(vk, img->samples, &p->samples, diag);
}

static xyl_result check_frame(const xyl_tess_frame *f, xyl_diag *diag)
{
    if (f->variant >= XYL_TESS_VARIANT_COUNT)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "frame: variant %u unknown",
                         f->variant);
    for (int k = 0; k < 16; ++k)
        if (!isfinite(f->view_proj[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, k,
                             "frame: view_proj[%d] is not finite", k);
    return XYL_OK;
}

/* The frame as given, then the wireframe overlay's copy of it. */
static void upload_frames(xyl_tess_vk *vk, const xyl_tess_frame *f)
{
    xyl_tess_frame line = *f;
    line.flags |= XYL_TESS_FLAG_WIREFRAME;
    memcpy(vk->frame.map, f, sizeof *f);
    memcpy((char *)vk->frame.map + vk->frame_stride, &line, sizeof line);
}

static xyl_result prepare_render(xyl_tess_vk *vk, const xyl_tess_batches *b,
                                 const xyl_tess_frame *f, const render_params *p, xyl_diag *diag)
{
    xyl_result r = check_batches(vk, b, diag);
    if (r == XYL_OK) r = reserve_common(vk, diag);
    if (r == XYL_OK) r = upload_batches(vk, b, diag);
    if (r == XYL_OK) r = xyl__vk_target_reserve(vk, p->width, p->height, p->samples, diag);
    if (r == XYL_OK)
        r = xyl__vk_buffer_reserve(vk, &vk->readback, (VkDeviceSize)p->width * p->height * 4u,
                                   VK_BUFFER_USAGE_TRANSFER_DST_BIT, diag);
    if (r != XYL_OK) return r;
    upload_frames(vk, f);
    update_set(vk);
    return XYL_OK;
}

xyl_result xyl_tess_vk_render_rgba(xyl_tess_vk *vk, const xyl_tess_batches *batches,
                                   const xyl_tess_frame *frame, const xyl_tess_image_desc *image,
                                   uint8_t *rgba, xyl_diag *diag)
{
    if (!vk || !batches || !frame || !image || !rgba)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "vk, batches, frame, image and rgba are required");
    render_params p = {0};
    xyl_result r = check_usable(vk, diag);
    if (r == XYL_OK) r = check_frame(frame, diag);
    if (r == XYL_OK) r = check_image(vk, image, &p, diag);
    if (r != XYL_OK) return r;
    p.backfaces = (frame->flags & XYL__TESS_FLAG_BACKFACES) != 0;
    r = prepare_render(vk, batches, frame, &p, diag);
    if (r == XYL_OK) r = record_render(vk, &p, batches->cmd_count, diag);
    if (r != XYL_OK) return r;
    read_gpu_time(vk);
    /* Framebuffer row 0 is the top row (view_proj already flips y), as the caller wants. */
    memcpy(rgba, vk->readback.map, (size_t)p.width * p.height * 4u);
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- capture ------------------------------------------------------------------------------- */

/* First capture slot of each instance's patch (a patch drawn twice would share its slots); sets
 * *total to the vertices captured. */
static xyl_result capture_offsets(xyl_tess_vk *vk, const xyl_tess_batches *b, uint64_t *total,
                                  xyl_diag *diag)
{
    const uint64_t max_slots = vk->props.limits.maxStorageBufferRange / (2u * 16u);
    xyl_result r = xyl__vk_buffer_reserve(vk, &vk->offsets, vk->patch_count * sizeof(uint32_t),
                                          BUF_STORAGE, diag);
    if (r != XYL_OK) return r;
    uint32_t *off = vk->offsets.map;
    memset(off, 0xff, vk->patch_count * sizeof(uint32_t)); /* ~0u: not drawn yet */
    uint64_t sum = 0;
    for (size_t i = 0; i < b->instance_count; ++i) {
        const xyl_tess_instance *in = &b->instances[i];
        if (off[in->patch] != UINT32_MAX)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)i,
                             "capture: patch %u has more than one instance record", in->patch);
        off[in->patch] = (uint32_t)sum;
        sum += range_of(vk, in->kind, in->level)->vertex_count;
        if (sum > max_slots)
            return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                             "capture: more than %llu vertices exceed the device's storage "
                             "buffer range", (unsigned long long)max_slots);
    }
    *total = sum;
    return XYL_OK;
}

static xyl_result prepare_capture(xyl_tess_vk *vk, const xyl_tess_batches *b,
                                  xyl_tess_variant variant, uint64_t *total, xyl_diag *diag)
{
    xyl_result r = check_batches(vk, b, diag);
    if (r == XYL_OK) r = reserve_common(vk, diag);
    if (r == XYL_OK) r = capture_offsets(vk, b, total, diag);
    if (r == XYL_OK) r = upload_batches(vk, b, diag);
    if (r == XYL_OK)
        r = xyl__vk_buffer_reserve(vk, &vk->capture_out, *total * 32u, BUF_STORAGE, diag);
    if (r != XYL_OK) return r;
    memset(vk->capture_out.map, 0, (size_t)*total * 32u); /* records no command draws stay 0 */
    xyl_tess_frame f;
    memset(&f, 0, sizeof f);
    for (int k = 0; k < 4; ++k) f.view_proj[5 * k] = 1.0f;
    f.variant = (uint32_t)variant;
    upload_frames(vk, &f);
    update_set(vk);
    return XYL_OK;
}

static xyl_result record_capture(xyl_tess_vk *vk, size_t cmd_count, xyl_diag *diag)
{
    xyl_result r = begin(vk, diag);
    if (r != XYL_OK) return r;
    VkRenderPassBeginInfo rb = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rb.renderPass = vk->capture_pass;
    rb.framebuffer = vk->capture_framebuffer;
    rb.renderArea.extent.width = 1;
    rb.renderArea.extent.height = 1;
    vkCmdBeginRenderPass(vk->cmd, &rb, VK_SUBPASS_CONTENTS_INLINE);
    set_viewport(vk->cmd, 1, 1);
    bind_geometry(vk, vk->capture, 0);
    draw_batches(vk, cmd_count);
    vkCmdEndRenderPass(vk->cmd);
    host_barrier(vk->cmd, VK_PIPELINE_STAGE_VERTEX_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
    return end_and_submit(vk, diag);
}

/* GPU positions and normals at their slots, coordinates (i, j, level) and patch from the
 * instance records and patterns. */
static void read_captured(const xyl_tess_vk *vk, const xyl_tess_batches *b,
                          xyl__tess_captured *out, size_t n)
{
    const float *slots = vk->capture_out.map;
    const uint32_t *off = vk->offsets.map;
    for (size_t i = 0; i < b->instance_count; ++i) {
        const xyl_tess_instance *in = &b->instances[i];
        const xyl_tess_pattern_range *r = range_of(vk, in->kind, in->level);
        for (uint32_t v = 0; v < r->vertex_count; ++v) {
            uint32_t pk = vk->lattice[r->first_vertex + v];
            size_t slot = (size_t)off[in->patch] + (pk >> XYL_TESS_PATTERN_SHIFT_LOCAL);
            if (slot >= n) continue;
            xyl__tess_captured *c = &out[slot];
            memcpy(c->position, slots + 8 * slot, sizeof c->position);
            memcpy(c->normal, slots + 8 * slot + 4, sizeof c->normal);
            c->coord[0] = (float)(pk & 0xffu);
            c->coord[1] = (float)((pk >> XYL_TESS_PATTERN_SHIFT_J) & 0xffu);
            c->coord[2] = (float)in->level;
            c->patch = in->patch;
        }
    }
}

xyl_result xyl__tess_vk_capture(xyl_tess_vk *vk, const xyl_tess_batches *batches,
                               xyl_tess_variant variant, xyl__tess_captured *out, size_t capacity,
                               size_t *count, xyl_diag *diag)
{
    if (!vk || !batches || !count || (capacity && !out))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "vk, batches, count (and out when capacity > 0) are required");
    if ((unsigned)variant >= XYL_TESS_VARIANT_COUNT)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "variant %d unknown",
                         (int)variant);
    xyl_result r = check_usable(vk, diag);
    if (r != XYL_OK) return r;
    if (!vk->capture)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: capture needs vertexPipelineStoresAndAtomics, which %s lacks",
                         vk->device_name);
    uint64_t total = 0;
    r = prepare_capture(vk, batches, variant, &total, diag);
    if (r == XYL_OK) r = record_capture(vk, batches->cmd_count, diag);
    if (r != XYL_OK) return r;
    read_captured(vk, batches, out, capacity < total ? capacity : (size_t)total);
    *count = (size_t)total;
    xyl__diag_ok(diag);
    return XYL_OK;
}

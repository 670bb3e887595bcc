/* Vulkan backend: the draws. xyl_tess_vk_cmd_draw records them into the caller's command buffer
 * and render pass; xyl_tess_vk_render_rgba records the same draws, through the same functions,
 * into the library's offscreen target, submits and reads back. Either way the draw's data is
 * checked and written into one slot's host-visible buffers at record time. */
#include <math.h>
#include <string.h>

#include "vk_internal.h"

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
    const xyl_tess_pattern_range *r = why ? NULL : xyl__vk_range(vk, bt.kind, bt.level);
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

/* ---- one slot's data, and the draws that read it ------------------------------------------- */

xyl_result xyl__vk_stage(xyl_tess_vk *vk, uint32_t slot, const xyl_tess_batches *b,
                         const xyl_tess_frame frames[2], xyl_diag *diag)
{
    xyl_result r = check_batches(vk, b, diag);
    if (r == XYL_OK && !vk->patches.buffer)
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1,
                      "Vulkan: no patch buffer since a failed xyl_tess_vk_set_patches");
    xyl__vk_slot *s = &vk->slots[slot];
    if (r == XYL_OK)
        r = xyl__vk_buffer_reserve(vk, &s->instances,
                                   b->instance_count * sizeof(xyl_tess_instance),
                                   VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, diag);
    if (r == XYL_OK)
        r = xyl__vk_buffer_reserve(vk, &s->cmds, b->cmd_count * sizeof(xyl_tess_draw_cmd),
                                   VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, diag);
    if (r != XYL_OK) return r;
    if (b->instance_count)
        memcpy(s->instances.map, b->instances, b->instance_count * sizeof(xyl_tess_instance));
    if (b->cmd_count) memcpy(s->cmds.map, b->cmds, b->cmd_count * sizeof(xyl_tess_draw_cmd));
    char *at = (char *)vk->frames.map + 2u * slot * vk->frame_stride;
    memcpy(at, &frames[0], sizeof frames[0]);
    memcpy(at + vk->frame_stride, &frames[1], sizeof frames[1]);
    return XYL_OK;
}

void xyl__vk_record(const xyl_tess_vk *vk, VkCommandBuffer cb, VkPipeline pipeline,
                    VkDescriptorSet set, uint32_t slot, uint32_t copy, size_t cmd_count)
{
    const xyl__vk_slot *s = &vk->slots[slot];
    uint32_t offset = (uint32_t)((2u * slot + copy) * vk->frame_stride);
    vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
    vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, vk->layout, 0, 1, &set, 1,
                            &offset);
    VkBuffer vbs[2] = {vk->pattern_vertices.buffer, s->instances.buffer};
    VkDeviceSize offs[2] = {0, 0};
    vkCmdBindVertexBuffers(cb, 0, 2, vbs, offs);
    vkCmdBindIndexBuffer(cb, vk->pattern_indices.buffer, 0, VK_INDEX_TYPE_UINT32);
    const uint32_t stride = sizeof(xyl_tess_draw_cmd);
    if (cmd_count == 0) return;
    if (vk->features.multiDrawIndirect && cmd_count <= vk->props.limits.maxDrawIndirectCount) {
        vkCmdDrawIndexedIndirect(cb, s->cmds.buffer, 0, (uint32_t)cmd_count, stride);
        return;
    }
    for (size_t c = 0; c < cmd_count; ++c)
        vkCmdDrawIndexedIndirect(cb, s->cmds.buffer, c * stride, 1, stride);
}

/* The surface, then (wireframe) its edges with the slot's second frame copy. */
static void record_draws(const xyl_tess_vk *vk, VkCommandBuffer cb, const xyl__vk_pipes *pipes,
                         uint32_t slot, size_t cmd_count, bool wireframe, bool backfaces)
{
    xyl__vk_record(vk, cb, pipes->fill[backfaces], vk->set, slot, 0, cmd_count);
    if (wireframe) xyl__vk_record(vk, cb, pipes->line[backfaces], vk->set, slot, 1, cmd_count);
}

void xyl__vk_set_viewport(VkCommandBuffer cb, uint32_t width, uint32_t height)
{
    VkViewport vp = {0.0f, 0.0f, (float)width, (float)height, 0.0f, 1.0f};
    VkRect2D sc = {{0, 0}, {width, height}};
    vkCmdSetViewport(cb, 0, 1, &vp);
    vkCmdSetScissor(cb, 0, 1, &sc);
}

void xyl__vk_host_barrier(VkCommandBuffer cb, VkPipelineStageFlags stage, VkAccessFlags access)
{
    VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = access;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cb, stage, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, NULL, 0, NULL);
}

/* ---- into the caller's command buffer ------------------------------------------------------ */

xyl_result xyl_tess_vk_cmd_draw(xyl_tess_vk *vk, VkCommandBuffer cmd, uint32_t frame_index,
                                const xyl_tess_batches *batches, const xyl_tess_frame *frame,
                                xyl_diag *diag)
{
    if (!vk || !cmd || !batches || !frame)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "vk, cmd, batches and frame are required");
    xyl_result r = xyl__vk_check_usable(vk, diag);
    if (r != XYL_OK) return r;
    if (!vk->pipes.fill[0])
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a context from xyl_tess_vk_create draws offscreen only; "
                         "xyl_tess_vk_create_for_device makes one for your device");
    if (frame_index >= vk->slot_count - 1)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "frame_index %u: the context has %u frames in flight", frame_index,
                         vk->slot_count - 1);
    r = check_frame(frame, diag);
    bool wireframe = (frame->flags & XYL_TESS_FLAG_WIREFRAME) != 0;
    if (r == XYL_OK && wireframe && !vk->pipes.line[0])
        r = xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                      "Vulkan: wireframe needs the fillModeNonSolid feature enabled");
    xyl_tess_frame frames[2] = {*frame, *frame};
    frames[0].flags &= ~XYL_TESS_FLAG_WIREFRAME;
    frames[1].flags |= XYL_TESS_FLAG_WIREFRAME;
    if (r == XYL_OK) r = xyl__vk_stage(vk, frame_index, batches, frames, diag);
    if (r != XYL_OK) return r;
    bool backfaces = (frame->flags & XYL__TESS_FLAG_BACKFACES) != 0;
    record_draws(vk, cmd, &vk->pipes, frame_index, batches->cmd_count, wireframe, backfaces);
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- offscreen ----------------------------------------------------------------------------- */

typedef struct render_params {
    uint32_t width, height;
    VkSampleCountFlagBits samples;
    bool wireframe, backfaces;
    float background[4];
} render_params;

static void record_pass(xyl_tess_vk *vk, const render_params *p, uint32_t slot, size_t cmd_count)
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
    xyl__vk_set_viewport(cb, p->width, p->height);
    record_draws(vk, cb, &t->pipes, slot, cmd_count, p->wireframe, p->backfaces);
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
    xyl__vk_host_barrier(vk->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
}

static xyl_result record_render(xyl_tess_vk *vk, const render_params *p, uint32_t slot,
                                size_t cmd_count, xyl_diag *diag)
{
    xyl_result r = xyl__vk_begin(vk, diag);
    if (r != XYL_OK) return r;
    if (vk->queries) {
        vkCmdResetQueryPool(vk->cmd, vk->queries, 0, 2);
        vkCmdWriteTimestamp(vk->cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, vk->queries, 0);
    }
    record_pass(vk, p, slot, cmd_count);
    if (vk->queries)
        vkCmdWriteTimestamp(vk->cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, vk->queries, 1);
    record_readback(vk, p);
    return xyl__vk_submit_wait(vk, diag);
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
    return xyl__vk_check_samples(vk, img->samples, &p->samples, diag);
}

xyl_result xyl_tess_vk_render_rgba(xyl_tess_vk *vk, const xyl_tess_batches *batches,
                                   const xyl_tess_frame *frame, const xyl_tess_image_desc *image,
                                   uint8_t *rgba, xyl_diag *diag)
{
    if (!vk || !batches || !frame || !image || !rgba)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "vk, batches, frame, image and rgba are required");
    render_params p = {0};
    xyl_result r = xyl__vk_check_usable(vk, diag);
    if (r == XYL_OK && !vk->queue)
        r = xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                      "Vulkan: offscreen renders need a queue (xyl_tess_vk_device_desc.queue)");
    if (r == XYL_OK) r = check_frame(frame, diag);
    if (r == XYL_OK) r = check_image(vk, image, &p, diag);
    if (r != XYL_OK) return r;
    p.backfaces = (frame->flags & XYL__TESS_FLAG_BACKFACES) != 0;
    /* The frame as given, then the wireframe overlay's copy of it. */
    xyl_tess_frame frames[2] = {*frame, *frame};
    frames[1].flags |= XYL_TESS_FLAG_WIREFRAME;
    uint32_t slot = vk->slot_count - 1; /* the offscreen calls' own */
    r = xyl__vk_stage(vk, slot, batches, frames, diag);
    if (r == XYL_OK) r = xyl__vk_target_reserve(vk, p.width, p.height, p.samples, diag);
    if (r == XYL_OK)
        r = xyl__vk_buffer_reserve(vk, &vk->readback, (VkDeviceSize)p.width * p.height * 4u,
                                   VK_BUFFER_USAGE_TRANSFER_DST_BIT, diag);
    if (r == XYL_OK) r = record_render(vk, &p, slot, batches->cmd_count, diag);
    if (r != XYL_OK) return r;
    read_gpu_time(vk);
    /* Framebuffer row 0 is the top row (view_proj already flips y), as the caller wants. */
    memcpy(rgba, vk->readback.map, (size_t)p.width * p.height * 4u);
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* Vulkan backend: the tests' readback of evaluated vertices (tess_debug.h). The capture variant of
 * the vertex shader writes each vertex at its patch's first slot plus its index in the pattern;
 * it draws the same commands as a render, with rasterisation discarded, from the offscreen
 * calls' slot and through a descriptor set of its own. */
#include <string.h>

#include "vk_internal.h"

#define BUF_STORAGE VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
#define SLOT_BYTES 32u /* (position, 1), (normal, 0) */

/* First capture slot of each instance's patch (a patch drawn twice would share its slots); sets
 * *total to the vertices captured. The batches are checked already. */
static xyl_result capture_offsets(xyl_tess_vk *vk, const xyl_tess_batches *b, uint64_t *total,
                                  xyl_diag *diag)
{
    const uint64_t max_slots = vk->props.limits.maxStorageBufferRange / SLOT_BYTES;
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
        sum += xyl__vk_range(vk, in->kind, in->level)->vertex_count;
        if (sum > max_slots)
            return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                             "capture: more than %llu vertices exceed the device's storage "
                             "buffer range", (unsigned long long)max_slots);
    }
    *total = sum;
    return XYL_OK;
}

static xyl_result prepare_capture(xyl_tess_vk *vk, uint32_t slot, const xyl_tess_batches *b,
                                  xyl_tess_variant variant, uint64_t *total, xyl_diag *diag)
{
    xyl_tess_frame f[2];
    memset(f, 0, sizeof f);
    for (int k = 0; k < 4; ++k) f[0].view_proj[5 * k] = 1.0f;
    f[0].variant = (uint32_t)variant;
    f[1] = f[0];
    xyl_result r = xyl__vk_stage(vk, slot, b, f, diag);
    if (r == XYL_OK) r = capture_offsets(vk, b, total, diag);
    if (r == XYL_OK)
        r = xyl__vk_buffer_reserve(vk, &vk->capture_out, *total * SLOT_BYTES, BUF_STORAGE, diag);
    if (r != XYL_OK) return r;
    memset(vk->capture_out.map, 0, (size_t)*total * SLOT_BYTES); /* what no command draws: 0 */
    xyl__vk_write_set(vk, vk->capture_set, 4);
    return XYL_OK;
}

static xyl_result record_capture(xyl_tess_vk *vk, uint32_t slot, size_t cmd_count,
                                 xyl_diag *diag)
{
    xyl_result r = xyl__vk_begin(vk, diag);
    if (r != XYL_OK) return r;
    VkRenderPassBeginInfo rb = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rb.renderPass = vk->capture_pass;
    rb.framebuffer = vk->capture_framebuffer;
    rb.renderArea.extent.width = 1;
    rb.renderArea.extent.height = 1;
    vkCmdBeginRenderPass(vk->cmd, &rb, VK_SUBPASS_CONTENTS_INLINE);
    xyl__vk_set_viewport(vk->cmd, 1, 1);
    xyl__vk_record(vk, vk->cmd, vk->capture, vk->capture_set, slot, 0, cmd_count);
    vkCmdEndRenderPass(vk->cmd);
    xyl__vk_host_barrier(vk->cmd, VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
                         VK_ACCESS_SHADER_WRITE_BIT);
    return xyl__vk_submit_wait(vk, diag);
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
        const xyl_tess_pattern_range *r = xyl__vk_range(vk, in->kind, in->level);
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
                                xyl_tess_variant variant, xyl__tess_captured *out,
                                size_t capacity, size_t *count, xyl_diag *diag)
{
    if (!vk || !batches || !count || (capacity && !out))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "vk, batches, count (and out when capacity > 0) are required");
    if ((unsigned)variant >= XYL_TESS_VARIANT_COUNT)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "variant %d unknown",
                         (int)variant);
    xyl_result r = xyl__vk_check_usable(vk, diag);
    if (r != XYL_OK) return r;
    if (!vk->queue || !vk->features.vertexPipelineStoresAndAtomics)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: capture needs a queue and vertexPipelineStoresAndAtomics, "
                         "which %s lacks", vk->device_name);
    uint32_t slot = vk->slot_count - 1;
    uint64_t total = 0;
    r = xyl__vk_capture_reserve(vk, diag);
    if (r == XYL_OK) r = prepare_capture(vk, slot, batches, variant, &total, diag);
    if (r == XYL_OK) r = record_capture(vk, slot, batches->cmd_count, diag);
    if (r != XYL_OK) return r;
    read_captured(vk, batches, out, capacity < total ? capacity : (size_t)total);
    *count = (size_t)total;
    xyl__diag_ok(diag);
    return XYL_OK;
}

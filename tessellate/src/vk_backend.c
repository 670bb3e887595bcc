/* The Vulkan 1.2 backend of tessellate/: contexts on the library's own device or on the
 * caller's, their patterns and patches. Drawing lives in vk_draw.c, setup in vk_setup.c,
 * passes and pipelines in vk_pipeline.c. */
#include <string.h>

#include "vk_internal.h"

#define BUF_STORAGE VK_BUFFER_USAGE_STORAGE_BUFFER_BIT

const xyl_tess_pattern_range *xyl__vk_range(const xyl_tess_vk *vk, uint32_t kind, uint32_t level)
{
    return &vk->ranges[kind == XYL_TESS_KIND_QUAD ? 0 : 1][level];
}

xyl_result xyl__vk_check_usable(const xyl_tess_vk *vk, xyl_diag *diag)
{
    if (vk->lost)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: the device was lost; destroy and recreate the backend");
    return XYL_OK;
}

xyl_result xyl__vk_check_samples(const xyl_tess_vk *vk, uint32_t samples,
                                 VkSampleCountFlagBits *out, xyl_diag *diag)
{
    uint32_t s = samples ? samples : 1u;
    if (s > 64 || (s & (s - 1u)) != 0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "%u samples is not a power of two up to 64", s);
    VkSampleCountFlags have = vk->props.limits.framebufferColorSampleCounts &
                              vk->props.limits.framebufferDepthSampleCounts;
    if (!(have & s))
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: %s offers no %u-sample colour + depth target", vk->device_name,
                         s);
    *out = (VkSampleCountFlagBits)s;
    return XYL_OK;
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
                                          p->vertex_count * sizeof(uint32_t),
                                          VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, diag);
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

void xyl__vk_write_set(const xyl_tess_vk *vk, VkDescriptorSet set, uint32_t count)
{
    VkDescriptorBufferInfo bi[4] = {{vk->patches.buffer, 0, VK_WHOLE_SIZE},
                                    {vk->frames.buffer, 0, sizeof(xyl_tess_frame)},
                                    {vk->capture_out.buffer, 0, VK_WHOLE_SIZE},
                                    {vk->offsets.buffer, 0, VK_WHOLE_SIZE}};
    VkWriteDescriptorSet w[4];
    for (uint32_t k = 0; k < count; ++k) {
        VkWriteDescriptorSet wk = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        wk.dstSet = set;
        wk.dstBinding = k; /* XYL_TESS_BINDING_PATCHES .. XYL_TESS_BINDING_OFFSETS */
        wk.descriptorCount = 1;
        wk.descriptorType = k == XYL_TESS_BINDING_FRAME ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC
                                                        : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        wk.pBufferInfo = &bi[k];
        w[k] = wk;
    }
    vkUpdateDescriptorSets(vk->device, count, w, 0, NULL);
}

/* The draws' set: the patches and the frame uniforms (a slot's copy by dynamic offset). */
static void write_draw_set(xyl_tess_vk *vk)
{
    xyl__vk_write_set(vk, vk->set, 2);
}

/* What both kinds of context draw with: layouts, sets, patterns, an empty patch buffer, and a
 * slot per frame in flight plus one for the offscreen calls. */
static xyl_result create_drawing(xyl_tess_vk *vk, const xyl_tess_patterns *patterns,
                                 uint32_t frames_in_flight, xyl_diag *diag)
{
    VkDeviceSize align = vk->props.limits.minUniformBufferOffsetAlignment;
    if (align < 1) align = 1;
    vk->frame_stride = (sizeof(xyl_tess_frame) + align - 1) / align * align;
    vk->slot_count = frames_in_flight + 1;
    vk->slots = xyl__calloc(&vk->alloc, vk->slot_count, sizeof *vk->slots);
    if (!vk->slots) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    xyl_result r = xyl__vk_create_layouts(vk, diag);
    if (r == XYL_OK) r = upload_patterns(vk, patterns, diag);
    if (r == XYL_OK)
        r = xyl__vk_buffer_reserve(vk, &vk->frames, 2 * vk->slot_count * vk->frame_stride,
                                   VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, diag);
    if (r == XYL_OK) r = xyl__vk_buffer_reserve(vk, &vk->patches, 0, BUF_STORAGE, diag);
    if (r == XYL_OK) write_draw_set(vk);
    return r;
}

static xyl_tess_vk *new_context(const xyl_allocator *alloc)
{
    xyl_tess_vk *vk = xyl__calloc(alloc, 1, sizeof *vk);
    if (!vk) return NULL;
    if (alloc) vk->alloc = *alloc;
    xyl__vk_init_callbacks(vk);
    vk->gpu_ms = -1.0;
    return vk;
}

static xyl_result finish_create(xyl_tess_vk *vk, xyl_result r, xyl_tess_vk **out,
                                xyl_diag *diag)
{
    if (r != XYL_OK) {
        xyl_tess_vk_destroy(vk);
        return r;
    }
    *out = vk;
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_result xyl_tess_vk_create(const xyl_tess_vk_desc *desc, const xyl_tess_patterns *patterns,
                              xyl_tess_vk **out, xyl_diag *diag)
{
    if (!patterns || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "patterns and out are required");
    xyl_result r = check_patterns(patterns, diag);
    if (r != XYL_OK) return r;
    xyl_tess_vk *vk = new_context(desc ? &desc->alloc : NULL);
    if (!vk) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    vk->owns_device = true;
    r = xyl__vk_create_instance(vk, desc && desc->validation, diag);
    if (r == XYL_OK) r = xyl__vk_pick_device(vk, desc ? desc->device_name : NULL, diag);
    if (r == XYL_OK) r = xyl__vk_create_device(vk, diag);
    if (r == XYL_OK) r = xyl__vk_create_commands(vk, diag);
    if (r == XYL_OK) r = create_drawing(vk, patterns, 0, diag);
    return finish_create(vk, r, out, diag);
}

static xyl_result check_device_desc(const xyl_tess_vk_device_desc *d, xyl_diag *diag)
{
    const char *why = NULL;
    if (!d->physical_device || !d->device) why = "physical_device and device are required";
    else if (!d->render_pass && d->color_format == VK_FORMAT_UNDEFINED)
        why = "a render_pass, or for dynamic rendering a color_format, is required";
    else if (d->frames_in_flight > XYL__VK_MAX_FRAMES)
        why = "frames_in_flight is above 16";
    else if (d->enabled_features && !d->enabled_features->drawIndirectFirstInstance)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: the device needs drawIndirectFirstInstance enabled (each "
                         "draw command starts at its batch's instance records)");
    return why ? xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "device desc: %s", why)
               : XYL_OK;
}

/* The caller's device as the context's: what the draws may use is what the caller enabled. */
static xyl_result adopt_device(xyl_tess_vk *vk, const xyl_tess_vk_device_desc *d,
                               xyl_diag *diag)
{
    vk->physical = d->physical_device;
    vk->device = d->device;
    vkGetPhysicalDeviceProperties(vk->physical, &vk->props);
    memcpy(vk->device_name, vk->props.deviceName, sizeof vk->device_name);
    vk->device_name[sizeof vk->device_name - 1] = '\0';
    if (d->enabled_features) {
        vk->features = *d->enabled_features;
    } else {
        memset(&vk->features, 0, sizeof vk->features);
        vk->features.drawIndirectFirstInstance = VK_TRUE;
    }
    if (!d->queue) return XYL_OK;
    uint32_t n = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(vk->physical, &n, NULL);
    if (d->queue_family >= n)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "device desc: queue_family %u, the device has %u", d->queue_family, n);
    vk->family = d->queue_family;
    vk->queue = d->queue;
    return xyl__vk_create_commands(vk, diag);
}

xyl_result xyl_tess_vk_create_for_device(const xyl_tess_vk_device_desc *desc,
                                         const xyl_tess_patterns *patterns, xyl_tess_vk **out,
                                         xyl_diag *diag)
{
    if (!desc || !patterns || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "desc, patterns and out are required");
    xyl_result r = check_device_desc(desc, diag);
    if (r == XYL_OK) r = check_patterns(patterns, diag);
    if (r != XYL_OK) return r;
    xyl_tess_vk *vk = new_context(&desc->alloc);
    if (!vk) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    xyl__vk_pass where = {desc->render_pass, desc->subpass, desc->color_format,
                          desc->depth_format, VK_SAMPLE_COUNT_1_BIT};
    r = adopt_device(vk, desc, diag);
    if (r == XYL_OK) r = xyl__vk_check_samples(vk, (uint32_t)desc->samples, &where.samples, diag);
    uint32_t frames = desc->frames_in_flight ? desc->frames_in_flight : 2u;
    if (r == XYL_OK) r = create_drawing(vk, patterns, frames, diag);
    if (r == XYL_OK) r = xyl__vk_create_pipes(vk, &where, &vk->pipes, diag);
    return finish_create(vk, r, out, diag);
}

static void destroy_buffers(xyl_tess_vk *vk)
{
    xyl__vk_buffer *all[] = {&vk->pattern_vertices, &vk->pattern_indices, &vk->patches,
                             &vk->frames, &vk->readback, &vk->capture_out, &vk->offsets};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; ++i) xyl__vk_buffer_destroy(vk, all[i]);
    for (uint32_t s = 0; vk->slots && s < vk->slot_count; ++s) {
        xyl__vk_buffer_destroy(vk, &vk->slots[s].instances);
        xyl__vk_buffer_destroy(vk, &vk->slots[s].cmds);
    }
}

/* A caller's device is not waited for: the caller makes sure nothing recorded with vk is
 * pending (xyl_tess_vk.h), and the offscreen calls wait for their own submissions. */
void xyl_tess_vk_destroy(xyl_tess_vk *vk)
{
    if (!vk) return;
    const VkAllocationCallbacks *a = vk->vkalloc;
    if (vk->device) {
        if (vk->owns_device) vkDeviceWaitIdle(vk->device);
        xyl__vk_target_destroy(vk, &vk->target);
        xyl__vk_destroy_pipes(vk, &vk->pipes);
        xyl__vk_destroy_capture(vk);
        xyl__vk_destroy_layouts(vk);
        destroy_buffers(vk);
        if (vk->queries) vkDestroyQueryPool(vk->device, vk->queries, a);
        if (vk->fence) vkDestroyFence(vk->device, vk->fence, a);
        if (vk->pool) vkDestroyCommandPool(vk->device, vk->pool, a);
        if (vk->owns_device) vkDestroyDevice(vk->device, a);
    }
    if (vk->messenger) vk->destroy_messenger(vk->instance, vk->messenger, a);
    if (vk->instance) vkDestroyInstance(vk->instance, a);
    xyl_allocator alloc = vk->alloc;
    xyl__free(&alloc, vk->patch_kinds);
    xyl__free(&alloc, vk->slots);
    xyl__free(&alloc, vk);
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

xyl_result xyl_tess_vk_set_patches(xyl_tess_vk *vk, const xyl_tess_patches *patches,
                                   xyl_diag *diag)
{
    if (!vk || !patches || (patches->count && !patches->records))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "vk and patches (with records) are required");
    xyl_result r = xyl__vk_check_usable(vk, diag);
    if (r != XYL_OK) return r;
    if (patches->count > vk->props.limits.maxStorageBufferRange / sizeof(xyl_tess_patch))
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu patches exceed the device's storage buffer range of %u bytes",
                         patches->count, vk->props.limits.maxStorageBufferRange);
    uint8_t *kinds = xyl__alloc_array(&vk->alloc, patches->count, 1);
    if (!kinds) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    /* The old patches are dropped first: a failed upload leaves none rather than stale ones. */
    xyl__free(&vk->alloc, vk->patch_kinds);
    vk->patch_kinds = NULL;
    vk->patch_count = 0;
    r = xyl__vk_buffer_reserve(vk, &vk->patches, patches->count * sizeof(xyl_tess_patch),
                               BUF_STORAGE, diag);
    if (r != XYL_OK) { /* the draws' set must not name the destroyed buffer */
        if (xyl__vk_buffer_reserve(vk, &vk->patches, 0, BUF_STORAGE, NULL) == XYL_OK)
            write_draw_set(vk);
        xyl__free(&vk->alloc, kinds);
        return r;
    }
    write_draw_set(vk); /* the buffer may be a new one */
    for (size_t i = 0; i < patches->count; ++i)
        kinds[i] = (uint8_t)xyl_tess_patch_kind(&patches->records[i]);
    if (patches->count)
        memcpy(vk->patches.map, patches->records, patches->count * sizeof(xyl_tess_patch));
    vk->patch_kinds = kinds;
    vk->patch_count = patches->count;
    xyl__diag_ok(diag);
    return XYL_OK;
}

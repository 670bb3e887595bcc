/* The Vulkan 1.2 leaf renderer on the caller's device: the species' packed leaves in one
 * storage buffer, each LOD recorded as its two ranges (per sector) of instanced 4-vertex strips
 * with firstInstance = the range's first record, the frame in push constants, and the tests'
 * capture (a vertex-stage store); the per-leaf cut as a compute pass into a list and an indirect
 * command, drawn by a pipeline whose vertex shader reads the list. Every entry point validates
 * all of its input before its first Vulkan call (foliage_draw.c): the shaders read the leaf
 * buffer unchecked. */
#include <string.h>

#include "foliage_draw.h"
#include "foliage_internal.h"
#include "foliage_vk_debug.h"
#include "foliage_vk_util.h"

extern const unsigned char xyl__shader_vk_foliage_leaf_vert[];
extern const size_t xyl__shader_vk_foliage_leaf_vert_size;
extern const unsigned char xyl__shader_vk_foliage_leaf_capture_vert[];
extern const size_t xyl__shader_vk_foliage_leaf_capture_vert_size;
extern const unsigned char xyl__shader_vk_foliage_leaf_frag[];
extern const size_t xyl__shader_vk_foliage_leaf_frag_size;
extern const unsigned char xyl__shader_vk_foliage_leaf_list_vert[];
extern const size_t xyl__shader_vk_foliage_leaf_list_vert_size;
extern const unsigned char xyl__shader_vk_foliage_cut_comp[];
extern const size_t xyl__shader_vk_foliage_cut_comp_size;

_Static_assert(sizeof(xyl_foliage_vk_push) == XYL_FOLIAGE_VK_PUSH_SIZE, "push block size");
_Static_assert(offsetof(xyl_foliage_vk_push, light) == 64, "std430: light follows the mat4");
_Static_assert(offsetof(xyl_foliage_vk_push, color) == 80, "std430: color");
_Static_assert(offsetof(xyl_foliage_vk_push, cutoff) == 96, "std430: cutoff");
_Static_assert(offsetof(xyl_foliage_vk_push, translucency) == 100, "std430: translucency");
_Static_assert(offsetof(xyl_foliage_vk_push, dither) == 104, "std430: the vec2 dither");
_Static_assert(sizeof(xyl__foliage_vk_captured) == 32, "std430 stride of the captured struct");
_Static_assert(sizeof(xyl_foliage_vk_cut_push) == XYL_FOLIAGE_VK_CUT_PUSH_SIZE, "cut push size");
_Static_assert(offsetof(xyl_foliage_vk_cut_push, per_distance) == 12, "std430: vec3, float");
_Static_assert(sizeof(VkDrawIndirectCommand) == 16, "the cut's command is four words");

#define CAPTURE_BYTES_PER_LEAF (4u * sizeof(xyl__foliage_vk_captured))
#define MAX_CAPTURE_BYTES ((uint64_t)1 << 31)

struct xyl_foliage_vk {
    xyl__fvk base; /* device, queue, allocator, memory types, command pool */
    VkPhysicalDeviceFeatures features;
    VkDeviceSize max_storage_range;
    uint32_t max_image_side;
    VkShaderModule vert, vert_capture, vert_list, frag, cut;
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout, cut_layout; /* the draws' push constants, the cut's */
    VkDescriptorPool pool;
    VkDescriptorSet set, capture_set; /* the capture's also has the capture buffer */
    VkPipeline pipeline, capture_pipeline, list_pipeline, cut_pipeline;
    VkRenderPass capture_pass; /* no attachments: the capture rasterizes nothing */
    VkFramebuffer capture_framebuffer;
    VkSampler sampler;
    xyl__fvk_buffer leaves;
    xyl__fvk_buffer nodes, list, command; /* the per-leaf cut's forest, chosen records, draw */
    bool has_cut;                   /* a cut was recorded since the last upload */
    xyl__fvk_image texture;
    xyl__foliage_tables tables; /* leaf_count 0: nothing uploaded */
};

/* ---- the leaf texture --------------------------------------------------------------------- */

static uint32_t mip_levels(uint32_t w, uint32_t h)
{
    uint32_t levels = 1;
    for (uint32_t side = w > h ? w : h; side > 1; side >>= 1) ++levels;
    return levels;
}

static xyl_result image_create(const xyl_foliage_vk *vk, uint32_t w, uint32_t h,
                               xyl__fvk_image *out, xyl_diag *diag)
{
    VkImageCreateInfo ii = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ii.imageType = VK_IMAGE_TYPE_2D;
    ii.format = VK_FORMAT_R8G8B8A8_UNORM;
    ii.extent = (VkExtent3D){w, h, 1};
    ii.mipLevels = mip_levels(w, h);
    ii.arrayLayers = 1;
    ii.samples = VK_SAMPLE_COUNT_1_BIT;
    ii.usage = VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
               VK_IMAGE_USAGE_SAMPLED_BIT;
    return xyl__fvk_image_create(&vk->base, &ii, VK_IMAGE_VIEW_TYPE_2D,
                                 VK_IMAGE_ASPECT_COLOR_BIT, out, diag);
}

static void level_barrier(VkCommandBuffer cmd, VkImage image, uint32_t level, uint32_t count,
                          VkImageLayout from, VkImageLayout to, VkAccessFlags src,
                          VkAccessFlags dst, VkPipelineStageFlags src_stage,
                          VkPipelineStageFlags dst_stage)
{
    VkImageMemoryBarrier b = {.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.srcAccessMask = src;
    b.dstAccessMask = dst;
    b.oldLayout = from;
    b.newLayout = to;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = image;
    b.subresourceRange.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    b.subresourceRange.baseMipLevel = level;
    b.subresourceRange.levelCount = count;
    b.subresourceRange.layerCount = 1;
    vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 0, NULL, 0, NULL, 1, &b);
}

/* Level 0 from the staging buffer, each further level blitted from the one before, every level
 * left in SHADER_READ_ONLY layout for the fragment shader. */
static void record_texture(VkCommandBuffer cmd, VkBuffer staging, VkImage image, uint32_t w,
                           uint32_t h)
{
    const VkPipelineStageFlags xfer = VK_PIPELINE_STAGE_TRANSFER_BIT;
    const VkImageLayout dst = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                        src = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                        read = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    uint32_t levels = mip_levels(w, h);
    level_barrier(cmd, image, 0, levels, VK_IMAGE_LAYOUT_UNDEFINED, dst, 0,
                  VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, xfer);
    VkBufferImageCopy copy = {0};
    copy.imageSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    copy.imageSubresource.layerCount = 1;
    copy.imageExtent = (VkExtent3D){w, h, 1};
    vkCmdCopyBufferToImage(cmd, staging, image, dst, 1, &copy);
    int32_t lw = (int32_t)w, lh = (int32_t)h;
    for (uint32_t i = 1; i < levels; ++i) {
        level_barrier(cmd, image, i - 1, 1, dst, src, VK_ACCESS_TRANSFER_WRITE_BIT,
                      VK_ACCESS_TRANSFER_READ_BIT, xfer, xfer);
        int32_t nw = lw > 1 ? lw / 2 : 1, nh = lh > 1 ? lh / 2 : 1;
        VkImageBlit blit = {0};
        blit.srcSubresource = (VkImageSubresourceLayers){VK_IMAGE_ASPECT_COLOR_BIT, i - 1, 0, 1};
        blit.srcOffsets[1] = (VkOffset3D){lw, lh, 1};
        blit.dstSubresource = (VkImageSubresourceLayers){VK_IMAGE_ASPECT_COLOR_BIT, i, 0, 1};
        blit.dstOffsets[1] = (VkOffset3D){nw, nh, 1};
        vkCmdBlitImage(cmd, image, src, image, dst, 1, &blit, VK_FILTER_LINEAR);
        level_barrier(cmd, image, i - 1, 1, src, read, VK_ACCESS_TRANSFER_READ_BIT,
                      VK_ACCESS_SHADER_READ_BIT, xfer, VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT);
        lw = nw;
        lh = nh;
    }
    level_barrier(cmd, image, levels - 1, 1, dst, read, VK_ACCESS_TRANSFER_WRITE_BIT,
                  VK_ACCESS_SHADER_READ_BIT, xfer, VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT);
}

/* Points binding `binding` of both sets at the buffer or the image. */
static void write_sets(const xyl_foliage_vk *vk, uint32_t binding, VkBuffer buffer,
                       VkImageView view)
{
    VkDescriptorBufferInfo bi = {buffer, 0, VK_WHOLE_SIZE};
    VkDescriptorImageInfo ii = {vk->sampler, view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    VkWriteDescriptorSet w[2];
    for (int k = 0; k < 2; ++k) {
        w[k] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        w[k].dstSet = k ? vk->capture_set : vk->set;
        w[k].dstBinding = binding;
        w[k].descriptorCount = 1;
        w[k].descriptorType = view ? VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER
                                   : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        w[k].pBufferInfo = view ? NULL : &bi;
        w[k].pImageInfo = view ? &ii : NULL;
    }
    vkUpdateDescriptorSets(vk->base.device, 2, w, 0, NULL);
}

/* A new image, swapped in only when its upload worked. */
static xyl_result upload_texture(xyl_foliage_vk *vk, const uint8_t *rgba, uint32_t w, uint32_t h,
                                 xyl_diag *diag)
{
    xyl__fvk_buffer staging = {0};
    xyl__fvk_image im = {0};
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    xyl_result r = xyl__fvk_buffer_create(&vk->base, (VkDeviceSize)w * h * 4u,
                                          VK_BUFFER_USAGE_TRANSFER_SRC_BIT, rgba, &staging, diag);
    if (r == XYL_OK) r = image_create(vk, w, h, &im, diag);
    if (r == XYL_OK) r = xyl__fvk_begin_once(&vk->base, &cmd, diag);
    if (r == XYL_OK) {
        record_texture(cmd, staging.buffer, im.image, w, h);
        r = xyl__fvk_submit_wait(&vk->base, cmd, diag);
    }
    xyl__fvk_buffer_destroy(&vk->base, &staging);
    if (r != XYL_OK) {
        xyl__fvk_image_destroy(&vk->base, &im);
        return r;
    }
    write_sets(vk, XYL_FOLIAGE_VK_BINDING_TEXTURE, VK_NULL_HANDLE, im.view);
    xyl__fvk_image_destroy(&vk->base, &vk->texture);
    vk->texture = im;
    return XYL_OK;
}

/* ---- creation ----------------------------------------------------------------------------- */

static xyl_result check_desc(const xyl_foliage_vk_desc *d, xyl_diag *diag)
{
    return xyl__fvk_check_target(d->physical_device, d->device, d->queue, d->render_pass,
                                 d->color_format, d->depth_format, d->samples, diag);
}

/* The device's version, queue family, sample count and limits, before anything is made. */
static xyl_result query_device(xyl_foliage_vk *vk, const xyl_foliage_vk_desc *d,
                               VkSampleCountFlagBits samples, xyl_diag *diag)
{
    xyl_result r = xyl__fvk_check_device(&vk->base, d->queue_family, samples, diag);
    if (r != XYL_OK) return r;
    vk->max_storage_range = vk->base.properties.limits.maxStorageBufferRange;
    vk->max_image_side = vk->base.properties.limits.maxImageDimension2D;
    if (d->enabled_features) vk->features = *d->enabled_features;
    return XYL_OK;
}

static xyl_result layouts(xyl_foliage_vk *vk, xyl_diag *diag)
{
    VkDescriptorSetLayoutBinding b[6] = {
        {XYL_FOLIAGE_VK_BINDING_LEAVES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
         VK_SHADER_STAGE_VERTEX_BIT, NULL},
        {XYL_FOLIAGE_VK_BINDING_TEXTURE, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1,
         VK_SHADER_STAGE_FRAGMENT_BIT, NULL},
        {XYL_FOLIAGE_VK_BINDING_CAPTURE, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
         VK_SHADER_STAGE_VERTEX_BIT, NULL},
        {XYL_FOLIAGE_VK_BINDING_LIST, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
         VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_COMPUTE_BIT, NULL},
        {XYL_FOLIAGE_VK_BINDING_NODES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
         VK_SHADER_STAGE_COMPUTE_BIT, NULL},
        {XYL_FOLIAGE_VK_BINDING_COMMAND, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
         VK_SHADER_STAGE_COMPUTE_BIT, NULL}};
    VkDescriptorSetLayoutCreateInfo li = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    li.bindingCount = 6;
    li.pBindings = b;
    XYL__FVK_TRY(
        vkCreateDescriptorSetLayout(vk->base.device, &li, vk->base.vkalloc, &vk->set_layout),
        "vkCreateDescriptorSetLayout");
    VkPushConstantRange pc = {VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                              XYL_FOLIAGE_VK_PUSH_SIZE};
    VkPipelineLayoutCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pi.setLayoutCount = 1;
    pi.pSetLayouts = &vk->set_layout;
    pi.pushConstantRangeCount = 1;
    pi.pPushConstantRanges = &pc;
    XYL__FVK_TRY(vkCreatePipelineLayout(vk->base.device, &pi, vk->base.vkalloc, &vk->layout),
           "vkCreatePipelineLayout");
    VkPushConstantRange cut_pc = {VK_SHADER_STAGE_COMPUTE_BIT, 0, XYL_FOLIAGE_VK_CUT_PUSH_SIZE};
    pi.pPushConstantRanges = &cut_pc;
    XYL__FVK_TRY(vkCreatePipelineLayout(vk->base.device, &pi, vk->base.vkalloc, &vk->cut_layout),
           "vkCreatePipelineLayout");
    VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 10},
                                     {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 2}};
    VkDescriptorPoolCreateInfo dp = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    dp.maxSets = 2;
    dp.poolSizeCount = 2;
    dp.pPoolSizes = sizes;
    XYL__FVK_TRY(vkCreateDescriptorPool(vk->base.device, &dp, vk->base.vkalloc, &vk->pool),
           "vkCreateDescriptorPool");
    VkDescriptorSetLayout sl[2] = {vk->set_layout, vk->set_layout};
    VkDescriptorSet sets[2];
    VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    ai.descriptorPool = vk->pool;
    ai.descriptorSetCount = 2;
    ai.pSetLayouts = sl;
    XYL__FVK_TRY(vkAllocateDescriptorSets(vk->base.device, &ai, sets), "vkAllocateDescriptorSets");
    vk->set = sets[0];
    vk->capture_set = sets[1];
    return XYL_OK;
}

/* A draw pipeline of the renderer's layout: capture (vertex stage only), the cut's list, or
 * the plain draw. */
static xyl_result pipeline(const xyl_foliage_vk *vk, xyl__fvk_pipe t, bool capture, bool list,
                           VkPipeline *out, xyl_diag *diag)
{
    t.vert = capture ? vk->vert_capture : list ? vk->vert_list : vk->vert;
    t.frag = capture ? VK_NULL_HANDLE : vk->frag;
    t.layout = vk->layout;
    return xyl__fvk_pipeline(&vk->base, &t, out, diag);
}

static xyl_result cut_pipeline(xyl_foliage_vk *vk, xyl_diag *diag)
{
    VkComputePipelineCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    ci.stage = (VkPipelineShaderStageCreateInfo){
        VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, NULL, 0,
        VK_SHADER_STAGE_COMPUTE_BIT, vk->cut, "main", NULL};
    ci.layout = vk->cut_layout;
    XYL__FVK_TRY(vkCreateComputePipelines(vk->base.device, VK_NULL_HANDLE, 1, &ci, vk->base.vkalloc,
                                    &vk->cut_pipeline),
           "vkCreateComputePipelines");
    return XYL_OK;
}

static xyl_result objects(xyl_foliage_vk *vk, const xyl_foliage_vk_desc *d,
                          VkSampleCountFlagBits samples, xyl_diag *diag)
{
    xyl_result r = xyl__fvk_shader(&vk->base, xyl__shader_vk_foliage_leaf_vert,
                          xyl__shader_vk_foliage_leaf_vert_size, &vk->vert, diag);
    if (r == XYL_OK)
        r = xyl__fvk_shader(&vk->base, xyl__shader_vk_foliage_leaf_capture_vert,
                   xyl__shader_vk_foliage_leaf_capture_vert_size, &vk->vert_capture, diag);
    if (r == XYL_OK)
        r = xyl__fvk_shader(&vk->base, xyl__shader_vk_foliage_leaf_frag,
                            xyl__shader_vk_foliage_leaf_frag_size, &vk->frag, diag);
    if (r == XYL_OK)
        r = xyl__fvk_shader(&vk->base, xyl__shader_vk_foliage_leaf_list_vert,
                   xyl__shader_vk_foliage_leaf_list_vert_size, &vk->vert_list, diag);
    if (r == XYL_OK)
        r = xyl__fvk_shader(&vk->base, xyl__shader_vk_foliage_cut_comp,
                            xyl__shader_vk_foliage_cut_comp_size, &vk->cut, diag);
    if (r == XYL_OK) r = layouts(vk, diag);
    xyl__fvk_pipe t = {0};
    t.pass = d->render_pass;
    t.subpass = d->subpass;
    t.color = d->color_format;
    t.depth = d->depth_format;
    t.samples = samples;
    if (r == XYL_OK) r = pipeline(vk, t, false, false, &vk->pipeline, diag);
    if (r == XYL_OK) r = pipeline(vk, t, false, true, &vk->list_pipeline, diag);
    if (r == XYL_OK) r = cut_pipeline(vk, diag);
    if (r != XYL_OK) return r;
    VkSamplerCreateInfo si = {.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    si.magFilter = si.minFilter = VK_FILTER_LINEAR;
    si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_LINEAR;
    si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    si.maxLod = VK_LOD_CLAMP_NONE;
    XYL__FVK_TRY(vkCreateSampler(vk->base.device, &si, vk->base.vkalloc, &vk->sampler),
           "vkCreateSampler");
    r = xyl__fvk_make_pool(&vk->base, d->queue_family, diag);
    if (r != XYL_OK) return r;
    const uint8_t white[4] = {255, 255, 255, 255};
    return upload_texture(vk, white, 1, 1, diag);
}

xyl_result xyl_foliage_vk_create(const xyl_foliage_vk_desc *desc, xyl_foliage_vk **out,
                                 xyl_diag *diag)
{
    if (!desc || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "desc and out are required");
    xyl_result r = check_desc(desc, diag);
    if (r != XYL_OK) return r;
    VkSampleCountFlagBits samples = desc->samples ? desc->samples : VK_SAMPLE_COUNT_1_BIT;
    xyl_allocator a = desc->alloc;
    xyl_foliage_vk *vk = xyl__calloc(&a, 1, sizeof *vk);
    if (!vk) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    xyl__fvk_init(&vk->base, &a, desc->physical_device, desc->device, desc->queue);
    r = query_device(vk, desc, samples, diag);
    if (r == XYL_OK) r = objects(vk, desc, samples, diag);
    if (r != XYL_OK) {
        xyl_foliage_vk_destroy(vk);
        return r;
    }
    *out = vk;
    xyl__diag_ok(diag);
    return XYL_OK;
}

void xyl_foliage_vk_destroy(xyl_foliage_vk *vk)
{
    if (!vk) return;
    VkDevice dev = vk->base.device;
    xyl__fvk_buffer_destroy(&vk->base, &vk->leaves);
    xyl__fvk_buffer_destroy(&vk->base, &vk->nodes);
    xyl__fvk_buffer_destroy(&vk->base, &vk->list);
    xyl__fvk_buffer_destroy(&vk->base, &vk->command);
    xyl__fvk_image_destroy(&vk->base, &vk->texture);
    xyl__fvk_finish(&vk->base);
    if (vk->sampler) vkDestroySampler(dev, vk->sampler, vk->base.vkalloc);
    if (vk->capture_pipeline) vkDestroyPipeline(dev, vk->capture_pipeline, vk->base.vkalloc);
    if (vk->capture_framebuffer)
        vkDestroyFramebuffer(dev, vk->capture_framebuffer, vk->base.vkalloc);
    if (vk->capture_pass) vkDestroyRenderPass(dev, vk->capture_pass, vk->base.vkalloc);
    VkPipeline pipes[3] = {vk->pipeline, vk->list_pipeline, vk->cut_pipeline};
    for (int k = 0; k < 3; ++k)
        if (pipes[k]) vkDestroyPipeline(dev, pipes[k], vk->base.vkalloc);
    if (vk->pool) vkDestroyDescriptorPool(dev, vk->pool, vk->base.vkalloc);
    if (vk->layout) vkDestroyPipelineLayout(dev, vk->layout, vk->base.vkalloc);
    if (vk->cut_layout) vkDestroyPipelineLayout(dev, vk->cut_layout, vk->base.vkalloc);
    if (vk->set_layout) vkDestroyDescriptorSetLayout(dev, vk->set_layout, vk->base.vkalloc);
    VkShaderModule mods[5] = {vk->vert, vk->vert_capture, vk->vert_list, vk->frag, vk->cut};
    for (int k = 0; k < 5; ++k)
        if (mods[k]) vkDestroyShaderModule(dev, mods[k], vk->base.vkalloc);
    xyl_allocator a = vk->base.alloc;
    xyl__foliage_tables_free(&vk->tables, &a);
    xyl__free(&a, vk);
}

/* ---- the species' leaves and texture ------------------------------------------------------ */

xyl_result xyl_foliage_vk_set_foliage(xyl_foliage_vk *vk, const xyl_foliage *foliage,
                                      xyl_diag *diag)
{
    if (!vk || !foliage)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "vk and foliage are required");
    size_t n = foliage->leaf_count;
    if (n > UINT32_MAX / 4 || (uint64_t)n * sizeof(xyl_foliage_gpu_leaf) > vk->max_storage_range)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu leaves exceed the device's storage buffer range (%llu bytes)", n,
                         (unsigned long long)vk->max_storage_range);
    xyl__foliage_tables tables;
    xyl_result r = xyl__foliage_tables_make(foliage, &vk->base.alloc, &tables, diag);
    if (r != XYL_OK) return r;
    xyl_foliage_gpu_leaf *records = xyl__alloc_array(&vk->base.alloc, n, sizeof *records);
    xyl__foliage_cut_node *nodes = xyl__alloc_array(&vk->base.alloc, n, sizeof *nodes);
    if (!records || !nodes) r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    if (r == XYL_OK) r = xyl_foliage_pack_gpu(foliage->leaves, n, records, diag);
    if (r == XYL_OK) r = xyl__foliage_cut_nodes(foliage, nodes, diag);
    /* the records, the cut's nodes, its list and its command, swapped in together */
    xyl__fvk_buffer b[4] = {{0}};
    const VkBufferUsageFlags storage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    if (r == XYL_OK)
        r = xyl__fvk_buffer_create(&vk->base, (VkDeviceSize)n * sizeof *records, storage, records,
                                   &b[0], diag);
    if (r == XYL_OK)
        r = xyl__fvk_buffer_create(&vk->base, (VkDeviceSize)n * sizeof *nodes, storage, nodes,
                                   &b[1], diag);
    if (r == XYL_OK)
        r = xyl__fvk_buffer_create(&vk->base, (VkDeviceSize)n * sizeof(uint32_t), storage, NULL,
                                   &b[2], diag);
    if (r == XYL_OK)
        r = xyl__fvk_buffer_create(&vk->base, sizeof(VkDrawIndirectCommand),
                          storage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                              VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                          NULL, &b[3], diag);
    xyl__free(&vk->base.alloc, records);
    xyl__free(&vk->base.alloc, nodes);
    if (r != XYL_OK) {
        for (int k = 0; k < 4; ++k) xyl__fvk_buffer_destroy(&vk->base, &b[k]);
        xyl__foliage_tables_free(&tables, &vk->base.alloc);
        return r;
    }
    write_sets(vk, XYL_FOLIAGE_VK_BINDING_LEAVES, b[0].buffer, VK_NULL_HANDLE);
    write_sets(vk, XYL_FOLIAGE_VK_BINDING_NODES, b[1].buffer, VK_NULL_HANDLE);
    write_sets(vk, XYL_FOLIAGE_VK_BINDING_LIST, b[2].buffer, VK_NULL_HANDLE);
    write_sets(vk, XYL_FOLIAGE_VK_BINDING_COMMAND, b[3].buffer, VK_NULL_HANDLE);
    xyl__fvk_buffer *mine[4] = {&vk->leaves, &vk->nodes, &vk->list, &vk->command};
    for (int k = 0; k < 4; ++k) {
        xyl__fvk_buffer_destroy(&vk->base, mine[k]);
        *mine[k] = b[k];
    }
    vk->has_cut = false;
    xyl__foliage_tables_free(&vk->tables, &vk->base.alloc);
    vk->tables = tables;
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_result xyl_foliage_vk_set_texture(xyl_foliage_vk *vk, const uint8_t *rgba, uint32_t width,
                                      uint32_t height, xyl_diag *diag)
{
    if (!vk || !rgba)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "vk and rgba are required");
    uint32_t cap = XYL_FOLIAGE_VK_MAX_TEXTURE_SIDE;
    if (vk->max_image_side > 0 && vk->max_image_side < cap) cap = vk->max_image_side;
    if (width == 0 || height == 0 || width > cap || height > cap)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a leaf texture of %u x %u: each side from 1 to %u", width, height, cap);
    xyl_result r = upload_texture(vk, rgba, width, height, diag);
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

/* ---- draws -------------------------------------------------------------------------------- */

static void fill_push(const xyl__foliage_frame *f, xyl_foliage_vk_push *push)
{
    memset(push, 0, sizeof *push);
    memcpy(push->view_proj, f->view_proj, sizeof push->view_proj);
    memcpy(push->light, f->light, sizeof f->light);
    memcpy(push->color, f->color, sizeof push->color);
    push->cutoff = f->cutoff;
    push->translucency = f->translucency;
    memcpy(push->dither, f->dither, sizeof push->dither);
}

static xyl_result check_draw(const xyl_foliage_vk *vk, const xyl_foliage_vk_frame *frame,
                             const uint32_t *lods, size_t lod_count, xyl_foliage_vk_push *push,
                             xyl_diag *diag)
{
    if (!vk || !frame || !lods)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "vk, frame and lods are required");
    xyl__foliage_frame f;
    const xyl__foliage_frame_in in = XYL__FOLIAGE_FRAME_IN(frame);
    xyl_result r = xyl__foliage_draw_check(&vk->tables, lods, lod_count, &in, &f, diag);
    if (r == XYL_OK) fill_push(&f, push);
    return r;
}

/* Per sector the LOD's two ranges, [base, base + a) and [base + b, base + b + c), each one
 * instanced draw whose instance index is the record's. */
static void record_draws(const xyl_foliage_vk *vk, VkCommandBuffer cmd, VkPipeline pipe,
                         VkDescriptorSet set, const xyl_foliage_vk_push *push,
                         const uint32_t *lods)
{
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipe);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, vk->layout, 0, 1, &set, 0,
                            NULL);
    vkCmdPushConstants(cmd, vk->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT,
                       0, sizeof *push, push);
    for (uint32_t s = 0; s < vk->tables.sector_count; ++s) {
        const xyl__foliage_sector_ref *sec = &vk->tables.sectors[s];
        const xyl__foliage_range *r = &vk->tables.ranges[sec->first_lod + lods[s]];
        const uint32_t first[2] = {sec->base, sec->base + r->b}, count[2] = {r->a, r->c};
        for (int k = 0; k < 2; ++k)
            if (count[k]) vkCmdDraw(cmd, 4, count[k], 0, first[k]);
    }
}

xyl_result xyl_foliage_vk_cmd_draw(xyl_foliage_vk *vk, VkCommandBuffer cmd,
                                   const xyl_foliage_vk_frame *frame, const uint32_t *lods,
                                   size_t lod_count, xyl_diag *diag)
{
    if (!cmd)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "cmd is required");
    xyl_foliage_vk_push push;
    xyl_result r = check_draw(vk, frame, lods, lod_count, &push, diag);
    if (r != XYL_OK) return r;
    record_draws(vk, cmd, vk->pipeline, vk->set, &push, lods);
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- the per-leaf cut --------------------------------------------------------------------- */

static void barrier(VkCommandBuffer cmd, VkPipelineStageFlags src, VkAccessFlags src_access,
                    VkPipelineStageFlags dst, VkAccessFlags dst_access)
{
    VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = src_access;
    mb.dstAccessMask = dst_access;
    vkCmdPipelineBarrier(cmd, src, dst, 0, 1, &mb, 0, NULL, 0, NULL);
}

xyl_result xyl_foliage_vk_cmd_cut(xyl_foliage_vk *vk, VkCommandBuffer cmd,
                                  const xyl_foliage_view *view, xyl_diag *diag)
{
    if (!vk || !cmd || !view)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "vk, cmd and view are required");
    if (!vk->tables.leaf_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "no foliage uploaded: call xyl_foliage_vk_set_foliage first");
    double eye[3], per_distance = 0.0;
    xyl_result r = xyl__foliage_view_resolve(view, eye, &per_distance, diag);
    if (r != XYL_OK) return r;
    xyl_foliage_vk_cut_push push = {{(float)eye[0], (float)eye[1], (float)eye[2]},
                                    (float)per_distance, (uint32_t)vk->tables.leaf_count};
    const VkPipelineStageFlags readers = VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT |
                                         VK_PIPELINE_STAGE_VERTEX_SHADER_BIT;
    const VkPipelineStageFlags writers = VK_PIPELINE_STAGE_TRANSFER_BIT |
                                         VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
    /* earlier draws of the list have read it before it is written again */
    barrier(cmd, readers, 0, writers, 0);
    const VkDrawIndirectCommand zero = {4, 0, 0, 0};
    vkCmdUpdateBuffer(cmd, vk->command.buffer, 0, sizeof zero, &zero);
    barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
            VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
            VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, vk->cut_pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, vk->cut_layout, 0, 1, &vk->set,
                            0, NULL);
    vkCmdPushConstants(cmd, vk->cut_layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof push, &push);
    vkCmdDispatch(cmd, (push.count + XYL_FOLIAGE_GL_CUT_GROUP - 1) / XYL_FOLIAGE_GL_CUT_GROUP, 1,
                  1);
    barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
            readers | VK_PIPELINE_STAGE_HOST_BIT,
            VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_SHADER_READ_BIT |
                VK_ACCESS_HOST_READ_BIT);
    vk->has_cut = true;
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_result xyl_foliage_vk_cmd_draw_cut(xyl_foliage_vk *vk, VkCommandBuffer cmd,
                                       const xyl_foliage_vk_frame *frame, xyl_diag *diag)
{
    if (!vk || !cmd || !frame)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "vk, cmd and frame are required");
    xyl__foliage_frame f;
    const xyl__foliage_frame_in in = XYL__FOLIAGE_FRAME_IN(frame);
    xyl_result r = xyl__foliage_frame_check(&vk->tables, &in, &f, diag);
    if (r != XYL_OK) return r;
    if (!vk->has_cut)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "no cut recorded since the foliage was uploaded: call "
                         "xyl_foliage_vk_cmd_cut first");
    xyl_foliage_vk_push push;
    fill_push(&f, &push);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, vk->list_pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, vk->layout, 0, 1, &vk->set, 0,
                            NULL);
    vkCmdPushConstants(cmd, vk->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT,
                       0, sizeof push, &push);
    vkCmdDrawIndirect(cmd, vk->command.buffer, 0, 1, sizeof(VkDrawIndirectCommand));
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_result xyl_foliage_vk_last_cut(xyl_foliage_vk *vk, uint32_t *out, size_t capacity,
                                   size_t *count, xyl_diag *diag)
{
    if (!vk || !count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "vk and count are required");
    if (!vk->has_cut)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "no cut recorded since the foliage was uploaded");
    VkDrawIndirectCommand command;
    void *map = NULL;
    VkResult vr = vkMapMemory(vk->base.device, vk->command.memory, 0, sizeof command, 0, &map);
    if (vr != VK_SUCCESS) return xyl__fvk_fail(diag, vr, "vkMapMemory");
    memcpy(&command, map, sizeof command);
    vkUnmapMemory(vk->base.device, vk->command.memory);
    size_t n = command.instanceCount;
    if (n > vk->tables.leaf_count || command.vertexCount != 4)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "the cut's command counts %zu of %zu leaves: has it run?", n,
                         vk->tables.leaf_count);
    if (out) {
        if (capacity < n)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                             "the cut has %zu leaves, out holds %zu", n, capacity);
        if (n) {
            vr = vkMapMemory(vk->base.device, vk->list.memory, 0, n * sizeof *out, 0, &map);
            if (vr != VK_SUCCESS) return xyl__fvk_fail(diag, vr, "vkMapMemory");
            memcpy(out, map, n * sizeof *out);
            vkUnmapMemory(vk->base.device, vk->list.memory);
        }
    }
    *count = n;
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- capture ------------------------------------------------------------------------------ */

static xyl_result capture_reserve(xyl_foliage_vk *vk, xyl_diag *diag)
{
    if (vk->capture_pipeline) return XYL_OK;
    if (!vk->features.vertexPipelineStoresAndAtomics)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "the capture needs vertexPipelineStoresAndAtomics enabled");
    /* each object once: a call that failed half-way resumes where it stopped */
    if (!vk->capture_pass) {
        VkSubpassDescription sub = {0};
        sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
        VkRenderPassCreateInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
        ri.subpassCount = 1;
        ri.pSubpasses = &sub;
        XYL__FVK_TRY(vkCreateRenderPass(vk->base.device, &ri, vk->base.vkalloc, &vk->capture_pass),
               "vkCreateRenderPass");
    }
    if (!vk->capture_framebuffer) {
        VkFramebufferCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
        fi.renderPass = vk->capture_pass;
        fi.width = fi.height = fi.layers = 1;
        XYL__FVK_TRY(
            vkCreateFramebuffer(vk->base.device, &fi, vk->base.vkalloc, &vk->capture_framebuffer),
            "vkCreateFramebuffer");
    }
    xyl__fvk_pipe t = {0};
    t.pass = vk->capture_pass;
    t.samples = VK_SAMPLE_COUNT_1_BIT;
    return pipeline(vk, t, true, false, &vk->capture_pipeline, diag);
}

static void record_capture(const xyl_foliage_vk *vk, VkCommandBuffer cmd,
                           const xyl_foliage_vk_push *push, const uint32_t *lods)
{
    VkRenderPassBeginInfo rb = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rb.renderPass = vk->capture_pass;
    rb.framebuffer = vk->capture_framebuffer;
    rb.renderArea.extent = (VkExtent2D){1, 1};
    vkCmdBeginRenderPass(cmd, &rb, VK_SUBPASS_CONTENTS_INLINE);
    VkViewport vp = {0.0f, 0.0f, 1.0f, 1.0f, 0.0f, 1.0f};
    VkRect2D sc = {{0, 0}, {1, 1}};
    vkCmdSetViewport(cmd, 0, 1, &vp);
    vkCmdSetScissor(cmd, 0, 1, &sc);
    record_draws(vk, cmd, vk->capture_pipeline, vk->capture_set, push, lods);
    vkCmdEndRenderPass(cmd);
    VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_VERTEX_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0,
                         1, &mb, 0, NULL, 0, NULL);
}

xyl_result xyl__foliage_vk_capture(xyl_foliage_vk *vk, const xyl_foliage_vk_frame *frame,
                                   const uint32_t *lods, size_t lod_count,
                                   xyl__foliage_vk_captured *out, size_t capacity,
                                   xyl_diag *diag)
{
    xyl_foliage_vk_push push;
    xyl_result r = check_draw(vk, frame, lods, lod_count, &push, diag);
    if (r != XYL_OK) return r;
    size_t entries = 4 * vk->tables.leaf_count;
    if (!out || capacity < entries)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "out must hold 4 entries per leaf, %zu", entries);
    uint64_t bytes = (uint64_t)vk->tables.leaf_count * CAPTURE_BYTES_PER_LEAF;
    if (bytes > MAX_CAPTURE_BYTES)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "a capture of %llu bytes exceeds 2 GiB", (unsigned long long)bytes);
    r = capture_reserve(vk, diag);
    if (r != XYL_OK) return r;
    memset(out, 0xff, entries * sizeof *out); /* leaf UINT32_MAX: no vertex stored */
    xyl__fvk_buffer b = {0};
    r = xyl__fvk_buffer_create(&vk->base, bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, out, &b, diag);
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    if (r == XYL_OK) r = xyl__fvk_begin_once(&vk->base, &cmd, diag);
    if (r == XYL_OK) {
        VkDescriptorBufferInfo bi = {b.buffer, 0, VK_WHOLE_SIZE};
        VkWriteDescriptorSet w = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        w.dstSet = vk->capture_set;
        w.dstBinding = XYL_FOLIAGE_VK_BINDING_CAPTURE;
        w.descriptorCount = 1;
        w.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        w.pBufferInfo = &bi;
        vkUpdateDescriptorSets(vk->base.device, 1, &w, 0, NULL);
        record_capture(vk, cmd, &push, lods);
        r = xyl__fvk_submit_wait(&vk->base, cmd, diag);
    }
    void *map = NULL;
    VkResult vr = VK_SUCCESS;
    if (r == XYL_OK &&
        (vr = vkMapMemory(vk->base.device, b.memory, 0, bytes, 0, &map)) != VK_SUCCESS)
        r = xyl__fvk_fail(diag, vr, "vkMapMemory");
    if (r == XYL_OK) {
        memcpy(out, map, (size_t)bytes);
        vkUnmapMemory(vk->base.device, b.memory);
    }
    xyl__fvk_buffer_destroy(&vk->base, &b);
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

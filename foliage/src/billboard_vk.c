/* A tree as a billboard on Vulkan (xyl_billboard_vk.h): each view of the GL billboard's bake
 * rendered by the caller's draws inside the library's own single-sample render pass, read
 * back, turned into the same maps as GL's by the same CPU code (billboard_shape.c) and
 * uploaded into a mipmapped array (or the octahedral atlas); drawn by the GL billboard's
 * shaders compiled for Vulkan, the frame in push constants, the billboard's fixed values in a
 * small uniform buffer. */
#include <string.h>

#include "billboard_shape.h"
#include "foliage_vk_util.h"
#include "xylem/xyl_billboard_vk.h"

extern const unsigned char xyl__shader_vk_billboard_vert[];
extern const size_t xyl__shader_vk_billboard_vert_size;
extern const unsigned char xyl__shader_vk_billboard_instances_vert[];
extern const size_t xyl__shader_vk_billboard_instances_vert_size;
extern const unsigned char xyl__shader_vk_billboard_frag[];
extern const size_t xyl__shader_vk_billboard_frag_size;
extern const unsigned char xyl__shader_vk_impostor_vert[];
extern const size_t xyl__shader_vk_impostor_vert_size;
extern const unsigned char xyl__shader_vk_impostor_frag[];
extern const size_t xyl__shader_vk_impostor_frag_size;

_Static_assert(sizeof(xyl_billboard_vk_push) == XYL_BILLBOARD_VK_PUSH_SIZE, "push block size");
_Static_assert(offsetof(xyl_billboard_vk_push, eye) == 64, "std430: eye follows the mat4");
_Static_assert(offsetof(xyl_billboard_vk_push, light) == 80, "std430: light");
_Static_assert(offsetof(xyl_billboard_vk_push, dither) == 96, "std430: the vec2 dither");
_Static_assert(offsetof(xyl_billboard_vk_push, first) == 104, "std430: first");
_Static_assert(sizeof(xyl_billboard_vk_constants) == XYL_BILLBOARD_VK_CONSTANTS_SIZE,
               "constants size");
_Static_assert(offsetof(xyl_billboard_vk_constants, half_size) == 32, "std140: half_size");
_Static_assert(offsetof(xyl_billboard_vk_constants, kind) == 40, "std140: kind");
_Static_assert(offsetof(xyl_billboard_vk_constants, to_coverage) == 48, "std140: to_coverage");

struct xyl_billboard_vk {
    xyl__fvk vk;
    xyl__billboard_shape shape;
    VkSampleCountFlagBits samples;
    bool alpha_to_one;
    uint32_t side, layers, levels; /* the images' extent, layers and mip levels */
    VkShaderModule vert, vert_instances, frag;
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkDescriptorPool pool;
    VkDescriptorSet set;
    VkPipeline pipeline, instances_pipeline; /* the latter: not for the octahedral kind */
    VkSampler sampler;
    xyl__fvk_image color, normal;
    xyl__fvk_buffer constants;
    VkDeviceSize instance_count; /* in the bound instance buffer; 0: none bound */
};

/* What the bake renders into and reads back through. */
typedef struct bake_target {
    VkRenderPass pass;
    xyl__fvk_image att[2]; /* colour, depth */
    VkFramebuffer framebuffer;
    xyl__fvk_buffer readback; /* colour, then depth: 8 bytes a texel */
    xyl__fvk_buffer staging;  /* the colour map, then the normal map: 8 bytes a texel */
} bake_target;

/* ---- checks ------------------------------------------------------------------------------- */

static xyl_result check_desc(const xyl_billboard_vk_desc *d, xyl_diag *diag)
{
    xyl_result r = xyl__fvk_check_target(d->physical_device, d->device, d->queue, d->render_pass,
                                         d->color_format, d->depth_format, d->samples, diag);
    if (r != XYL_OK) return r;
    const xyl__billboard_params p = {d->kind, d->planes, d->resolution, d->grid,
                                     d->lo, d->hi, d->light_dir};
    return xyl__billboard_check(&p, diag);
}

/* The images' size against the device's limits, the formats' features. */
static xyl_result check_limits(const xyl_billboard_vk *bb, xyl_diag *diag)
{
    const VkPhysicalDeviceLimits *l = &bb->vk.properties.limits;
    if (bb->side > l->maxImageDimension2D)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "billboard images of %u texels a side exceed the device's %u",
                         bb->side, l->maxImageDimension2D);
    if (bb->layers > l->maxImageArrayLayers)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "%u views exceed the device's %u array layers", bb->layers,
                         l->maxImageArrayLayers);
    VkFormatProperties fc, fd;
    vkGetPhysicalDeviceFormatProperties(bb->vk.physical, XYL_BILLBOARD_VK_BAKE_COLOR, &fc);
    vkGetPhysicalDeviceFormatProperties(bb->vk.physical, XYL_BILLBOARD_VK_BAKE_DEPTH, &fd);
    const VkFormatFeatureFlags need_c =
        VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT |
        VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT | VK_FORMAT_FEATURE_BLIT_SRC_BIT |
        VK_FORMAT_FEATURE_BLIT_DST_BIT;
    if ((fc.optimalTilingFeatures & need_c) != need_c ||
        !(fd.optimalTilingFeatures & VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT))
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "%s cannot render, sample and blit R8G8B8A8_UNORM or render "
                         "D32_SFLOAT depth", bb->vk.properties.deviceName);
    return XYL_OK;
}

/* ---- images ------------------------------------------------------------------------------- */

/* A sampled RGBA8 map: the views' array, or the octahedral atlas. */
static xyl_result map_create(const xyl_billboard_vk *bb, xyl__fvk_image *out, xyl_diag *diag)
{
    VkImageCreateInfo ii = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ii.imageType = VK_IMAGE_TYPE_2D;
    ii.format = VK_FORMAT_R8G8B8A8_UNORM;
    ii.extent = (VkExtent3D){bb->side, bb->side, 1};
    ii.mipLevels = bb->levels;
    ii.arrayLayers = bb->layers;
    ii.samples = VK_SAMPLE_COUNT_1_BIT;
    ii.usage = VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
               VK_IMAGE_USAGE_SAMPLED_BIT;
    return xyl__fvk_image_create(&bb->vk, &ii,
                        bb->shape.grid ? VK_IMAGE_VIEW_TYPE_2D : VK_IMAGE_VIEW_TYPE_2D_ARRAY,
                        VK_IMAGE_ASPECT_COLOR_BIT, out, diag);
}

static void barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect,
                    uint32_t level, uint32_t levels, uint32_t layers, VkImageLayout from,
                    VkImageLayout to, VkAccessFlags src, VkAccessFlags dst,
                    VkPipelineStageFlags src_stage, VkPipelineStageFlags dst_stage)
{
    VkImageMemoryBarrier b = {.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.srcAccessMask = src;
    b.dstAccessMask = dst;
    b.oldLayout = from;
    b.newLayout = to;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = image;
    b.subresourceRange = (VkImageSubresourceRange){aspect, level, levels, 0, layers};
    vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 0, NULL, 0, NULL, 1, &b);
}

/* Each level after the first blitted from the one before (all layers at once), every level
 * left in SHADER_READ_ONLY layout. */
static void record_mipmaps(const xyl_billboard_vk *bb, VkCommandBuffer cmd, VkImage image)
{
    const VkPipelineStageFlags xfer = VK_PIPELINE_STAGE_TRANSFER_BIT,
                               frag = VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT;
    const VkImageLayout dst = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                        src = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                        read = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    const VkImageAspectFlags c = VK_IMAGE_ASPECT_COLOR_BIT;
    int32_t side = (int32_t)bb->side;
    for (uint32_t i = 1; i < bb->levels; ++i) {
        barrier(cmd, image, c, i - 1, 1, bb->layers, dst, src, VK_ACCESS_TRANSFER_WRITE_BIT,
                VK_ACCESS_TRANSFER_READ_BIT, xfer, xfer);
        int32_t next = side > 1 ? side / 2 : 1;
        VkImageBlit blit = {0};
        blit.srcSubresource = (VkImageSubresourceLayers){c, i - 1, 0, bb->layers};
        blit.srcOffsets[1] = (VkOffset3D){side, side, 1};
        blit.dstSubresource = (VkImageSubresourceLayers){c, i, 0, bb->layers};
        blit.dstOffsets[1] = (VkOffset3D){next, next, 1};
        vkCmdBlitImage(cmd, image, src, image, dst, 1, &blit, VK_FILTER_LINEAR);
        barrier(cmd, image, c, i - 1, 1, bb->layers, src, read, VK_ACCESS_TRANSFER_READ_BIT,
                VK_ACCESS_SHADER_READ_BIT, xfer, frag);
        side = next;
    }
    barrier(cmd, image, c, bb->levels - 1, 1, bb->layers, dst, read, VK_ACCESS_TRANSFER_WRITE_BIT,
            VK_ACCESS_SHADER_READ_BIT, xfer, frag);
}

/* Where view v lies in the maps: its layer, or its cell of the atlas. */
static VkBufferImageCopy view_region(const xyl_billboard_vk *bb, uint32_t v, VkDeviceSize offset)
{
    uint32_t n = bb->shape.resolution, g = bb->shape.grid;
    VkBufferImageCopy c = {0};
    c.bufferOffset = offset;
    c.imageSubresource = (VkImageSubresourceLayers){VK_IMAGE_ASPECT_COLOR_BIT, 0, g ? 0 : v, 1};
    if (g) c.imageOffset = (VkOffset3D){(int32_t)(v % g * n), (int32_t)(v / g * n), 0};
    c.imageExtent = (VkExtent3D){n, n, 1};
    return c;
}

/* ---- pipelines ---------------------------------------------------------------------------- */

static xyl_result layouts(xyl_billboard_vk *bb, xyl_diag *diag)
{
    const xyl__fvk *vk = &bb->vk;
    const VkShaderStageFlags both = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
    VkDescriptorSetLayoutBinding b[4] = {
        {XYL_BILLBOARD_VK_BINDING_COLOR, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1,
         VK_SHADER_STAGE_FRAGMENT_BIT, NULL},
        {XYL_BILLBOARD_VK_BINDING_NORMAL, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1,
         VK_SHADER_STAGE_FRAGMENT_BIT, NULL},
        {XYL_BILLBOARD_VK_BINDING_CONSTANTS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, both, NULL},
        {XYL_BILLBOARD_VK_BINDING_INSTANCES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
         VK_SHADER_STAGE_VERTEX_BIT, NULL}};
    VkDescriptorSetLayoutCreateInfo li = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    li.bindingCount = 4;
    li.pBindings = b;
    XYL__FVK_TRY(vkCreateDescriptorSetLayout(vk->device, &li, vk->vkalloc, &bb->set_layout),
           "vkCreateDescriptorSetLayout");
    VkPushConstantRange pc = {both, 0, XYL_BILLBOARD_VK_PUSH_SIZE};
    VkPipelineLayoutCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pi.setLayoutCount = 1;
    pi.pSetLayouts = &bb->set_layout;
    pi.pushConstantRangeCount = 1;
    pi.pPushConstantRanges = &pc;
    XYL__FVK_TRY(vkCreatePipelineLayout(vk->device, &pi, vk->vkalloc, &bb->layout),
           "vkCreatePipelineLayout");
    VkDescriptorPoolSize sizes[3] = {{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 2},
                                     {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1},
                                     {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1}};
    VkDescriptorPoolCreateInfo dp = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    dp.maxSets = 1;
    dp.poolSizeCount = 3;
    dp.pPoolSizes = sizes;
    XYL__FVK_TRY(vkCreateDescriptorPool(vk->device, &dp, vk->vkalloc, &bb->pool),
           "vkCreateDescriptorPool");
    VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    ai.descriptorPool = bb->pool;
    ai.descriptorSetCount = 1;
    ai.pSetLayouts = &bb->set_layout;
    XYL__FVK_TRY(vkAllocateDescriptorSets(vk->device, &ai, &bb->set), "vkAllocateDescriptorSets");
    return XYL_OK;
}

/* A draw pipeline into the desc's pass (or dynamic rendering) with the vertex stage vert. */
static xyl_result pipeline(const xyl_billboard_vk *bb, const xyl_billboard_vk_desc *d,
                           VkShaderModule vert, VkPipeline *out, xyl_diag *diag)
{
    xyl__fvk_pipe p = {0};
    p.vert = vert;
    p.frag = bb->frag;
    p.layout = bb->layout;
    p.pass = d->render_pass;
    p.subpass = d->subpass;
    p.color = d->color_format;
    p.depth = d->depth_format;
    p.samples = bb->samples;
    p.alpha_to_coverage = bb->samples != VK_SAMPLE_COUNT_1_BIT;
    p.alpha_to_one = p.alpha_to_coverage && bb->alpha_to_one;
    /* the alpha that went to coverage is not the pixel's opacity: without alpha-to-one it is
     * not written, so the pixel keeps the alpha it had (an opaque clear stays opaque) */
    p.keep_alpha = p.alpha_to_coverage && !p.alpha_to_one;
    return xyl__fvk_pipeline(&bb->vk, &p, out, diag);
}

/* Shaders, layouts, pipelines, sampler, the maps and the constants, the descriptor set. */
static xyl_result objects(xyl_billboard_vk *bb, const xyl_billboard_vk_desc *d, xyl_diag *diag)
{
    const xyl__fvk *vk = &bb->vk;
    bool octa = bb->shape.kind == XYL_BILLBOARD_OCTAHEDRAL;
    xyl_result r = xyl__fvk_shader(
        vk, octa ? xyl__shader_vk_impostor_vert : xyl__shader_vk_billboard_vert,
        octa ? xyl__shader_vk_impostor_vert_size : xyl__shader_vk_billboard_vert_size,
        &bb->vert, diag);
    if (r == XYL_OK)
        r = xyl__fvk_shader(
            vk, octa ? xyl__shader_vk_impostor_frag : xyl__shader_vk_billboard_frag,
            octa ? xyl__shader_vk_impostor_frag_size : xyl__shader_vk_billboard_frag_size,
            &bb->frag, diag);
    if (r == XYL_OK && !octa)
        r = xyl__fvk_shader(vk, xyl__shader_vk_billboard_instances_vert,
                            xyl__shader_vk_billboard_instances_vert_size, &bb->vert_instances,
                            diag);
    if (r == XYL_OK) r = layouts(bb, diag);
    if (r == XYL_OK) r = pipeline(bb, d, bb->vert, &bb->pipeline, diag);
    if (r == XYL_OK && !octa)
        r = pipeline(bb, d, bb->vert_instances, &bb->instances_pipeline, diag);
    if (r == XYL_OK) r = map_create(bb, &bb->color, diag);
    if (r == XYL_OK) r = map_create(bb, &bb->normal, diag);
    if (r != XYL_OK) return r;
    VkSamplerCreateInfo si = {.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    si.magFilter = si.minFilter = VK_FILTER_LINEAR;
    si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_LINEAR;
    si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    si.maxLod = VK_LOD_CLAMP_NONE;
    XYL__FVK_TRY(vkCreateSampler(vk->device, &si, vk->vkalloc, &bb->sampler), "vkCreateSampler");
    const xyl__billboard_shape *s = &bb->shape;
    xyl_billboard_vk_constants c;
    memset(&c, 0, sizeof c);
    memcpy(c.center, s->center, sizeof s->center);
    c.center[3] = s->radius;
    memcpy(c.bake_light, s->bake_light, sizeof s->bake_light);
    memcpy(c.half_size, s->half, sizeof s->half);
    c.kind = (int32_t)s->kind;
    c.planes = (int32_t)(octa ? s->grid : s->views);
    c.to_coverage = bb->samples != VK_SAMPLE_COUNT_1_BIT;
    r = xyl__fvk_buffer_create(vk, sizeof c, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, &c,
                               &bb->constants, diag);
    if (r != XYL_OK) return r;
    VkDescriptorImageInfo ii[2] = {
        {bb->sampler, bb->color.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
        {bb->sampler, bb->normal.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL}};
    VkDescriptorBufferInfo bi = {bb->constants.buffer, 0, VK_WHOLE_SIZE};
    VkWriteDescriptorSet w[3];
    for (int k = 0; k < 3; ++k) {
        w[k] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        w[k].dstSet = bb->set;
        w[k].dstBinding = (uint32_t)k; /* colour 0, normal 1, constants 2 */
        w[k].descriptorCount = 1;
        w[k].descriptorType = k < 2 ? VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER
                                    : VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
        w[k].pImageInfo = k < 2 ? &ii[k] : NULL;
        w[k].pBufferInfo = k < 2 ? NULL : &bi;
    }
    vkUpdateDescriptorSets(vk->device, 3, w, 0, NULL);
    return XYL_OK;
}

/* ---- the bake ----------------------------------------------------------------------------- */

static void target_free(const xyl__fvk *vk, bake_target *t)
{
    if (t->framebuffer) vkDestroyFramebuffer(vk->device, t->framebuffer, vk->vkalloc);
    if (t->pass) vkDestroyRenderPass(vk->device, t->pass, vk->vkalloc);
    for (int k = 0; k < 2; ++k) xyl__fvk_image_destroy(vk, &t->att[k]);
    xyl__fvk_buffer_destroy(vk, &t->readback);
    xyl__fvk_buffer_destroy(vk, &t->staging);
}

/* One subpass: colour and depth cleared, both kept and left ready for their copy. */
static xyl_result bake_pass(const xyl__fvk *vk, bake_target *t, xyl_diag *diag)
{
    VkAttachmentDescription att[2];
    memset(att, 0, sizeof att);
    const VkFormat formats[2] = {XYL_BILLBOARD_VK_BAKE_COLOR, XYL_BILLBOARD_VK_BAKE_DEPTH};
    for (int k = 0; k < 2; ++k) {
        att[k].format = formats[k];
        att[k].samples = VK_SAMPLE_COUNT_1_BIT;
        att[k].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        att[k].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        att[k].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        att[k].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        att[k].finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    }
    VkAttachmentReference color = {0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth = {1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub = {0};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.colorAttachmentCount = 1;
    sub.pColorAttachments = &color;
    sub.pDepthStencilAttachment = &depth;
    /* the one dependency of the usual offscreen pass (the header's): render passes are only
     * compatible with the same dependencies, so the depth's copy is ordered by a barrier */
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
    XYL__FVK_TRY(vkCreateRenderPass(vk->device, &ri, vk->vkalloc, &t->pass), "vkCreateRenderPass");
    return XYL_OK;
}

static xyl_result target_make(const xyl__fvk *vk, uint32_t n, bake_target *t, xyl_diag *diag)
{
    xyl_result r = bake_pass(vk, t, diag);
    for (int k = 0; k < 2 && r == XYL_OK; ++k) {
        VkImageCreateInfo ii = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
        ii.imageType = VK_IMAGE_TYPE_2D;
        ii.format = k ? XYL_BILLBOARD_VK_BAKE_DEPTH : XYL_BILLBOARD_VK_BAKE_COLOR;
        ii.extent = (VkExtent3D){n, n, 1};
        ii.mipLevels = ii.arrayLayers = 1;
        ii.samples = VK_SAMPLE_COUNT_1_BIT;
        ii.usage = VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                   (k ? VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT
                      : VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT);
        r = xyl__fvk_image_create(vk, &ii, VK_IMAGE_VIEW_TYPE_2D,
                         k ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT, &t->att[k],
                         diag);
    }
    if (r != XYL_OK) return r;
    VkImageView views[2] = {t->att[0].view, t->att[1].view};
    VkFramebufferCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fi.renderPass = t->pass;
    fi.attachmentCount = 2;
    fi.pAttachments = views;
    fi.width = fi.height = n;
    fi.layers = 1;
    XYL__FVK_TRY(vkCreateFramebuffer(vk->device, &fi, vk->vkalloc, &t->framebuffer),
           "vkCreateFramebuffer");
    VkDeviceSize bytes = 8u * (VkDeviceSize)n * n;
    r = xyl__fvk_buffer_create(vk, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, NULL, &t->readback,
                               diag);
    if (r == XYL_OK)
        r = xyl__fvk_buffer_create(vk, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, NULL,
                                   &t->staging, diag);
    return r;
}

/* The staged maps of view v into their place in both maps. */
static void record_upload(const xyl_billboard_vk *bb, VkCommandBuffer cmd, const bake_target *t,
                          uint32_t v)
{
    VkDeviceSize half = 4u * (VkDeviceSize)bb->shape.resolution * bb->shape.resolution;
    VkBufferImageCopy c = view_region(bb, v, 0), n = view_region(bb, v, half);
    vkCmdCopyBufferToImage(cmd, t->staging.buffer, bb->color.image,
                           VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &c);
    vkCmdCopyBufferToImage(cmd, t->staging.buffer, bb->normal.image,
                           VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &n);
}

/* Column-major GL clip (y up, depth -1..1) to Vulkan's (y down, depth 0..1). */
static void vulkan_clip(const float gl[16], float vk[16])
{
    for (int c = 0; c < 4; ++c) {
        vk[c * 4 + 0] = gl[c * 4 + 0];
        vk[c * 4 + 1] = -gl[c * 4 + 1];
        vk[c * 4 + 2] = 0.5f * (gl[c * 4 + 2] + gl[c * 4 + 3]);
        vk[c * 4 + 3] = gl[c * 4 + 3];
    }
}

/* View v: the previous view's maps uploaded, the pass with the caller's draws, its colour and
 * depth copied to the read-back buffer; submitted and waited for. */
static xyl_result render_view(xyl_billboard_vk *bb, const bake_target *t, uint32_t v,
                              xyl_billboard_vk_draw_fn draw, void *user, xyl_diag *diag)
{
    const xyl__fvk *vk = &bb->vk;
    uint32_t n = bb->shape.resolution;
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    xyl_result r = xyl__fvk_begin_once(vk, &cmd, diag);
    if (r != XYL_OK) return r;
    if (v == 0) {
        VkImage maps[2] = {bb->color.image, bb->normal.image};
        for (int k = 0; k < 2; ++k)
            barrier(cmd, maps[k], VK_IMAGE_ASPECT_COLOR_BIT, 0, bb->levels, bb->layers,
                    VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 0,
                    VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                    VK_PIPELINE_STAGE_TRANSFER_BIT);
    } else {
        record_upload(bb, cmd, t, v - 1);
    }
    /* the previous view's copies have read the attachments before they are cleared */
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                         VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT |
                             VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT,
                         0, 0, NULL, 0, NULL, 0, NULL);
    VkClearValue clear[2];
    memset(clear, 0, sizeof clear);
    clear[1].depthStencil.depth = 1.0f;
    VkRenderPassBeginInfo rb = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rb.renderPass = t->pass;
    rb.framebuffer = t->framebuffer;
    rb.renderArea.extent = (VkExtent2D){n, n};
    rb.clearValueCount = 2;
    rb.pClearValues = clear;
    vkCmdBeginRenderPass(cmd, &rb, VK_SUBPASS_CONTENTS_INLINE);
    VkViewport vp = {0.0f, 0.0f, (float)n, (float)n, 0.0f, 1.0f};
    VkRect2D sc = {{0, 0}, {n, n}};
    vkCmdSetViewport(cmd, 0, 1, &vp);
    vkCmdSetScissor(cmd, 0, 1, &sc);
    float gl[16], m[16], light[3];
    xyl__billboard_bake_camera(&bb->shape, v, gl, light);
    vulkan_clip(gl, m);
    r = draw(user, cmd, t->pass, m, light, diag);
    vkCmdEndRenderPass(cmd);
    barrier(cmd, t->att[1].image, VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 1,
            VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
            VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT,
            VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT);
    VkBufferImageCopy copy = {0};
    copy.imageSubresource = (VkImageSubresourceLayers){VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = (VkExtent3D){n, n, 1};
    vkCmdCopyImageToBuffer(cmd, t->att[0].image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                           t->readback.buffer, 1, &copy);
    copy.bufferOffset = 4u * (VkDeviceSize)n * n;
    copy.imageSubresource.aspectMask = VK_IMAGE_ASPECT_DEPTH_BIT;
    vkCmdCopyImageToBuffer(cmd, t->att[1].image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                           t->readback.buffer, 1, &copy);
    VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1,
                         &mb, 0, NULL, 0, NULL);
    if (r != XYL_OK) { /* the caller's error: nothing of this view is submitted */
        vkEndCommandBuffer(cmd);
        vkFreeCommandBuffers(vk->device, vk->commands, 1, &cmd);
        return r;
    }
    return xyl__fvk_submit_wait(vk, cmd, diag);
}

/* The read-back of the last view (rows top to bottom) into its maps in the staging buffer,
 * through host rows bottom to top, as GL reads them and the shared code takes them. */
static xyl_result stage_maps(const xyl_billboard_vk *bb, const bake_target *t, uint8_t *rgba,
                             float *depth, uint8_t *normal, xyl_diag *diag)
{
    const xyl__fvk *vk = &bb->vk;
    uint32_t n = bb->shape.resolution;
    size_t texels = (size_t)n * n, row = 4u * (size_t)n;
    void *map = NULL;
    XYL__FVK_TRY(vkMapMemory(vk->device, t->readback.memory, 0, VK_WHOLE_SIZE, 0, &map),
                 "vkMapMemory");
    const uint8_t *src = map;
    for (uint32_t y = 0; y < n; ++y) {
        memcpy(rgba + (size_t)(n - 1 - y) * row, src + (size_t)y * row, row);
        memcpy(depth + (size_t)(n - 1 - y) * n, src + 4 * texels + (size_t)y * row, row);
    }
    vkUnmapMemory(vk->device, t->readback.memory);
    xyl__billboard_maps(&bb->shape, depth, rgba, normal);
    XYL__FVK_TRY(vkMapMemory(vk->device, t->staging.memory, 0, VK_WHOLE_SIZE, 0, &map),
                 "vkMapMemory");
    memcpy(map, rgba, 4 * texels);
    memcpy((uint8_t *)map + 4 * texels, normal, 4 * texels);
    vkUnmapMemory(vk->device, t->staging.memory);
    return XYL_OK;
}

static xyl_result bake_views(xyl_billboard_vk *bb, xyl_billboard_vk_draw_fn draw, void *user,
                             xyl_diag *diag)
{
    const xyl__fvk *vk = &bb->vk;
    xyl_allocator a = vk->alloc;
    size_t texels = (size_t)bb->shape.resolution * bb->shape.resolution;
    uint8_t *maps = xyl__alloc_array(&a, texels, 8);
    float *depth = xyl__alloc_array(&a, texels, sizeof *depth);
    bake_target t;
    memset(&t, 0, sizeof t);
    xyl_result r =
        maps && depth ? XYL_OK : xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    if (r == XYL_OK) r = target_make(vk, bb->shape.resolution, &t, diag);
    for (uint32_t v = 0; r == XYL_OK && v < bb->shape.views; ++v) {
        r = render_view(bb, &t, v, draw, user, diag);
        if (r == XYL_OK) r = stage_maps(bb, &t, maps, depth, maps + 4 * texels, diag);
    }
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    if (r == XYL_OK) r = xyl__fvk_begin_once(vk, &cmd, diag);
    if (r == XYL_OK) {
        record_upload(bb, cmd, &t, bb->shape.views - 1);
        record_mipmaps(bb, cmd, bb->color.image);
        record_mipmaps(bb, cmd, bb->normal.image);
        r = xyl__fvk_submit_wait(vk, cmd, diag);
    }
    target_free(vk, &t);
    xyl__free(&a, maps);
    xyl__free(&a, depth);
    return r;
}

xyl_result xyl_billboard_vk_bake(const xyl_billboard_vk_desc *desc,
                                 xyl_billboard_vk_draw_fn draw, void *user,
                                 xyl_billboard_vk **out, xyl_diag *diag)
{
    if (!desc || !draw || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "desc, draw and out are required");
    xyl_result r = check_desc(desc, diag);
    if (r != XYL_OK) return r;
    xyl_allocator a = desc->alloc;
    xyl_billboard_vk *bb = xyl__calloc(&a, 1, sizeof *bb);
    if (!bb) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    xyl__fvk_init(&bb->vk, &a, desc->physical_device, desc->device, desc->queue);
    const xyl__billboard_params p = {desc->kind, desc->planes, desc->resolution, desc->grid,
                                     desc->lo, desc->hi, desc->light_dir};
    xyl__billboard_shape_of(&p, &bb->shape);
    bb->samples = desc->samples ? desc->samples : VK_SAMPLE_COUNT_1_BIT;
    bb->alpha_to_one = desc->enabled_features && desc->enabled_features->alphaToOne;
    bb->side = bb->shape.resolution * (bb->shape.grid ? bb->shape.grid : 1);
    bb->layers = bb->shape.grid ? 1 : bb->shape.views;
    bb->levels = 1;
    for (uint32_t s = bb->side; s > 1; s >>= 1) ++bb->levels;
    r = xyl__fvk_check_device(&bb->vk, desc->queue_family, bb->samples, diag);
    if (r == XYL_OK) r = check_limits(bb, diag);
    if (r == XYL_OK) r = xyl__fvk_make_pool(&bb->vk, desc->queue_family, diag);
    if (r == XYL_OK) r = objects(bb, desc, diag);
    if (r == XYL_OK) r = bake_views(bb, draw, user, diag);
    if (r != XYL_OK) {
        xyl_billboard_vk_destroy(bb);
        return r;
    }
    *out = bb;
    xyl__diag_ok(diag);
    return XYL_OK;
}

void xyl_billboard_vk_destroy(xyl_billboard_vk *bb)
{
    if (!bb) return;
    xyl__fvk *vk = &bb->vk;
    VkDevice dev = vk->device;
    xyl__fvk_image_destroy(vk, &bb->color);
    xyl__fvk_image_destroy(vk, &bb->normal);
    xyl__fvk_buffer_destroy(vk, &bb->constants);
    if (bb->sampler) vkDestroySampler(dev, bb->sampler, vk->vkalloc);
    VkPipeline pipes[2] = {bb->pipeline, bb->instances_pipeline};
    for (int k = 0; k < 2; ++k)
        if (pipes[k]) vkDestroyPipeline(dev, pipes[k], vk->vkalloc);
    if (bb->pool) vkDestroyDescriptorPool(dev, bb->pool, vk->vkalloc);
    if (bb->layout) vkDestroyPipelineLayout(dev, bb->layout, vk->vkalloc);
    if (bb->set_layout) vkDestroyDescriptorSetLayout(dev, bb->set_layout, vk->vkalloc);
    VkShaderModule mods[3] = {bb->vert, bb->vert_instances, bb->frag};
    for (int k = 0; k < 3; ++k)
        if (mods[k]) vkDestroyShaderModule(dev, mods[k], vk->vkalloc);
    xyl__fvk_finish(vk);
    xyl_allocator a = vk->alloc;
    xyl__free(&a, bb);
}

uint32_t xyl_billboard_vk_view_count(const xyl_billboard_vk *bb)
{
    return bb ? bb->shape.views : 0;
}

/* ---- read-back ---------------------------------------------------------------------------- */

xyl_result xyl_billboard_vk_read_view(const xyl_billboard_vk *bb, uint32_t view, bool normal,
                                      uint8_t *rgba, xyl_diag *diag)
{
    if (!bb || !rgba)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "bb and rgba are required");
    if (view >= bb->shape.views)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "view %u of a billboard with %u", view, bb->shape.views);
    const xyl__fvk *vk = &bb->vk;
    uint32_t n = bb->shape.resolution;
    size_t row = 4u * (size_t)n;
    xyl__fvk_buffer b = {0};
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    xyl_result r = xyl__fvk_buffer_create(vk, row * n, VK_BUFFER_USAGE_TRANSFER_DST_BIT, NULL,
                                          &b, diag);
    if (r == XYL_OK) r = xyl__fvk_begin_once(vk, &cmd, diag);
    if (r == XYL_OK) {
        VkImage im = normal ? bb->normal.image : bb->color.image;
        const VkImageLayout read = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                            src = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        const VkPipelineStageFlags frag = VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
                                   xfer = VK_PIPELINE_STAGE_TRANSFER_BIT;
        barrier(cmd, im, VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, bb->layers, read, src,
                VK_ACCESS_SHADER_READ_BIT, VK_ACCESS_TRANSFER_READ_BIT, frag, xfer);
        VkBufferImageCopy c = view_region(bb, view, 0);
        vkCmdCopyImageToBuffer(cmd, im, src, b.buffer, 1, &c);
        barrier(cmd, im, VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, bb->layers, src, read,
                VK_ACCESS_TRANSFER_READ_BIT, VK_ACCESS_SHADER_READ_BIT, xfer, frag);
        VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        mb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
        vkCmdPipelineBarrier(cmd, xfer, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, NULL, 0, NULL);
        r = xyl__fvk_submit_wait(vk, cmd, diag);
    }
    void *map = NULL;
    VkResult vr = VK_SUCCESS;
    if (r == XYL_OK && (vr = vkMapMemory(vk->device, b.memory, 0, VK_WHOLE_SIZE, 0, &map)) !=
                           VK_SUCCESS)
        r = xyl__fvk_fail(diag, vr, "vkMapMemory");
    if (r == XYL_OK) { /* stored bottom row first, returned top row first */
        for (uint32_t y = 0; y < n; ++y)
            memcpy(rgba + (size_t)y * row, (const uint8_t *)map + (size_t)(n - 1 - y) * row, row);
        vkUnmapMemory(vk->device, b.memory);
    }
    xyl__fvk_buffer_destroy(vk, &b);
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

/* ---- draws -------------------------------------------------------------------------------- */

static xyl_result frame_push(const xyl_billboard_vk_frame *f, uint32_t first,
                             xyl_billboard_vk_push *push, xyl_diag *diag)
{
    float light[3], cutoff;
    xyl_result r = xyl__billboard_frame_check(f->view_proj, f->eye, f->light_dir,
                                              f->alpha_cutoff, f->dither, light, &cutoff, diag);
    if (r != XYL_OK) return r;
    memset(push, 0, sizeof *push);
    memcpy(push->view_proj, f->view_proj, sizeof push->view_proj);
    memcpy(push->eye, f->eye, sizeof f->eye);
    push->eye[3] = cutoff;
    memcpy(push->light, light, sizeof light);
    memcpy(push->dither, f->dither, sizeof push->dither);
    push->first = first;
    return XYL_OK;
}

static void record_draw(const xyl_billboard_vk *bb, VkCommandBuffer cmd, VkPipeline pipe,
                        const xyl_billboard_vk_push *push, uint32_t instances)
{
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipe);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, bb->layout, 0, 1, &bb->set, 0,
                            NULL);
    vkCmdPushConstants(cmd, bb->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT,
                       0, sizeof *push, push);
    vkCmdDraw(cmd, 4, instances, 0, 0);
}

xyl_result xyl_billboard_vk_cmd_draw(xyl_billboard_vk *bb, VkCommandBuffer cmd,
                                     const xyl_billboard_vk_frame *frame, xyl_diag *diag)
{
    if (!bb || !cmd || !frame)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "bb, cmd and frame are required");
    xyl_billboard_vk_push push;
    xyl_result r = frame_push(frame, 0, &push, diag);
    if (r != XYL_OK) return r;
    record_draw(bb, cmd, bb->pipeline, &push,
                bb->shape.kind == XYL_BILLBOARD_OCTAHEDRAL ? 1 : bb->shape.views);
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_result xyl_billboard_vk_set_instances(xyl_billboard_vk *bb, VkBuffer instances,
                                          VkDeviceSize size, xyl_diag *diag)
{
    if (!bb || !instances)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "bb and instances are required");
    if (bb->shape.kind == XYL_BILLBOARD_OCTAHEDRAL)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "an octahedral billboard has no instanced draw");
    if (size < XYL_FOREST_INSTANCE_SIZE || size % XYL_FOREST_INSTANCE_SIZE != 0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "an instance buffer of %llu bytes: a whole number of %d-byte instances",
                         (unsigned long long)size, XYL_FOREST_INSTANCE_SIZE);
    if (size > bb->vk.properties.limits.maxStorageBufferRange)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "an instance buffer of %llu bytes exceeds the device's storage buffer "
                         "range (%u bytes)", (unsigned long long)size,
                         bb->vk.properties.limits.maxStorageBufferRange);
    VkDescriptorBufferInfo bi = {instances, 0, size};
    VkWriteDescriptorSet w = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = bb->set;
    w.dstBinding = XYL_BILLBOARD_VK_BINDING_INSTANCES;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    w.pBufferInfo = &bi;
    vkUpdateDescriptorSets(bb->vk.device, 1, &w, 0, NULL);
    bb->instance_count = size / XYL_FOREST_INSTANCE_SIZE;
    xyl__diag_ok(diag);
    return XYL_OK;
}

xyl_result xyl_billboard_vk_cmd_draw_instances(xyl_billboard_vk *bb, VkCommandBuffer cmd,
                                               const xyl_billboard_vk_frame *frame,
                                               uint32_t first, uint32_t count, xyl_diag *diag)
{
    if (!bb || !cmd || !frame)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "bb, cmd and frame are required");
    if (!bb->instance_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "no instances bound: call xyl_billboard_vk_set_instances first");
    if (count == 0 || (uint64_t)first + count > bb->instance_count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "instances %u .. %llu of %llu bound (count at least 1)", first,
                         (unsigned long long)first + count,
                         (unsigned long long)bb->instance_count);
    uint32_t planes = bb->shape.kind == XYL_BILLBOARD_CROSS ? bb->shape.views : 1;
    if ((uint64_t)count * planes > UINT32_MAX)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%u instances of %u planes exceed one draw's instance count", count,
                         planes);
    xyl_billboard_vk_push push;
    xyl_result r = frame_push(frame, first, &push, diag);
    if (r != XYL_OK) return r;
    record_draw(bb, cmd, bb->instances_pipeline, &push, count * planes);
    xyl__diag_ok(diag);
    return XYL_OK;
}

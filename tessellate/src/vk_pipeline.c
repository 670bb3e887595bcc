/* Vulkan backend: shader modules, the descriptor sets, render passes, the offscreen target and
 * the graphics pipelines (shade, wireframe overlay, capture) for any pass they draw in. */
#include <string.h>

#include "shader_sources.h"
#include "vk_internal.h"

#define COLOR_FORMAT XYL__VK_COLOR_FORMAT
#define DEPTH_FORMAT XYL__VK_DEPTH_FORMAT

static xyl_result shader(xyl_tess_vk *vk, const unsigned char *code, size_t size,
                         VkShaderModule *out, xyl_diag *diag)
{
    VkShaderModuleCreateInfo si = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    si.codeSize = size;
    si.pCode = (const uint32_t *)(const void *)code; /* the embedded arrays are 4-byte aligned */
    VkResult r = vkCreateShaderModule(vk->device, &si, vk->vkalloc, out);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkCreateShaderModule");
}

/* One layout for every pipeline: patches, frame (dynamic offset: a slot's shade or wireframe
 * copy), capture output, capture offsets. The draws' set leaves the last two unwritten: their
 * shaders do not use them. */
static xyl_result descriptor_layout(xyl_tess_vk *vk, xyl_diag *diag)
{
    const VkShaderStageFlags vf = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
    VkDescriptorSetLayoutBinding b[4] = {
        {XYL_TESS_BINDING_PATCHES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, vf, NULL},
        {XYL_TESS_BINDING_FRAME, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, 1, vf, NULL},
        {XYL_TESS_BINDING_CAPTURE, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
         VK_SHADER_STAGE_VERTEX_BIT, NULL},
        {XYL_TESS_BINDING_OFFSETS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
         VK_SHADER_STAGE_VERTEX_BIT, NULL},
    };
    VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    li.bindingCount = 4;
    li.pBindings = b;
    VkResult r = vkCreateDescriptorSetLayout(vk->device, &li, vk->vkalloc, &vk->set_layout);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkCreateDescriptorSetLayout");
    VkPipelineLayoutCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pi.setLayoutCount = 1;
    pi.pSetLayouts = &vk->set_layout;
    r = vkCreatePipelineLayout(vk->device, &pi, vk->vkalloc, &vk->layout);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkCreatePipelineLayout");
}

/* Two sets: the draws' (written by set_patches only, so recorded draws stay valid while the
 * caller's frames are in flight) and the capture's (rewritten by every capture). */
static xyl_result descriptor_sets(xyl_tess_vk *vk, xyl_diag *diag)
{
    VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 6},
                                     {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, 2}};
    VkDescriptorPoolCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pi.maxSets = 2;
    pi.poolSizeCount = 2;
    pi.pPoolSizes = sizes;
    VkResult r = vkCreateDescriptorPool(vk->device, &pi, vk->vkalloc, &vk->descriptor_pool);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkCreateDescriptorPool");
    VkDescriptorSetLayout layouts[2] = {vk->set_layout, vk->set_layout};
    VkDescriptorSet sets[2];
    VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    ai.descriptorPool = vk->descriptor_pool;
    ai.descriptorSetCount = 2;
    ai.pSetLayouts = layouts;
    r = vkAllocateDescriptorSets(vk->device, &ai, sets);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkAllocateDescriptorSets");
    vk->set = sets[0];
    vk->capture_set = sets[1];
    return XYL_OK;
}

/* ---- render passes ------------------------------------------------------------------------- */

static VkAttachmentDescription attachment(VkFormat format, VkSampleCountFlagBits samples,
                                          VkAttachmentLoadOp load, VkAttachmentStoreOp store,
                                          VkImageLayout final_layout)
{
    VkAttachmentDescription a = {0};
    a.format = format;
    a.samples = samples;
    a.loadOp = load;
    a.storeOp = store;
    a.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    a.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    a.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED; /* cleared every frame */
    a.finalLayout = final_layout;
    return a;
}

/* The colour image that is read back ends in TRANSFER_SRC layout; the dependencies order the
 * previous frame's copy before this frame's writes and this frame's writes before its copy. */
static xyl_result create_pass(xyl_tess_vk *vk, VkSampleCountFlagBits samples, VkRenderPass *out,
                              xyl_diag *diag)
{
    bool msaa = samples != VK_SAMPLE_COUNT_1_BIT;
    VkAttachmentDescription att[3] = {
        attachment(COLOR_FORMAT, samples, VK_ATTACHMENT_LOAD_OP_CLEAR,
                   msaa ? VK_ATTACHMENT_STORE_OP_DONT_CARE : VK_ATTACHMENT_STORE_OP_STORE,
                   msaa ? VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
                        : VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL),
        attachment(DEPTH_FORMAT, samples, VK_ATTACHMENT_LOAD_OP_CLEAR,
                   VK_ATTACHMENT_STORE_OP_DONT_CARE,
                   VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL),
        attachment(COLOR_FORMAT, VK_SAMPLE_COUNT_1_BIT, VK_ATTACHMENT_LOAD_OP_DONT_CARE,
                   VK_ATTACHMENT_STORE_OP_STORE, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL)};
    VkAttachmentReference color = {0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth = {1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkAttachmentReference resolve = {2, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub = {0};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.colorAttachmentCount = 1;
    sub.pColorAttachments = &color;
    sub.pResolveAttachments = msaa ? &resolve : NULL;
    sub.pDepthStencilAttachment = &depth;
    const VkPipelineStageFlags out_stages = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT |
                                            VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                                            VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    const VkAccessFlags out_access = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT |
                                     VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    VkSubpassDependency dep[2] = {
        {VK_SUBPASS_EXTERNAL, 0, VK_PIPELINE_STAGE_TRANSFER_BIT | out_stages, out_stages,
         out_access, out_access, 0},
        {0, VK_SUBPASS_EXTERNAL, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
         VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
         VK_ACCESS_TRANSFER_READ_BIT, 0}};
    VkRenderPassCreateInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    ri.attachmentCount = msaa ? 3 : 2;
    ri.pAttachments = att;
    ri.subpassCount = 1;
    ri.pSubpasses = &sub;
    ri.dependencyCount = 2;
    ri.pDependencies = dep;
    VkResult r = vkCreateRenderPass(vk->device, &ri, vk->vkalloc, out);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkCreateRenderPass");
}

/* Capture draws with rasterisation discarded: a pass without attachments and a 1 x 1
 * framebuffer. */
static xyl_result create_capture_pass(xyl_tess_vk *vk, xyl_diag *diag)
{
    VkSubpassDescription sub = {0};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    VkRenderPassCreateInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    ri.subpassCount = 1;
    ri.pSubpasses = &sub;
    VkResult r = vkCreateRenderPass(vk->device, &ri, vk->vkalloc, &vk->capture_pass);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkCreateRenderPass");
    VkFramebufferCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fi.renderPass = vk->capture_pass;
    fi.width = 1;
    fi.height = 1;
    fi.layers = 1;
    r = vkCreateFramebuffer(vk->device, &fi, vk->vkalloc, &vk->capture_framebuffer);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkCreateFramebuffer");
}

/* ---- pipelines ----------------------------------------------------------------------------- */

typedef struct pipe_desc {
    xyl__vk_pass where;
    VkPolygonMode mode;
    VkCullModeFlags cull;
    bool overlay; /* wireframe: depth bias towards the eye, test LESS_OR_EQUAL, no depth write */
    bool discard; /* capture: vertex stage only */
} pipe_desc;

/* Pattern vertex (binding 0, per vertex) and instance record (binding 1, per instance). */
static const VkVertexInputBindingDescription vertex_bindings[2] = {
    {0, sizeof(uint32_t), VK_VERTEX_INPUT_RATE_VERTEX},
    {1, sizeof(xyl_tess_instance), VK_VERTEX_INPUT_RATE_INSTANCE}};
static const VkVertexInputAttributeDescription vertex_attributes[2] = {
    {0, 0, VK_FORMAT_R32_UINT, 0}, {1, 1, VK_FORMAT_R32G32B32A32_UINT, 0}};

static VkPipelineRasterizationStateCreateInfo raster_state(const pipe_desc *d)
{
    VkPipelineRasterizationStateCreateInfo rs = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    rs.rasterizerDiscardEnable = d->discard;
    rs.polygonMode = d->mode;
    rs.cullMode = d->cull;
    /* view_proj flips y for Vulkan's y-down framebuffer, and Vulkan's winding is measured with y
     * down: the two mirrors cancel, so GL's counter-clockwise outward faces stay front faces
     * (checked by test_tess_vk's render tests). */
    rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
    rs.depthBiasEnable = d->overlay;
    rs.depthBiasConstantFactor = d->overlay ? -1.0f : 0.0f;
    rs.depthBiasSlopeFactor = d->overlay ? -1.0f : 0.0f;
    rs.lineWidth = 1.0f;
    return rs;
}

static VkPipelineDepthStencilStateCreateInfo depth_state(const pipe_desc *d)
{
    VkPipelineDepthStencilStateCreateInfo ds = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
    ds.depthTestEnable = VK_TRUE;
    ds.depthWriteEnable = d->overlay ? VK_FALSE : VK_TRUE;
    ds.depthCompareOp = d->overlay ? VK_COMPARE_OP_LESS_OR_EQUAL : VK_COMPARE_OP_LESS;
    return ds;
}

static xyl_result create_pipeline(xyl_tess_vk *vk, const pipe_desc *d, VkPipeline *out,
                                  xyl_diag *diag)
{
    VkPipelineShaderStageCreateInfo st[2] = {
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, NULL, 0, VK_SHADER_STAGE_VERTEX_BIT,
         d->discard ? vk->vert_capture : vk->vert, "main", NULL},
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, NULL, 0,
         VK_SHADER_STAGE_FRAGMENT_BIT, vk->frag, "main", NULL}};
    VkPipelineVertexInputStateCreateInfo vi = {
        VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO, NULL, 0, 2, vertex_bindings, 2,
        vertex_attributes};
    VkPipelineInputAssemblyStateCreateInfo ia = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    VkPipelineViewportStateCreateInfo vp = {.sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    vp.viewportCount = 1;
    vp.scissorCount = 1;
    VkPipelineRasterizationStateCreateInfo rs = raster_state(d);
    VkPipelineMultisampleStateCreateInfo ms = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    ms.rasterizationSamples = d->where.samples;
    VkPipelineDepthStencilStateCreateInfo ds = depth_state(d);
    VkPipelineColorBlendAttachmentState blend = {0};
    blend.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT |
                           VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
    VkPipelineColorBlendStateCreateInfo cb = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    cb.attachmentCount = d->discard ? 0 : 1;
    cb.pAttachments = &blend;
    VkDynamicState dyn[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    VkPipelineDynamicStateCreateInfo dy = {VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO,
                                           NULL, 0, 2, dyn};
    VkGraphicsPipelineCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    pi.stageCount = d->discard ? 1 : 2;
    pi.pStages = st;
    pi.pVertexInputState = &vi;
    pi.pInputAssemblyState = &ia;
    pi.pViewportState = &vp;
    pi.pRasterizationState = &rs;
    pi.pMultisampleState = &ms;
    pi.pDepthStencilState = d->discard ? NULL : &ds;
    pi.pColorBlendState = &cb;
    pi.pDynamicState = &dy;
    pi.layout = vk->layout;
    pi.renderPass = d->where.pass;
    pi.subpass = d->where.subpass;
    VkPipelineRenderingCreateInfoKHR ri = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO_KHR};
    if (!d->where.pass) { /* dynamic rendering */
        ri.colorAttachmentCount = 1;
        ri.pColorAttachmentFormats = &d->where.color;
        ri.depthAttachmentFormat = d->where.depth;
        pi.pNext = &ri;
    }
    VkResult r = vkCreateGraphicsPipelines(vk->device, VK_NULL_HANDLE, 1, &pi, vk->vkalloc, out);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkCreateGraphicsPipelines");
}

xyl_result xyl__vk_create_layouts(xyl_tess_vk *vk, xyl_diag *diag)
{
    xyl_result r = shader(vk, xyl__shader_vk_instanced_vert, xyl__shader_vk_instanced_vert_size,
                          &vk->vert, diag);
    if (r == XYL_OK)
        r = shader(vk, xyl__shader_vk_instanced_capture_vert,
                   xyl__shader_vk_instanced_capture_vert_size, &vk->vert_capture, diag);
    if (r == XYL_OK)
        r = shader(vk, xyl__shader_vk_shade_frag, xyl__shader_vk_shade_frag_size, &vk->frag, diag);
    if (r == XYL_OK) r = descriptor_layout(vk, diag);
    if (r == XYL_OK) r = descriptor_sets(vk, diag);
    return r;
}

void xyl__vk_destroy_layouts(xyl_tess_vk *vk)
{
    VkDevice dev = vk->device;
    const VkAllocationCallbacks *a = vk->vkalloc;
    if (vk->descriptor_pool) vkDestroyDescriptorPool(dev, vk->descriptor_pool, a);
    if (vk->layout) vkDestroyPipelineLayout(dev, vk->layout, a);
    if (vk->set_layout) vkDestroyDescriptorSetLayout(dev, vk->set_layout, a);
    if (vk->frag) vkDestroyShaderModule(dev, vk->frag, a);
    if (vk->vert_capture) vkDestroyShaderModule(dev, vk->vert_capture, a);
    if (vk->vert) vkDestroyShaderModule(dev, vk->vert, a);
}

/* Shaded and wireframe pipelines, each with back faces culled and with nothing culled. */
xyl_result xyl__vk_create_pipes(xyl_tess_vk *vk, const xyl__vk_pass *where, xyl__vk_pipes *out,
                                xyl_diag *diag)
{
    xyl_result r = XYL_OK;
    for (int k = 0; k < 2 && r == XYL_OK; ++k) {
        VkCullModeFlags cull = k ? VK_CULL_MODE_NONE : VK_CULL_MODE_BACK_BIT;
        pipe_desc fill = {*where, VK_POLYGON_MODE_FILL, cull, false, false};
        pipe_desc line = {*where, VK_POLYGON_MODE_LINE, cull, true, false};
        r = create_pipeline(vk, &fill, &out->fill[k], diag);
        if (r == XYL_OK && vk->features.fillModeNonSolid)
            r = create_pipeline(vk, &line, &out->line[k], diag);
    }
    if (r != XYL_OK) xyl__vk_destroy_pipes(vk, out);
    return r;
}

void xyl__vk_destroy_pipes(xyl_tess_vk *vk, xyl__vk_pipes *p)
{
    for (int k = 0; k < 2; ++k) {
        if (p->fill[k]) vkDestroyPipeline(vk->device, p->fill[k], vk->vkalloc);
        if (p->line[k]) vkDestroyPipeline(vk->device, p->line[k], vk->vkalloc);
    }
    memset(p, 0, sizeof *p);
}

xyl_result xyl__vk_capture_reserve(xyl_tess_vk *vk, xyl_diag *diag)
{
    if (vk->capture) return XYL_OK;
    xyl_result r = vk->capture_pass ? XYL_OK : create_capture_pass(vk, diag);
    if (r != XYL_OK) return r;
    pipe_desc d = {{vk->capture_pass, 0, VK_FORMAT_UNDEFINED, VK_FORMAT_UNDEFINED,
                    VK_SAMPLE_COUNT_1_BIT},
                   VK_POLYGON_MODE_FILL, VK_CULL_MODE_NONE, false, true};
    return create_pipeline(vk, &d, &vk->capture, diag);
}

void xyl__vk_destroy_capture(xyl_tess_vk *vk)
{
    VkDevice dev = vk->device;
    if (vk->capture) vkDestroyPipeline(dev, vk->capture, vk->vkalloc);
    if (vk->capture_framebuffer) vkDestroyFramebuffer(dev, vk->capture_framebuffer, vk->vkalloc);
    if (vk->capture_pass) vkDestroyRenderPass(dev, vk->capture_pass, vk->vkalloc);
}

/* ---- offscreen target ---------------------------------------------------------------------- */

void xyl__vk_target_destroy(xyl_tess_vk *vk, xyl__vk_target *t)
{
    xyl__vk_destroy_pipes(vk, &t->pipes);
    if (t->framebuffer) vkDestroyFramebuffer(vk->device, t->framebuffer, vk->vkalloc);
    if (t->pass) vkDestroyRenderPass(vk->device, t->pass, vk->vkalloc);
    xyl__vk_image_destroy(vk, &t->color);
    xyl__vk_image_destroy(vk, &t->depth);
    xyl__vk_image_destroy(vk, &t->resolve);
    memset(t, 0, sizeof *t);
}

static xyl_result target_images(xyl_tess_vk *vk, xyl__vk_target *t, xyl_diag *diag)
{
    bool msaa = t->samples != VK_SAMPLE_COUNT_1_BIT;
    VkImageUsageFlags cu = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT |
                           (msaa ? 0 : VK_IMAGE_USAGE_TRANSFER_SRC_BIT);
    xyl_result r = xyl__vk_image_create(vk, &t->color, COLOR_FORMAT, t->width, t->height,
                                        t->samples, cu, VK_IMAGE_ASPECT_COLOR_BIT, diag);
    if (r == XYL_OK)
        r = xyl__vk_image_create(vk, &t->depth, DEPTH_FORMAT, t->width, t->height, t->samples,
                                 VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                                 VK_IMAGE_ASPECT_DEPTH_BIT, diag);
    if (r == XYL_OK && msaa)
        r = xyl__vk_image_create(vk, &t->resolve, COLOR_FORMAT, t->width, t->height,
                                 VK_SAMPLE_COUNT_1_BIT,
                                 VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT |
                                     VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                 VK_IMAGE_ASPECT_COLOR_BIT, diag);
    if (r != XYL_OK) return r;
    VkImageView views[3] = {t->color.view, t->depth.view, t->resolve.view};
    VkFramebufferCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fi.renderPass = t->pass;
    fi.attachmentCount = msaa ? 3 : 2;
    fi.pAttachments = views;
    fi.width = t->width;
    fi.height = t->height;
    fi.layers = 1;
    VkResult vr = vkCreateFramebuffer(vk->device, &fi, vk->vkalloc, &t->framebuffer);
    return vr == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, vr, "vkCreateFramebuffer");
}

xyl_result xyl__vk_target_reserve(xyl_tess_vk *vk, uint32_t width, uint32_t height,
                                  VkSampleCountFlagBits samples, xyl_diag *diag)
{
    xyl__vk_target *t = &vk->target;
    if (t->pass && t->width == width && t->height == height && t->samples == samples)
        return XYL_OK;
    xyl__vk_target_destroy(vk, t);
    t->width = width;
    t->height = height;
    t->samples = samples;
    xyl_result r = create_pass(vk, samples, &t->pass, diag);
    if (r == XYL_OK) r = target_images(vk, t, diag);
    xyl__vk_pass where = {t->pass, 0, COLOR_FORMAT, DEPTH_FORMAT, samples};
    if (r == XYL_OK) r = xyl__vk_create_pipes(vk, &where, &t->pipes, diag);
    if (r != XYL_OK) xyl__vk_target_destroy(vk, t);
    return r;
}

/* foliage/'s shared Vulkan helpers (foliage_vk_util.h). */
#include <string.h>

#include "foliage_vk_util.h"

/* Vulkan's host allocations through the caller's allocator (core's aligned blocks). */
static void *VKAPI_PTR vk_alloc(void *user, size_t size, size_t align,
                                VkSystemAllocationScope scope)
{
    (void)scope;
    return xyl__alloc_aligned(user, size, align);
}

static void VKAPI_PTR vk_free(void *user, void *p)
{
    xyl__free_aligned(user, p);
}

static void *VKAPI_PTR vk_realloc(void *user, void *old, size_t size, size_t align,
                                  VkSystemAllocationScope scope)
{
    (void)scope;
    return xyl__realloc_aligned(user, old, size, align);
}

void xyl__fvk_init(xyl__fvk *vk, const xyl_allocator *alloc, VkPhysicalDevice physical,
                   VkDevice device, VkQueue queue)
{
    vk->alloc = *alloc;
    if (alloc->alloc) { /* else the driver's default: as good as malloc */
        vk->callbacks.pUserData = &vk->alloc;
        vk->callbacks.pfnAllocation = vk_alloc;
        vk->callbacks.pfnReallocation = vk_realloc;
        vk->callbacks.pfnFree = vk_free;
        vk->vkalloc = &vk->callbacks;
    }
    vk->physical = physical;
    vk->device = device;
    vk->queue = queue;
}

xyl_result xyl__fvk_fail(xyl_diag *diag, VkResult r, const char *what)
{
    if (r == VK_ERROR_OUT_OF_HOST_MEMORY || r == VK_ERROR_OUT_OF_DEVICE_MEMORY)
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "%s: out of memory (%d)", what,
                         (int)r);
    return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "%s failed: VkResult %d", what, (int)r);
}

xyl_result xyl__fvk_check_device(xyl__fvk *vk, uint32_t queue_family,
                                 VkSampleCountFlagBits samples, xyl_diag *diag)
{
    VkPhysicalDeviceProperties *p = &vk->properties;
    vkGetPhysicalDeviceProperties(vk->physical, p);
    if (p->apiVersion < VK_API_VERSION_1_2)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "%s offers Vulkan %u.%u, not 1.2",
                         p->deviceName, VK_API_VERSION_MAJOR(p->apiVersion),
                         VK_API_VERSION_MINOR(p->apiVersion));
    uint32_t nq = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(vk->physical, &nq, NULL);
    VkQueueFamilyProperties q[32];
    if (nq > 32) nq = 32;
    vkGetPhysicalDeviceQueueFamilyProperties(vk->physical, &nq, q);
    if (queue_family >= nq || !(q[queue_family].queueFlags & VK_QUEUE_GRAPHICS_BIT))
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "queue family %u of %s has no graphics queues", queue_family,
                         p->deviceName);
    VkSampleCountFlags offered =
        p->limits.framebufferColorSampleCounts & p->limits.framebufferDepthSampleCounts;
    if (!(offered & samples))
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "%s does not offer %u samples",
                         p->deviceName, (unsigned)samples);
    vkGetPhysicalDeviceMemoryProperties(vk->physical, &vk->memory);
    return XYL_OK;
}

xyl_result xyl__fvk_make_pool(xyl__fvk *vk, uint32_t queue_family, xyl_diag *diag)
{
    VkCommandPoolCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    ci.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
    ci.queueFamilyIndex = queue_family;
    XYL__FVK_TRY(vkCreateCommandPool(vk->device, &ci, vk->vkalloc, &vk->commands),
                 "vkCreateCommandPool");
    return XYL_OK;
}

void xyl__fvk_finish(xyl__fvk *vk)
{
    if (vk->commands) vkDestroyCommandPool(vk->device, vk->commands, vk->vkalloc);
    vk->commands = VK_NULL_HANDLE;
}

xyl_result xyl__fvk_allocate(const xyl__fvk *vk, VkMemoryRequirements req,
                             VkMemoryPropertyFlags need, VkDeviceMemory *out, xyl_diag *diag)
{
    uint32_t type = 0;
    while (type < vk->memory.memoryTypeCount &&
           (!(req.memoryTypeBits & (1u << type)) ||
            (vk->memory.memoryTypes[type].propertyFlags & need) != need))
        ++type;
    if (type == vk->memory.memoryTypeCount)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "no memory type fits a resource");
    VkMemoryAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = type;
    XYL__FVK_TRY(vkAllocateMemory(vk->device, &ai, vk->vkalloc, out), "vkAllocateMemory");
    return XYL_OK;
}

void xyl__fvk_buffer_destroy(const xyl__fvk *vk, xyl__fvk_buffer *b)
{
    if (b->buffer) vkDestroyBuffer(vk->device, b->buffer, vk->vkalloc);
    if (b->memory) vkFreeMemory(vk->device, b->memory, vk->vkalloc);
    memset(b, 0, sizeof *b);
}

xyl_result xyl__fvk_buffer_create(const xyl__fvk *vk, VkDeviceSize size,
                                  VkBufferUsageFlags usage, const void *data,
                                  xyl__fvk_buffer *out, xyl_diag *diag)
{
    xyl__fvk_buffer b = {0};
    VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = size;
    bi.usage = usage;
    VkResult vr = vkCreateBuffer(vk->device, &bi, vk->vkalloc, &b.buffer);
    if (vr != VK_SUCCESS) return xyl__fvk_fail(diag, vr, "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(vk->device, b.buffer, &req);
    xyl_result r = xyl__fvk_allocate(vk, req,
                                     VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                         VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                     &b.memory, diag);
    void *map = NULL;
    if (r == XYL_OK && (vr = vkBindBufferMemory(vk->device, b.buffer, b.memory, 0)) != VK_SUCCESS)
        r = xyl__fvk_fail(diag, vr, "vkBindBufferMemory");
    if (r == XYL_OK && (vr = vkMapMemory(vk->device, b.memory, 0, size, 0, &map)) != VK_SUCCESS)
        r = xyl__fvk_fail(diag, vr, "vkMapMemory");
    if (r != XYL_OK) {
        xyl__fvk_buffer_destroy(vk, &b);
        return r;
    }
    if (data) memcpy(map, data, (size_t)size);
    else memset(map, 0, (size_t)size);
    vkUnmapMemory(vk->device, b.memory);
    *out = b;
    return XYL_OK;
}

xyl_result xyl__fvk_shader(const xyl__fvk *vk, const unsigned char *code, size_t size,
                           VkShaderModule *out, xyl_diag *diag)
{
    VkShaderModuleCreateInfo si = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    si.codeSize = size;
    si.pCode = (const uint32_t *)(const void *)code; /* the embedded arrays are 4-byte aligned */
    XYL__FVK_TRY(vkCreateShaderModule(vk->device, &si, vk->vkalloc, out), "vkCreateShaderModule");
    return XYL_OK;
}

xyl_result xyl__fvk_begin_once(const xyl__fvk *vk, VkCommandBuffer *cmd, xyl_diag *diag)
{
    VkCommandBufferAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = vk->commands;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    XYL__FVK_TRY(vkAllocateCommandBuffers(vk->device, &ai, cmd), "vkAllocateCommandBuffers");
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    VkResult vr = vkBeginCommandBuffer(*cmd, &bi);
    if (vr != VK_SUCCESS) {
        vkFreeCommandBuffers(vk->device, vk->commands, 1, cmd);
        return xyl__fvk_fail(diag, vr, "vkBeginCommandBuffer");
    }
    return XYL_OK;
}

xyl_result xyl__fvk_submit_wait(const xyl__fvk *vk, VkCommandBuffer cmd, xyl_diag *diag)
{
    VkFence fence = VK_NULL_HANDLE;
    VkFenceCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkResult vr = vkEndCommandBuffer(cmd);
    const char *what = "vkEndCommandBuffer";
    if (vr == VK_SUCCESS) {
        vr = vkCreateFence(vk->device, &fi, vk->vkalloc, &fence);
        what = "vkCreateFence";
    }
    if (vr == VK_SUCCESS) {
        VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO};
        si.commandBufferCount = 1;
        si.pCommandBuffers = &cmd;
        vr = vkQueueSubmit(vk->queue, 1, &si, fence);
        what = "vkQueueSubmit";
    }
    if (vr == VK_SUCCESS) {
        vr = vkWaitForFences(vk->device, 1, &fence, VK_TRUE, UINT64_MAX);
        what = "vkWaitForFences";
    }
    if (fence) vkDestroyFence(vk->device, fence, vk->vkalloc);
    vkFreeCommandBuffers(vk->device, vk->commands, 1, &cmd);
    return vr == VK_SUCCESS ? XYL_OK : xyl__fvk_fail(diag, vr, what);
}

xyl_result xyl__fvk_pipeline(const xyl__fvk *vk, const xyl__fvk_pipe *p, VkPipeline *out,
                             xyl_diag *diag)
{
    bool vertex_only = p->frag == VK_NULL_HANDLE;
    VkPipelineShaderStageCreateInfo st[2] = {
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, NULL, 0, VK_SHADER_STAGE_VERTEX_BIT,
         p->vert, "main", NULL},
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, NULL, 0,
         VK_SHADER_STAGE_FRAGMENT_BIT, p->frag, "main", NULL}};
    VkPipelineVertexInputStateCreateInfo vi = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    VkPipelineInputAssemblyStateCreateInfo ia = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_STRIP;
    VkPipelineViewportStateCreateInfo vp = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    vp.viewportCount = vp.scissorCount = 1;
    VkPipelineRasterizationStateCreateInfo rs = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    rs.rasterizerDiscardEnable = vertex_only;
    rs.polygonMode = VK_POLYGON_MODE_FILL;
    rs.cullMode = VK_CULL_MODE_NONE; /* leaves and cross planes are seen from both sides */
    /* view_proj flips y and Vulkan measures winding with y down: the mirrors cancel, so the
     * counter-clockwise side is the front, as in GL, and gl_FrontFacing agrees with GL's */
    rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
    rs.lineWidth = 1.0f;
    VkPipelineMultisampleStateCreateInfo ms = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    ms.rasterizationSamples = p->samples;
    ms.alphaToCoverageEnable = p->alpha_to_coverage;
    ms.alphaToOneEnable = p->alpha_to_one;
    VkPipelineDepthStencilStateCreateInfo ds = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
    ds.depthTestEnable = ds.depthWriteEnable = VK_TRUE;
    ds.depthCompareOp = VK_COMPARE_OP_LESS;
    VkPipelineColorBlendAttachmentState blend = {0};
    blend.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT |
                           VK_COLOR_COMPONENT_B_BIT |
                           (p->keep_alpha ? 0 : VK_COLOR_COMPONENT_A_BIT);
    VkPipelineColorBlendStateCreateInfo cb = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    cb.attachmentCount = vertex_only ? 0 : 1;
    cb.pAttachments = &blend;
    VkDynamicState dyn[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    VkPipelineDynamicStateCreateInfo dy = {VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO,
                                           NULL, 0, 2, dyn};
    VkGraphicsPipelineCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    pi.stageCount = vertex_only ? 1 : 2;
    pi.pStages = st;
    pi.pVertexInputState = &vi;
    pi.pInputAssemblyState = &ia;
    pi.pViewportState = &vp;
    pi.pRasterizationState = &rs;
    pi.pMultisampleState = &ms;
    pi.pDepthStencilState = vertex_only ? NULL : &ds;
    pi.pColorBlendState = &cb;
    pi.pDynamicState = &dy;
    pi.layout = p->layout;
    pi.renderPass = p->pass;
    pi.subpass = p->subpass;
    VkPipelineRenderingCreateInfoKHR ri = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO_KHR};
    if (!p->pass) { /* dynamic rendering */
        ri.colorAttachmentCount = 1;
        ri.pColorAttachmentFormats = &p->color;
        ri.depthAttachmentFormat = p->depth;
        pi.pNext = &ri;
    }
    XYL__FVK_TRY(vkCreateGraphicsPipelines(vk->device, VK_NULL_HANDLE, 1, &pi, vk->vkalloc, out),
                 "vkCreateGraphicsPipelines");
    return XYL_OK;
}

xyl_result xyl__fvk_check_target(VkPhysicalDevice physical, VkDevice device, VkQueue queue,
                                 VkRenderPass pass, VkFormat color, VkFormat depth,
                                 VkSampleCountFlagBits samples, xyl_diag *diag)
{
    if (!physical || !device || !queue)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "desc.physical_device, desc.device and desc.queue are required");
    if (!pass && (color == VK_FORMAT_UNDEFINED || depth == VK_FORMAT_UNDEFINED))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "desc.render_pass, or colour and depth formats for dynamic rendering, "
                         "are required");
    uint32_t s = (uint32_t)samples;
    if (s != 0 && ((s & (s - 1)) != 0 || s > 64))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "desc.samples %u is not a power of two up to 64", s);
    return XYL_OK;
}

void xyl__fvk_image_destroy(const xyl__fvk *vk, xyl__fvk_image *im)
{
    if (im->view) vkDestroyImageView(vk->device, im->view, vk->vkalloc);
    if (im->image) vkDestroyImage(vk->device, im->image, vk->vkalloc);
    if (im->memory) vkFreeMemory(vk->device, im->memory, vk->vkalloc);
    memset(im, 0, sizeof *im);
}

xyl_result xyl__fvk_image_create(const xyl__fvk *vk, const VkImageCreateInfo *ii,
                                 VkImageViewType type, VkImageAspectFlags aspect,
                                 xyl__fvk_image *out, xyl_diag *diag)
{
    XYL__FVK_TRY(vkCreateImage(vk->device, ii, vk->vkalloc, &out->image), "vkCreateImage");
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(vk->device, out->image, &req);
    xyl_result r = xyl__fvk_allocate(vk, req, 0, &out->memory, diag);
    if (r != XYL_OK) return r;
    XYL__FVK_TRY(vkBindImageMemory(vk->device, out->image, out->memory, 0), "vkBindImageMemory");
    VkImageViewCreateInfo vi = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = out->image;
    vi.viewType = type;
    vi.format = ii->format;
    vi.subresourceRange.aspectMask = aspect;
    vi.subresourceRange.levelCount = ii->mipLevels;
    vi.subresourceRange.layerCount = ii->arrayLayers;
    XYL__FVK_TRY(vkCreateImageView(vk->device, &vi, vk->vkalloc, &out->view),
                 "vkCreateImageView");
    return XYL_OK;
}

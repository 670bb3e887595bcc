/* The Vulkan application of the foliage/ Vulkan suites (test_foliage_vk, test_billboard_vk):
 * an instance with the validation layer and its own messenger, a device, queue and command
 * pool, a single-sample render pass of COLOR_FORMAT and DEPTH_FORMAT, and a SIDE x SIDE target
 * read back into host memory. The including suite defines SIDE, COLOR_FORMAT and DEPTH_FORMAT
 * first. Set XYL_TEST_VK_VERBOSE to see every validation message on stderr. */
#ifndef XYL_TESTS_VK_APP_H
#define XYL_TESTS_VK_APP_H

#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <vulkan/vulkan.h>

/* What an application has: instance (validation on, its own messenger), device, queue, command
 * pool, a render pass with a colour and a depth attachment, and a SIDE x SIDE target. */
typedef struct app {
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    uint32_t messages;
    /* while set, the layer's report of an injected VK_ERROR_OUT_OF_HOST_MEMORY is counted
     * here instead (a test that fails the caller's allocator on purpose) */
    bool expect_oom;
    uint32_t oom_messages;
    char first[XYL_DIAG_MESSAGE_SIZE];
    VkPhysicalDevice physical;
    VkPhysicalDeviceFeatures features;
    bool dynamic_rendering; /* Vulkan 1.3's, enabled where instance and device have 1.3 */
    VkDevice device;
    uint32_t family;
    VkQueue queue;
    VkCommandPool pool;
    VkRenderPass pass;
    VkImage image[2];
    VkDeviceMemory memory[3];
    VkImageView view[2];
    VkFramebuffer framebuffer;
    VkBuffer readback;
    void *pixels;
} app;

static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                 VkDebugUtilsMessageTypeFlagsEXT types,
                                                 const VkDebugUtilsMessengerCallbackDataEXT *data,
                                                 void *user)
{
    (void)severity, (void)types; /* the messenger asks for warnings and errors only */
    app *a = user;
    if (a->expect_oom && strstr(data->pMessage, "VK_ERROR_OUT_OF_HOST_MEMORY")) {
        a->oom_messages++;
        return VK_FALSE;
    }
    if (a->messages++ == 0) snprintf(a->first, sizeof a->first, "%s", data->pMessage);
    if (getenv("XYL_TEST_VK_VERBOSE")) fprintf(stderr, "%s\n", data->pMessage);
    return VK_FALSE;
}

static void vk_ok(VkResult r, const char *what)
{
    if (r != VK_SUCCESS) fail_msg("%s: VkResult %d", what, (int)r);
}

/* ---- the application ------------------------------------------------------------------------ */

static VkResult make_instance(app *a)
{
    uint32_t version = VK_API_VERSION_1_2;
    if (vkEnumerateInstanceVersion(&version) != VK_SUCCESS) version = VK_API_VERSION_1_2;
    VkApplicationInfo ai = {.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO};
    ai.apiVersion = version >= VK_API_VERSION_1_3 ? VK_API_VERSION_1_3 : VK_API_VERSION_1_2;
    a->dynamic_rendering = ai.apiVersion >= VK_API_VERSION_1_3;
    VkDebugUtilsMessengerCreateInfoEXT mi = {
        .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                         VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    mi.pfnUserCallback = on_message;
    mi.pUserData = a;
    const char *layer = "VK_LAYER_KHRONOS_validation", *ext = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    VkInstanceCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ci.pNext = &mi;
    ci.pApplicationInfo = &ai;
    ci.enabledLayerCount = 1;
    ci.ppEnabledLayerNames = &layer;
    ci.enabledExtensionCount = 1;
    ci.ppEnabledExtensionNames = &ext;
    VkResult r = vkCreateInstance(&ci, NULL, &a->instance);
    if (r != VK_SUCCESS) return r;
    PFN_vkCreateDebugUtilsMessengerEXT create = (PFN_vkCreateDebugUtilsMessengerEXT)
        vkGetInstanceProcAddr(a->instance, "vkCreateDebugUtilsMessengerEXT");
    return create ? create(a->instance, &mi, NULL, &a->messenger) : VK_ERROR_EXTENSION_NOT_PRESENT;
}

/* The first Vulkan 1.2 device with a graphics queue; with vertex_stores,
 * vertexPipelineStoresAndAtomics enabled (the leaf renderer's capture). */
static bool make_device(app *a, bool vertex_stores, char *why, size_t why_size)
{
    uint32_t n = 1;
    VkResult r = vkEnumeratePhysicalDevices(a->instance, &n, &a->physical);
    VkPhysicalDeviceProperties props;
    if ((r != VK_SUCCESS && r != VK_INCOMPLETE) || n == 0) {
        snprintf(why, why_size, "no Vulkan device");
        return false;
    }
    vkGetPhysicalDeviceProperties(a->physical, &props);
    a->dynamic_rendering = a->dynamic_rendering && props.apiVersion >= VK_API_VERSION_1_3;
    VkPhysicalDeviceFeatures have;
    vkGetPhysicalDeviceFeatures(a->physical, &have);
    if (props.apiVersion < VK_API_VERSION_1_2 ||
        (vertex_stores && !have.vertexPipelineStoresAndAtomics)) {
        snprintf(why, why_size, "%s lacks Vulkan 1.2 or vertex stores", props.deviceName);
        return false;
    }
    VkQueueFamilyProperties q[8];
    uint32_t nq = 8;
    vkGetPhysicalDeviceQueueFamilyProperties(a->physical, &nq, q);
    for (a->family = 0; a->family < nq; ++a->family)
        if (q[a->family].queueFlags & VK_QUEUE_GRAPHICS_BIT) break;
    if (a->family == nq) {
        snprintf(why, why_size, "%s has no graphics queue", props.deviceName);
        return false;
    }
    memset(&a->features, 0, sizeof a->features);
    a->features.vertexPipelineStoresAndAtomics = vertex_stores;
    float priority = 1.0f;
    VkDeviceQueueCreateInfo qi = {.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qi.queueFamilyIndex = a->family;
    qi.queueCount = 1;
    qi.pQueuePriorities = &priority;
    VkPhysicalDeviceVulkan13Features v13 = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    v13.dynamicRendering = VK_TRUE;
    VkDeviceCreateInfo di = {.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    di.pNext = a->dynamic_rendering ? &v13 : NULL;
    di.queueCreateInfoCount = 1;
    di.pQueueCreateInfos = &qi;
    di.pEnabledFeatures = &a->features;
    vk_ok(vkCreateDevice(a->physical, &di, NULL, &a->device), "vkCreateDevice");
    vkGetDeviceQueue(a->device, a->family, 0, &a->queue);
    VkCommandPoolCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pi.queueFamilyIndex = a->family;
    vk_ok(vkCreateCommandPool(a->device, &pi, NULL, &a->pool), "vkCreateCommandPool");
    return true;
}

static void make_pass(app *a)
{
    VkAttachmentDescription att[2] = {{0}, {0}};
    att[0].format = COLOR_FORMAT;
    att[0].finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    att[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    att[1].format = DEPTH_FORMAT;
    att[1].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    att[1].storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    for (int k = 0; k < 2; ++k) {
        att[k].samples = VK_SAMPLE_COUNT_1_BIT;
        att[k].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        att[k].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        att[k].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    }
    VkAttachmentReference color = {0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth = {1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub = {0};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.colorAttachmentCount = 1;
    sub.pColorAttachments = &color;
    sub.pDepthStencilAttachment = &depth;
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
    vk_ok(vkCreateRenderPass(a->device, &ri, NULL, &a->pass), "vkCreateRenderPass");
}

static VkDeviceMemory memory_for(const app *a, VkMemoryRequirements req,
                                 VkMemoryPropertyFlags need)
{
    VkPhysicalDeviceMemoryProperties mp;
    vkGetPhysicalDeviceMemoryProperties(a->physical, &mp);
    uint32_t type = 0;
    while (type < mp.memoryTypeCount && (!(req.memoryTypeBits & (1u << type)) ||
                                         (mp.memoryTypes[type].propertyFlags & need) != need))
        ++type;
    assert_true(type < mp.memoryTypeCount);
    VkMemoryAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = type;
    VkDeviceMemory m;
    vk_ok(vkAllocateMemory(a->device, &ai, NULL, &m), "vkAllocateMemory");
    return m;
}

static void make_target(app *a)
{
    const VkFormat formats[2] = {COLOR_FORMAT, DEPTH_FORMAT};
    const VkImageUsageFlags usage[2] = {
        VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
        VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT};
    for (int k = 0; k < 2; ++k) {
        VkImageCreateInfo ii = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
        ii.imageType = VK_IMAGE_TYPE_2D;
        ii.format = formats[k];
        ii.extent = (VkExtent3D){SIDE, SIDE, 1};
        ii.mipLevels = ii.arrayLayers = 1;
        ii.samples = VK_SAMPLE_COUNT_1_BIT;
        ii.usage = usage[k];
        vk_ok(vkCreateImage(a->device, &ii, NULL, &a->image[k]), "vkCreateImage");
        VkMemoryRequirements req;
        vkGetImageMemoryRequirements(a->device, a->image[k], &req);
        a->memory[k] = memory_for(a, req, 0);
        vk_ok(vkBindImageMemory(a->device, a->image[k], a->memory[k], 0), "vkBindImageMemory");
        VkImageViewCreateInfo vi = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
        vi.image = a->image[k];
        vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
        vi.format = formats[k];
        vi.subresourceRange.aspectMask = k ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
        vi.subresourceRange.levelCount = vi.subresourceRange.layerCount = 1;
        vk_ok(vkCreateImageView(a->device, &vi, NULL, &a->view[k]), "vkCreateImageView");
    }
    VkFramebufferCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fi.renderPass = a->pass;
    fi.attachmentCount = 2;
    fi.pAttachments = a->view;
    fi.width = fi.height = SIDE;
    fi.layers = 1;
    vk_ok(vkCreateFramebuffer(a->device, &fi, NULL, &a->framebuffer), "vkCreateFramebuffer");
    VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = 4u * SIDE * SIDE;
    bi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    vk_ok(vkCreateBuffer(a->device, &bi, NULL, &a->readback), "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(a->device, a->readback, &req);
    a->memory[2] = memory_for(a, req, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                          VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    vk_ok(vkBindBufferMemory(a->device, a->readback, a->memory[2], 0), "vkBindBufferMemory");
    vk_ok(vkMapMemory(a->device, a->memory[2], 0, VK_WHOLE_SIZE, 0, &a->pixels), "vkMapMemory");
}

static void image_barrier(VkCommandBuffer cb, VkImage image, VkImageAspectFlags aspect,
                          VkImageLayout from, VkImageLayout to, VkPipelineStageFlags src_stage,
                          VkAccessFlags src, VkPipelineStageFlags dst_stage, VkAccessFlags dst)
{
    VkImageMemoryBarrier b = {.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.srcAccessMask = src;
    b.dstAccessMask = dst;
    b.oldLayout = from;
    b.newLayout = to;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = image;
    b.subresourceRange.aspectMask = aspect;
    b.subresourceRange.levelCount = b.subresourceRange.layerCount = 1;
    vkCmdPipelineBarrier(cb, src_stage, dst_stage, 0, 0, NULL, 0, NULL, 1, &b);
}

/* Dynamic rendering into the same images: their layouts are the application's to set. */
static void begin_dynamic(const app *a, VkCommandBuffer cb, const VkClearValue *clear)
{
    image_barrier(cb, a->image[0], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                  VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0,
                  VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                  VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT);
    image_barrier(cb, a->image[1], VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                  VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0,
                  VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                      VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                  VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                      VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT);
    VkRenderingAttachmentInfo color = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    color.imageView = a->view[0];
    color.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    color.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    color.clearValue = clear[0];
    VkRenderingAttachmentInfo depth = color;
    depth.imageView = a->view[1];
    depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
    depth.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    depth.clearValue = clear[1];
    VkRenderingInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDERING_INFO};
    ri.renderArea.extent = (VkExtent2D){SIDE, SIDE};
    ri.layerCount = 1;
    ri.colorAttachmentCount = 1;
    ri.pColorAttachments = &color;
    ri.pDepthAttachment = &depth;
    vkCmdBeginRendering(cb, &ri);
}

static void end_dynamic(const app *a, VkCommandBuffer cb)
{
    vkCmdEndRendering(cb);
    image_barrier(cb, a->image[0], VK_IMAGE_ASPECT_COLOR_BIT,
                  VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                  VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                  VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                  VK_ACCESS_TRANSFER_READ_BIT);
}

/* Everything of the application, in reverse order (what was never made is skipped). */
static void close_app(app *a)
{
    if (a->device) {
        vkDeviceWaitIdle(a->device);
        if (a->framebuffer) vkDestroyFramebuffer(a->device, a->framebuffer, NULL);
        if (a->readback) vkDestroyBuffer(a->device, a->readback, NULL);
        for (int k = 0; k < 2; ++k) {
            if (a->view[k]) vkDestroyImageView(a->device, a->view[k], NULL);
            if (a->image[k]) vkDestroyImage(a->device, a->image[k], NULL);
        }
        for (int k = 0; k < 3; ++k)
            if (a->memory[k]) vkFreeMemory(a->device, a->memory[k], NULL);
        if (a->pass) vkDestroyRenderPass(a->device, a->pass, NULL);
        if (a->pool) vkDestroyCommandPool(a->device, a->pool, NULL);
        vkDestroyDevice(a->device, NULL);
    }
    if (a->messenger) {
        PFN_vkDestroyDebugUtilsMessengerEXT destroy = (PFN_vkDestroyDebugUtilsMessengerEXT)
            vkGetInstanceProcAddr(a->instance, "vkDestroyDebugUtilsMessengerEXT");
        destroy(a->instance, a->messenger, NULL);
    }
    if (a->instance) vkDestroyInstance(a->instance, NULL);
}

#endif

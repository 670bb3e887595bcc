/* Vulkan backend: allocation callbacks over the caller's allocator, instance (with the
 * validation layer and a messenger that counts what it reports), physical device and its
 * features, logical device, host-visible buffers, images, submission. */
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "vk_internal.h"

static const char *const validation_layer = "VK_LAYER_KHRONOS_validation";

static const char *vk_result_name(VkResult r)
{
    switch (r) {
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS";
    case VK_ERROR_FORMAT_NOT_SUPPORTED: return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    case VK_ERROR_FRAGMENTED_POOL: return "VK_ERROR_FRAGMENTED_POOL";
    case VK_ERROR_OUT_OF_POOL_MEMORY: return "VK_ERROR_OUT_OF_POOL_MEMORY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    default: return "VkResult";
    }
}

xyl_result xyl__vk_fail(xyl_tess_vk *vk, xyl_diag *diag, VkResult r, const char *what)
{
    xyl_result code = XYL_ERR_UNSUPPORTED;
    if (r == VK_ERROR_OUT_OF_HOST_MEMORY || r == VK_ERROR_OUT_OF_DEVICE_MEMORY ||
        r == VK_ERROR_OUT_OF_POOL_MEMORY || r == VK_ERROR_FRAGMENTED_POOL ||
        r == VK_ERROR_TOO_MANY_OBJECTS)
        code = XYL_ERR_OUT_OF_MEMORY;
    if (r == VK_ERROR_DEVICE_LOST && vk) vk->lost = true;
    return xyl__fail(diag, code, 0, 0, -1, "Vulkan: %s failed: %s (%d)", what,
                     vk_result_name(r), (int)r);
}

/* ---- allocation callbacks ------------------------------------------------------------------ */

/* The caller's xyl_allocator with the alignment and realloc Vulkan asks for (core's aligned
 * blocks). */
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

void xyl__vk_init_callbacks(xyl_tess_vk *vk)
{
    vk->vkalloc = NULL; /* the default allocator: Vulkan's own is as good */
    if (!vk->alloc.alloc) return;
    memset(&vk->callbacks, 0, sizeof vk->callbacks);
    vk->callbacks.pUserData = &vk->alloc;
    vk->callbacks.pfnAllocation = vk_alloc;
    vk->callbacks.pfnReallocation = vk_realloc;
    vk->callbacks.pfnFree = vk_free;
    vk->vkalloc = &vk->callbacks;
}

/* ---- instance ------------------------------------------------------------------------------ */

static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                 VkDebugUtilsMessageTypeFlagsEXT types,
                                                 const VkDebugUtilsMessengerCallbackDataEXT *data,
                                                 void *user)
{
    (void)types;
    xyl__vk_messages *m = user;
    if (!(severity & (VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                      VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)))
        return VK_FALSE;
    if (m->count++ == 0 && data && data->pMessage)
        snprintf(m->first, sizeof m->first, "%s", data->pMessage);
    return VK_FALSE; /* the call goes on, as the layer's reports must not change behaviour */
}

static bool has_layer(const xyl_tess_vk *vk, const char *name)
{
    uint32_t n = 0;
    if (vkEnumerateInstanceLayerProperties(&n, NULL) != VK_SUCCESS || n == 0) return false;
    VkLayerProperties *props = xyl__alloc_array(&vk->alloc, n, sizeof *props);
    bool found = false;
    if (props && vkEnumerateInstanceLayerProperties(&n, props) >= VK_SUCCESS)
        for (uint32_t i = 0; i < n && !found; ++i) found = strcmp(props[i].layerName, name) == 0;
    xyl__free(&vk->alloc, props);
    return found;
}

static VkDebugUtilsMessengerCreateInfoEXT messenger_info(xyl_tess_vk *vk)
{
    VkDebugUtilsMessengerCreateInfoEXT mi = {.sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                         VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    mi.pfnUserCallback = on_message;
    mi.pUserData = &vk->messages;
    return mi;
}

static xyl_result create_messenger(xyl_tess_vk *vk, xyl_diag *diag)
{
    PFN_vkCreateDebugUtilsMessengerEXT create = (PFN_vkCreateDebugUtilsMessengerEXT)
        vkGetInstanceProcAddr(vk->instance, "vkCreateDebugUtilsMessengerEXT");
    vk->destroy_messenger = (PFN_vkDestroyDebugUtilsMessengerEXT)
        vkGetInstanceProcAddr(vk->instance, "vkDestroyDebugUtilsMessengerEXT");
    if (!create || !vk->destroy_messenger)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: VK_EXT_debug_utils has no messenger entry points");
    VkDebugUtilsMessengerCreateInfoEXT mi = messenger_info(vk);
    VkResult r = create(vk->instance, &mi, vk->vkalloc, &vk->messenger);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkCreateDebugUtilsMessengerEXT");
}

xyl_result xyl__vk_create_instance(xyl_tess_vk *vk, bool validation, xyl_diag *diag)
{
    uint32_t version = 0;
    if (vkEnumerateInstanceVersion(&version) != VK_SUCCESS || version < VK_API_VERSION_1_2)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: the loader offers no Vulkan 1.2 instance");
    if (validation && !has_layer(vk, validation_layer))
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: validation asked for but %s is not installed",
                         validation_layer);
    VkApplicationInfo app = {.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "xylem";
    app.pEngineName = "xylem";
    app.apiVersion = VK_API_VERSION_1_2;
    const char *ext = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    /* Chained so that instance creation and destruction are reported too. */
    VkDebugUtilsMessengerCreateInfoEXT mi = messenger_info(vk);
    VkInstanceCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ci.pApplicationInfo = &app;
    if (validation) {
        ci.pNext = &mi;
        ci.enabledLayerCount = 1;
        ci.ppEnabledLayerNames = &validation_layer;
        ci.enabledExtensionCount = 1;
        ci.ppEnabledExtensionNames = &ext;
    }
    VkResult r = vkCreateInstance(&ci, vk->vkalloc, &vk->instance);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkCreateInstance");
    return validation ? create_messenger(vk, diag) : XYL_OK;
}

/* ---- physical device ----------------------------------------------------------------------- */

static bool graphics_family(const xyl_tess_vk *vk, VkPhysicalDevice pd, uint32_t *family)
{
    uint32_t n = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, NULL);
    VkQueueFamilyProperties *q = xyl__alloc_array(&vk->alloc, n, sizeof *q);
    bool found = false;
    if (q) {
        vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, q);
        for (uint32_t i = 0; i < n && !found; ++i)
            if (q[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) {
                *family = i;
                found = true;
            }
    }
    xyl__free(&vk->alloc, q);
    return found;
}

/* A device qualifies with Vulkan 1.2, a graphics queue, drawIndirectFirstInstance (the commands'
 * base_instance) and D32_SFLOAT depth; the name filters when given. */
static bool qualifies(const xyl_tess_vk *vk, VkPhysicalDevice pd, const char *name,
                      uint32_t *family)
{
    VkPhysicalDeviceProperties p;
    VkPhysicalDeviceFeatures f;
    VkFormatProperties fp;
    vkGetPhysicalDeviceProperties(pd, &p);
    vkGetPhysicalDeviceFeatures(pd, &f);
    vkGetPhysicalDeviceFormatProperties(pd, VK_FORMAT_D32_SFLOAT, &fp);
    if (p.apiVersion < VK_API_VERSION_1_2 || !f.drawIndirectFirstInstance) return false;
    if (!(fp.optimalTilingFeatures & VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT)) return false;
    if (name && !strstr(p.deviceName, name)) return false;
    return graphics_family(vk, pd, family);
}

xyl_result xyl__vk_pick_device(xyl_tess_vk *vk, const char *name, xyl_diag *diag)
{
    uint32_t n = 0;
    VkResult r = vkEnumeratePhysicalDevices(vk->instance, &n, NULL);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkEnumeratePhysicalDevices");
    VkPhysicalDevice *pds = xyl__alloc_array(&vk->alloc, n, sizeof *pds);
    if (!pds) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    r = vkEnumeratePhysicalDevices(vk->instance, &n, pds);
    for (uint32_t i = 0; r >= VK_SUCCESS && i < n && !vk->physical; ++i)
        if (qualifies(vk, pds[i], name, &vk->family)) vk->physical = pds[i];
    xyl__free(&vk->alloc, pds);
    if (r < VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkEnumeratePhysicalDevices");
    if (!vk->physical)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: no device%s%s%s with Vulkan 1.2, a graphics queue, "
                         "drawIndirectFirstInstance and D32_SFLOAT depth (of %u)",
                         name ? " named like '" : "", name ? name : "", name ? "'" : "", n);
    vkGetPhysicalDeviceProperties(vk->physical, &vk->props);
    snprintf(vk->device_name, sizeof vk->device_name, "%s", vk->props.deviceName);
    return XYL_OK;
}

/* ---- logical device ------------------------------------------------------------------------ */

/* Required: drawIndirectFirstInstance. Optional, each enabling one thing: multiDrawIndirect
 * (one call for all commands), fillModeNonSolid (wireframe), vertexPipelineStoresAndAtomics
 * (capture). */
static VkPhysicalDeviceFeatures wanted_features(VkPhysicalDevice pd)
{
    VkPhysicalDeviceFeatures have, want = {0};
    vkGetPhysicalDeviceFeatures(pd, &have);
    want.drawIndirectFirstInstance = VK_TRUE;
    want.multiDrawIndirect = have.multiDrawIndirect;
    want.fillModeNonSolid = have.fillModeNonSolid;
    want.vertexPipelineStoresAndAtomics = have.vertexPipelineStoresAndAtomics;
    return want;
}

static xyl_result create_queries(xyl_tess_vk *vk, xyl_diag *diag)
{
    uint32_t n = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(vk->physical, &n, NULL);
    VkQueueFamilyProperties *q = xyl__alloc_array(&vk->alloc, n, sizeof *q);
    if (!q) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    vkGetPhysicalDeviceQueueFamilyProperties(vk->physical, &n, q);
    uint32_t bits = vk->family < n ? q[vk->family].timestampValidBits : 0;
    xyl__free(&vk->alloc, q);
    if (bits == 0) return XYL_OK; /* no timestamps: xyl_tess_vk_last_gpu_ms stays negative */
    vk->timestamp_bits = bits;
    VkQueryPoolCreateInfo qi = {.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qi.queryCount = 2;
    VkResult r = vkCreateQueryPool(vk->device, &qi, vk->vkalloc, &vk->queries);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkCreateQueryPool");
}

xyl_result xyl__vk_create_commands(xyl_tess_vk *vk, xyl_diag *diag)
{
    VkCommandPoolCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pi.queueFamilyIndex = vk->family;
    VkResult r = vkCreateCommandPool(vk->device, &pi, vk->vkalloc, &vk->pool);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkCreateCommandPool");
    VkCommandBufferAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = vk->pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    r = vkAllocateCommandBuffers(vk->device, &ai, &vk->cmd);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkAllocateCommandBuffers");
    VkFenceCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    r = vkCreateFence(vk->device, &fi, vk->vkalloc, &vk->fence);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkCreateFence");
    return create_queries(vk, diag);
}

xyl_result xyl__vk_create_device(xyl_tess_vk *vk, xyl_diag *diag)
{
    float priority = 1.0f;
    VkDeviceQueueCreateInfo qi = {.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qi.queueFamilyIndex = vk->family;
    qi.queueCount = 1;
    qi.pQueuePriorities = &priority;
    vk->features = wanted_features(vk->physical);
    VkDeviceCreateInfo di = {.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    di.queueCreateInfoCount = 1;
    di.pQueueCreateInfos = &qi;
    di.pEnabledFeatures = &vk->features;
    VkResult r = vkCreateDevice(vk->physical, &di, vk->vkalloc, &vk->device);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkCreateDevice");
    vkGetDeviceQueue(vk->device, vk->family, 0, &vk->queue);
    return XYL_OK;
}

/* ---- memory -------------------------------------------------------------------------------- */

static bool memory_type(xyl_tess_vk *vk, uint32_t allowed, VkMemoryPropertyFlags need,
                        uint32_t *type)
{
    VkPhysicalDeviceMemoryProperties mp;
    vkGetPhysicalDeviceMemoryProperties(vk->physical, &mp);
    for (uint32_t i = 0; i < mp.memoryTypeCount; ++i)
        if ((allowed & (1u << i)) && (mp.memoryTypes[i].propertyFlags & need) == need) {
            *type = i;
            return true;
        }
    return false;
}

static xyl_result allocate(xyl_tess_vk *vk, VkMemoryRequirements req, VkMemoryPropertyFlags need,
                           VkMemoryPropertyFlags prefer, VkDeviceMemory *out, xyl_diag *diag)
{
    uint32_t type;
    if (!memory_type(vk, req.memoryTypeBits, need | prefer, &type) &&
        !memory_type(vk, req.memoryTypeBits, need, &type))
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "Vulkan: no memory type with properties 0x%x for a resource",
                         (unsigned)need);
    VkMemoryAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = type;
    VkResult r = vkAllocateMemory(vk->device, &ai, vk->vkalloc, out);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkAllocateMemory");
}

void xyl__vk_buffer_destroy(xyl_tess_vk *vk, xyl__vk_buffer *b)
{
    if (b->buffer) vkDestroyBuffer(vk->device, b->buffer, vk->vkalloc);
    if (b->memory) vkFreeMemory(vk->device, b->memory, vk->vkalloc); /* unmaps implicitly */
    memset(b, 0, sizeof *b);
}

xyl_result xyl__vk_buffer_reserve(xyl_tess_vk *vk, xyl__vk_buffer *b, VkDeviceSize size,
                                  VkBufferUsageFlags usage, xyl_diag *diag)
{
    if (size < 256) size = 256; /* never a zero-sized buffer, and few regrowths of small ones */
    if (b->buffer && b->size >= size) return XYL_OK;
    xyl__vk_buffer_destroy(vk, b);
    VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = size;
    bi.usage = usage;
    bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    VkResult r = vkCreateBuffer(vk->device, &bi, vk->vkalloc, &b->buffer);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(vk->device, b->buffer, &req);
    xyl_result res = allocate(vk, req, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                              VK_MEMORY_PROPERTY_HOST_COHERENT_BIT, 0, &b->memory, diag);
    if (res == XYL_OK && (r = vkBindBufferMemory(vk->device, b->buffer, b->memory, 0)) != VK_SUCCESS)
        res = xyl__vk_fail(vk, diag, r, "vkBindBufferMemory");
    if (res == XYL_OK && (r = vkMapMemory(vk->device, b->memory, 0, VK_WHOLE_SIZE, 0, &b->map)))
        res = xyl__vk_fail(vk, diag, r, "vkMapMemory");
    if (res != XYL_OK) {
        xyl__vk_buffer_destroy(vk, b);
        return res;
    }
    b->size = size;
    return XYL_OK;
}

void xyl__vk_image_destroy(xyl_tess_vk *vk, xyl__vk_image *img)
{
    if (img->view) vkDestroyImageView(vk->device, img->view, vk->vkalloc);
    if (img->image) vkDestroyImage(vk->device, img->image, vk->vkalloc);
    if (img->memory) vkFreeMemory(vk->device, img->memory, vk->vkalloc);
    memset(img, 0, sizeof *img);
}

static xyl_result image_view(xyl_tess_vk *vk, xyl__vk_image *img, VkFormat format,
                             VkImageAspectFlags aspect, xyl_diag *diag)
{
    VkImageViewCreateInfo vi = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = img->image;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = format;
    vi.subresourceRange.aspectMask = aspect;
    vi.subresourceRange.levelCount = 1;
    vi.subresourceRange.layerCount = 1;
    VkResult r = vkCreateImageView(vk->device, &vi, vk->vkalloc, &img->view);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkCreateImageView");
}

xyl_result xyl__vk_image_create(xyl_tess_vk *vk, xyl__vk_image *img, VkFormat format,
                                uint32_t width, uint32_t height, VkSampleCountFlagBits samples,
                                VkImageUsageFlags usage, VkImageAspectFlags aspect,
                                xyl_diag *diag)
{
    VkImageCreateInfo ii = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ii.imageType = VK_IMAGE_TYPE_2D;
    ii.format = format;
    ii.extent.width = width;
    ii.extent.height = height;
    ii.extent.depth = 1;
    ii.mipLevels = 1;
    ii.arrayLayers = 1;
    ii.samples = samples;
    ii.tiling = VK_IMAGE_TILING_OPTIMAL;
    ii.usage = usage;
    ii.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    ii.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    VkResult r = vkCreateImage(vk->device, &ii, vk->vkalloc, &img->image);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkCreateImage");
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(vk->device, img->image, &req);
    xyl_result res =
        allocate(vk, req, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, &img->memory, diag);
    if (res == XYL_OK && (r = vkBindImageMemory(vk->device, img->image, img->memory, 0)))
        res = xyl__vk_fail(vk, diag, r, "vkBindImageMemory");
    if (res == XYL_OK) res = image_view(vk, img, format, aspect, diag);
    if (res != XYL_OK) xyl__vk_image_destroy(vk, img);
    return res;
}

/* ---- submission ---------------------------------------------------------------------------- */

xyl_result xyl__vk_begin(xyl_tess_vk *vk, xyl_diag *diag)
{
    VkResult r = vkResetCommandBuffer(vk->cmd, 0);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkResetCommandBuffer");
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    r = vkBeginCommandBuffer(vk->cmd, &bi);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkBeginCommandBuffer");
}

xyl_result xyl__vk_submit_wait(xyl_tess_vk *vk, xyl_diag *diag)
{
    VkResult r = vkEndCommandBuffer(vk->cmd);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkEndCommandBuffer");
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &vk->cmd;
    r = vkResetFences(vk->device, 1, &vk->fence);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkResetFences");
    r = vkQueueSubmit(vk->queue, 1, &si, vk->fence);
    if (r != VK_SUCCESS) return xyl__vk_fail(vk, diag, r, "vkQueueSubmit");
    /* No timeout: resources may only be reused or freed once the GPU is done with them. */
    r = vkWaitForFences(vk->device, 1, &vk->fence, VK_TRUE, UINT64_MAX);
    return r == VK_SUCCESS ? XYL_OK : xyl__vk_fail(vk, diag, r, "vkWaitForFences");
}

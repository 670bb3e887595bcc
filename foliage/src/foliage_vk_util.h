/* What foliage/'s Vulkan objects share: the device they live on, the caller's allocator as
 * VkAllocationCallbacks, memory, host-visible buffers, one-off submissions and the checks of
 * a device. Not installed. */
#ifndef XYL_FOLIAGE_VK_UTIL_H
#define XYL_FOLIAGE_VK_UTIL_H

#include <vulkan/vulkan.h>

#include "foliage_internal.h"

typedef struct xyl__fvk {
    xyl_allocator alloc;
    VkAllocationCallbacks callbacks;
    const VkAllocationCallbacks *vkalloc; /* &callbacks with a caller's allocator, else NULL */
    VkPhysicalDevice physical;
    VkDevice device;
    VkQueue queue;
    VkCommandPool commands; /* transient, of the queue's family */
    VkPhysicalDeviceMemoryProperties memory;
    VkPhysicalDeviceProperties properties;
} xyl__fvk;

typedef struct xyl__fvk_buffer {
    VkBuffer buffer;
    VkDeviceMemory memory;
} xyl__fvk_buffer;

/* Returns the failure of a Vulkan call from a function with a `diag` in scope. */
#define XYL__FVK_TRY(call, what)                                                               \
    do {                                                                                       \
        VkResult vr_ = (call);                                                                 \
        if (vr_ != VK_SUCCESS) return xyl__fvk_fail(diag, vr_, what);                          \
    } while (0)

typedef struct xyl__fvk_image {
    VkImage image;
    VkDeviceMemory memory;
    VkImageView view;
} xyl__fvk_image;

/* Takes the allocator (vk must not move afterwards: the callbacks point into it). */
void xyl__fvk_init(xyl__fvk *vk, const xyl_allocator *alloc, VkPhysicalDevice physical,
                   VkDevice device, VkQueue queue);
/* A VkResult as a result code and message: OUT_OF_MEMORY or UNSUPPORTED. */
xyl_result xyl__fvk_fail(xyl_diag *diag, VkResult r, const char *what);
/* The device's version (1.2), graphics on the queue family, the sample count offered; fills
 * vk->properties and vk->memory. */
xyl_result xyl__fvk_check_device(xyl__fvk *vk, uint32_t queue_family,
                                 VkSampleCountFlagBits samples, xyl_diag *diag);
xyl_result xyl__fvk_make_pool(xyl__fvk *vk, uint32_t queue_family, xyl_diag *diag);
xyl_result xyl__fvk_allocate(const xyl__fvk *vk, VkMemoryRequirements req,
                             VkMemoryPropertyFlags need, VkDeviceMemory *out, xyl_diag *diag);
/* A host-visible, coherent buffer holding data (or zeros: NULL) of size bytes. */
xyl_result xyl__fvk_buffer_create(const xyl__fvk *vk, VkDeviceSize size,
                                  VkBufferUsageFlags usage, const void *data,
                                  xyl__fvk_buffer *out, xyl_diag *diag);
void xyl__fvk_buffer_destroy(const xyl__fvk *vk, xyl__fvk_buffer *b);
xyl_result xyl__fvk_shader(const xyl__fvk *vk, const unsigned char *code, size_t size,
                           VkShaderModule *out, xyl_diag *diag);
/* The draw target of a desc: a device and queue, a render pass or dynamic rendering's
 * formats, a sample count that is 0 or a power of two up to 64 (XYL_ERR_INVALID_ARGUMENT). */
xyl_result xyl__fvk_check_target(VkPhysicalDevice physical, VkDevice device, VkQueue queue,
                                 VkRenderPass pass, VkFormat color, VkFormat depth,
                                 VkSampleCountFlagBits samples, xyl_diag *diag);
/* An image of ii, device-local, with a view of all its levels and layers. */
xyl_result xyl__fvk_image_create(const xyl__fvk *vk, const VkImageCreateInfo *ii,
                                 VkImageViewType type, VkImageAspectFlags aspect,
                                 xyl__fvk_image *out, xyl_diag *diag);
void xyl__fvk_image_destroy(const xyl__fvk *vk, xyl__fvk_image *im);

/* A graphics pipeline of 4-vertex triangle strips expanded in the vertex shader (no vertex
 * input), viewport and scissor dynamic, nothing culled, counter-clockwise front faces (the y
 * flip of Vulkan's clip convention and its y-down winding cancel), depth test LESS and
 * writes, no blending: into subpass `subpass` of `pass`, or with pass VK_NULL_HANDLE dynamic
 * rendering of one colour and one depth attachment of these formats. frag VK_NULL_HANDLE:
 * the vertex stage alone, rasterizer off, no attachments. */
typedef struct xyl__fvk_pipe {
    VkShaderModule vert, frag;
    VkPipelineLayout layout;
    VkRenderPass pass;
    uint32_t subpass;
    VkFormat color, depth;
    VkSampleCountFlagBits samples;
    bool alpha_to_coverage, alpha_to_one;
    bool keep_alpha; /* the colour's alpha is not written */
} xyl__fvk_pipe;
xyl_result xyl__fvk_pipeline(const xyl__fvk *vk, const xyl__fvk_pipe *p, VkPipeline *out,
                             xyl_diag *diag);

/* A one-time command buffer of the pool, begun; submit_wait ends, submits, waits and frees. */
xyl_result xyl__fvk_begin_once(const xyl__fvk *vk, VkCommandBuffer *cmd, xyl_diag *diag);
xyl_result xyl__fvk_submit_wait(const xyl__fvk *vk, VkCommandBuffer cmd, xyl_diag *diag);
void xyl__fvk_finish(xyl__fvk *vk); /* the command pool */

#endif

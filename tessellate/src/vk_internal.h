/* Internal to the Vulkan backend (vk_setup.c: instance, device, memory; vk_pipeline.c: render
 * passes, targets, pipelines; vk_backend.c: the public calls). Not installed. */
#ifndef XYL_VK_INTERNAL_H
#define XYL_VK_INTERNAL_H

#include <vulkan/vulkan.h>

#include "tess_debug.h"
#include "xyl_internal.h"
#include "xylem/xyl_tess_vk.h"

#define XYL__VK_MAX_IMAGE 8192u /* xyl_tess_image_desc: at most 8192 pixels each way */

/* A buffer in host-visible, coherent memory, mapped for its whole life: everything the GPU reads
 * is written by the CPU right before a submit, and every submit is waited for. */
typedef struct xyl__vk_buffer {
    VkBuffer buffer;
    VkDeviceMemory memory;
    void *map;
    VkDeviceSize size;
} xyl__vk_buffer;

typedef struct xyl__vk_image {
    VkImage image;
    VkDeviceMemory memory;
    VkImageView view;
} xyl__vk_image;

/* The offscreen target of one (width, height, samples) and the pipelines drawing into it. */
typedef struct xyl__vk_target {
    uint32_t width, height;
    VkSampleCountFlagBits samples;
    xyl__vk_image color, depth, resolve; /* resolve only when samples > 1 */
    VkRenderPass pass;
    VkFramebuffer framebuffer;
    VkPipeline fill[2]; /* [0] back faces culled, [1] nothing culled */
    VkPipeline line[2]; /* wireframe overlay, same culling; absent without fillModeNonSolid */
} xyl__vk_target;

/* What the validation layer's messenger writes to; outlives the instance. */
typedef struct xyl__vk_messages {
    uint32_t count;
    char first[XYL_DIAG_MESSAGE_SIZE];
} xyl__vk_messages;

struct xyl_tess_vk {
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    PFN_vkDestroyDebugUtilsMessengerEXT destroy_messenger;
    VkPhysicalDevice physical;
    VkPhysicalDeviceProperties props;
    VkPhysicalDeviceFeatures features; /* the ones enabled */
    VkDevice device;
    uint32_t family;
    VkQueue queue;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
    VkQueryPool queries; /* 2 timestamps; VK_NULL_HANDLE when the queue has none */
    uint32_t timestamp_bits;

    VkShaderModule vert, vert_capture, frag;
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkDescriptorPool descriptor_pool;
    VkDescriptorSet set;
    VkRenderPass capture_pass; /* no attachments: the capture pipeline discards rasterisation */
    VkFramebuffer capture_framebuffer;
    VkPipeline capture; /* absent without vertexPipelineStoresAndAtomics */
    xyl__vk_target target;

    xyl__vk_buffer pattern_vertices, pattern_indices, patches, instances, cmds, frame, capture_out,
        offsets, readback;
    xyl_tess_pattern_range ranges[2][XYL_TESS_MAX_LEVEL + 1];
    uint32_t max_level;
    const uint32_t *lattice; /* the mapped pattern vertices, for captured coordinates */
    uint8_t *patch_kinds;    /* of the uploaded patches, to check instance records */
    size_t patch_count;
    VkDeviceSize frame_stride; /* two xyl_tess_frame copies (shade, wireframe) per UBO */

    char device_name[VK_MAX_PHYSICAL_DEVICE_NAME_SIZE];
    double gpu_ms;
    bool lost; /* VK_ERROR_DEVICE_LOST: every later call fails */
    xyl__vk_messages messages;
    xyl_allocator alloc;
};

/* ---- vk_setup.c ----------------------------------------------------------------------------- */

/* Maps a failed VkResult to a result code with "<what>: <VkResult name>" in diag. */
xyl_result xyl__vk_fail(xyl_tess_vk *vk, xyl_diag *diag, VkResult r, const char *what);
xyl_result xyl__vk_create_instance(xyl_tess_vk *vk, bool validation, xyl_diag *diag);
xyl_result xyl__vk_pick_device(xyl_tess_vk *vk, const char *name, xyl_diag *diag);
xyl_result xyl__vk_create_device(xyl_tess_vk *vk, xyl_diag *diag);
/* Creates (or grows to at least size bytes) a mapped host buffer; contents are not kept. */
xyl_result xyl__vk_buffer_reserve(xyl_tess_vk *vk, xyl__vk_buffer *b, VkDeviceSize size,
                                  VkBufferUsageFlags usage, xyl_diag *diag);
void xyl__vk_buffer_destroy(xyl_tess_vk *vk, xyl__vk_buffer *b);
xyl_result xyl__vk_image_create(xyl_tess_vk *vk, xyl__vk_image *img, VkFormat format,
                                uint32_t width, uint32_t height, VkSampleCountFlagBits samples,
                                VkImageUsageFlags usage, VkImageAspectFlags aspect,
                                xyl_diag *diag);
void xyl__vk_image_destroy(xyl_tess_vk *vk, xyl__vk_image *img);
/* Submits vk->cmd (recorded) and waits for it. */
xyl_result xyl__vk_submit_wait(xyl_tess_vk *vk, xyl_diag *diag);

/* ---- vk_pipeline.c -------------------------------------------------------------------------- */

/* Shader modules, descriptor set, pipeline layout, capture pass and pipeline. */
xyl_result xyl__vk_create_pipelines(xyl_tess_vk *vk, xyl_diag *diag);
/* Makes vk->target match (width, height, samples), rebuilding it when it does not. */
xyl_result xyl__vk_target_reserve(xyl_tess_vk *vk, uint32_t width, uint32_t height,
                                  VkSampleCountFlagBits samples, xyl_diag *diag);
void xyl__vk_target_destroy(xyl_tess_vk *vk, xyl__vk_target *t);
void xyl__vk_destroy_pipelines(xyl_tess_vk *vk);

#endif /* XYL_VK_INTERNAL_H */

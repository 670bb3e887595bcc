/* Internal to the Vulkan backend: vk_setup.c (allocation callbacks, instance, devices, memory,
 * submission), vk_pipeline.c (shaders, descriptor sets, passes, pipelines, the offscreen
 * target), vk_backend.c (contexts, patterns, patches), vk_draw.c (input checks, uploads and the
 * one recording of the draws, into the caller's command buffer or the offscreen target),
 * vk_capture.c (the tests' readback of evaluated vertices). Not installed. */
#ifndef XYL_VK_INTERNAL_H
#define XYL_VK_INTERNAL_H

#include <vulkan/vulkan.h>

#include "tess_debug.h"
#include "xyl_internal.h"
#include "xylem/xyl_tess_vk.h"

#define XYL__VK_MAX_IMAGE 8192u /* xyl_tess_image_desc: at most 8192 pixels each way */
#define XYL__VK_MAX_FRAMES 16u  /* xyl_tess_vk_device_desc.frames_in_flight */
#define XYL__VK_COLOR_FORMAT VK_FORMAT_R8G8B8A8_UNORM /* the offscreen target's attachments */
#define XYL__VK_DEPTH_FORMAT VK_FORMAT_D32_SFLOAT

/* A buffer in host-visible, coherent memory, mapped for its whole life: the host writes it
 * before the submission that reads it, which makes the writes visible to the device. */
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

/* Where pipelines draw: a subpass of a render pass, or (pass VK_NULL_HANDLE) dynamic rendering
 * into one colour and one depth attachment of these formats. */
typedef struct xyl__vk_pass {
    VkRenderPass pass;
    uint32_t subpass;
    VkFormat color, depth;
    VkSampleCountFlagBits samples;
} xyl__vk_pass;

/* The draw pipelines for one xyl__vk_pass. */
typedef struct xyl__vk_pipes {
    VkPipeline fill[2]; /* [0] back faces culled, [1] nothing culled (the debug back-face view) */
    VkPipeline line[2]; /* wireframe overlay, same culling; absent without fillModeNonSolid */
} xyl__vk_pipes;

/* The offscreen target of one (width, height, samples) and the pipelines drawing into it. */
typedef struct xyl__vk_target {
    uint32_t width, height;
    VkSampleCountFlagBits samples;
    xyl__vk_image color, depth, resolve; /* resolve only when samples > 1 */
    VkRenderPass pass;
    VkFramebuffer framebuffer;
    xyl__vk_pipes pipes;
} xyl__vk_target;

/* One recorded draw's own data (the frame uniforms are its two copies in vk->frames): written
 * when the draw is recorded, read when it executes. */
typedef struct xyl__vk_slot {
    xyl__vk_buffer instances, cmds;
} xyl__vk_slot;

/* What the validation layer's messenger writes to; outlives the instance. */
typedef struct xyl__vk_messages {
    uint32_t count;
    char first[XYL_DIAG_MESSAGE_SIZE];
} xyl__vk_messages;

struct xyl_tess_vk {
    xyl_allocator alloc;
    VkAllocationCallbacks callbacks;
    const VkAllocationCallbacks *vkalloc; /* &callbacks with a caller's allocator, else NULL */

    /* The device: the library's own (instance, messenger and device owned) or the caller's. */
    bool owns_device;
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    PFN_vkDestroyDebugUtilsMessengerEXT destroy_messenger;
    VkPhysicalDevice physical;
    VkPhysicalDeviceProperties props;
    VkPhysicalDeviceFeatures features; /* the ones enabled */
    VkDevice device;
    uint32_t family;
    VkQueue queue; /* VK_NULL_HANDLE: no offscreen calls */

    /* Drawing, shared by xyl_tess_vk_cmd_draw and the offscreen calls. */
    VkShaderModule vert, vert_capture, frag;
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkDescriptorPool descriptor_pool;
    VkDescriptorSet set;         /* draws: patches, frame */
    VkDescriptorSet capture_set; /* capture: patches, frame, capture output, offsets */
    xyl__vk_buffer pattern_vertices, pattern_indices, patches, frames;
    xyl__vk_slot *slots;    /* the caller's frames in flight, then one for the offscreen calls */
    uint32_t slot_count;
    VkDeviceSize frame_stride; /* frames holds two xyl_tess_frame (shade, wireframe) per slot */
    xyl__vk_pipes pipes;       /* for the caller's pass (xyl_tess_vk_create_for_device) */
    xyl_tess_pattern_range ranges[2][XYL_TESS_MAX_LEVEL + 1];
    uint32_t max_level;
    const uint32_t *lattice; /* the mapped pattern vertices, for captured coordinates */
    uint8_t *patch_kinds;    /* of the uploaded patches, to check instance records */
    size_t patch_count;

    /* Offscreen: render_rgba and capture, submitted to queue and waited for. */
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
    VkQueryPool queries; /* 2 timestamps; VK_NULL_HANDLE when the queue has none */
    uint32_t timestamp_bits;
    xyl__vk_target target;
    xyl__vk_buffer readback;
    VkRenderPass capture_pass; /* no attachments: the capture pipeline discards rasterisation */
    VkFramebuffer capture_framebuffer;
    VkPipeline capture; /* made by the first capture */
    xyl__vk_buffer capture_out, offsets;

    char device_name[VK_MAX_PHYSICAL_DEVICE_NAME_SIZE];
    double gpu_ms;
    bool lost; /* VK_ERROR_DEVICE_LOST: every later call fails */
    xyl__vk_messages messages;
};

/* ---- vk_setup.c ----------------------------------------------------------------------------- */

/* Maps a failed VkResult to a result code with "<what>: <VkResult name>" in diag. */
xyl_result xyl__vk_fail(xyl_tess_vk *vk, xyl_diag *diag, VkResult r, const char *what);
/* Routes Vulkan's host allocations through vk->alloc when it is a caller's allocator. */
void xyl__vk_init_callbacks(xyl_tess_vk *vk);
xyl_result xyl__vk_create_instance(xyl_tess_vk *vk, bool validation, xyl_diag *diag);
xyl_result xyl__vk_pick_device(xyl_tess_vk *vk, const char *name, xyl_diag *diag);
xyl_result xyl__vk_create_device(xyl_tess_vk *vk, xyl_diag *diag);
/* The offscreen calls' command pool and buffer, fence and timestamp queries on vk->queue. */
xyl_result xyl__vk_create_commands(xyl_tess_vk *vk, xyl_diag *diag);
/* Creates (or grows to at least size bytes) a mapped host buffer; contents are not kept. */
xyl_result xyl__vk_buffer_reserve(xyl_tess_vk *vk, xyl__vk_buffer *b, VkDeviceSize size,
                                  VkBufferUsageFlags usage, xyl_diag *diag);
void xyl__vk_buffer_destroy(xyl_tess_vk *vk, xyl__vk_buffer *b);
xyl_result xyl__vk_image_create(xyl_tess_vk *vk, xyl__vk_image *img, VkFormat format,
                                uint32_t width, uint32_t height, VkSampleCountFlagBits samples,
                                VkImageUsageFlags usage, VkImageAspectFlags aspect,
                                xyl_diag *diag);
void xyl__vk_image_destroy(xyl_tess_vk *vk, xyl__vk_image *img);
/* Resets and begins vk->cmd for one submission. */
xyl_result xyl__vk_begin(xyl_tess_vk *vk, xyl_diag *diag);
/* Ends vk->cmd, submits it and waits for it. */
xyl_result xyl__vk_submit_wait(xyl_tess_vk *vk, xyl_diag *diag);

/* ---- vk_pipeline.c -------------------------------------------------------------------------- */

/* Shader modules, the descriptor set layout, pipeline layout and both descriptor sets. */
xyl_result xyl__vk_create_layouts(xyl_tess_vk *vk, xyl_diag *diag);
void xyl__vk_destroy_layouts(xyl_tess_vk *vk);
xyl_result xyl__vk_create_pipes(xyl_tess_vk *vk, const xyl__vk_pass *where, xyl__vk_pipes *out,
                                xyl_diag *diag);
void xyl__vk_destroy_pipes(xyl_tess_vk *vk, xyl__vk_pipes *p);
/* The capture pass, framebuffer and pipeline, made once. */
xyl_result xyl__vk_capture_reserve(xyl_tess_vk *vk, xyl_diag *diag);
void xyl__vk_destroy_capture(xyl_tess_vk *vk);
/* Makes vk->target match (width, height, samples), rebuilding it when it does not. */
xyl_result xyl__vk_target_reserve(xyl_tess_vk *vk, uint32_t width, uint32_t height,
                                  VkSampleCountFlagBits samples, xyl_diag *diag);
void xyl__vk_target_destroy(xyl_tess_vk *vk, xyl__vk_target *t);

/* ---- vk_backend.c --------------------------------------------------------------------------- */

xyl_result xyl__vk_check_usable(const xyl_tess_vk *vk, xyl_diag *diag);
const xyl_tess_pattern_range *xyl__vk_range(const xyl_tess_vk *vk, uint32_t kind, uint32_t level);
/* Writes the first count bindings of set: patches, frame uniforms, capture output, offsets. */
void xyl__vk_write_set(const xyl_tess_vk *vk, VkDescriptorSet set, uint32_t count);
/* samples (0: 1) as a sample count the device offers for colour + depth attachments. */
xyl_result xyl__vk_check_samples(const xyl_tess_vk *vk, uint32_t samples,
                                 VkSampleCountFlagBits *out, xyl_diag *diag);

/* ---- vk_draw.c ------------------------------------------------------------------------------ */

/* Checks batches against the uploaded patches and the patterns, then writes the instance
 * records, commands and the two frame copies into slot's buffers. */
xyl_result xyl__vk_stage(xyl_tess_vk *vk, uint32_t slot, const xyl_tess_batches *batches,
                         const xyl_tess_frame frames[2], xyl_diag *diag);
/* Binds pipeline with set, slot's frame copy and buffers, then draws every command. */
void xyl__vk_record(const xyl_tess_vk *vk, VkCommandBuffer cb, VkPipeline pipeline,
                    VkDescriptorSet set, uint32_t slot, uint32_t copy, size_t cmd_count);
void xyl__vk_set_viewport(VkCommandBuffer cb, uint32_t width, uint32_t height);
/* Makes what the device wrote at stage (with access) visible to the host. */
void xyl__vk_host_barrier(VkCommandBuffer cb, VkPipelineStageFlags stage, VkAccessFlags access);

#endif /* XYL_VK_INTERNAL_H */

/* xyl_tess_vk.h: the Vulkan 1.2 backend of tessellate/ (instanced path).
 *
 * How to use
 *   In your renderer, on your device, in your render pass and command buffers:
 *     1. Create the device with drawIndirectFirstInstance (each draw command starts at its
 *        batch's instance records); fillModeNonSolid enables the wireframe overlay and
 *        multiDrawIndirect one call for all commands.
 *     2. xyl_tess_vk_create_for_device(&desc, patterns, &vk): desc names the physical device
 *        and device, the features you enabled, the subpass the stems are drawn in (or, for
 *        dynamic rendering, the attachment formats), the sample count and your frames in flight.
 *     3. xyl_tess_vk_set_patches(vk, patches) while nothing recorded with vk is pending.
 *     4. Each frame, once frame i's fence has signalled (as you wait anyway before reusing its
 *        command buffer): xyl_tess_select(), then, inside the render pass with viewport and
 *        scissor set, xyl_tess_vk_cmd_draw(vk, cmd, i, batches, &frame). Submit as usual.
 *   Standalone (tools, tests, machines without a display): xyl_tess_vk_create(&desc, patterns,
 *     &vk) makes its own instance and device (lavapipe where there is no GPU), with the Khronos
 *     validation layer when desc.validation is set; xyl_tess_vk_render_rgba() records the same
 *     draws into an offscreen image, submits, waits and reads it back.
 *   The draws are vkCmdDrawIndexedIndirect, one command per (kind, level), instance records as a
 *   per-instance vertex buffer; the shaders are the GL backend's GLSL, compiled to SPIR-V at
 *   build time. Frames use Vulkan's clip convention (xyl_tess_camera_matrix with
 *   XYL_TESS_CLIP_VULKAN): depth 0 near, 1 far, tested with LESS against a depth buffer cleared
 *   to 1; counter-clockwise outward faces are front faces.
 *
 * Synchronisation (xyl_tess_vk_cmd_draw)
 *   - The call checks the batches and writes the draw's instance records, indirect commands and
 *     frame uniforms into host-visible, coherent buffers of slot frame_index at once, while you
 *     record; the GPU reads them when the command buffer executes. The submit makes those host
 *     writes visible, so no barrier is needed before or after the draws.
 *   - Hence the rule: before a call with frame_index i, the command buffer recorded by the
 *     previous call with i must have finished executing (or never be submitted). A loop of
 *     frames_in_flight frames that waits for frame i's fence before recording frame i keeps it.
 *     Several draws in one frame (two views, two trees on one context) need indices of their
 *     own: count them into frames_in_flight.
 *   - xyl_tess_vk_set_patches and xyl_tess_vk_destroy replace or free what every recorded draw
 *     reads: call them when no command buffer recorded with vk is pending (after
 *     vkDeviceWaitIdle, or every frame's fence). The library never waits on your device.
 *   - cmd_draw only records: it binds its pipeline, descriptor set 0, vertex bindings 0 and 1
 *     and the index buffer (rebind yours after it) and reads the viewport and scissor you set.
 *   - With desc.queue, xyl_tess_vk_render_rgba works on your device too: it submits to that
 *     queue and waits for its own fence, through a slot of its own, so frames in flight are not
 *     disturbed; Vulkan requires that no other thread uses the queue meanwhile.
 * Threads: a context is used by one thread at a time. Allocation: every host allocation of the
 * backend, Vulkan's own included (as VkAllocationCallbacks), goes through desc.alloc when one is
 * given.
 *
 * <vulkan/vulkan.h> is included for the handle types: this header is only of use to code that
 * talks Vulkan, which has the header anyway, and typed handles catch a swapped argument that
 * opaque ones would not. With VK_NO_PROTOTYPES (volk and the like) nothing here needs the
 * prototypes; the library itself calls Vulkan through the loader, which serves any device
 * created through it.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_TESS_VK_H
#define XYL_TESS_VK_H

#include <vulkan/vulkan.h>

#include "xylem/xyl_tessellate.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct xyl_tess_vk xyl_tess_vk;

/* ---- on the library's own device -------------------------------------------------------- */

typedef struct xyl_tess_vk_desc {
    bool validation;         /* enable VK_LAYER_KHRONOS_validation + debug messenger */
    const char *device_name; /* substring of the device to pick; default (NULL): the first */
    xyl_allocator alloc;     /* host allocations, Vulkan's included; default: malloc / free */
} xyl_tess_vk_desc;

/* Errors: XYL_ERR_INVALID_ARGUMENT (patterns or out NULL, patterns inconsistent),
 * XYL_ERR_UNSUPPORTED (no Vulkan 1.2 device, a missing feature or the validation layer asked
 * for but absent: the message says which), XYL_ERR_OUT_OF_MEMORY. On failure *out is
 * untouched. */
XYL_API xyl_result xyl_tess_vk_create(const xyl_tess_vk_desc *desc,
                                      const xyl_tess_patterns *patterns, xyl_tess_vk **out,
                                      xyl_diag *diag);

/* ---- on the caller's device ------------------------------------------------------------- */

typedef struct xyl_tess_vk_device_desc {
    VkPhysicalDevice physical_device; /* required */
    VkDevice device;                  /* required; made with drawIndirectFirstInstance */
    /* The features the device was made with (what the draws may use); default (NULL):
     * drawIndirectFirstInstance only. */
    const VkPhysicalDeviceFeatures *enabled_features;
    /* Where the draws are recorded: this subpass of render_pass (or a compatible pass), with
     * one colour attachment and a depth attachment... */
    VkRenderPass render_pass;
    uint32_t subpass;
    /* ...or, with render_pass VK_NULL_HANDLE, dynamic rendering (Vulkan 1.3 or
     * VK_KHR_dynamic_rendering, enabled) into one colour attachment of color_format and a
     * depth attachment of depth_format (and no stencil attachment). */
    VkFormat color_format;
    VkFormat depth_format;
    VkSampleCountFlagBits samples; /* of those attachments; default (0): 1 */
    uint32_t frames_in_flight;     /* frame indices of xyl_tess_vk_cmd_draw; default (0): 2;
                                      at most 16 */
    VkQueue queue;          /* optional: a queue of queue_family for xyl_tess_vk_render_rgba */
    uint32_t queue_family;  /* read only with a queue */
    xyl_allocator alloc;    /* host allocations, Vulkan's included; default: malloc / free */
} xyl_tess_vk_device_desc;

/* A context that records its draws into the caller's command buffers. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL, no device, neither a render pass nor a colour format,
 * frames_in_flight above 16, a bad sample count or queue family, patterns inconsistent),
 * XYL_ERR_UNSUPPORTED (drawIndirectFirstInstance not enabled, a sample count the device does not
 * offer, a pipeline the driver refuses), XYL_ERR_OUT_OF_MEMORY. On failure *out is untouched. */
XYL_API xyl_result xyl_tess_vk_create_for_device(const xyl_tess_vk_device_desc *desc,
                                                 const xyl_tess_patterns *patterns,
                                                 xyl_tess_vk **out, xyl_diag *diag);

/* Records the batches' draws into cmd, which is recording inside the desc's subpass (or a
 * dynamic rendering instance with its formats), with viewport and scissor set: the surface
 * (depth-tested and written, back faces culled) and, with XYL_TESS_FLAG_WIREFRAME in
 * frame->flags, its triangle edges in frame->line_color on top. The per-draw data goes into
 * frame_index's buffers now (see "Synchronisation" above). Errors: XYL_ERR_INVALID_ARGUMENT
 * (NULL, a context from xyl_tess_vk_create, frame_index >= frames_in_flight, an unknown variant,
 * batches from another patch set or with a level the patterns lack), XYL_ERR_NON_FINITE
 * (view_proj), XYL_ERR_UNSUPPORTED (wireframe without fillModeNonSolid), XYL_ERR_OUT_OF_MEMORY;
 * on error nothing is recorded. */
XYL_API xyl_result xyl_tess_vk_cmd_draw(xyl_tess_vk *vk, VkCommandBuffer cmd,
                                        uint32_t frame_index, const xyl_tess_batches *batches,
                                        const xyl_tess_frame *frame, xyl_diag *diag);

/* ---- both ------------------------------------------------------------------------------- */

/* Waits for nothing on a caller's device: see "Synchronisation". NULL is a no-op. */
XYL_API void xyl_tess_vk_destroy(xyl_tess_vk *vk);
XYL_API const char *xyl_tess_vk_device_name(const xyl_tess_vk *vk);

/* Uploads the patch records (replacing earlier ones). Errors: XYL_ERR_INVALID_ARGUMENT,
 * XYL_ERR_LIMIT_EXCEEDED (more than the device's storage buffer range),
 * XYL_ERR_OUT_OF_MEMORY (then no patches are uploaded). */
XYL_API xyl_result xyl_tess_vk_set_patches(xyl_tess_vk *vk, const xyl_tess_patches *patches,
                                           xyl_diag *diag);

/* As xyl_tess_gl_render_rgba (frame->view_proj in Vulkan's clip convention): records the draws
 * into the library's own colour (R8G8B8A8_UNORM) + depth (D32_SFLOAT) target, submits, waits,
 * and writes width * height RGBA8 pixels, top row first. Errors also XYL_ERR_UNSUPPORTED for a
 * context on the caller's device made without a queue. */
XYL_API xyl_result xyl_tess_vk_render_rgba(xyl_tess_vk *vk, const xyl_tess_batches *batches,
                                           const xyl_tess_frame *frame,
                                           const xyl_tess_image_desc *image, uint8_t *rgba,
                                           xyl_diag *diag);

/* Milliseconds of GPU time of the last render_rgba (timestamp queries), negative if unknown. */
XYL_API double xyl_tess_vk_last_gpu_ms(const xyl_tess_vk *vk);

/* Messages of severity warning or error the validation layer reported since creation (a
 * context on the caller's device has no messenger of its own: 0). */
XYL_API uint32_t xyl_tess_vk_validation_messages(const xyl_tess_vk *vk);
/* The first such message ("" if none). */
XYL_API const char *xyl_tess_vk_first_message(const xyl_tess_vk *vk);

#ifdef __cplusplus
}
#endif

#endif /* XYL_TESS_VK_H */

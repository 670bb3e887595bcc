/* xyl_foliage_vk.h: leaves drawn with Vulkan 1.2 on the application's device, into its render
 * pass and command buffers: the whole species' leaf array uploaded once, any LOD recorded as
 * its two ranges (docs/foliage.md, "Drawing on the GPU"). The GL renderer's twin
 * (xylem/xyl_foliage_gl.h): same shaders, compiled to SPIR-V at build time, same input rules.
 *
 * How to use
 *     xyl_foliage_vk_desc desc = {0};
 *     desc.physical_device = phys;  desc.device = dev;     // yours
 *     desc.queue = queue;  desc.queue_family = family;     // uploads are submitted here
 *     desc.render_pass = pass;  desc.subpass = 0;          // or colour + depth formats
 *     xyl_foliage_vk *leaves = NULL;
 *     if (xyl_foliage_vk_create(&desc, &leaves, &diag)) puts(diag.message);
 *     xyl_foliage_vk_set_foliage(leaves, foliage, &diag);      // once per species
 *     xyl_foliage_vk_set_texture(leaves, rgba, 128, 256, &diag); // optional, RGBA8
 *
 *     // each frame, inside the render pass, viewport and scissor set
 *     xyl_foliage_vk_frame fr = {0};   // zero = leaf green, cutoff 0.5, light from +Y
 *     xyl_tess_camera_matrix(&cam, XYL_TESS_CLIP_VULKAN, fr.view_proj, &diag);
 *     xyl_foliage_pick(foliage, &view, lod, sector_count, &diag);
 *     xyl_foliage_vk_cmd_draw(leaves, cmd, &fr, lod, sector_count, &diag);
 *     // or per leaf, chosen on the GPU: the cut before the render pass, its draw inside
 *     xyl_foliage_vk_cmd_cut(leaves, cmd, &view, &diag);       // outside a render pass
 *     ...vkCmdBeginRenderPass...
 *     xyl_foliage_vk_cmd_draw_cut(leaves, cmd, &fr, &diag);    // one indirect draw
 *     ...
 *     xyl_foliage_vk_destroy(leaves);  // once nothing recorded with it is pending
 *
 * A draw is, per sector, two vkCmdDraw of a 4-vertex triangle strip, instanced over the LOD's
 * two ranges of the one storage buffer of 32-byte records (firstInstance = the range's first
 * record); the vertex shader expands each record to its quad. The frame's values travel as
 * push constants, so a recorded draw owns everything it reads but the leaf buffer and the
 * texture: no per-frame buffers, no frame slots. The per-leaf cut is the exception: its list
 * of records and its indirect command live in one buffer pair per renderer, so one cut is in
 * flight at a time (record the next cut once the previous frame's draw has run).
 *
 * Clip space and winding: frame.view_proj is in Vulkan's convention (xyl_tess_camera_matrix
 * with XYL_TESS_CLIP_VULKAN: y flipped for the y-down framebuffer, depth 0 near, 1 far), as for
 * xyl_tess_vk. The flip and Vulkan's y-down winding cancel, so the pipeline's front faces are
 * counter-clockwise, and gl_FrontFacing (which side of a blade is lit) agrees with GL.
 *
 * Synchronisation: set_foliage, set_texture and destroy replace or free what recorded draws
 * read: call them while no command buffer recorded with the renderer is pending. set_foliage
 * and set_texture submit their copies to desc.queue and wait for their own fence (no other
 * thread may use the queue meanwhile). cmd_draw only records: it binds its pipeline, descriptor
 * set 0 and push constants (rebind yours after it) and uses the viewport and scissor you set.
 *
 * Every call checks its input before its first Vulkan call. Threads: one renderer is used by
 * one thread at a time. Allocation: every host allocation of the renderer, the driver's for its
 * objects included (as VkAllocationCallbacks), goes through desc.alloc when one is given.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_FOLIAGE_VK_H
#define XYL_FOLIAGE_VK_H

#include <vulkan/vulkan.h>

#include "xylem/xyl_foliage.h"

#ifdef __cplusplus
extern "C" {
#endif

#define XYL_FOLIAGE_VK_MAX_TEXTURE_SIDE 8192 /* and the device's maxImageDimension2D */

typedef struct xyl_foliage_vk xyl_foliage_vk;

typedef struct xyl_foliage_vk_desc {
    VkPhysicalDevice physical_device; /* required */
    VkDevice device;                  /* required; Vulkan 1.2 */
    VkQueue queue;                    /* required: a graphics queue of queue_family, for the
                                         uploads of set_foliage and set_texture */
    uint32_t queue_family;
    /* Where the draws are recorded: this subpass of render_pass (or a compatible pass), with
     * one colour attachment and a depth attachment... */
    VkRenderPass render_pass;
    uint32_t subpass;
    /* ...or, with render_pass VK_NULL_HANDLE, dynamic rendering (Vulkan 1.3 or
     * VK_KHR_dynamic_rendering, enabled) into one colour attachment of color_format and a
     * depth attachment of depth_format. */
    VkFormat color_format;
    VkFormat depth_format;
    VkSampleCountFlagBits samples; /* of those attachments; default (0): 1 */
    /* The features the device was made with; default (NULL): none. The tests' capture needs
     * vertexPipelineStoresAndAtomics; drawing needs none. */
    const VkPhysicalDeviceFeatures *enabled_features;
    xyl_allocator alloc; /* host allocations, Vulkan's included; default: malloc / free */
} xyl_foliage_vk_desc;

/* The values of a draw: those of xyl_foliage_gl_frame, with view_proj in Vulkan's convention. */
typedef struct xyl_foliage_vk_frame {
    float view_proj[16];  /* column-major world-to-clip matrix, Vulkan clip convention
                             (XYL_TESS_CLIP_VULKAN); all 0 is refused */
    float light_dir[3];   /* towards the light, normalised by the call; default (all 0): +Y */
    float color[4];       /* multiplies the texture's colour; default (all 0): 0.42, 0.62,
                             0.25, 1 */
    float alpha_cutoff;   /* texels with alpha below it are discarded, (0, 1]; default (0): 0.5 */
    float translucency;   /* light from behind shining through a blade, [0, 1]; default (0):
                             0.5; negative: none */
    float dither[2];      /* keep range [lo, hi) of the screen-door dither that cross-fades two
                             levels of detail (docs/foliage.md, "Transitions"; xyl_fade_update
                             gives it); default (0, 0): every fragment. Otherwise
                             0 <= lo < hi <= 1 */
} xyl_foliage_vk_frame;

/* Shader modules, descriptor set, pipeline, sampler and a 1 x 1 opaque white texture. desc is
 * required. Errors: XYL_ERR_INVALID_ARGUMENT (NULL desc or out, no physical device, device or
 * queue, neither a render pass nor a colour and depth format, a sample count that is not a
 * power of two up to 64), XYL_ERR_UNSUPPORTED (a device below Vulkan 1.2, a queue family
 * without graphics, a sample count the device does not offer, a pipeline the driver refuses),
 * XYL_ERR_OUT_OF_MEMORY. On failure *out is untouched and nothing is left on the device. */
XYL_API xyl_result xyl_foliage_vk_create(const xyl_foliage_vk_desc *desc, xyl_foliage_vk **out,
                                         xyl_diag *diag);
/* NULL is fine. Frees the renderer's objects on the device; waits for nothing. */
XYL_API void xyl_foliage_vk_destroy(xyl_foliage_vk *vk);

/* Packs foliage->leaves (xyl_foliage_pack_gpu) into the storage buffer and keeps a copy of the
 * sectors' LOD tables, replacing what was uploaded before. Errors: XYL_ERR_INVALID_ARGUMENT
 * (NULL vk or foliage, a foliage without leaves, a malformed table), XYL_ERR_LIMIT_EXCEEDED
 * (more leaves than the device's maxStorageBufferRange holds), those of xyl_foliage_pack_gpu,
 * XYL_ERR_OUT_OF_MEMORY (host or device). On failure the previous upload stays. */
XYL_API xyl_result xyl_foliage_vk_set_foliage(xyl_foliage_vk *vk, const xyl_foliage *foliage,
                                              xyl_diag *diag);

/* The leaf texture, as xyl_foliage_gl_set_texture: width * height RGBA8 texels (UNORM), rows
 * top to bottom, the top row the leaves' tip end (v = 1), alpha the blade's shape. Mipmapped
 * (blits), linear filtering, clamped at the edges. Errors: XYL_ERR_INVALID_ARGUMENT (NULL vk
 * or rgba, a side of 0 or over XYL_FOLIAGE_VK_MAX_TEXTURE_SIDE or the device's limit),
 * XYL_ERR_OUT_OF_MEMORY. On failure the previous texture stays. */
XYL_API xyl_result xyl_foliage_vk_set_texture(xyl_foliage_vk *vk, const uint8_t *rgba,
                                              uint32_t width, uint32_t height, xyl_diag *diag);

/* Records the LOD lods[s] of each sector s (lod_count = the uploaded foliage's sector count)
 * into cmd, which is recording inside the desc's subpass (or a dynamic rendering instance of
 * its formats) with viewport and scissor set: depth test LESS and depth writes, nothing
 * culled (the leaves are double-sided), no blending. Errors: XYL_ERR_INVALID_ARGUMENT (NULL vk,
 * cmd, frame or lods, no foliage uploaded, lod_count != sector count, a LOD beyond its sector's
 * merged_count: diag.index = the sector, an all-zero matrix, an alpha_cutoff outside [0, 1] or a
 * translucency over 1, a dither range other than (0, 0) outside 0 <= lo < hi <= 1),
 * XYL_ERR_NON_FINITE (a matrix, light, colour or dither entry); on error nothing
 * is recorded. */
XYL_API xyl_result xyl_foliage_vk_cmd_draw(xyl_foliage_vk *vk, VkCommandBuffer cmd,
                                           const xyl_foliage_vk_frame *frame,
                                           const uint32_t *lods, size_t lod_count,
                                           xyl_diag *diag);

/* Per-leaf LOD (docs/foliage.md, "Per-leaf LOD"), the GL renderer's
 * xyl_foliage_gl_draw_adaptive in two steps, since a compute dispatch cannot be recorded
 * inside a render pass. cmd_cut records, outside any render pass, the compute pass over the
 * uploaded collapse forest that keeps per cluster the coarsest leaf within the view's budget
 * (xyl_foliage_cut's test, in float), writes the chosen records' indices to the renderer's list
 * and their count into its indirect command, with the barriers that make both visible to
 * indirect draws, vertex shaders and host reads. view gives the eye in the foliage's
 * coordinates, fovy, viewport height and pixel budget as xyl_foliage_pick takes them (zero
 * fields: its defaults). It binds its compute pipeline, descriptor set 0 and push constants.
 * Errors: XYL_ERR_INVALID_ARGUMENT (NULL vk, cmd or view, no foliage uploaded, the view's bad
 * values as xyl_foliage_pick refuses them), XYL_ERR_NON_FINITE; on error nothing is recorded.
 * The list and command are the renderer's own: a cut overwrites the previous one, so record it
 * only when no submitted work still reads that one. */
XYL_API xyl_result xyl_foliage_vk_cmd_cut(xyl_foliage_vk *vk, VkCommandBuffer cmd,
                                          const xyl_foliage_view *view, xyl_diag *diag);

/* Records one vkCmdDrawIndirect of the last recorded cut's leaves, inside the render pass, with
 * the state and frame rules of xyl_foliage_vk_cmd_draw. Errors: XYL_ERR_INVALID_ARGUMENT (NULL
 * vk, cmd or frame, no cut recorded since the foliage was uploaded, the frame's bad values),
 * XYL_ERR_NON_FINITE; on error nothing is recorded. */
XYL_API xyl_result xyl_foliage_vk_cmd_draw_cut(xyl_foliage_vk *vk, VkCommandBuffer cmd,
                                               const xyl_foliage_vk_frame *frame,
                                               xyl_diag *diag);

/* The record indices of the last cut, in the GPU's order (invocations append as they finish),
 * read from the renderer's host-visible list: call it after the command buffer that ran the cut
 * has completed. For statistics and tests. Count-then-fill: out NULL sets *count only; with
 * capacity < *count, XYL_ERR_INVALID_ARGUMENT. Errors: XYL_ERR_INVALID_ARGUMENT (NULL vk or
 * count, no cut recorded since the last upload), XYL_ERR_UNSUPPORTED (a count above the leaf
 * count: the cut has not run), those of vkMapMemory. */
XYL_API xyl_result xyl_foliage_vk_last_cut(xyl_foliage_vk *vk, uint32_t *out, size_t capacity,
                                           size_t *count, xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif /* XYL_FOLIAGE_VK_H */

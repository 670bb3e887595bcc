/* xyl_billboard_vk.h: a whole tree (stems and leaves) as a billboard baked and drawn with
 * Vulkan 1.2 on the application's device: the GL billboard's twin (xylem/xyl_billboard_gl.h,
 * docs/foliage.md "Billboards"), with the same four kinds, bake cameras, maps, shading, dither
 * and alpha-to-coverage, the shaders compiled to SPIR-V at build time.
 *
 * How to use
 *     // the tree's draws recorded into cmd, inside the bake's render pass (below), viewport
 *     // and scissor set, with a world-to-clip matrix in Vulkan's convention and a light
 *     static xyl_result draw_tree(void *user, VkCommandBuffer cmd, VkRenderPass pass,
 *                                 const float view_proj[16], const float light_dir[3],
 *                                 xyl_diag *diag);
 *     xyl_billboard_vk_desc bd = {0};
 *     bd.physical_device = phys;  bd.device = dev;         // yours
 *     bd.queue = queue;  bd.queue_family = family;         // the bake is submitted here
 *     bd.render_pass = pass;  bd.subpass = 0;              // where the draws are recorded
 *     bd.kind = XYL_BILLBOARD_OCTAHEDRAL;  bd.grid = 8;    // as xyl_billboard_gl_desc
 *     bd.resolution = 512;
 *     memcpy(bd.lo, lo, sizeof bd.lo);  memcpy(bd.hi, hi, sizeof bd.hi);
 *     memcpy(bd.light_dir, light, sizeof bd.light_dir);    // the scene's light
 *     xyl_billboard_vk *bb = NULL;
 *     if (xyl_billboard_vk_bake(&bd, draw_tree, tree, &bb, &diag)) puts(diag.message);
 *     // each frame, inside the render pass, viewport and scissor set
 *     xyl_billboard_vk_frame fr = {0};       // view_proj (XYL_TESS_CLIP_VULKAN), eye, light
 *     xyl_billboard_vk_cmd_draw(bb, cmd, &fr, &diag);
 *     ...
 *     xyl_billboard_vk_destroy(bb);          // once nothing recorded with it is pending
 *
 * The bake: for each view the library begins its own render pass over a resolution x
 * resolution target, one subpass with one colour attachment of XYL_BILLBOARD_VK_BAKE_COLOR
 * (cleared to 0, 0, 0, 0) and a depth attachment of XYL_BILLBOARD_VK_BAKE_DEPTH (cleared to
 * 1), one sample, sets viewport and scissor, and calls draw with the view's camera: the matrix
 * of the GL billboard's documented bake camera in Vulkan's clip convention (y flipped, depth
 * 0..1), and the bake's light. Pipelines made for any render pass compatible with that one
 * (the same two formats, one sample: e.g. the application's own single-sample R8G8B8A8_UNORM
 * and D32_SFLOAT pass, or pass itself) draw in it; the tree is expected to test and write
 * depth with LESS. The colour and depth are read back and turned into the GL bake's maps (the
 * same CPU code: coverage from depth, colour premultiplied by it, normals and heights
 * reconstructed from depth), stored in sampled RGBA8 images with mipmaps: a 2D array of the
 * views, or for the octahedral kind one atlas of grid x grid cells (row 0 at the bottom, as
 * GL's). The bake submits to desc.queue and waits for its own fence after each view (no other
 * thread may use the queue meanwhile).
 *
 * The draw records one 4-vertex strip per quad (one quad, or the cross's planes) with the GL
 * billboard's shaders: depth test LESS and writes, nothing culled, no blending, the alpha test
 * at the frame's cutoff; with desc.samples > 1 the filtered coverage goes to
 * alpha-to-coverage instead, and alpha-to-one makes the covered samples opaque where
 * desc.enabled_features has alphaToOne; without it the draw does not write alpha (the
 * samples keep the alpha they had: an opaque clear stays opaque, as GL's alpha-to-one).
 * The frame's values travel as push constants, so a recorded draw owns all it reads but the
 * billboard's images and constants. It binds its pipeline, descriptor set 0 and push
 * constants (rebind yours after it). Clip space and winding as xyl_foliage_vk: the y flip and
 * Vulkan's y-down winding cancel, so gl_FrontFacing agrees with GL. The screen-door dither
 * reads gl_FragCoord, whose origin is the top left corner in Vulkan and the bottom left in GL:
 * the same keep range keeps the same share of pixels, in another pattern.
 *
 * Every call checks its input before its first Vulkan call. Threads: one billboard is used by
 * one thread at a time. Allocation: every host allocation, the driver's for its objects
 * included (as VkAllocationCallbacks), goes through desc.alloc when one is given.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_BILLBOARD_VK_H
#define XYL_BILLBOARD_VK_H

#include <vulkan/vulkan.h>

#include "xylem/xyl_foliage.h"

#ifdef __cplusplus
extern "C" {
#endif

#define XYL_BILLBOARD_VK_BAKE_COLOR VK_FORMAT_R8G8B8A8_UNORM
#define XYL_BILLBOARD_VK_BAKE_DEPTH VK_FORMAT_D32_SFLOAT

/* Records the whole tree's draws into cmd, inside the bake's render pass `pass` (subpass 0,
 * viewport and scissor set), with this column-major world-to-clip matrix (Vulkan's clip
 * convention) and light direction (towards the light, unit length). Anything but XYL_OK
 * stops the bake and is returned as is. */
typedef xyl_result (*xyl_billboard_vk_draw_fn)(void *user, VkCommandBuffer cmd,
                                               VkRenderPass pass, const float view_proj[16],
                                               const float light_dir[3], xyl_diag *diag);

typedef struct xyl_billboard_vk_desc {
    VkPhysicalDevice physical_device; /* required */
    VkDevice device;                  /* required; Vulkan 1.2 */
    VkQueue queue;                    /* required: a graphics queue of queue_family */
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
    /* The features the device was made with; default (NULL): none. alphaToOne is used when
     * enabled. */
    const VkPhysicalDeviceFeatures *enabled_features;
    /* The billboard, as xyl_billboard_gl_desc: */
    xyl_billboard_kind kind;
    uint32_t planes;     /* cross: 2..XYL_BILLBOARD_MAX_PLANES; spherical, cylindrical: 0 or 1 */
    uint32_t resolution; /* XYL_BILLBOARD_MIN_RESOLUTION..XYL_BILLBOARD_MAX_RESOLUTION (and the
                            device's maxImageDimension2D) */
    uint32_t grid;       /* octahedral: XYL_BILLBOARD_MIN_GRID..XYL_BILLBOARD_MAX_GRID, grid *
                            resolution at most XYL_BILLBOARD_MAX_ATLAS (and the device's
                            limit); 0: XYL_BILLBOARD_DEFAULT_GRID. Other kinds: 0 */
    float lo[3], hi[3];  /* the tree's box, lo < hi on every axis, finite */
    float light_dir[3];  /* the bake's light, normalised by the call; default (all 0): each
                            view's own camera direction. Give the scene's light */
    xyl_allocator alloc; /* host allocations, Vulkan's included; default: malloc / free */
} xyl_billboard_vk_desc;

typedef struct xyl_billboard_vk xyl_billboard_vk;

/* The values of a draw: those of xyl_billboard_gl_frame, with view_proj in Vulkan's
 * convention. */
typedef struct xyl_billboard_vk_frame {
    float view_proj[16]; /* column-major world-to-clip matrix, Vulkan clip convention
                            (XYL_TESS_CLIP_VULKAN); all 0 refused */
    float eye[3];        /* the camera's position */
    float light_dir[3];  /* towards the light, normalised by the call; default (all 0): +Y */
    float alpha_cutoff;  /* [0, 1]; default (0): 0.5 (ignored with alpha-to-coverage) */
    float dither[2];     /* keep range [lo, hi) of the screen-door dither (xyl_fade_update);
                            default (0, 0): every fragment; otherwise 0 <= lo < hi <= 1 */
} xyl_billboard_vk_frame;

/* Bakes the billboard (one call of draw per view) and makes its draw pipeline. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL desc, draw or out, no physical device, device or queue,
 * neither a render pass nor a colour and depth format, a sample count that is not a power of
 * two up to 64, and the billboard's bad values as xyl_billboard_gl_bake refuses them, a
 * resolution or atlas over the device's maxImageDimension2D), XYL_ERR_NON_FINITE (a box or
 * light coordinate), XYL_ERR_UNSUPPORTED (a device below Vulkan 1.2, a queue family without
 * graphics, a sample count the device does not offer, bake formats it cannot render or
 * sample, a pipeline the driver refuses), XYL_ERR_OUT_OF_MEMORY (host or device), whatever
 * draw returns. On failure *out is untouched and nothing is left on the device. */
XYL_API xyl_result xyl_billboard_vk_bake(const xyl_billboard_vk_desc *desc,
                                         xyl_billboard_vk_draw_fn draw, void *user,
                                         xyl_billboard_vk **out, xyl_diag *diag);
/* NULL is fine. Frees the billboard's objects on the device; waits for nothing. */
XYL_API void xyl_billboard_vk_destroy(xyl_billboard_vk *bb);

/* How many views were baked: 1, the cross's planes, or grid^2. 0 for NULL. */
XYL_API uint32_t xyl_billboard_vk_view_count(const xyl_billboard_vk *bb);

/* A baked view read back from its image, as xyl_billboard_gl_read_view: colour (normal false;
 * premultiplied by alpha) or normal map (normal true; height in alpha), resolution^2 RGBA8
 * texels, top row first. Submits to desc.queue and waits. Errors: XYL_ERR_INVALID_ARGUMENT
 * (NULL bb or rgba, view >= xyl_billboard_vk_view_count), XYL_ERR_OUT_OF_MEMORY, those of
 * the submission. */
XYL_API xyl_result xyl_billboard_vk_read_view(const xyl_billboard_vk *bb, uint32_t view,
                                              bool normal, uint8_t *rgba, xyl_diag *diag);

/* Records the billboard's draw into cmd, recording inside the desc's subpass (or a dynamic
 * rendering instance of its formats) with viewport and scissor set. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL bb, cmd or frame, an all-zero matrix, a cutoff outside
 * [0, 1], a dither range other than (0, 0) outside 0 <= lo < hi <= 1), XYL_ERR_NON_FINITE (a
 * matrix, eye, light or dither entry); on error nothing is recorded. */
XYL_API xyl_result xyl_billboard_vk_cmd_draw(xyl_billboard_vk *bb, VkCommandBuffer cmd,
                                             const xyl_billboard_vk_frame *frame,
                                             xyl_diag *diag);

/* A forest's billboards: the caller's storage buffer of 16-byte forest instances
 * (xyl_forest_instance, the layout in xyl_foliage_shared.h; xyl_forest_instance_pack writes
 * it), bound once here (call it while no command buffer recorded with bb is pending), then
 * drawn in runs by cmd_draw_instances: instances [first, first + count) of the buffer, each
 * the billboard placed at its position, turned and scaled as forest_billboard.vert places GL's
 * (cross planes turn with the instance, spherical and cylindrical quads face the eye); the
 * LOD bits are not read. Spherical, cylindrical and cross kinds only. Errors
 * (set_instances): XYL_ERR_INVALID_ARGUMENT (NULL bb, a null buffer, a size below 16 bytes or
 * not a multiple of 16), XYL_ERR_LIMIT_EXCEEDED (a size over the device's
 * maxStorageBufferRange), XYL_ERR_UNSUPPORTED (the octahedral kind). */
XYL_API xyl_result xyl_billboard_vk_set_instances(xyl_billboard_vk *bb, VkBuffer instances,
                                                  VkDeviceSize size, xyl_diag *diag);
/* Errors: those of cmd_draw, XYL_ERR_INVALID_ARGUMENT (no instances bound, first + count over
 * the bound buffer's instances, a count of 0), XYL_ERR_LIMIT_EXCEEDED (count times the cross's
 * planes over UINT32_MAX); on error nothing is recorded. */
XYL_API xyl_result xyl_billboard_vk_cmd_draw_instances(xyl_billboard_vk *bb,
                                                       VkCommandBuffer cmd,
                                                       const xyl_billboard_vk_frame *frame,
                                                       uint32_t first, uint32_t count,
                                                       xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif /* XYL_BILLBOARD_VK_H */

/* xyl_tess_vk.h: the Vulkan 1.2 backend of tessellate/ (instanced path).
 *
 * How to use
 *   - xyl_tess_vk_create(&desc, patterns, &vk) creates its own instance and device (headless:
 *     no surface; lavapipe on machines without a GPU), with the Khronos validation layer when
 *     desc.validation is set; xyl_tess_vk_validation_messages() counts what it reported.
 *   - xyl_tess_vk_set_patches(), then per frame (after xyl_tess_select()) render into an
 *     offscreen image with xyl_tess_vk_render_rgba(). The draws are vkCmdDrawIndexedIndirect,
 *     one command per (kind, level), instance records as a per-instance vertex buffer.
 * Shaders are the same GLSL as the GL backend's, compiled to SPIR-V by glslang at build time.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_TESS_VK_H
#define XYL_TESS_VK_H

#include "xylem/xyl_tessellate.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct xyl_tess_vk xyl_tess_vk;

typedef struct xyl_tess_vk_desc {
    bool validation;         /* enable VK_LAYER_KHRONOS_validation + debug messenger */
    const char *device_name; /* substring of the device to pick; default (NULL): the first */
} xyl_tess_vk_desc;

/* Errors: XYL_ERR_UNSUPPORTED (no Vulkan 1.2 device, a missing feature or the validation layer
 * asked for but absent: the message says which), XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_tess_vk_create(const xyl_tess_vk_desc *desc,
                                      const xyl_tess_patterns *patterns, xyl_tess_vk **out,
                                      xyl_diag *diag);
XYL_API void xyl_tess_vk_destroy(xyl_tess_vk *vk);
XYL_API const char *xyl_tess_vk_device_name(const xyl_tess_vk *vk);

XYL_API xyl_result xyl_tess_vk_set_patches(xyl_tess_vk *vk, const xyl_tess_patches *patches,
                                           xyl_diag *diag);

/* As xyl_tess_gl_render_rgba (frame->view_proj in Vulkan's clip convention). */
XYL_API xyl_result xyl_tess_vk_render_rgba(xyl_tess_vk *vk, const xyl_tess_batches *batches,
                                           const xyl_tess_frame *frame,
                                           const xyl_tess_image_desc *image, uint8_t *rgba,
                                           xyl_diag *diag);

/* Milliseconds of GPU time of the last render (timestamp queries), negative if unknown. */
XYL_API double xyl_tess_vk_last_gpu_ms(const xyl_tess_vk *vk);

/* Messages of severity warning or error the validation layer reported since creation. */
XYL_API uint32_t xyl_tess_vk_validation_messages(const xyl_tess_vk *vk);
/* The first such message ("" if none). */
XYL_API const char *xyl_tess_vk_first_message(const xyl_tess_vk *vk);

#ifdef __cplusplus
}
#endif

#endif /* XYL_TESS_VK_H */

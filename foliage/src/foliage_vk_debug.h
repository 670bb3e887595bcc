/* Internal to foliage/ and its tests: the Vulkan leaf renderer's vertices read back, so tests
 * compare the clip-space corners the GPU computes with a CPU reference and see which records a
 * draw reached. Not installed, not API. */
#ifndef XYL_FOLIAGE_VK_DEBUG_H
#define XYL_FOLIAGE_VK_DEBUG_H

#include "xylem/xyl_foliage_vk.h"

/* What the capture vertex shader stored for corner c of record i, at 4 i + c: gl_Position, the
 * corner (s, t) in {-1, 1}^2 and the record; leaf is UINT32_MAX where no vertex was run. */
typedef struct xyl__foliage_vk_captured {
    float clip[4];
    float st[2];
    uint32_t leaf;
    uint32_t pad;
} xyl__foliage_vk_captured;

/* Records the draw of xyl_foliage_vk_cmd_draw with the capture vertex shader and the
 * rasterizer off into a command buffer of its own, submits it to desc.queue, waits, and copies
 * 4 * (uploaded leaf count) entries into out. Errors as xyl_foliage_vk_cmd_draw (cmd aside),
 * and XYL_ERR_INVALID_ARGUMENT (NULL out, capacity below 4 * leaf count),
 * XYL_ERR_UNSUPPORTED (a device made without vertexPipelineStoresAndAtomics),
 * XYL_ERR_OUT_OF_MEMORY. */
xyl_result xyl__foliage_vk_capture(xyl_foliage_vk *vk, const xyl_foliage_vk_frame *frame,
                                   const uint32_t *lods, size_t lod_count,
                                   xyl__foliage_vk_captured *out, size_t capacity,
                                   xyl_diag *diag);

#endif /* XYL_FOLIAGE_VK_DEBUG_H */

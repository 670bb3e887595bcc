/* Internal to tessellate/ and its tests: what the test suites need to look inside the GPU
 * backends (evaluated vertices read back, the CPU reference of a hardware-path vertex), the
 * level rule of xyl_tess_select alone, and the debug view flags. Not installed and not part of
 * the API: everything here is xyl__-prefixed and hidden. */
#ifndef XYL_TESS_DEBUG_INTERNAL_H
#define XYL_TESS_DEBUG_INTERNAL_H

#include "xylem/xyl_tessellate.h"
#include "xyl_tess_debug.h" /* shaders/: the flags, shared with GLSL */

typedef struct xyl_tess_gl xyl_tess_gl;
typedef struct xyl_tess_vk xyl_tess_vk;

/* One vertex as a GPU evaluated it. Instanced path: coord = (i, j, level) of the lattice point,
 * whose CPU reference is xyl_tess_eval_lattice; hardware path: coord = gl_TessCoord, whose
 * reference is xyl__tess_reference_hardware. */
typedef struct xyl__tess_captured {
    float position[3];
    float normal[3];
    float coord[3];
    uint32_t patch;
} xyl__tess_captured;

/* The tessellation evaluation shader's rule for gl_TessCoord tc of a patch drawn with the
 * instance record's edge_levels: points on a side snapped to k / le of that side's level and
 * evaluated by xyl_tess_eval_edge, the rest by xyl_tess_eval. */
void xyl__tess_reference_hardware(const xyl_tess_patch *patch, xyl_tess_variant variant,
                                  const float tc[3], uint32_t edge_levels, float pos[3],
                                  float normal[3]);

/* Evaluates the batches on the GPU and reads the vertices back (instanced path: every pattern
 * vertex of every instance, batches->vertices in all, in instance order then pattern order;
 * hardware path: every vertex the tessellator emitted, three per triangle). Writes the first
 * `capacity` into out and the total into *count. Errors as xyl_tess_gl_draw, and
 * XYL_ERR_LIMIT_EXCEEDED (more vertices than a storage block holds). */
xyl_result xyl__tess_gl_capture(xyl_tess_gl *gl, const xyl_tess_batches *batches,
                                xyl_tess_variant variant, xyl_tess_path path,
                                xyl__tess_captured *out, size_t capacity, size_t *count,
                                xyl_diag *diag);

/* As xyl__tess_gl_capture for the instanced path; XYL_ERR_UNSUPPORTED without the device's
 * vertexPipelineStoresAndAtomics. */
xyl_result xyl__tess_vk_capture(xyl_tess_vk *vk, const xyl_tess_batches *batches,
                                xyl_tess_variant variant, xyl__tess_captured *out,
                                size_t capacity, size_t *count, xyl_diag *diag);

/* Level that keeps a world error coefficient (world units * L^2) under the view's error_px seen
 * from distance d: ceil(sqrt(coef * scale / (d * error_px))), clamped to [1, max_level]; the
 * rule xyl_tess_select applies to every patch and edge. */
uint32_t xyl__tess_level_for(float coefficient, float distance, const xyl_tess_view *view,
                             uint32_t max_level);

#endif /* XYL_TESS_DEBUG_INTERNAL_H */

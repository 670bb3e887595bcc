/* What the GL and Vulkan billboards (xyl_billboard_gl.h, xyl_billboard_vk.h) share on the CPU:
 * the checks of a bake's parameters and of a frame, the quads' and views' geometry (the
 * documented bake cameras, the octahedral grid) and the bake's read-back turned into coverage
 * and normal maps. Not installed. */
#ifndef XYL_BILLBOARD_SHAPE_H
#define XYL_BILLBOARD_SHAPE_H

#include "xylem/xyl_foliage.h"

/* A bake's parameters, as both descs give them. */
typedef struct xyl__billboard_params {
    xyl_billboard_kind kind;
    uint32_t planes, resolution, grid;
    const float *lo, *hi, *light_dir; /* 3 floats each */
} xyl__billboard_params;

/* What a bake makes of them. */
typedef struct xyl__billboard_shape {
    xyl_billboard_kind kind;
    uint32_t views, resolution, grid; /* grid: the octahedral kind's, else 0 */
    float center[3], half[2]; /* the quads' centre, half width and half height */
    float radius;             /* 1.01 times the box's half diagonal */
    float bake_light[3];      /* the bake's light; all 0: each view's own direction */
} xyl__billboard_shape;

/* The rules of xyl_billboard_gl_bake's desc (XYL_ERR_INVALID_ARGUMENT, XYL_ERR_NON_FINITE). */
xyl_result xyl__billboard_check(const xyl__billboard_params *p, xyl_diag *diag);
/* The shape of checked parameters. */
void xyl__billboard_shape_of(const xyl__billboard_params *p, xyl__billboard_shape *out);

/* View v's frame: d from the centre towards its camera, right and up across its picture. */
void xyl__billboard_view_frame(const xyl__billboard_shape *s, uint32_t v, float right[3],
                               float up[3], float d[3]);
/* View v's orthographic world-to-clip matrix (column-major, GL clip), and its light. */
void xyl__billboard_bake_camera(const xyl__billboard_shape *s, uint32_t v, float m[16],
                                float light[3]);

/* The read-back of a view (rows bottom to top; rgba as drawn, depth in [0, 1], 1 = nothing)
 * into the stored colour (premultiplied by coverage) and normal map (height in alpha). */
void xyl__billboard_maps(const xyl__billboard_shape *s, const float *depth, uint8_t *rgba,
                         uint8_t *normal);

/* The checks of a draw's frame (XYL_ERR_INVALID_ARGUMENT, XYL_ERR_NON_FINITE): light gets the
 * normalised light (+Y by default), *cutoff the cutoff (0.5 by default). */
xyl_result xyl__billboard_frame_check(const float view_proj[16], const float eye[3],
                                      const float light_dir[3], float alpha_cutoff,
                                      const float dither[2], float light[3], float *cutoff,
                                      xyl_diag *diag);

#endif

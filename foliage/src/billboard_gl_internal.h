/* What the forest renderer (forest_gl.c) reads of a baked billboard to draw it per instance
 * with its own program. Not installed. */
#ifndef XYL_BILLBOARD_GL_INTERNAL_H
#define XYL_BILLBOARD_GL_INTERNAL_H

#include <epoxy/gl.h>

#include "xylem/xyl_billboard_gl.h"

typedef struct xyl__billboard_parts {
    GLuint color_tex, normal_tex; /* 2D array textures, one layer a view */
    int kind;                     /* an xyl_billboard_kind */
    uint32_t views;
    uint32_t grid;                /* the octahedral kind's views per side (else 0) */
    float center[3], half[2];     /* the quads' centre, half width and half height; an
                                     octahedral one's sphere radius is half[0] */
    float bake_light[3];          /* the bake's light; all 0: each view's own direction */
} xyl__billboard_parts;

void xyl__billboard_gl_parts(const xyl_billboard_gl *bb, xyl__billboard_parts *out);

#endif

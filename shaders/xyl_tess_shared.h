/* xyl_tess_shared.h: the one header read by both C and GLSL (layouts, limits, enums).
 *
 * In GLSL the build puts "#define XYL_GLSL 1" before this file; in C it is included from
 * xylem/xyl_tessellate.h, which pins every layout with _Static_assert. Keep both halves in step:
 * a field added on one side without the other fails those asserts or the GPU = CPU tests.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_TESS_SHARED_H
#define XYL_TESS_SHARED_H

/* Levels are 1..64: a level-L pattern has L segments per edge (quads: (L+1)^2 vertices, 2 L^2
 * triangles; triangles: (L+1)(L+2)/2 vertices, L^2 triangles). */
#define XYL_TESS_MAX_LEVEL 64

/* Patch kinds (the number of corners). */
#define XYL_TESS_KIND_TRIANGLE 3
#define XYL_TESS_KIND_QUAD 4

/* Edge handle rules, all local to one edge. */
#define XYL_TESS_VARIANT_PN 0       /* 1/3 of the tangent-projected edge (Vlachos 2001) */
#define XYL_TESS_VARIANT_ROUNDED 1  /* 1/2 of it (Skjermo 2008) */
#define XYL_TESS_VARIANT_CIRCLE 2   /* (4/3) tan(phi/4) r: exact on a circular arc */
#define XYL_TESS_VARIANT_ARC 3      /* circle, and along a vertex's curve (its axis) the handle
                                       follows that curve: exact on bent tubes too */
#define XYL_TESS_VARIANT_COUNT 4

/* The arc variant's vertex axis: the unit tangent of the curve through a regular vertex and its
 * two opposite neighbours along the branch, stored as an angle in the vertex's tangent plane
 * (xyl_tess_axis_frame of its normal), n[c].w = angle + XYL_TESS_AXIS_BIAS; 0 means none. */
#define XYL_TESS_AXIS_BIAS 4.0

/* A pattern vertex is one uint: lattice index i in bits 0..7, j in bits 8..15, and the vertex's
 * index within its pattern in bits 16..31 (capture buffers use it; no base-vertex builtin is
 * needed, which GL and Vulkan define differently). Quads: (u, v) = (i, j) / L. Triangles:
 * weights (L - i - j, i, j) / L of corners 0, 1, 2. */
#define XYL_TESS_PATTERN_SHIFT_J 8u
#define XYL_TESS_PATTERN_SHIFT_LOCAL 16u

/* Bindings shared by both backends (Vulkan: descriptor set 0). */
#define XYL_TESS_BINDING_PATCHES 0   /* storage: xyl_tess_patch[] */
#define XYL_TESS_BINDING_FRAME 1     /* uniform: xyl_tess_frame */
#define XYL_TESS_BINDING_CAPTURE 2   /* storage: vec4 pairs (position, normal) per vertex */
#define XYL_TESS_BINDING_OFFSETS 3   /* storage: uint first capture slot per patch */
#define XYL_TESS_BINDING_INSTANCES 4 /* storage: instance records (hardware path) */

/* xyl_tess_frame.flags; the other bits are reserved (0) */
#define XYL_TESS_FLAG_WIREFRAME 1u  /* the fragment shader outputs the line colour (a draw
                                       call given it draws the surface, then the edges) */

/* Instance record bits: edge level e (1..64) in bits 8e .. 8e+7 of edge_levels. */
#define XYL_TESS_EDGE_LEVEL_BITS 8u

#ifdef XYL_GLSL

/* One patch: corner positions (w = kind, 3.0 or 4.0, on corner 0 only) and unit corner normals
 * (w = the corner's axis for the arc variant, else 0). Triangles leave corner 3 zero. std430:
 * 128 bytes. */
struct xyl_tess_patch {
    vec4 p[4];
    vec4 n[4];
};

/* One drawn instance (a vertex attribute with divisor 1, so base-instance offsets apply):
 * x = patch index, y = packed edge levels, z = patch level, w = kind. */

/* Per-frame uniforms, std140: 128 bytes. */
struct xyl_tess_frame {
    mat4 view_proj;  /* world to clip, in the API's clip convention */
    vec4 light_dir;  /* xyz: unit direction towards the light */
    vec4 color;      /* rgb: surface albedo; a: unused */
    vec4 line_color; /* wireframe overlay colour */
    uint variant;    /* XYL_TESS_VARIANT_* */
    uint flags;      /* XYL_TESS_FLAG_*; other bits reserved (0) */
    uint base_instance; /* hardware path: first instance record of the draw */
    uint dither;     /* keep range of the screen-door dither (xyl_tess_dither); 0: all */
};

/* Two unit vectors spanning the plane normal to the unit n (Duff et al. 2017, branchless). */
void xyl_tess_axis_frame(vec3 n, out vec3 e1, out vec3 e2)
{
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float b = n.x * n.y * a;
    e1 = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    e2 = vec3(b, s + n.y * n.y * a, -n.y);
}

/* The axis of a corner from its stored w and its normal; (0, 0, 0) where it has none. */
vec3 xyl_tess_axis(vec3 n, float w)
{
    if (w == 0.0) return vec3(0.0);
    vec3 e1, e2;
    xyl_tess_axis_frame(n, e1, e2);
    float ang = w - XYL_TESS_AXIS_BIAS;
    return e1 * cos(ang) + e2 * sin(ang);
}

/* The keep range [lo, hi) packed in xyl_tess_frame.dither: lo in bits 0..15, hi in 16..31. */
vec2 xyl_tess_keep(uint dither)
{
    return vec2(float(dither & 0xffffu), float(dither >> 16u)) / 65535.0;
}

#else /* C */

#include <stdint.h>

typedef struct xyl_tess_patch {
    float p[4][4];
    float n[4][4];
} xyl_tess_patch;

typedef struct xyl_tess_instance {
    uint32_t patch;       /* index into the patch array */
    uint32_t edge_levels; /* edge e's level in bits 8e..8e+7; never above level */
    uint32_t level;       /* interior level 1..64 (the pattern drawn) */
    uint32_t kind;        /* XYL_TESS_KIND_TRIANGLE or XYL_TESS_KIND_QUAD */
} xyl_tess_instance;

typedef struct xyl_tess_frame {
    float view_proj[16]; /* column-major */
    float light_dir[4];
    float color[4];
    float line_color[4];
    uint32_t variant;
    uint32_t flags; /* XYL_TESS_FLAG_*; other bits reserved (0) */
    uint32_t base_instance;
    uint32_t dither; /* the screen-door dither's keep range, from xyl_tess_dither (cross-fades
                        between levels of detail, docs/foliage.md "Transitions"); 0: every
                        fragment */
} xyl_tess_frame;

/* The layout of both glDrawElementsIndirect's and vkCmdDrawIndexedIndirect's command. */
typedef struct xyl_tess_draw_cmd {
    uint32_t index_count;
    uint32_t instance_count;
    uint32_t first_index;
    int32_t base_vertex;
    uint32_t base_instance;
} xyl_tess_draw_cmd;

#endif

#endif /* XYL_TESS_SHARED_H */

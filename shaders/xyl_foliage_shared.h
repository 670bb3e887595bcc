/* xyl_foliage_shared.h: the leaf record read by both C and GLSL.
 *
 * In GLSL the build puts "#define XYL_GLSL 1" before this file; in C it is included from
 * xylem/xyl_foliage.h, which pins the layout with _Static_assert, and tests/foliage_glsl.cmake
 * compiles it into a shader and checks the offsets glslang gives the GLSL half. Keep both
 * halves in step.
 *
 * One leaf in 32 bytes, the same in C and in a std430 buffer (an array stride of 32):
 *   bytes  0..11  centre: 3 floats, the leaf's own (world coordinates keep full float
 *                 precision);
 *   bytes 12..23  the half-axes as 6 IEEE binary16 half floats, axis x, y, z then side x, y, z
 *                 (GLSL: unpackHalf2x16 of the words at 12, 16 and 20). A half keeps an 11-bit
 *                 significand: relative error <= 2^-11 for 6.1e-5 <= |x| <= 65504; below
 *                 6.1e-5 it is subnormal, absolute error <= 2^-25 (a component that small
 *                 next to a half-axis of 6.1e-5 or more changes the direction by < 2^-11);
 *                 |x| > 65504 does not fit (xyl_foliage_pack_gpu refuses it);
 *   bytes 24..31  the texture rectangle u0, v0, u1, v1 as unorm16 (value / 65535; GLSL:
 *                 unpackUnorm2x16 of the words at 24 and 28): error <= 0.5 / 65535.
 * The normal is not stored: normal = normalize(cross(side, axis)), the handedness of xyl_leaf
 * ((side, axis, normal) like (x, y, z)); it is within 2^-9 radians of the leaf's when both
 * half-axes are at least 6.1e-5 long (tested). Count and node stay on the CPU. Words are read
 * little-endian, as on every GPU host xylem targets. */
#ifndef XYL_FOLIAGE_SHARED_H
#define XYL_FOLIAGE_SHARED_H

#define XYL_FOLIAGE_GPU_LEAF_SIZE 32

/* The GL leaf renderer's resources (foliage_leaf.vert / .frag, xylem/xyl_foliage_gl.h): the
 * storage buffer of records, the leaf texture's unit and the uniforms' locations. */
#define XYL_FOLIAGE_GL_BINDING_LEAVES 0
#define XYL_FOLIAGE_GL_BINDING_TEXTURE 0
#define XYL_FOLIAGE_GL_UNIFORM_VIEW_PROJ 0
#define XYL_FOLIAGE_GL_UNIFORM_BASE 1
#define XYL_FOLIAGE_GL_UNIFORM_LIGHT 2
#define XYL_FOLIAGE_GL_UNIFORM_COLOR 3
#define XYL_FOLIAGE_GL_UNIFORM_CUTOFF 4
#define XYL_FOLIAGE_GL_UNIFORM_TRANSLUCENCY 5
#define XYL_FOLIAGE_GL_UNIFORM_DITHER 7 /* vec2: the keep range of xyl_dither.h */
/* The per-leaf cut (foliage_cut.comp, xyl_foliage_gl_draw_adaptive): the drawn records'
 * indices (the vertex shader reads them when u_list is 1), the collapse forest's nodes, and the
 * indirect draw command whose instance count the cut counts up. */
#define XYL_FOLIAGE_GL_UNIFORM_LIST 6
#define XYL_FOLIAGE_GL_BINDING_LIST 1
#define XYL_FOLIAGE_GL_BINDING_NODES 2
#define XYL_FOLIAGE_GL_BINDING_COMMAND 3
#define XYL_FOLIAGE_GL_UNIFORM_CUT_EYE 0
#define XYL_FOLIAGE_GL_UNIFORM_CUT_PER_DISTANCE 1
#define XYL_FOLIAGE_GL_UNIFORM_CUT_COUNT 2
#define XYL_FOLIAGE_GL_CUT_GROUP 64

/* The Vulkan leaf renderer's (xylem/xyl_foliage_vk.h): descriptor set 0 holds the records, the
 * leaf texture and, in the tests' capture pipeline only, the captured vertices; the draw's
 * values are push constants (xyl_foliage_vk_push below). */
#define XYL_FOLIAGE_VK_BINDING_LEAVES 0
#define XYL_FOLIAGE_VK_BINDING_TEXTURE 1
#define XYL_FOLIAGE_VK_BINDING_CAPTURE 2
#define XYL_FOLIAGE_VK_PUSH_SIZE 112
/* The Vulkan per-leaf cut (foliage_cut.comp with XYL_CUT, xyl_foliage_vk_cmd_cut): the drawn
 * records' indices (read by the list pipeline's vertex shader), the collapse forest's nodes and
 * the indirect draw command, in the same set; the cut's values are push constants
 * (xyl_foliage_vk_cut_push below). */
#define XYL_FOLIAGE_VK_BINDING_LIST 3
#define XYL_FOLIAGE_VK_BINDING_NODES 4
#define XYL_FOLIAGE_VK_BINDING_COMMAND 5
#define XYL_FOLIAGE_VK_CUT_PUSH_SIZE 20

/* The Vulkan billboard's (xylem/xyl_billboard_vk.h, billboard.* and impostor.* with
 * XYL_BILLBOARD): set 0 holds the baked colour and normal maps, the billboard's constants (a
 * uniform buffer, xyl_billboard_vk_constants below) and, for a forest's instanced draw, the
 * instances; a draw's values are push constants (xyl_billboard_vk_push below). */
#define XYL_BILLBOARD_VK_BINDING_COLOR 0
#define XYL_BILLBOARD_VK_BINDING_NORMAL 1
#define XYL_BILLBOARD_VK_BINDING_CONSTANTS 2
#define XYL_BILLBOARD_VK_BINDING_INSTANCES 3
#define XYL_BILLBOARD_VK_PUSH_SIZE 112
#define XYL_BILLBOARD_VK_CONSTANTS_SIZE 64

/* The forest renderer's (xylem/xyl_forest_gl.h, forest_*.vert): a frame's instances sorted by
 * species and level in one storage buffer of xyl_forest_instance records, the leaf records at
 * XYL_FOLIAGE_GL_BINDING_LEAVES, and the uniforms its vertex shaders add to the leaf and
 * billboard fragment shaders' own (from 16 up, clear of theirs). */
#define XYL_FOREST_GL_BINDING_INSTANCES 4
#define XYL_FOREST_GL_UNIFORM_FIRST 16    /* first leaf record of the range drawn */
#define XYL_FOREST_GL_UNIFORM_LENGTH 17   /* leaves in the range */
#define XYL_FOREST_GL_UNIFORM_INSTANCE 18 /* first instance of the bucket drawn */
#define XYL_FOREST_GL_UNIFORM_STEM_COLOR 19
#define XYL_FOREST_GL_UNIFORM_BB_CENTER 20
#define XYL_FOREST_GL_UNIFORM_BB_HALF 21
#define XYL_FOREST_GL_UNIFORM_BB_KIND 22
#define XYL_FOREST_GL_UNIFORM_BB_PLANES 23
#define XYL_FOREST_GL_UNIFORM_EYE 24
#define XYL_FOREST_GL_UNIFORM_LIGHT 25    /* the world's light (impostors relight per instance) */

/* A forest instance in 16 bytes (the same in C and std430):
 *   bytes 0..11  the tree's base point, 3 floats, world units;
 *   bytes 12..15 bits, one little-endian word: bits 0..7 the LOD (a leaf level, or
 *                XYL_FOREST_LOD_BILLBOARD), bits 8..13 the species, bits 14..23 the rotation
 *                about +Y in steps of 2 pi / 1024, bits 24..31 the scale as (q + 1) / 64, so
 *                1/64 to 4 in steps of 1/64. */
#define XYL_FOREST_INSTANCE_SIZE 16
#define XYL_FOREST_LOD_BILLBOARD 255u
#define XYL_FOREST_ROTATION_STEPS 1024u
#define XYL_FOREST_SCALE_STEPS 64.0

#ifdef XYL_GLSL

struct xyl_forest_instance {
    vec3 position;
    uint bits;
};

/* The instance's rotation about +Y as (cos, sin) and its scale. */
vec3 xyl_forest_rotation_scale(uint bits)
{
    float a = float((bits >> 14) & 1023u) * (6.283185307179586 / 1024.0);
    return vec3(cos(a), sin(a), float((bits >> 24) + 1u) / 64.0);
}

/* A point of the species' own coordinates placed by the instance: turned about +Y by the
 * angle a (x' = x cos a + z sin a, z' = -x sin a + z cos a), scaled, moved. */
vec3 xyl_forest_place(vec3 p, vec3 cs, vec3 position)
{
    return position + cs.z * vec3(cs.x * p.x + cs.y * p.z, p.y, -cs.y * p.x + cs.x * p.z);
}

/* The dither keep range of a sorted instance's copy (its LOD byte, forest_gl's fade): 0 keeps
 * every pixel; q = bits 0..6 in 64ths, bit 7 set: the coarser level's copy, [0, q / 64);
 * clear: the finer one's, [q / 64, 1). */
vec2 xyl_forest_keep(uint bits)
{
    uint f = bits & 255u;
    float t = float(f & 127u) / 64.0;
    return f == 0u ? vec2(0.0) : (f & 128u) != 0u ? vec2(0.0, t) : vec2(t, 1.0);
}

vec3 xyl_forest_turn(vec3 n, vec3 cs)
{
    return vec3(cs.x * n.x + cs.y * n.z, n.y, -cs.y * n.x + cs.x * n.z);
}

struct xyl_foliage_gpu_leaf {
    vec3 center;
    uint axis_xy;       /* packHalf2x16(axis.x, axis.y) */
    uint axis_z_side_x; /* packHalf2x16(axis.z, side.x) */
    uint side_yz;       /* packHalf2x16(side.y, side.z) */
    uint uv0;           /* packUnorm2x16(u0, v0) */
    uint uv1;           /* packUnorm2x16(u1, v1) */
};

vec3 xyl_foliage_axis(xyl_foliage_gpu_leaf l)
{
    return vec3(unpackHalf2x16(l.axis_xy), unpackHalf2x16(l.axis_z_side_x).x);
}

vec3 xyl_foliage_side(xyl_foliage_gpu_leaf l)
{
    return vec3(unpackHalf2x16(l.axis_z_side_x).y, unpackHalf2x16(l.side_yz));
}

vec3 xyl_foliage_normal(xyl_foliage_gpu_leaf l)
{
    return normalize(cross(xyl_foliage_side(l), xyl_foliage_axis(l)));
}

/* u0, v0, u1, v1 */
vec4 xyl_foliage_uv_rect(xyl_foliage_gpu_leaf l)
{
    return vec4(unpackUnorm2x16(l.uv0), unpackUnorm2x16(l.uv1));
}

/* The point centre + st.x side + st.y axis, st in [-1, 1]^2, and its texture coordinate. */
vec3 xyl_foliage_corner(xyl_foliage_gpu_leaf l, vec2 st)
{
    return l.center + st.x * xyl_foliage_side(l) + st.y * xyl_foliage_axis(l);
}

vec2 xyl_foliage_corner_uv(xyl_foliage_gpu_leaf l, vec2 st)
{
    vec4 r = xyl_foliage_uv_rect(l);
    return mix(r.xy, r.zw, 0.5 * st + 0.5);
}

#if defined(XYL_VULKAN) && defined(XYL_BILLBOARD)
/* A Vulkan billboard draw's values, in push constants (std430 offsets: 0, 64, 80, 96, 104). */
layout(push_constant) uniform xyl_billboard_vk_push {
    mat4 view_proj;     /* Vulkan clip convention (y down, depth 0..1) */
    vec4 eye;           /* xyz: the camera; w: the alpha cutoff */
    vec4 light;         /* xyz: towards the light, normalised */
    vec2 dither;        /* the keep range of xyl_dither.h; (0, 0): every fragment */
    uint first;         /* an instanced draw's first instance */
    uint pad;
} xyl_bpush;
/* The billboard's own values, fixed at its bake (std140 offsets: 0, 16, 32, 40, 44, 48). */
layout(std140, set = 0, binding = XYL_BILLBOARD_VK_BINDING_CONSTANTS) uniform
xyl_billboard_vk_constants {
    vec4 center;        /* xyz: the quads' centre; w: the octahedral kind's radius */
    vec4 bake_light;    /* xyz: the bake's light, all 0: each view's own direction */
    vec2 half_size;     /* the quads' half width and half height */
    int kind;           /* an xyl_billboard_kind */
    int planes;         /* cross: the planes; octahedral: the grid */
    int to_coverage;    /* 1 in a multisampled target: alpha goes to alpha-to-coverage */
} xyl_bconst;
#elif defined(XYL_VULKAN) && !defined(XYL_CUT)
/* A Vulkan draw's values, in push constants (std430 offsets: 0, 64, 80, 96, 100, 104). */
layout(push_constant) uniform xyl_foliage_vk_push {
    mat4 view_proj;     /* Vulkan clip convention (y down, depth 0..1) */
    vec4 light;         /* xyz: towards the light, normalised */
    vec4 color;
    float cutoff;
    float translucency;
    vec2 dither;        /* the keep range of xyl_dither.h; (0, 0): every fragment */
} xyl_push;
#endif

#else /* C */

#include <stdint.h>

typedef struct xyl_foliage_gpu_leaf {
    float center[3];
    uint16_t axis[3]; /* binary16 bits */
    uint16_t side[3]; /* binary16 bits */
    uint16_t uv[4];   /* unorm16: u0, v0, u1, v1 */
} xyl_foliage_gpu_leaf;

/* The push constants of a Vulkan leaf draw (pinned in foliage/src/foliage_vk.c). */
typedef struct xyl_foliage_vk_push {
    float view_proj[16];
    float light[4];
    float color[4];
    float cutoff;
    float translucency;
    float dither[2];
} xyl_foliage_vk_push;

/* The push constants and constants of a Vulkan billboard draw (pinned in
 * foliage/src/billboard_vk.c). */
typedef struct xyl_billboard_vk_push {
    float view_proj[16];
    float eye[4];
    float light[4];
    float dither[2];
    uint32_t first;
    uint32_t pad;
} xyl_billboard_vk_push;

typedef struct xyl_billboard_vk_constants {
    float center[4];
    float bake_light[4];
    float half_size[2];
    int32_t kind;
    int32_t planes;
    int32_t to_coverage;
    int32_t pad[3];
} xyl_billboard_vk_constants;

/* The push constants of the Vulkan per-leaf cut (pinned in foliage/src/foliage_vk.c). */
typedef struct xyl_foliage_vk_cut_push {
    float eye[3];
    float per_distance;
    uint32_t count;
} xyl_foliage_vk_cut_push;

/* One forest instance (the layout above; xyl_forest_instance_pack / _unpack read and write it). */
typedef struct xyl_forest_instance {
    float position[3];
    uint32_t bits;
} xyl_forest_instance;

#endif

#endif /* XYL_FOLIAGE_SHARED_H */

// One leaf a instance: the record (xyl_foliage_shared.h) at the instance's index expanded to
// its quad, a 4-vertex triangle strip: vertex v is the corner st = (v & 1 ? 1 : -1,
// v & 2 ? 1 : -1), so the strip runs (-1,-1) (1,-1) (-1,1) (1,1), counter-clockwise seen from
// the side the normal points to. No index buffer, no per-leaf CPU work. GL adds u_base to
// gl_InstanceID, or with u_list = 1 (the per-leaf cut's indirect draw) reads the record's
// index at gl_InstanceID of the list foliage_cut.comp wrote; Vulkan draws each range with
// firstInstance = its first record, which gl_InstanceIndex includes, or with XYL_LIST (the
// cut's indirect draw) reads the record's index at gl_InstanceIndex of the list. With
// XYL_CAPTURE (Vulkan, the tests' capture pipeline) each vertex also stores what it computed at
// 4 * record + corner.

#ifdef XYL_VULKAN
layout(std430, set = 0, binding = XYL_FOLIAGE_VK_BINDING_LEAVES) readonly buffer xyl_leaf_buffer {
    xyl_foliage_gpu_leaf xyl_leaves[];
};
#ifdef XYL_LIST // the per-leaf cut's indirect draw: the record at gl_InstanceIndex of the list
layout(std430, set = 0, binding = XYL_FOLIAGE_VK_BINDING_LIST) readonly buffer xyl_list_buffer {
    uint xyl_list[];
};
#define XYL_LEAF_INDEX xyl_list[gl_InstanceIndex]
#else
#define XYL_LEAF_INDEX uint(gl_InstanceIndex)
#endif
#define XYL_CORNER gl_VertexIndex
#define u_view_proj xyl_push.view_proj
#ifdef XYL_CAPTURE
struct xyl_foliage_vk_captured {
    vec4 clip;
    vec2 st;
    uint leaf;
    uint pad;
};
layout(std430, set = 0, binding = XYL_FOLIAGE_VK_BINDING_CAPTURE) writeonly buffer xyl_capture {
    xyl_foliage_vk_captured xyl_captured[];
};
#endif
#else
layout(std430, binding = XYL_FOLIAGE_GL_BINDING_LEAVES) readonly buffer xyl_leaf_buffer {
    xyl_foliage_gpu_leaf xyl_leaves[];
};
layout(location = XYL_FOLIAGE_GL_UNIFORM_VIEW_PROJ) uniform mat4 u_view_proj;
layout(location = XYL_FOLIAGE_GL_UNIFORM_BASE) uniform uint u_base;
layout(location = XYL_FOLIAGE_GL_UNIFORM_LIST) uniform uint u_list;
layout(std430, binding = XYL_FOLIAGE_GL_BINDING_LIST) readonly buffer xyl_list_buffer {
    uint xyl_list[];
};
#define XYL_LEAF_INDEX (u_list != 0u ? xyl_list[gl_InstanceID] : u_base + uint(gl_InstanceID))
#define XYL_CORNER gl_VertexID
#endif

layout(location = 0) out vec3 v_normal;
layout(location = 1) out vec2 v_uv;
#ifndef XYL_VULKAN // GL's transform feedback capture reads these back
layout(location = 2) out vec2 v_st;      // the corner
layout(location = 3) flat out uint v_leaf; // the record
#endif

void main()
{
    uint leaf = XYL_LEAF_INDEX;
    xyl_foliage_gpu_leaf l = xyl_leaves[leaf];
    vec2 st = vec2((XYL_CORNER & 1) != 0 ? 1.0 : -1.0, (XYL_CORNER & 2) != 0 ? 1.0 : -1.0);
    vec3 p = xyl_foliage_corner(l, st);
    gl_Position = u_view_proj * vec4(p, 1.0);
    v_normal = xyl_foliage_normal(l);
    v_uv = xyl_foliage_corner_uv(l, st);
#ifndef XYL_VULKAN
    v_st = st;
    v_leaf = leaf;
#elif defined(XYL_CAPTURE)
    xyl_captured[4u * leaf + uint(XYL_CORNER)] = xyl_foliage_vk_captured(gl_Position, st, leaf, 0u);
#endif
}

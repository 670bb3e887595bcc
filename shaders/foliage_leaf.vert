
// One leaf a instance: the record (xyl_foliage_shared.h) at u_base + gl_InstanceID expanded to
// its quad, a 4-vertex triangle strip: vertex v is the corner st = (v & 1 ? 1 : -1,
// v & 2 ? 1 : -1), so the strip runs (-1,-1) (1,-1) (-1,1) (1,1), counter-clockwise seen from
// the side the normal points to. No index buffer, no per-leaf CPU work.

layout(std430, binding = XYL_FOLIAGE_GL_BINDING_LEAVES) readonly buffer xyl_leaf_buffer {
    xyl_foliage_gpu_leaf xyl_leaves[];
};

layout(location = XYL_FOLIAGE_GL_UNIFORM_VIEW_PROJ) uniform mat4 u_view_proj;
layout(location = XYL_FOLIAGE_GL_UNIFORM_BASE) uniform uint u_base;

layout(location = 0) out vec3 v_normal;
layout(location = 1) out vec2 v_uv;
layout(location = 2) out vec2 v_st;      // the corner; read back by the capture
layout(location = 3) flat out uint v_leaf; // the record; read back by the capture

void main()
{
    uint leaf = u_base + uint(gl_InstanceID);
    xyl_foliage_gpu_leaf l = xyl_leaves[leaf];
    vec2 st = vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0);
    vec3 p = xyl_foliage_corner(l, st);
    gl_Position = u_view_proj * vec4(p, 1.0);
    v_normal = xyl_foliage_normal(l);
    v_uv = xyl_foliage_corner_uv(l, st);
    v_st = st;
    v_leaf = leaf;
}

// A forest's leaves (xyl_forest_gl.h): one instanced draw covers one range of a leaf level for
// a bucket of instances, gl_InstanceID = bucket instance * u_length + leaf in the range. The
// record is expanded to its quad as foliage_leaf.vert does, then placed by the instance
// (rotation about +Y, scale, position). Feeds foliage_leaf.frag. With XYL_LIST (a per-leaf
// instance's indirect draw) gl_InstanceID indexes the list of records its cut kept
// (foliage_cut.comp), and the instance is u_instance itself.

layout(std430, binding = XYL_FOLIAGE_GL_BINDING_LEAVES) readonly buffer xyl_leaf_buffer {
    xyl_foliage_gpu_leaf xyl_leaves[];
};
layout(std430, binding = XYL_FOREST_GL_BINDING_INSTANCES) readonly buffer xyl_instance_buffer {
    xyl_forest_instance xyl_instances[];
};
layout(location = XYL_FOLIAGE_GL_UNIFORM_VIEW_PROJ) uniform mat4 u_view_proj;
layout(location = XYL_FOREST_GL_UNIFORM_FIRST) uniform uint u_first;
layout(location = XYL_FOREST_GL_UNIFORM_LENGTH) uniform uint u_length;
layout(location = XYL_FOREST_GL_UNIFORM_INSTANCE) uniform uint u_instance;
#ifdef XYL_LIST
layout(std430, binding = XYL_FOLIAGE_GL_BINDING_LIST) readonly buffer xyl_list_buffer {
    uint xyl_list[];
};
#endif

layout(location = 0) out vec3 v_normal;
layout(location = 1) out vec2 v_uv;
layout(location = 2) flat out vec2 v_keep; // the copy's cross-fade share

void main()
{
    uint id = uint(gl_InstanceID);
#ifdef XYL_LIST
    xyl_forest_instance inst = xyl_instances[u_instance];
    xyl_foliage_gpu_leaf l = xyl_leaves[xyl_list[id]];
#else
    xyl_forest_instance inst = xyl_instances[u_instance + id / u_length];
    xyl_foliage_gpu_leaf l = xyl_leaves[u_first + id % u_length];
#endif
    vec2 st = vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0);
    vec3 cs = xyl_forest_rotation_scale(inst.bits);
    vec3 p = xyl_forest_place(xyl_foliage_corner(l, st), cs, inst.position);
    gl_Position = u_view_proj * vec4(p, 1.0);
    v_normal = xyl_forest_turn(xyl_foliage_normal(l), cs);
    v_uv = xyl_foliage_corner_uv(l, st);
    v_keep = xyl_forest_keep(inst.bits);
}

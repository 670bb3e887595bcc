// A forest's stems (xyl_forest_gl.h): the species' base mesh, instanced over a run of sorted
// instances starting at u_instance, placed as the leaves are.

layout(std430, binding = XYL_FOREST_GL_BINDING_INSTANCES) readonly buffer xyl_instance_buffer {
    xyl_forest_instance xyl_instances[];
};
layout(location = XYL_FOLIAGE_GL_UNIFORM_VIEW_PROJ) uniform mat4 u_view_proj;
layout(location = XYL_FOREST_GL_UNIFORM_INSTANCE) uniform uint u_instance;

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 0) out vec3 v_normal;
layout(location = 1) flat out vec2 v_keep; // the copy's cross-fade share

void main()
{
    xyl_forest_instance inst = xyl_instances[u_instance + uint(gl_InstanceID)];
    vec3 cs = xyl_forest_rotation_scale(inst.bits);
    gl_Position = u_view_proj * vec4(xyl_forest_place(a_position, cs, inst.position), 1.0);
    v_normal = xyl_forest_turn(a_normal, cs);
    v_keep = xyl_forest_keep(inst.bits);
}

// A forest's billboards (xyl_forest_gl.h): billboard.vert's quads for a run of sorted
// instances, gl_InstanceID = instance * u_planes + plane, each placed by its instance. Cross
// planes turn with the instance; spherical and cylindrical quads face the eye. Feeds
// billboard.frag.

layout(std430, binding = XYL_FOREST_GL_BINDING_INSTANCES) readonly buffer xyl_instance_buffer {
    xyl_forest_instance xyl_instances[];
};
layout(location = 0) uniform mat4 u_view_proj;
layout(location = XYL_FOREST_GL_UNIFORM_INSTANCE) uniform uint u_instance;
layout(location = XYL_FOREST_GL_UNIFORM_BB_CENTER) uniform vec3 u_center;
layout(location = XYL_FOREST_GL_UNIFORM_BB_HALF) uniform vec2 u_half;
layout(location = XYL_FOREST_GL_UNIFORM_BB_KIND) uniform int u_kind;
layout(location = XYL_FOREST_GL_UNIFORM_BB_PLANES) uniform int u_planes;
layout(location = XYL_FOREST_GL_UNIFORM_EYE) uniform vec3 u_eye;

layout(location = 0) out vec2 v_uv;
layout(location = 1) flat out vec3 v_right;
layout(location = 2) flat out vec3 v_up;
layout(location = 3) flat out vec3 v_facing;
layout(location = 4) flat out int v_layer;
layout(location = 5) flat out vec2 v_keep; // the copy's cross-fade share

void main()
{
    int plane = gl_InstanceID % u_planes;
    xyl_forest_instance inst = xyl_instances[u_instance + uint(gl_InstanceID / u_planes)];
    vec3 cs = xyl_forest_rotation_scale(inst.bits);
    vec3 center = xyl_forest_place(u_center, cs, inst.position);
    vec2 st = vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0);
    vec3 d;
    vec3 up = vec3(0.0, 1.0, 0.0);
    v_layer = 0;
    if (u_kind == 2) {
        float a = 3.14159265358979 * float(plane) / float(u_planes);
        d = xyl_forest_turn(vec3(sin(a), 0.0, cos(a)), cs);
        v_layer = plane;
    } else {
        vec3 to_eye = u_eye - center;
        if (u_kind == 1) to_eye.y = 0.0;
        d = dot(to_eye, to_eye) > 1e-12 ? normalize(to_eye) : vec3(0.0, 0.0, 1.0);
        if (u_kind == 0) {
            vec3 r = cross(up, d);
            up = dot(r, r) > 1e-8 ? normalize(cross(d, normalize(r))) : vec3(0.0, 0.0, -1.0);
        }
    }
    vec3 right = normalize(cross(up, d));
    vec3 p = center + cs.z * (u_half.x * st.x * right + u_half.y * st.y * up);
    gl_Position = u_view_proj * vec4(p, 1.0);
    v_uv = st * 0.5 + 0.5;
    v_right = right;
    v_up = up;
    v_facing = d;
    v_keep = xyl_forest_keep(inst.bits);
}

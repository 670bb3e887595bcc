// A forest's octahedral impostors (xyl_forest_gl.h): impostor.vert's quad and grid views for a
// run of sorted instances, one quad each. Everything the fragment stage computes happens in the
// instance's own frame (the species' coordinates the impostor was baked in): the eye and the
// light are turned and scaled into it and handed on flat, and only the quad's corner is placed
// into the world. Feeds impostor.frag built with XYL_FOREST.

layout(std430, binding = XYL_FOREST_GL_BINDING_INSTANCES) readonly buffer xyl_instance_buffer {
    xyl_forest_instance xyl_instances[];
};
layout(location = 0) uniform mat4 u_view_proj;
layout(location = 2) uniform vec3 u_center;
layout(location = 3) uniform float u_radius;
layout(location = 4) uniform int u_grid;
layout(location = XYL_FOREST_GL_UNIFORM_INSTANCE) uniform uint u_instance;
layout(location = XYL_FOREST_GL_UNIFORM_EYE) uniform vec3 u_world_eye;
layout(location = XYL_FOREST_GL_UNIFORM_LIGHT) uniform vec3 u_world_light;

layout(location = 0) out vec3 v_world; // the species' frame, as impostor.frag reads it
layout(location = 1) flat out ivec3 v_views;
layout(location = 2) flat out vec3 v_weights;
layout(location = 3) flat out vec3 v_eye;
layout(location = 4) flat out vec3 v_light;
layout(location = 5) flat out vec2 v_keep;

vec2 sign_not_zero(vec2 v)
{
    return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
}

void main()
{
    xyl_forest_instance inst = xyl_instances[u_instance + uint(gl_InstanceID)];
    vec3 cs = xyl_forest_rotation_scale(inst.bits);
    vec3 back = vec3(cs.x, -cs.y, 1.0); // the inverse turn
    v_eye = xyl_forest_turn((u_world_eye - inst.position) / cs.z, back);
    v_light = xyl_forest_turn(u_world_light, back);
    v_keep = xyl_forest_keep(inst.bits);

    vec2 st = vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0);
    vec3 to_eye = v_eye - u_center;
    float dist = length(to_eye);
    vec3 d = dist > 1e-6 * u_radius ? to_eye / dist : vec3(0.0, 0.0, 1.0);
    vec3 r = cross(vec3(0.0, 1.0, 0.0), d);
    vec3 right = dot(r, r) > 1e-8 ? normalize(r) : vec3(1.0, 0.0, 0.0);
    vec3 up = cross(d, right);
    float far = max(dist, 1.05 * u_radius);
    float half_side = u_radius * far / sqrt(far * far - u_radius * u_radius);
    v_world = u_center + half_side * (st.x * right + st.y * up);
    gl_Position = u_view_proj * vec4(xyl_forest_place(v_world, cs, inst.position), 1.0);

    vec2 o = d.xz / (abs(d.x) + abs(d.y) + abs(d.z));
    if (d.y < 0.0) o = (1.0 - abs(o.yx)) * sign_not_zero(o);
    vec2 g = (o * 0.5 + 0.5) * float(u_grid - 1);
    ivec2 c = clamp(ivec2(floor(g)), ivec2(0), ivec2(u_grid - 2));
    vec2 f = clamp(g - vec2(c), 0.0, 1.0);
    ivec2 a = c + ivec2(1, 0), b = c + ivec2(0, 1), n;
    if (f.x + f.y <= 1.0) {
        n = c;
        v_weights = vec3(1.0 - f.x - f.y, f.x, f.y);
    } else {
        n = c + ivec2(1, 1);
        v_weights = vec3(f.x + f.y - 1.0, 1.0 - f.y, 1.0 - f.x);
    }
    v_views = ivec3(n.x + n.y * u_grid, a.x + a.y * u_grid, b.x + b.y * u_grid);
}

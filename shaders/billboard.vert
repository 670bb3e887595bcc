// A tree's billboard (xyl_billboard_gl.h): quad q (gl_InstanceID) as a 4-vertex triangle strip,
// corner st = (v & 1 ? 1 : -1, v & 2 ? 1 : -1). Kind 0 (spherical) faces the eye, 1
// (cylindrical) turns about the vertical axis through u_center to face it, 2 (cross) is plane q
// of u_planes, at pi * q / u_planes about +Y. The quad's frame (right, up, towards the bake
// camera) goes to the fragment stage to turn the baked quad-space normals into world space.
// Vulkan (XYL_BILLBOARD, xyl_billboard_vk.h) reads the same values from its push constants and
// constants; with XYL_INSTANCES each quad is placed by a forest instance, as
// forest_billboard.vert places GL's: instance xyl_bpush.first + gl_InstanceIndex / planes,
// plane gl_InstanceIndex % planes.

#ifdef XYL_VULKAN
#define u_view_proj xyl_bpush.view_proj
#define u_eye xyl_bpush.eye.xyz
#define u_center xyl_bconst.center.xyz
#define u_half xyl_bconst.half_size
#define u_kind xyl_bconst.kind
#define u_planes xyl_bconst.planes
#define XYL_VERTEX gl_VertexIndex
#define XYL_INSTANCE gl_InstanceIndex
#ifdef XYL_INSTANCES
layout(std430, set = 0, binding = XYL_BILLBOARD_VK_BINDING_INSTANCES) readonly buffer
xyl_instance_buffer {
    xyl_forest_instance xyl_instances[];
};
#endif
#else
layout(location = 0) uniform mat4 u_view_proj;
layout(location = 1) uniform vec3 u_eye;
layout(location = 2) uniform vec3 u_center;
layout(location = 3) uniform vec2 u_half; // half width, half height
layout(location = 4) uniform int u_kind;
layout(location = 5) uniform int u_planes;
#define XYL_VERTEX gl_VertexID
#define XYL_INSTANCE gl_InstanceID
#endif

layout(location = 0) out vec2 v_uv;
layout(location = 1) flat out vec3 v_right;
layout(location = 2) flat out vec3 v_up;
layout(location = 3) flat out vec3 v_facing;
layout(location = 4) flat out int v_layer;

void main()
{
    vec2 st = vec2((XYL_VERTEX & 1) != 0 ? 1.0 : -1.0, (XYL_VERTEX & 2) != 0 ? 1.0 : -1.0);
#ifdef XYL_INSTANCES
    int planes = u_kind == 2 ? u_planes : 1;
    int plane = XYL_INSTANCE % planes;
    xyl_forest_instance inst = xyl_instances[xyl_bpush.first + uint(XYL_INSTANCE / planes)];
    vec3 cs = xyl_forest_rotation_scale(inst.bits);
    vec3 center = xyl_forest_place(u_center, cs, inst.position);
    float size = cs.z;
#else
    int plane = XYL_INSTANCE;
    vec3 center = u_center;
    float size = 1.0;
#endif
    vec3 d;
    vec3 up = vec3(0.0, 1.0, 0.0);
    v_layer = 0;
    if (u_kind == 2) {
        float a = 3.14159265358979 * float(plane) / float(u_planes);
        d = vec3(sin(a), 0.0, cos(a));
#ifdef XYL_INSTANCES
        d = xyl_forest_turn(d, cs);
#endif
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
    vec3 p = center + size * (u_half.x * st.x * right + u_half.y * st.y * up);
    gl_Position = u_view_proj * vec4(p, 1.0);
    v_uv = st * 0.5 + 0.5;
    v_right = right;
    v_up = up;
    v_facing = d;
}

// A tree's octahedral impostor (xyl_billboard_gl.h): one quad facing the eye (a 4-vertex
// triangle strip, corner st = (v & 1 ? 1 : -1, v & 2 ? 1 : -1)) through the centre of the tree's
// bounding sphere, large enough to cover the sphere's perspective outline. The direction towards
// the eye is encoded on the octahedron and the three grid views around it are handed on with
// their barycentric weights; the fragment stage blends them.

#ifdef XYL_VULKAN
#define u_view_proj xyl_bpush.view_proj
#define u_eye xyl_bpush.eye.xyz
#define u_center xyl_bconst.center.xyz
#define u_radius xyl_bconst.center.w
#define u_grid xyl_bconst.planes
#define XYL_VERTEX gl_VertexIndex
#else
layout(location = 0) uniform mat4 u_view_proj;
layout(location = 1) uniform vec3 u_eye;
layout(location = 2) uniform vec3 u_center;
layout(location = 3) uniform float u_radius;
layout(location = 4) uniform int u_grid;
#define XYL_VERTEX gl_VertexID
#endif

layout(location = 0) out vec3 v_world;
layout(location = 1) flat out ivec3 v_views; // grid views, column + row * u_grid
layout(location = 2) flat out vec3 v_weights;

vec2 sign_not_zero(vec2 v)
{
    return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
}

void main()
{
    vec2 st = vec2((XYL_VERTEX & 1) != 0 ? 1.0 : -1.0, (XYL_VERTEX & 2) != 0 ? 1.0 : -1.0);
    vec3 to_eye = u_eye - u_center;
    float dist = length(to_eye);
    vec3 d = dist > 1e-6 * u_radius ? to_eye / dist : vec3(0.0, 0.0, 1.0);
    vec3 r = cross(vec3(0.0, 1.0, 0.0), d);
    vec3 right = dot(r, r) > 1e-8 ? normalize(r) : vec3(1.0, 0.0, 0.0);
    vec3 up = cross(d, right);
    // the sphere's outline seen from dist cuts the quad's plane in a circle of radius
    // R dist / sqrt(dist^2 - R^2); from inside or nearly, 3 R
    float far = max(dist, 1.05 * u_radius);
    float half_side = u_radius * far / sqrt(far * far - u_radius * u_radius);
    v_world = u_center + half_side * (st.x * right + st.y * up);
    gl_Position = u_view_proj * vec4(v_world, 1.0);

    // octahedral encoding of d: x and z over the L1 norm, the lower half folded out
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

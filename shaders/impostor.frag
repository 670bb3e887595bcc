// A tree's octahedral impostor: for each of the three grid views the eye ray through this
// fragment meets the view's plane (through the centre, facing the view's direction), and that
// point's place in the view's orthographic frame is where the view is sampled in its atlas cell.
// Each view is relit as the billboards are (colour * shade(n, u_light) / shade(n, its bake
// direction)), and the views are blended by weight times coverage; colours are stored
// premultiplied by coverage.

layout(binding = 0) uniform sampler2D u_color_map;
layout(binding = 1) uniform sampler2D u_normal_map;
layout(location = 1) uniform vec3 u_eye;
layout(location = 2) uniform vec3 u_center;
layout(location = 3) uniform float u_radius;
layout(location = 4) uniform int u_grid;
layout(location = 6) uniform vec3 u_light;
layout(location = 7) uniform float u_cutoff;

layout(location = 0) in vec3 v_world;
layout(location = 1) flat in ivec3 v_views;
layout(location = 2) flat in vec3 v_weights;
layout(location = 0) out vec4 out_color;

float shade(vec3 n, vec3 l)
{
    float hemi = 0.5 + 0.5 * n.y;
    return 0.65 * max(dot(n, l), 0.0) + 0.35 * mix(0.35, 1.0, hemi);
}

vec2 sign_not_zero(vec2 v)
{
    return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
}

// the direction of grid view (column, row), as the bake computes it
vec3 grid_dir(ivec2 cell)
{
    vec2 o = vec2(cell) * (2.0 / float(u_grid - 1)) - 1.0;
    float y = 1.0 - abs(o.x) - abs(o.y);
    if (y < 0.0) o = (1.0 - abs(o.yx)) * sign_not_zero(o);
    return normalize(vec3(o.x, y, o.y));
}

void main()
{
    vec3 ray = v_world - u_eye;
    vec4 sum = vec4(0.0);
    for (int k = 0; k < 3; ++k) {
        int view = v_views[k];
        ivec2 cell = ivec2(view % u_grid, view / u_grid);
        vec3 d = grid_dir(cell);
        vec3 r = cross(vec3(0.0, 1.0, 0.0), d);
        vec3 right = dot(r, r) > 1e-8 ? normalize(r) : vec3(1.0, 0.0, 0.0);
        vec3 up = cross(d, right);
        float den = dot(ray, d);
        float t = abs(den) > 1e-8 ? dot(u_center - u_eye, d) / den : 0.0;
        vec3 hit = u_eye + t * ray - u_center;
        vec2 uv = vec2(dot(hit, right), dot(hit, up)) / (2.0 * u_radius) + 0.5;
        bool inside = den < 0.0 && all(greaterThanEqual(uv, vec2(0.0))) &&
                      all(lessThanEqual(uv, vec2(1.0)));
        vec2 at = (vec2(cell) + clamp(uv, 0.0, 1.0)) / float(u_grid);
        vec4 texel = texture(u_color_map, at);
        vec3 q = texture(u_normal_map, at).xyz * 2.0 - 1.0;
        vec3 n = normalize(q.x * right + q.y * up + q.z * d);
        float ratio = clamp(shade(n, u_light) / max(shade(n, d), 0.05), 0.0, 4.0);
        float w = inside ? v_weights[k] : 0.0;
        sum += w * vec4(texel.rgb * ratio, texel.a);
    }
    if (sum.a < u_cutoff) discard;
    out_color = vec4(min(sum.rgb / sum.a, vec3(1.0)), 1.0);
}

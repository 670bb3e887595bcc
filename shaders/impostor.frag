// A tree's octahedral impostor: for each of the three grid views the eye ray through this
// fragment is marched through the view's height field (the height over the view's plane,
// baked in the normal map's alpha) to the surface the view saw, and that point's place in the
// view's orthographic frame is where the view is sampled in its atlas cell (parallax
// correction: the three views then agree on where a branch is). Each view is relit as the billboards are (colour * shade(n, u_light) / shade(n, its bake
// direction)), and the views are blended by weight times coverage; colours are stored
// premultiplied by coverage.

#ifdef XYL_VULKAN
layout(set = 0, binding = XYL_BILLBOARD_VK_BINDING_COLOR) uniform sampler2D u_color_map;
layout(set = 0, binding = XYL_BILLBOARD_VK_BINDING_NORMAL) uniform sampler2D u_normal_map;
#define u_eye xyl_bpush.eye.xyz
#define u_center xyl_bconst.center.xyz
#define u_radius xyl_bconst.center.w
#define u_grid xyl_bconst.planes
#define u_light xyl_bpush.light.xyz
#define u_cutoff xyl_bpush.eye.w
#define u_bake_light xyl_bconst.bake_light.xyz
#define u_to_coverage xyl_bconst.to_coverage
#define u_dither xyl_bpush.dither
#else
layout(binding = 0) uniform sampler2D u_color_map;
layout(binding = 1) uniform sampler2D u_normal_map;
#ifdef XYL_FOREST
// forest_impostor.vert: the eye and the light in the instance's own frame, its fade share
layout(location = 3) flat in vec3 v_eye;
layout(location = 4) flat in vec3 v_light;
layout(location = 5) flat in vec2 v_keep;
#define u_eye v_eye
#define u_light v_light
#else
layout(location = 1) uniform vec3 u_eye;
#endif
layout(location = 2) uniform vec3 u_center;
layout(location = 3) uniform float u_radius;
layout(location = 4) uniform int u_grid;
#ifndef XYL_FOREST
layout(location = 6) uniform vec3 u_light;
#endif
layout(location = 7) uniform float u_cutoff;
layout(location = 8) uniform vec3 u_bake_light; // all 0: each view lit from its own camera
// 1 in a multisampled target: alpha (the filtered coverage) goes to alpha-to-coverage
layout(location = 9) uniform int u_to_coverage;
layout(location = 10) uniform vec2 u_dither; // a cross-fade's keep range (xyl_dither.h)
#endif

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

// where a point (relative to the centre) projects in a view's picture, [0, 1]^2 over the square
vec2 view_uv(vec3 p, vec3 right, vec3 up)
{
    return vec2(dot(p, right), dot(p, up)) / (2.0 * u_radius) + 0.5;
}

const int STEPS = 32;

void main()
{
    if (!xyl_dither_keeps(gl_FragCoord.xy, u_dither)) discard;
#ifdef XYL_FOREST
    if (!xyl_dither_keeps(gl_FragCoord.xy, v_keep)) discard;
#endif
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
        float t0 = abs(den) > 1e-8 ? dot(u_center - u_eye, d) / den : 0.0;
        vec2 uv0 = view_uv(u_eye + t0 * ray - u_center, right, up);
        vec2 gx = dFdx(uv0) / float(u_grid), gy = dFdy(uv0) / float(u_grid);
        // parallax: march the eye's ray down through the view's slab of heights [R, -R] and
        // stop at the first point under the height baked where it projects, on a covered
        // texel; a ray that meets nothing in this view takes no coverage from it
        vec2 uv = uv0;
        bool found = false;
        for (int i = 0; i <= STEPS && den < -1e-8; ++i) {
            float s = u_radius * (1.0 - 2.0 * float(i) / float(STEPS));
            vec2 ui = view_uv(u_eye + (t0 + s / den) * ray - u_center, right, up);
            if (any(lessThan(ui, vec2(0.0))) || any(greaterThan(ui, vec2(1.0)))) continue;
            vec2 ai = (vec2(cell) + ui) / float(u_grid);
            float h = (textureLod(u_normal_map, ai, 0.0).a * 2.0 - 1.0) * u_radius;
            if (textureLod(u_color_map, ai, 0.0).a > 0.5 && h >= s - u_radius / float(STEPS)) {
                uv = view_uv(u_eye + (t0 + h / den) * ray - u_center, right, up);
                found = true;
                break;
            }
        }
        vec2 at = (vec2(cell) + clamp(uv, 0.0, 1.0)) / float(u_grid);
        vec4 texel = textureGrad(u_color_map, at, gx, gy);
        vec3 q = textureGrad(u_normal_map, at, gx, gy).xyz * 2.0 - 1.0;
        vec3 n = normalize(q.x * right + q.y * up + q.z * d);
        vec3 bake = dot(u_bake_light, u_bake_light) > 0.0 ? u_bake_light : d;
        float ratio = clamp(shade(n, u_light) / max(shade(n, bake), 0.05), 0.0, 4.0);
        float w = found ? v_weights[k] : 0.0;
        sum += w * vec4(texel.rgb * ratio, texel.a);
    }
    if (sum.a < (u_to_coverage != 0 ? 1.0 / 255.0 : u_cutoff)) discard;
    out_color = vec4(min(sum.rgb / sum.a, vec3(1.0)), u_to_coverage != 0 ? sum.a : 1.0);
}

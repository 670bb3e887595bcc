// A tree's billboard, alpha-tested and relit: the bake lit the tree from u_bake_light (all 0:
// from its camera), so a texel's colour is albedo * shade(n, bake light); it is drawn as
// colour * shade(n, u_light) / shade(n, bake light), shade being the stems'
// Lambert-plus-sky term (tess_shade.frag), n the baked normal turned into world space. The
// colour is stored premultiplied by coverage, so a filtered texel's colour is texel.rgb / texel.a.

#ifdef XYL_VULKAN
layout(set = 0, binding = XYL_BILLBOARD_VK_BINDING_COLOR) uniform sampler2DArray u_color_map;
layout(set = 0, binding = XYL_BILLBOARD_VK_BINDING_NORMAL) uniform sampler2DArray u_normal_map;
#define u_light xyl_bpush.light.xyz
#define u_cutoff xyl_bpush.eye.w
#define u_bake_light xyl_bconst.bake_light.xyz
#define u_to_coverage xyl_bconst.to_coverage
#define u_dither xyl_bpush.dither
#else
layout(binding = 0) uniform sampler2DArray u_color_map;
layout(binding = 1) uniform sampler2DArray u_normal_map;
layout(location = 6) uniform vec3 u_light;
layout(location = 7) uniform float u_cutoff;
layout(location = 8) uniform vec3 u_bake_light; // all 0: each view lit from its own camera
// 1 in a multisampled target: alpha (the filtered coverage) goes to alpha-to-coverage
layout(location = 9) uniform int u_to_coverage;
layout(location = 10) uniform vec2 u_dither; // a cross-fade's keep range (xyl_dither.h)
#endif

layout(location = 0) in vec2 v_uv;
layout(location = 1) flat in vec3 v_right;
layout(location = 2) flat in vec3 v_up;
layout(location = 3) flat in vec3 v_facing;
layout(location = 4) flat in int v_layer;
#ifdef XYL_FOREST
layout(location = 5) flat in vec2 v_keep; // forest_billboard.vert: the instance's fade share
#endif
layout(location = 0) out vec4 out_color;

float shade(vec3 n, vec3 l)
{
    float hemi = 0.5 + 0.5 * n.y;
    return 0.65 * max(dot(n, l), 0.0) + 0.35 * mix(0.35, 1.0, hemi);
}

void main()
{
    // seen from behind, a cross plane shows its view mirrored: u runs the other way in the
    // quad's frame, and the normals' z points away from this side
    if (!xyl_dither_keeps(gl_FragCoord.xy, u_dither)) discard;
#ifdef XYL_FOREST
    if (!xyl_dither_keeps(gl_FragCoord.xy, v_keep)) discard;
#endif
    vec4 texel = texture(u_color_map, vec3(v_uv, float(v_layer)));
    if (texel.a < (u_to_coverage != 0 ? 1.0 / 255.0 : u_cutoff)) discard;
    vec3 q = texture(u_normal_map, vec3(v_uv, float(v_layer))).xyz * 2.0 - 1.0;
    float side = gl_FrontFacing ? 1.0 : -1.0;
    vec3 n = normalize(q.x * v_right + q.y * v_up + side * q.z * v_facing);
    vec3 bake_dir = dot(u_bake_light, u_bake_light) > 0.0 ? u_bake_light : side * v_facing;
    float ratio = shade(n, u_light) / max(shade(n, bake_dir), 0.05);
    vec3 albedo_lit = texel.rgb / texel.a; // stored premultiplied by coverage
    out_color = vec4(min(albedo_lit * clamp(ratio, 0.0, 4.0), vec3(1.0)),
                     u_to_coverage != 0 ? texel.a : 1.0);
}

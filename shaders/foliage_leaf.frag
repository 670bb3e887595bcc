
// Alpha-tested, double-sided leaves: the side facing the viewer is lit by Lambert's law plus a
// sky/ground hemisphere term (as the stems are), and light arriving from behind shines through
// the blade, tinted yellow-green, in proportion to u_translucency. A cross-fade keeps only the
// pixels of its dither range (xyl_dither.h).

#ifdef XYL_VULKAN
layout(set = 0, binding = XYL_FOLIAGE_VK_BINDING_TEXTURE) uniform sampler2D u_texture;
#define u_light xyl_push.light.xyz
#define u_color xyl_push.color
#define u_cutoff xyl_push.cutoff
#define u_translucency xyl_push.translucency
#define u_dither xyl_push.dither
#else
layout(binding = XYL_FOLIAGE_GL_BINDING_TEXTURE) uniform sampler2D u_texture;
layout(location = XYL_FOLIAGE_GL_UNIFORM_LIGHT) uniform vec3 u_light;
layout(location = XYL_FOLIAGE_GL_UNIFORM_COLOR) uniform vec4 u_color;
layout(location = XYL_FOLIAGE_GL_UNIFORM_CUTOFF) uniform float u_cutoff;
layout(location = XYL_FOLIAGE_GL_UNIFORM_TRANSLUCENCY) uniform float u_translucency;
layout(location = XYL_FOLIAGE_GL_UNIFORM_DITHER) uniform vec2 u_dither;
#endif

layout(location = 0) in vec3 v_normal;
layout(location = 1) in vec2 v_uv;
#ifdef XYL_FOREST
layout(location = 2) flat in vec2 v_keep; // forest_leaf.vert: the instance's fade share
#endif
layout(location = 0) out vec4 out_color;

void main()
{
    if (!xyl_dither_keeps(gl_FragCoord.xy, u_dither)) discard; // a cross-fade's share
#ifdef XYL_FOREST
    if (!xyl_dither_keeps(gl_FragCoord.xy, v_keep)) discard;
#endif
    // The image is stored top row first, as image files are, with the tip end (v = 1) at the
    // top; t = 0 is the first row stored, in GL and in Vulkan alike.
    vec4 texel = texture(u_texture, vec2(v_uv.x, 1.0 - v_uv.y));
    if (texel.a < u_cutoff) discard;
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) n = -n;
    float facing = dot(n, u_light);
    float diffuse = max(facing, 0.0);
    float through = u_translucency * max(-facing, 0.0);
    float hemi = 0.5 + 0.5 * n.y;
    vec3 base = texel.rgb * u_color.rgb;
    vec3 rgb = base * (0.65 * diffuse + 0.35 * mix(0.6, 1.0, hemi)) +
               base * vec3(1.1, 1.2, 0.55) * through;
    out_color = vec4(min(rgb, vec3(1.0)), 1.0);
}

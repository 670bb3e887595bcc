// A forest's stems, shaded as tess_shade.frag shades the tessellated ones: Lambert from one
// light plus a sky/ground hemisphere term, back faces with the flipped normal; an instance's
// copy in a cross-fade keeps its share of the pixels (xyl_dither.h).

layout(location = XYL_FOLIAGE_GL_UNIFORM_LIGHT) uniform vec3 u_light;
layout(location = XYL_FOREST_GL_UNIFORM_STEM_COLOR) uniform vec4 u_stem_color;

layout(location = 0) in vec3 v_normal;
layout(location = 1) flat in vec2 v_keep;
layout(location = 0) out vec4 out_color;

void main()
{
    if (!xyl_dither_keeps(gl_FragCoord.xy, v_keep)) discard;
    vec3 n = dot(v_normal, v_normal) > 1e-12 ? normalize(v_normal) : vec3(0.0, 1.0, 0.0);
    if (!gl_FrontFacing) n = -n;
    float diffuse = max(dot(n, u_light), 0.0);
    float hemi = 0.5 + 0.5 * n.y;
    out_color = vec4(u_stem_color.rgb * (0.65 * diffuse + 0.35 * mix(0.35, 1.0, hemi)), 1.0);
}

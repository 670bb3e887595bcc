// A simple lit material: Lambert from one directional light plus a sky/ground hemisphere term.
// Back faces (seen through a crack or from inside) are lit with the flipped normal.

layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 0) out vec4 out_color;

void main()
{
    if (!xyl_dither_keeps(gl_FragCoord.xy, xyl_tess_keep(xyl_frame.dither))) discard;
    if ((xyl_frame.flags & XYL_TESS_FLAG_WIREFRAME) != 0u) {
        out_color = xyl_frame.line_color;
        return;
    }
    if ((xyl_frame.flags & XYL__TESS_FLAG_BACKFACES) != 0u && !gl_FrontFacing) {
        out_color = vec4(1.0, 0.0, 0.0, 1.0);
        return;
    }
    vec3 n = xyl_normalize_or(v_normal, vec3(0.0, 1.0, 0.0));
    if (!gl_FrontFacing) n = -n;
    float diffuse = max(dot(n, xyl_frame.light_dir.xyz), 0.0);
    float hemi = 0.5 + 0.5 * n.y;
    vec3 rgb = xyl_frame.color.rgb * (0.65 * diffuse + 0.35 * mix(0.35, 1.0, hemi));
    out_color = vec4(rgb, 1.0);
}

// Hardware tessellation path, evaluation stage: the instanced path's formulas. A point on a
// patch side is turned back into its index k of the side's level and evaluated by the same
// canonical edge function, so shared sides match the neighbour and the instanced path.
#ifdef XYL_TRIANGLES
layout(triangles, equal_spacing, ccw) in;
#else
layout(quads, equal_spacing, ccw) in;
#endif

patch in uvec4 tc_instance;

layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec3 v_tess_coord; // for capture by transform feedback
layout(location = 3) flat out uint v_patch;   // likewise: which patch a captured vertex is on

bool xyl_side_point(vec3 tc, out uint e, out float t)
{
    e = 0u; t = 0.0;
#ifdef XYL_TRIANGLES
    if (tc.z == 0.0) { e = 0u; t = tc.y; return true; }
    if (tc.x == 0.0) { e = 1u; t = tc.z; return true; }
    if (tc.y == 0.0) { e = 2u; t = tc.x; return true; }
#else
    if (tc.y == 0.0) { e = 0u; t = tc.x; return true; }
    if (tc.x == 1.0) { e = 1u; t = tc.y; return true; }
    if (tc.y == 1.0) { e = 2u; t = 1.0 - tc.x; return true; }
    if (tc.x == 0.0) { e = 3u; t = 1.0 - tc.y; return true; }
#endif
    return false;
}

void main()
{
    uvec4 inst = tc_instance;
    vec3 c[4], n[4], a[4];
    xyl_load_patch(inst.x, xyl_frame.variant, c, n, a);
    vec3 tc = gl_TessCoord;
    vec3 pos, nrm;
    uint e;
    float t;
    if (xyl_side_point(tc, e, t)) {
        uint le = (inst.y >> (XYL_TESS_EDGE_LEVEL_BITS * e)) & 0xffu;
        uint k = uint(round(t * float(le)));
        uint e1 = (e + 1u == inst.w) ? 0u : e + 1u;
        xyl_eval_edge(c[e], n[e], a[e], c[e1], n[e1], a[e1], k, le, xyl_frame.variant, pos, nrm);
    } else {
#ifdef XYL_TRIANGLES
        xyl_eval_triangle(c, n, a, tc.x, tc.y, tc.z, xyl_frame.variant, pos, nrm);
#else
        xyl_eval_quad(c, n, a, tc.x, tc.y, xyl_frame.variant, pos, nrm);
#endif
    }
    v_position = pos;
    v_normal = nrm;
    v_tess_coord = tc;
    v_patch = inst.x;
    gl_Position = xyl_frame.view_proj * vec4(pos, 1.0);
}

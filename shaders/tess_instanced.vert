// Instanced tessellation (Boubekeur & Schlick 2005): one pattern per level drawn once per patch;
// each pattern vertex is a lattice point evaluated on the instance's patch.

layout(location = 0) in uint in_lattice;   // i | j << 8 | local << 16
layout(location = 1) in uvec4 in_instance; // patch, edge levels, level, kind

layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;

void main()
{
    vec3 c[4], n[4], a[4];
    xyl_load_patch(in_instance.x, xyl_frame.variant, c, n, a);
    uint i = in_lattice & 0xffu;
    uint j = (in_lattice >> XYL_TESS_PATTERN_SHIFT_J) & 0xffu;
    vec3 pos, nrm;
    xyl_eval_lattice(c, n, a, in_instance.w, in_instance.z, in_instance.y, i, j, xyl_frame.variant,
                     pos, nrm);
#ifdef XYL_CAPTURE
    uint slot = xyl_capture_offsets[in_instance.x] + (in_lattice >> XYL_TESS_PATTERN_SHIFT_LOCAL);
    xyl_captured[2u * slot] = vec4(pos, 1.0);
    xyl_captured[2u * slot + 1u] = vec4(nrm, 0.0);
#endif
    v_position = pos;
    v_normal = nrm;
    gl_Position = xyl_frame.view_proj * vec4(pos, 1.0);
}

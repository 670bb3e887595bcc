// Resources shared by the refinement stages (after xyl_tess_shared.h and xyl_tess_eval.glsl).

layout(std430, binding = XYL_TESS_BINDING_PATCHES) readonly buffer xyl_patch_buffer {
    xyl_tess_patch xyl_patches[];
};

layout(std140, binding = XYL_TESS_BINDING_FRAME) uniform xyl_frame_block {
    xyl_tess_frame xyl_frame;
};

#ifdef XYL_CAPTURE
// Debug readback: each evaluated vertex writes (position, 1) and (normal, 0) at slot
// xyl_capture_offsets[patch] + local index, for comparison with the CPU reference.
layout(std430, binding = XYL_TESS_BINDING_CAPTURE) writeonly buffer xyl_capture_buffer {
    vec4 xyl_captured[];
};
layout(std430, binding = XYL_TESS_BINDING_OFFSETS) readonly buffer xyl_offset_buffer {
    uint xyl_capture_offsets[];
};
#endif

// A patch's corners. Only the arc rule reads the corners' axes, so the other variants (a uniform
// branch) skip their decoding, a cosine and a sine per corner per lattice vertex.
void xyl_load_patch(uint index, uint variant, out vec3 c[4], out vec3 n[4], out vec3 a[4])
{
    bool axes = variant == uint(XYL_TESS_VARIANT_ARC);
    for (int k = 0; k < 4; ++k) {
        c[k] = xyl_patches[index].p[k].xyz;
        vec4 nk = xyl_patches[index].n[k];
        n[k] = nk.xyz;
        a[k] = axes ? xyl_tess_axis(nk.xyz, nk.w) : vec3(0.0);
    }
}

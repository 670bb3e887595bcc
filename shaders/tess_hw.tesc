// Hardware tessellation path, control stage: levels from the same instance records as the
// instanced path (edge e of the patch -> the hardware's outer level for that side).
#ifdef XYL_TRIANGLES
layout(vertices = 3) out;
#else
layout(vertices = 4) out;
#endif

layout(std430, binding = XYL_TESS_BINDING_INSTANCES) readonly buffer xyl_instance_buffer {
    uvec4 xyl_instances[];
};

layout(location = 0) in uint vs_vertex[]; // index in the draw (tess_hw.vert)

patch out uvec4 tc_instance;

void main()
{
    if (gl_InvocationID != 0) return;
    uint patch_in_draw = vs_vertex[0] / uint(gl_PatchVerticesIn);
    uvec4 inst = xyl_instances[xyl_frame.base_instance + patch_in_draw];
    tc_instance = inst;
    float le[4];
    for (uint e = 0u; e < 4u; ++e)
        le[e] = float((inst.y >> (XYL_TESS_EDGE_LEVEL_BITS * e)) & 0xffu);
#ifdef XYL_TRIANGLES
    // triangle domain: outer[0] is the side opposite corner 0 (our edge 1), outer[1] opposite
    // corner 1 (edge 2), outer[2] opposite corner 2 (edge 0)
    gl_TessLevelOuter[0] = le[1];
    gl_TessLevelOuter[1] = le[2];
    gl_TessLevelOuter[2] = le[0];
    gl_TessLevelInner[0] = float(inst.z);
#else
    // quad domain: outer[0] is u = 0 (edge 3), [1] v = 0 (edge 0), [2] u = 1 (edge 1), [3] v = 1
    gl_TessLevelOuter[0] = le[3];
    gl_TessLevelOuter[1] = le[0];
    gl_TessLevelOuter[2] = le[1];
    gl_TessLevelOuter[3] = le[2];
    gl_TessLevelInner[0] = float(inst.z);
    gl_TessLevelInner[1] = float(inst.z);
#endif
}

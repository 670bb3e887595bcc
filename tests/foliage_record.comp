// A compute shader that reads every field of xyl_foliage_gpu_leaf through the helpers of
// shaders/xyl_foliage_shared.h, which tests/foliage_glsl.cmake puts in front of it (after
// "#version 450" and "#define XYL_GLSL 1"): the GLSL half must compile, and glslang's offsets
// must be the ones the C half pins.
layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Leaves {
    xyl_foliage_gpu_leaf leaves[];
};

// per leaf: 4 corners (xyz, u) and the normal (xyz, v of the first corner)
layout(std430, binding = 1) writeonly buffer Corners {
    vec4 corners[];
};

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(leaves.length())) return;
    xyl_foliage_gpu_leaf l = leaves[i];
    const vec2 st[4] = vec2[4](vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0));
    for (int c = 0; c < 4; ++c)
        corners[5u * i + uint(c)] = vec4(xyl_foliage_corner(l, st[c]),
                                         xyl_foliage_corner_uv(l, st[c]).x);
    corners[5u * i + 4u] = vec4(xyl_foliage_normal(l), xyl_foliage_corner_uv(l, st[0]).y);
}

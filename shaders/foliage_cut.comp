// The per-leaf cut of the collapse forest (xyl_foliage_cut in double on the CPU; docs/foliage.md,
// "Per-leaf LOD"): one invocation a node (a record of the leaf array). A node is drawn when its
// error is within the budget from the eye and no ancestor's is: the topmost node within the
// budget on every path from an original to its root, a valid cut whatever the errors. Drawn
// nodes append their record index to the list and count the indirect draw's instances up.

layout(local_size_x = XYL_FOLIAGE_GL_CUT_GROUP) in;

struct xyl_cut_node {
    vec4 sphere;  // centre, radius: the quad's half diagonal grown by the error
    float error;  // world units, 0 for an original
    int parent;   // -1 for a root
    uint pad0, pad1;
};

#ifdef XYL_VULKAN // set 0 of the leaf renderer, the values in push constants
#define XYL_CUT_BINDING(gl, vk) set = 0, binding = vk
layout(push_constant) uniform xyl_foliage_vk_cut_push {
    vec3 eye;
    float per_distance;
    uint count;
} xyl_cut;
#define u_eye xyl_cut.eye
#define u_per_distance xyl_cut.per_distance
#define u_count xyl_cut.count
#else
#define XYL_CUT_BINDING(gl, vk) binding = gl
layout(location = XYL_FOLIAGE_GL_UNIFORM_CUT_EYE) uniform vec3 u_eye;
layout(location = XYL_FOLIAGE_GL_UNIFORM_CUT_PER_DISTANCE) uniform float u_per_distance;
layout(location = XYL_FOLIAGE_GL_UNIFORM_CUT_COUNT) uniform uint u_count;
#endif

layout(std430, XYL_CUT_BINDING(XYL_FOLIAGE_GL_BINDING_NODES, XYL_FOLIAGE_VK_BINDING_NODES))
    readonly buffer xyl_node_buffer {
    xyl_cut_node xyl_nodes[];
};
layout(std430, XYL_CUT_BINDING(XYL_FOLIAGE_GL_BINDING_LIST, XYL_FOLIAGE_VK_BINDING_LIST))
    writeonly buffer xyl_list_buffer {
    uint xyl_list[];
};
// the indirect draw command (GL's glDrawArraysIndirect and Vulkan's VkDrawIndirectCommand
// alike): vertex count (4), instance count, first vertex, first instance
layout(std430, XYL_CUT_BINDING(XYL_FOLIAGE_GL_BINDING_COMMAND, XYL_FOLIAGE_VK_BINDING_COMMAND))
    buffer xyl_command_buffer {
    uint xyl_command[4];
};

bool within_budget(uint k)
{
    xyl_cut_node n = xyl_nodes[k];
    float d = length(u_eye - n.sphere.xyz) - n.sphere.w;
    return n.error <= u_per_distance * max(d, 0.0);
}

void main()
{
    uint k = gl_GlobalInvocationID.x;
    if (k >= u_count || !within_budget(k)) return;
    int p = xyl_nodes[k].parent;
    for (uint steps = 0u; p >= 0 && steps < u_count; ++steps) {
        if (within_budget(uint(p))) return; // an ancestor stands for this node's originals
        p = xyl_nodes[p].parent;
    }
    uint at = atomicAdd(xyl_command[1], 1u);
    xyl_list[at] = k;
}

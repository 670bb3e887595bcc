// Hardware tessellation path, wireframe overlay: each tessellated front-facing triangle becomes
// its three edges as a line strip. Drawing the edges this way, rather than rasterising the
// triangles with glPolygonMode(GL_LINE), is a workaround: llvmpipe (Mesa 22.3) draws stray lines
// across the image in line mode after tessellation. Line primitives get no polygon offset, so
// the edges are pulled towards the viewer here by the same small depth offset instead.
layout(triangles) in;
layout(line_strip, max_vertices = 4) out;

layout(location = 0) in vec3 g_position[];
layout(location = 1) in vec3 g_normal[];
layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;

void main()
{
    vec4 p0 = gl_in[0].gl_Position, p1 = gl_in[1].gl_Position, p2 = gl_in[2].gl_Position;
    if (!(p0.w > 0.0 && p1.w > 0.0 && p2.w > 0.0)) return; // crosses the eye plane
    vec2 a = p0.xy / p0.w, b = p1.xy / p1.w, c = p2.xy / p2.w;
    if ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x) <= 0.0) return; // back face
    for (int i = 0; i < 4; ++i) {
        int k = i == 3 ? 0 : i;
        vec4 p = gl_in[k].gl_Position;
        gl_Position = vec4(p.xy, p.z - 2e-4 * p.w, p.w);
        v_position = g_position[k];
        v_normal = g_normal[k];
        EmitVertex();
    }
    EndPrimitive();
}

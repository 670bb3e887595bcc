// Hardware tessellation path: a vertex carries only its index in the draw, from which the
// control stage finds the patch's instance record. (gl_PrimitiveID would do by the spec, but
// llvmpipe restarts it every 4096 vertices of a draw, and gl_VertexID it gets right.)
layout(location = 0) out uint vs_vertex;

void main()
{
    vs_vertex = uint(gl_VertexID);
    gl_Position = vec4(0.0);
}

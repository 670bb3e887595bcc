/* The shaders embedded at build time (cmake/XylemShaders.cmake): NUL-terminated GLSL text for
 * the GL backend, SPIR-V words for Vulkan (4-byte aligned; _size in bytes, without the NUL). */
#ifndef XYL_SHADER_SOURCES_H
#define XYL_SHADER_SOURCES_H

#include <stddef.h>

#define XYL__SHADER(name)                        \
    extern const unsigned char xyl__shader_##name[]; \
    extern const size_t xyl__shader_##name##_size;

XYL__SHADER(gl_instanced_vert)
XYL__SHADER(gl_instanced_capture_vert)
XYL__SHADER(gl_shade_frag)
XYL__SHADER(gl_hw_vert)
XYL__SHADER(gl_hw_quad_tesc)
XYL__SHADER(gl_hw_quad_tese)
XYL__SHADER(gl_hw_tri_tesc)
XYL__SHADER(gl_hw_tri_tese)
XYL__SHADER(gl_hw_edges_geom)
XYL__SHADER(vk_instanced_vert)
XYL__SHADER(vk_instanced_capture_vert)
XYL__SHADER(vk_shade_frag)

#undef XYL__SHADER

#endif /* XYL_SHADER_SOURCES_H */

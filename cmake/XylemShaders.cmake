# GLSL in shaders/ -> complete stage sources (one prefix of #version and #defines, the shared
# header and the debug flags' header, the evaluation code, the resources, the stage) ->
# embedded C arrays: GLSL text for the GL backend, SPIR-V from glslangValidator for Vulkan. glslangValidator also validates every GL
# stage at build time, so a shader that does not compile fails the build, not a test run.
find_program(XYL_GLSLANG glslangValidator REQUIRED)
set(XYL_SHADER_DIR ${PROJECT_SOURCE_DIR}/shaders)
set(XYL_SHADER_OUT ${PROJECT_BINARY_DIR}/shaders)
file(MAKE_DIRECTORY ${XYL_SHADER_OUT})
set(XYL_SHADER_COMMON ${XYL_SHADER_DIR}/xyl_dither.h ${XYL_SHADER_DIR}/xyl_tess_shared.h ${XYL_SHADER_DIR}/xyl_tess_debug.h
    ${XYL_SHADER_DIR}/xyl_tess_eval.glsl ${XYL_SHADER_DIR}/xyl_tess_io.glsl)

# The foliage module's GL shaders read the leaf record only (foliage/ does not see tessellate/).
set(XYL_FOLIAGE_SHADER_COMMON ${XYL_SHADER_DIR}/xyl_dither.h ${XYL_SHADER_DIR}/xyl_foliage_shared.h)

# xyl_shader(<name> <stage file> <gl|vulkan|gl_foliage|vk_foliage> [DEFINE...]): appends the
# generated C file to XYL_GL_SHADER_SOURCES, XYL_VK_SHADER_SOURCES, or (the *_foliage kinds:
# assembled with the leaf record's header) XYL_FOLIAGE_GL_SHADER_SOURCES (GLSL text) or
# XYL_FOLIAGE_VK_SHADER_SOURCES (SPIR-V); the symbol is xyl__shader_<name>.
function(xyl_shader name stage api)
  set(common ${XYL_SHADER_COMMON})
  if(api MATCHES "_foliage$")
    set(common ${XYL_FOLIAGE_SHADER_COMMON})
  endif()
  get_filename_component(ext ${stage} LAST_EXT)
  string(SUBSTRING ${ext} 1 -1 ext)
  set(prefix_text "#version 450\n#define XYL_GLSL 1\n")
  if(api STREQUAL "vulkan" OR api STREQUAL "vk_foliage")
    string(APPEND prefix_text "#define XYL_VULKAN 1\n")
  endif()
  foreach(d IN LISTS ARGN)
    string(APPEND prefix_text "#define ${d} 1\n")
  endforeach()
  set(prefix ${XYL_SHADER_OUT}/${name}.prefix)
  file(CONFIGURE OUTPUT ${prefix} CONTENT "${prefix_text}" @ONLY)
  set(src ${XYL_SHADER_OUT}/${name}.${ext})
  set(inputs ${common} ${XYL_SHADER_DIR}/${stage})
  string(REPLACE ";" "\\;" inputs_arg "${inputs}")
  add_custom_command(OUTPUT ${src}
    COMMAND ${CMAKE_COMMAND} -DOUT=${src} -DPREFIX_FILE=${prefix} -DIN=${inputs_arg}
            -P ${PROJECT_SOURCE_DIR}/cmake/xyl_concat.cmake
    DEPENDS ${inputs} ${prefix} ${PROJECT_SOURCE_DIR}/cmake/xyl_concat.cmake
    COMMENT "Assembling shader ${name}.${ext}" VERBATIM)
  set(c_out ${XYL_SHADER_OUT}/xyl_shader_${name}.c)
  if(api STREQUAL "gl" OR api STREQUAL "gl_foliage")
    add_custom_command(OUTPUT ${c_out}
      COMMAND ${XYL_GLSLANG} --quiet ${src}
      COMMAND ${CMAKE_COMMAND} -DOUT=${c_out} -DNAME=xyl__shader_${name} -DIN=${src}
              -P ${PROJECT_SOURCE_DIR}/cmake/xyl_embed.cmake
      DEPENDS ${src} ${PROJECT_SOURCE_DIR}/cmake/xyl_embed.cmake
      COMMENT "Validating and embedding GLSL ${name}" VERBATIM)
    if(api STREQUAL "gl")
      set(XYL_GL_SHADER_SOURCES ${XYL_GL_SHADER_SOURCES} ${c_out} PARENT_SCOPE)
    else()
      set(XYL_FOLIAGE_GL_SHADER_SOURCES ${XYL_FOLIAGE_GL_SHADER_SOURCES} ${c_out} PARENT_SCOPE)
    endif()
  else()
    set(spv ${XYL_SHADER_OUT}/${name}.spv)
    add_custom_command(OUTPUT ${c_out}
      COMMAND ${XYL_GLSLANG} --quiet -V --target-env vulkan1.2 -o ${spv} ${src}
      COMMAND ${CMAKE_COMMAND} -DOUT=${c_out} -DNAME=xyl__shader_${name} -DIN=${spv}
              -P ${PROJECT_SOURCE_DIR}/cmake/xyl_embed.cmake
      DEPENDS ${src} ${PROJECT_SOURCE_DIR}/cmake/xyl_embed.cmake
      BYPRODUCTS ${spv}
      COMMENT "Compiling ${name} to SPIR-V" VERBATIM)
    if(api STREQUAL "vulkan")
      set(XYL_VK_SHADER_SOURCES ${XYL_VK_SHADER_SOURCES} ${c_out} PARENT_SCOPE)
    else()
      set(XYL_FOLIAGE_VK_SHADER_SOURCES ${XYL_FOLIAGE_VK_SHADER_SOURCES} ${c_out} PARENT_SCOPE)
    endif()
    set(XYL_VK_SPIRV ${XYL_VK_SPIRV} ${spv} PARENT_SCOPE)
  endif()
endfunction()

set(XYL_GL_SHADER_SOURCES)
set(XYL_VK_SHADER_SOURCES)
set(XYL_VK_SPIRV)
set(XYL_FOLIAGE_GL_SHADER_SOURCES)
set(XYL_FOLIAGE_VK_SHADER_SOURCES)
xyl_shader(gl_instanced_vert tess_instanced.vert gl)
xyl_shader(gl_instanced_capture_vert tess_instanced.vert gl XYL_CAPTURE)
xyl_shader(gl_shade_frag tess_shade.frag gl)
xyl_shader(gl_hw_vert tess_hw.vert gl)
xyl_shader(gl_hw_quad_tesc tess_hw.tesc gl)
xyl_shader(gl_hw_quad_tese tess_hw.tese gl)
xyl_shader(gl_hw_tri_tesc tess_hw.tesc gl XYL_TRIANGLES)
xyl_shader(gl_hw_tri_tese tess_hw.tese gl XYL_TRIANGLES)
xyl_shader(gl_hw_edges_geom tess_hw_edges.geom gl)
xyl_shader(vk_instanced_vert tess_instanced.vert vulkan)
xyl_shader(vk_instanced_capture_vert tess_instanced.vert vulkan XYL_CAPTURE)
xyl_shader(vk_shade_frag tess_shade.frag vulkan)
xyl_shader(gl_foliage_leaf_vert foliage_leaf.vert gl_foliage)
xyl_shader(gl_foliage_leaf_frag foliage_leaf.frag gl_foliage)
xyl_shader(gl_foliage_cut_comp foliage_cut.comp gl_foliage)
xyl_shader(gl_billboard_vert billboard.vert gl_foliage)
xyl_shader(gl_billboard_frag billboard.frag gl_foliage)
xyl_shader(gl_impostor_vert impostor.vert gl_foliage)
xyl_shader(gl_impostor_frag impostor.frag gl_foliage)
xyl_shader(gl_forest_leaf_vert forest_leaf.vert gl_foliage)
xyl_shader(gl_forest_leaf_list_vert forest_leaf.vert gl_foliage XYL_LIST)
xyl_shader(gl_forest_stem_vert forest_stem.vert gl_foliage)
xyl_shader(gl_forest_stem_frag forest_stem.frag gl_foliage)
xyl_shader(gl_forest_billboard_vert forest_billboard.vert gl_foliage)
xyl_shader(gl_forest_leaf_frag foliage_leaf.frag gl_foliage XYL_FOREST)
xyl_shader(gl_forest_billboard_frag billboard.frag gl_foliage XYL_FOREST)
xyl_shader(gl_forest_impostor_vert forest_impostor.vert gl_foliage)
xyl_shader(gl_forest_impostor_frag impostor.frag gl_foliage XYL_FOREST)
xyl_shader(vk_foliage_leaf_vert foliage_leaf.vert vk_foliage)
xyl_shader(vk_foliage_leaf_capture_vert foliage_leaf.vert vk_foliage XYL_CAPTURE)
xyl_shader(vk_foliage_leaf_frag foliage_leaf.frag vk_foliage)
xyl_shader(vk_foliage_leaf_list_vert foliage_leaf.vert vk_foliage XYL_LIST)
xyl_shader(vk_foliage_cut_comp foliage_cut.comp vk_foliage XYL_CUT)
xyl_shader(vk_billboard_vert billboard.vert vk_foliage XYL_BILLBOARD)
xyl_shader(vk_billboard_instances_vert billboard.vert vk_foliage XYL_BILLBOARD XYL_INSTANCES)
xyl_shader(vk_billboard_frag billboard.frag vk_foliage XYL_BILLBOARD)
xyl_shader(vk_impostor_vert impostor.vert vk_foliage XYL_BILLBOARD)
xyl_shader(vk_impostor_frag impostor.frag vk_foliage XYL_BILLBOARD)

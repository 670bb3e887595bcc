cmake_policy(VERSION 3.25)
# The GLSL half of shaders/xyl_foliage_shared.h: a compute shader that uses every helper
# (tests/foliage_record.comp) compiles for OpenGL 4.5 and for Vulkan 1.2 (SPIR-V), and the
# offsets and array stride glslang gives the record are the ones xylem/xyl_foliage.h pins on
# the C side with _Static_assert.
# cmake -DGLSLANG=<glslangValidator> -DHEADER=<shared header> -DSTAGE=<.comp> -DWORK=<dir>
#       -P foliage_glsl.cmake
foreach(v GLSLANG HEADER STAGE WORK)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "foliage_glsl.cmake: -D${v}= is missing")
  endif()
endforeach()
file(MAKE_DIRECTORY "${WORK}")
file(READ "${HEADER}" header)
file(READ "${STAGE}" stage)
set(src "${WORK}/foliage_record.comp")
file(WRITE "${src}" "#version 450\n#define XYL_GLSL 1\n${header}\n${stage}")

execute_process(COMMAND "${GLSLANG}" -q --target-env opengl "${src}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the OpenGL compile failed:\n${out}")
endif()
# field, offset in bytes (C: offsetof in xyl_foliage_gpu_leaf; the halves pair up into words)
set(expect center 0 axis_xy 12 axis_z_side_x 16 side_yz 20 uv0 24 uv1 28)
list(LENGTH expect n)
math(EXPR last "${n} - 1")
foreach(i RANGE 0 ${last} 2)
  math(EXPR j "${i} + 1")
  list(GET expect ${i} field)
  list(GET expect ${j} offset)
  if(NOT out MATCHES "leaves\\.${field}: offset ${offset},[^\n]*topLevelArrayStride 32")
    message(FATAL_ERROR "glslang does not put ${field} at offset ${offset} with an array "
                        "stride of 32:\n${out}")
  endif()
endforeach()

execute_process(COMMAND "${GLSLANG}" -V --target-env vulkan1.2 -o "${WORK}/foliage_record.spv" "${src}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the Vulkan compile failed:\n${out}")
endif()
message(STATUS "xyl_foliage_gpu_leaf: GLSL offsets and stride match the C layout")

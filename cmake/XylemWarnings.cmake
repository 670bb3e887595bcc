# Strict warnings for every xylem target; -Werror when XYL_WERROR is on (CI turns it on).
function(xyl_module_options target)
  if(CMAKE_C_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${target} PRIVATE
      -Wall -Wextra -Wshadow -Wconversion -Wsign-conversion -Wpedantic
      -Wstrict-prototypes -Wmissing-prototypes -Wno-sign-conversion
      # Bit-identical results across compilers: no fused multiply-add contraction.
      -ffp-contract=off)
    if(XYL_WERROR)
      target_compile_options(${target} PRIVATE -Werror)
    endif()
  endif()
  target_compile_definitions(${target} PRIVATE XYL_BUILDING)
endfunction()

# Looser set for tests and samples (cmocka macros trip -Wconversion), still warnings-as-errors in CI.
function(xyl_app_options target)
  if(CMAKE_C_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wshadow -ffp-contract=off)
    if(XYL_WERROR)
      target_compile_options(${target} PRIVATE -Werror)
    endif()
  endif()
endfunction()

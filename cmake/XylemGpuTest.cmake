# GPU suites run on whatever driver the machine has; CI has none, so Mesa's llvmpipe / lavapipe.
#
# Under the sanitizers: the loader / EGL unload Mesa's driver when the last context or instance
# goes, so the driver's process-lifetime state is orphaned and LeakSanitizer reports it with
# "<unknown module>" frames that no suppression can name. Preloading the driver keeps it mapped:
# its globals stay reachable (GL then reports nothing) and what it really keeps past
# vkDestroyDevice (lavapipe's per-pipeline LLVM state) is named, and suppressed by
# tests/lsan.supp. Leak checking of xylem's own code stays on.
function(xyl_gpu_test name)
  set_tests_properties(${name} PROPERTIES LABELS gpu)
  if(NOT XYL_SANITIZE)
    return()
  endif()
  set(asan "abort_on_error=1:strict_string_checks=1:verify_asan_link_order=0")
  set(preload)
  foreach(driver_name IN LISTS ARGN)
    find_file(XYL_DRIVER_${driver_name} ${driver_name}
      PATHS /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/dri /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}
            /usr/lib64/dri /usr/lib64 /usr/lib/dri /usr/lib NO_DEFAULT_PATH)
    if(NOT XYL_DRIVER_${driver_name})
      message(WARNING "${driver_name} not found: ${name} runs without leak checking")
      set_tests_properties(${name} PROPERTIES ENVIRONMENT
        "CMOCKA_MESSAGE_OUTPUT=stdout;ASAN_OPTIONS=detect_leaks=0:${asan}")
      return()
    endif()
    list(APPEND preload ${XYL_DRIVER_${driver_name}})
  endforeach()
  string(REPLACE ";" ":" preload "${preload}")
  set_tests_properties(${name} PROPERTIES ENVIRONMENT
    "CMOCKA_MESSAGE_OUTPUT=stdout;LD_PRELOAD=${preload};ASAN_OPTIONS=detect_leaks=1:${asan};LSAN_OPTIONS=suppressions=${PROJECT_SOURCE_DIR}/tests/lsan.supp")
endfunction()

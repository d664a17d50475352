# Included by scripts/test.sh into the sanitizer build only
# (CMAKE_PROJECT_INCLUDE): once CMakeLists.txt is processed, every module
# library (sflsh_*) is compiled as a unity build (its sources concatenated in
# batches of SFLSH_UNITY_BATCH, default 8), which cuts the from-scratch build
# of the sanitizer suite by parsing Eigen and the project headers once per
# batch instead of once per file. Test executables keep one object per file.
# Sources that cannot share a unit with others (clashing file-local names)
# are listed in SFLSH_UNITY_SKIP (paths relative to the source dir).
if(NOT DEFINED SFLSH_UNITY_BATCH)
  set(SFLSH_UNITY_BATCH 8)
endif()
function(sflsh_sanitize_unity)
  get_property(targets DIRECTORY "${CMAKE_SOURCE_DIR}" PROPERTY BUILDSYSTEM_TARGETS)
  foreach(t IN LISTS targets)
    get_target_property(type ${t} TYPE)
    if(t MATCHES "^sflsh_" AND type STREQUAL "STATIC_LIBRARY")
      set_target_properties(${t} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE ${SFLSH_UNITY_BATCH})
    endif()
  endforeach()
  foreach(f IN LISTS SFLSH_UNITY_SKIP)
    set_source_files_properties("${CMAKE_SOURCE_DIR}/${f}" DIRECTORY "${CMAKE_SOURCE_DIR}"
                                PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
  endforeach()
endfunction()
cmake_language(DEFER DIRECTORY "${CMAKE_SOURCE_DIR}" CALL sflsh_sanitize_unity)

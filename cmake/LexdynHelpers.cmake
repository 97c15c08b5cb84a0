# lexdyn_add_test(NAME <name> SOURCES <src...> LABELS <label...> [LIBS <lib...>] [TIMEOUT <s>])
# Builds one GoogleTest executable and registers it with ctest under the given labels
# (unit, property, regression, slow).
function(lexdyn_add_test)
  cmake_parse_arguments(T "" "NAME;TIMEOUT" "SOURCES;LABELS;LIBS" ${ARGN})
  add_executable(${T_NAME} ${T_SOURCES})
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main)
  target_include_directories(${T_NAME} PRIVATE ${PROJECT_SOURCE_DIR})
  target_compile_definitions(${T_NAME} PRIVATE
    LEXDYN_SOURCE_DIR="${PROJECT_SOURCE_DIR}" LEXDYN_BINARY_DIR="${PROJECT_BINARY_DIR}")
  add_test(NAME ${T_NAME} COMMAND ${T_NAME} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 600)
  endif()
  set_tests_properties(${T_NAME} PROPERTIES LABELS "${T_LABELS}" TIMEOUT ${T_TIMEOUT})
endfunction()

# Translation units that include Simbody headers must be compiled without NDEBUG:
# Debian's Simbody 3.7 was built without it and one class layout depends on it
# (docs/architecture.md, "Simbody and NDEBUG").
function(lexdyn_simbody_sources)
  set_source_files_properties(${ARGN} PROPERTIES COMPILE_OPTIONS "-UNDEBUG")
endfunction()

# lexdyn-harness: runs case files, checks stored traces, compares methods, golden traces
# (docs/simulator.md, docs/cases.md).
add_executable(lexdyn-harness ${CMAKE_CURRENT_LIST_DIR}/harness_main.cpp ${CMAKE_CURRENT_LIST_DIR}/sweep_cmd.cpp
  ${CMAKE_CURRENT_LIST_DIR}/robot_cmd.cpp)
target_link_libraries(lexdyn-harness PRIVATE lexdyn::cases lexdyn::golden lexdyn::sweep lexdyn::robot CLI11::CLI11)
target_compile_definitions(lexdyn-harness PRIVATE LEXDYN_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
install(TARGETS lexdyn-harness RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

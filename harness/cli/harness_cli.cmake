# lexdyn-harness: runs case files (docs/simulator.md, "Running a case").
add_executable(lexdyn-harness ${CMAKE_CURRENT_LIST_DIR}/harness_main.cpp)
target_link_libraries(lexdyn-harness PRIVATE lexdyn::cases CLI11::CLI11)
install(TARGETS lexdyn-harness RUNTIME DESTINATION bin)

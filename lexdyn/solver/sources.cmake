target_sources(lexdyn PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/problem.cpp
  ${CMAKE_CURRENT_LIST_DIR}/problem_io.cpp
  ${CMAKE_CURRENT_LIST_DIR}/hls_factorization.cpp
  ${CMAKE_CURRENT_LIST_DIR}/solver.cpp)

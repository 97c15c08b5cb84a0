target_sources(lexdyn PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/controller.cpp
  ${CMAKE_CURRENT_LIST_DIR}/augmentation.cpp
  ${CMAKE_CURRENT_LIST_DIR}/switching.cpp)

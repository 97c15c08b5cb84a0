# Shared by every component: input errors, number formatting, input text and YAML readers, the
# problem lists of a file's checks.
target_sources(lexdyn PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/error.cpp
  ${CMAKE_CURRENT_LIST_DIR}/format.cpp
  ${CMAKE_CURRENT_LIST_DIR}/input_text.cpp
  ${CMAKE_CURRENT_LIST_DIR}/yaml_strict.cpp
  ${CMAKE_CURRENT_LIST_DIR}/problems.cpp)

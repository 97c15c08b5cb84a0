# The controller (docs/controller.md): the tick, the switching rule, and the methods, one file
# pair each in methods/ plus the registry (docs/architecture.md, "Adding a method").
target_sources(lexdyn PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/controller.cpp
  ${CMAKE_CURRENT_LIST_DIR}/switching.cpp
  ${CMAKE_CURRENT_LIST_DIR}/methods/registry.cpp
  ${CMAKE_CURRENT_LIST_DIR}/methods/velocity_domain.cpp
  ${CMAKE_CURRENT_LIST_DIR}/methods/lexdyn_bfgs.cpp
  ${CMAKE_CURRENT_LIST_DIR}/methods/lexdyn_ah.cpp
  ${CMAKE_CURRENT_LIST_DIR}/methods/gauss_newton.cpp
  ${CMAKE_CURRENT_LIST_DIR}/methods/wls.cpp)

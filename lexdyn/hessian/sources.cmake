# Second-order augmentation (docs/controller.md, "Hessians"): analytic Hessians of geometric task
# functions, Higham's nearest positive semi-definite regularisation, per-level BFGS / SR1.
target_sources(lexdyn PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/kinematic_hessian.cpp
  ${CMAKE_CURRENT_LIST_DIR}/higham.cpp
  ${CMAKE_CURRENT_LIST_DIR}/bfgs.cpp)

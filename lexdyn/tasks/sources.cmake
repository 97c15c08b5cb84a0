# Tasks and constraints of the controller (docs/controller.md, "Task types"): one file pair per
# task type, plus the shared helpers (parameter checks, PD rows, the bases of the target-tracking
# tasks and of the tasks whose rows are variables, velocity damper, Jc^T).
target_sources(lexdyn PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/task.cpp
  ${CMAKE_CURRENT_LIST_DIR}/task_params.cpp
  ${CMAKE_CURRENT_LIST_DIR}/tracking.cpp
  ${CMAKE_CURRENT_LIST_DIR}/variable_rows.cpp
  ${CMAKE_CURRENT_LIST_DIR}/contact_jacobian.cpp
  ${CMAKE_CURRENT_LIST_DIR}/contact_force_bounds.cpp
  ${CMAKE_CURRENT_LIST_DIR}/contact_margins.cpp
  ${CMAKE_CURRENT_LIST_DIR}/joint_limits.cpp
  ${CMAKE_CURRENT_LIST_DIR}/equation_of_motion.cpp
  ${CMAKE_CURRENT_LIST_DIR}/torque_limits.cpp
  ${CMAKE_CURRENT_LIST_DIR}/trust_region.cpp
  ${CMAKE_CURRENT_LIST_DIR}/self_collision.cpp
  ${CMAKE_CURRENT_LIST_DIR}/contact.cpp
  ${CMAKE_CURRENT_LIST_DIR}/position.cpp
  ${CMAKE_CURRENT_LIST_DIR}/orientation.cpp
  ${CMAKE_CURRENT_LIST_DIR}/com.cpp
  ${CMAKE_CURRENT_LIST_DIR}/com_box.cpp
  ${CMAKE_CURRENT_LIST_DIR}/joint_position.cpp
  ${CMAKE_CURRENT_LIST_DIR}/posture.cpp
  ${CMAKE_CURRENT_LIST_DIR}/velocity_min.cpp
  ${CMAKE_CURRENT_LIST_DIR}/wrench_min.cpp)

# Controller-side robot model (urdfdom + data file -> Simbody matter subsystem), see docs/model.md.
target_sources(lexdyn PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/data_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/inertia.cpp
  ${CMAKE_CURRENT_LIST_DIR}/resource_path.cpp
  ${CMAKE_CURRENT_LIST_DIR}/robot_description.cpp
  ${CMAKE_CURRENT_LIST_DIR}/urdf_reader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/robot_model.cpp)
# Translation units that include Simbody headers (docs/architecture.md, "Simbody and NDEBUG").
lexdyn_simbody_sources(${CMAKE_CURRENT_LIST_DIR}/robot_model.cpp)
target_link_libraries(lexdyn PRIVATE
  SimTKsimbody SimTKmath SimTKcommon urdfdom::urdfdom_model yaml-cpp)

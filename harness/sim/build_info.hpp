// What a trace header records about the build: compiler, flags and library versions.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace lexdyn::sim {

/// (key, value) pairs, in a fixed order: compiler, build_type, cxx_flags, eigen, simbody,
/// sundials, urdfdom, yaml_cpp, lexdyn.
std::vector<std::pair<std::string, std::string>> buildInfo();

}  // namespace lexdyn::sim

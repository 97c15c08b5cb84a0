#include "harness/sim/build_info.hpp"

#include "harness/sim/cvode_integrator.hpp"

#include <Eigen/Core>

// Declared by simbody/internal/common.h (a plain C function of libSimTKsimbody); declared here
// so that this file does not need Simbody's headers.
extern "C" void SimTK_version_simbody(int* major, int* minor, int* build);

namespace lexdyn::sim {

std::vector<std::pair<std::string, std::string>> buildInfo() {
  int major = 0, minor = 0, build = 0;
  SimTK_version_simbody(&major, &minor, &build);
  const std::string simbody = std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(build);
  const std::string eigen =
      std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." + std::to_string(EIGEN_MINOR_VERSION);
  return {
      {"compiler", LEXDYN_BUILD_COMPILER " (" __VERSION__ ")"},
      {"build_type", LEXDYN_BUILD_TYPE},
      {"cxx_flags", LEXDYN_BUILD_FLAGS},
      {"eigen", eigen},
      {"simbody", simbody},
      {"sundials", CvodeIntegrator::sundialsVersion()},
      {"urdfdom", LEXDYN_URDFDOM_VERSION},
      {"yaml_cpp", LEXDYN_YAML_CPP_VERSION},
      {"lexdyn", LEXDYN_VERSION},
  };
}

}  // namespace lexdyn::sim

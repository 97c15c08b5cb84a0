// Fuzz target: URDF files through TinyXML and urdfdom (lexdyn/model/urdf_reader.cpp: the lenient
// readings, lumping, inertia projection, mimic and massless locking), and the Simbody model built
// from what they accept (lexdyn/model/robot_model.cpp). The data file is the minimal one for the
// robot the URDF names; the input's size picks a fixed base or a free flyer, and strict mode.
#include "fuzz_target.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/model/robot_description.hpp"
#include "lexdyn/model/robot_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string urdf(reinterpret_cast<const char*>(data), size);
  std::string name = "robot";
  const size_t r = urdf.find("<robot name=\"");
  if (r != std::string::npos) {
    const size_t b = r + 13, e = urdf.find('"', b);
    if (e != std::string::npos && e - b < 200) name = urdf.substr(b, e - b);
  }
  const std::string yaml = "format: lexdyn-robot-data/1\nrobot: \"" + name + "\"\nbase: " + (size % 2 ? "free_flyer" : "fixed") + "\n";
  lexdyn::model::LoadOptions options;
  options.strict = size % 3 == 0;
  options.use_ros_package_path = false;
  try {
    lexdyn::model::RobotDescription d = lexdyn::model::parseRobotDescription(urdf, "fuzz.urdf", yaml, "fuzz.yaml", options);
    const lexdyn::model::RobotModel m(std::move(d));
    (void)m;
  } catch (const lexdyn::InputError& e) {
    lexdyn::fuzz::noteRejected(e.what());
  }
  return 0;
}

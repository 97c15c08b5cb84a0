// Fuzz target: trace files (harness/checks/trace.cpp, parseTrace), then the checks that need no
// case (a controller_status and an active_set_peak check) on what it accepts.
#include <sstream>

#include "fuzz_target.hpp"
#include "harness/checks/checks.hpp"
#include "harness/checks/health_checks.hpp"
#include "lexdyn/common/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const lexdyn::checks::TraceTable t = lexdyn::checks::parseTrace(in, "fuzz.csv", size % 2 == 1);
    (void)t.completeness();
    std::vector<lexdyn::checks::CheckSpec> specs(2);
    specs[0].name = "status";
    specs[0].type = "controller_status";
    specs[0].params = lexdyn::checks::ControllerStatusParams{{"ok"}};
    specs[1].name = "peak";
    specs[1].type = "active_set_peak";
    specs[1].limit = 50;
    (void)lexdyn::checks::runChecks(specs, t);
  } catch (const lexdyn::InputError& e) {
    lexdyn::fuzz::noteRejected(e.what());
  }
  return 0;
}

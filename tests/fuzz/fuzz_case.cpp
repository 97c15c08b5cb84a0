// Fuzz target: case files (harness/cases/case_file.cpp, loadCase). The input is written to
// cases/fuzz.yaml of the scratch directory, so that the repository's cases, with their relative
// robot and trajectory paths, are valid seeds.
#include "fuzz_target.hpp"
#include "harness/cases/case_file.hpp"
#include "lexdyn/common/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = lexdyn::fuzz::writeScratch("cases/fuzz.yaml", data, size);
  try {
    const lexdyn::cases::CaseSpec spec = lexdyn::cases::loadCase(path);
    (void)spec;
  } catch (const lexdyn::InputError& e) {
    lexdyn::fuzz::noteRejected(e.what());
  }
  return 0;
}

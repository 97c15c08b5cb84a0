// Fuzz target: case files (harness/cases/case_file.cpp, loadCase). The input is written to
// cases/fuzz.yaml of the scratch directory, so that the repository's cases, with their relative
// robot and trajectory paths, are valid seeds.
#include "fuzz_target.hpp"
#include "harness/cases/case_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return lexdyn::fuzz::parseScratchFile("cases/fuzz.yaml", data, size, [](const std::string& path) {
    const lexdyn::cases::CaseSpec spec = lexdyn::cases::loadCase(path);
    (void)spec;
  });
}

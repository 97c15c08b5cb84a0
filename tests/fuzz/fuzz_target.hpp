// Fuzz targets: one file per parser, each defining LLVMFuzzerTestOneInput (docs/architecture.md,
// "Fuzzing"). The contract every target checks: the parser either accepts the input or throws
// lexdyn::InputError; anything else (another exception, a crash, a hang, an out-of-bounds access
// under AddressSanitizer) is a finding. Built two ways (tests/fuzz/CMakeLists.txt): with clang's
// libFuzzer (LEXDYN_BUILD_FUZZERS, coverage-guided, harness/scripts/fuzz.sh) and, in the normal
// build, with fuzz_driver.cpp (replay of the kept inputs under ctest, and a seeded mutation runner).
#pragma once

#include "lexdyn/common/error.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

namespace lexdyn::fuzz {

/// A scratch directory of this process where relative paths of the repository's case files and
/// manifests resolve: models/ and the case files (cases/*.yaml, cases/trajectories) are linked
/// from the source tree; the targets write their input into it (cases/fuzz.yaml,
/// cases/sweeps/fuzz.yaml, golden/...).
const std::string& scratchDir();

/// Writes `size` bytes to `path` (a file of the scratch directory) and returns the path.
std::string writeScratch(const std::string& relative_path, const std::uint8_t* data, std::size_t size);

/// Records that the target refused its input with an InputError (the expected outcome of bad
/// input); the replay driver counts them and prints the message with LEXDYN_FUZZ_VERBOSE=1.
void noteRejected(const char* message);
long rejectedCount();

/// The body of a target whose parser reads a file: writes the input to `relative_path` of the
/// scratch directory and runs parse(path); an InputError is a refusal (noteRejected), anything
/// else goes through (a finding). Returns 0, libFuzzer's convention.
template <class Parse>
int parseScratchFile(const char* relative_path, const std::uint8_t* data, std::size_t size, Parse parse) {
  const std::string path = writeScratch(relative_path, data, size);
  try {
    parse(path);
  } catch (const InputError& e) {
    noteRejected(e.what());
  }
  return 0;
}

}  // namespace lexdyn::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

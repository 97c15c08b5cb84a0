// Fuzz target: golden manifests (harness/golden/golden.cpp, loadManifest). The input is written
// to golden/manifest.yaml of the scratch directory, whose ../cases holds the repository's cases.
#include "fuzz_target.hpp"
#include "harness/golden/golden.hpp"
#include "lexdyn/common/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = lexdyn::fuzz::writeScratch("golden/manifest.yaml", data, size);
  try {
    const lexdyn::golden::Manifest m = lexdyn::golden::loadManifest(path);
    (void)m;
  } catch (const lexdyn::InputError& e) {
    lexdyn::fuzz::noteRejected(e.what());
  }
  return 0;
}

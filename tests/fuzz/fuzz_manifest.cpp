// Fuzz target: golden manifests (harness/golden/golden.cpp, loadManifest). The input is written
// to golden/manifest.yaml of the scratch directory, whose ../cases holds the repository's cases.
#include "fuzz_target.hpp"
#include "harness/golden/golden.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return lexdyn::fuzz::parseScratchFile("golden/manifest.yaml", data, size, [](const std::string& path) {
    const lexdyn::golden::Manifest m = lexdyn::golden::loadManifest(path);
    (void)m;
  });
}

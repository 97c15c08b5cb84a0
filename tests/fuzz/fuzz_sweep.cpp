// Fuzz target: sweep files (harness/sweep/sweep_file.cpp, loadSweep with validation: the base
// case loads, and every parameter's extreme values are applied to it). The input is written to
// cases/sweeps/fuzz.yaml of the scratch directory, so that the committed sweeps, whose base is
// ../<case>.yaml, are valid seeds. An accepted sweep must also give the values and overrides of
// its first and last points without anything but an InputError.
#include "fuzz_target.hpp"
#include "harness/sweep/sweep_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return lexdyn::fuzz::parseScratchFile("cases/sweeps/fuzz.yaml", data, size, [](const std::string& path) {
    const lexdyn::sweep::SweepSpec s = lexdyn::sweep::loadSweep(path);
    for (const long i : {0L, s.points - 1}) {
      if (i < 0) continue;
      const lexdyn::sweep::Point p = lexdyn::sweep::pointAt(s, i);
      (void)lexdyn::sweep::overridesOf(s, p.values);
    }
  });
}

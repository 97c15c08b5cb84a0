#include "fuzz_target.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace lexdyn::fuzz {

namespace fs = std::filesystem;

const std::string& scratchDir() {
  static const std::string dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    const fs::path d = fs::path(tmp && *tmp ? tmp : "/tmp") / ("lexdyn-fuzz-" + std::to_string(::getpid()));
    std::error_code ec;
    fs::remove_all(d, ec);
    fs::create_directories(d / "cases" / "sweeps");
    fs::create_directories(d / "golden");
    const fs::path src(LEXDYN_SOURCE_DIR);
    fs::create_directory_symlink(src / "models", d / "models");
    fs::create_directory_symlink(src / "cases" / "trajectories", d / "cases" / "trajectories");
    for (const auto& e : fs::directory_iterator(src / "cases")) {
      if (e.path().extension() == ".yaml") fs::create_symlink(e.path(), d / "cases" / e.path().filename());
    }
    // Removed at exit (a crash leaves it behind: it holds links and the last input only).
    static const std::string keep = d.string();
    std::atexit([] {
      std::error_code ec2;
      fs::remove_all(keep, ec2);
    });
    return d.string();
  }();
  return dir;
}

std::string writeScratch(const std::string& relative_path, const std::uint8_t* data, std::size_t size) {
  const std::string path = scratchDir() + "/" + relative_path;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

namespace {
long g_rejected = 0;
}

void noteRejected(const char* message) {
  ++g_rejected;
  static const bool verbose = std::getenv("LEXDYN_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "  refused: %s\n", message);
}

long rejectedCount() { return g_rejected; }

}  // namespace lexdyn::fuzz

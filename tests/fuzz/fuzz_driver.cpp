// The main() of the fuzz targets in the normal build (docs/architecture.md, "Fuzzing"):
//
//   lexdyn-fuzz-NAME INPUT_OR_DIR...             replays every input once (ctest does this with
//                                                the kept inputs, tests/fuzz/corpus/NAME)
//   lexdyn-fuzz-NAME --seconds S [--runs N] [--seed K] [--out DIR] [--timeout T] SEEDS...
//                                                a seeded mutation runner: mutates the seeds
//                                                (bytes, numbers, structure tokens, splices) for S
//                                                seconds or N runs, whichever comes first
//
// A finding is an input for which the target does not return: an exception other than
// lexdyn::InputError escapes it (written to DIR/finding-<run>.bin and counted), or the process
// dies (a crash, std::abort, or the per-input timeout T seconds by SIGALRM): then DIR/current.bin
// is the input, which harness/scripts/fuzz.sh keeps. The mutation sequence depends on --seed
// only (and on the seeds), never on the clock (the clock only ends the loop).
//
// Exit codes: 0 no finding; 1 a finding (replay: an input that failed); 2 bad usage.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "fuzz_target.hpp"

namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

Bytes readBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void writeBytes(const fs::path& p, const Bytes& b) {
  const fs::path tmp = p.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  }
  fs::rename(tmp, p);
}

std::vector<fs::path> expand(const std::vector<std::string>& args) {
  std::vector<fs::path> out;
  for (const auto& a : args) {
    if (fs::is_directory(a)) {
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(a)) {
        if (e.is_regular_file() && e.path().filename().string()[0] != '.') files.push_back(e.path());
      }
      std::sort(files.begin(), files.end());
      out.insert(out.end(), files.begin(), files.end());
    } else {
      out.emplace_back(a);
    }
  }
  return out;
}

// Runs the target on one input; an escaping exception is a finding (described in `what`).
bool runOne(const Bytes& b, std::string& what) {
  try {
    LLVMFuzzerTestOneInput(b.empty() ? nullptr : b.data(), b.size());
    return true;
  } catch (const std::exception& e) {
    what = std::string("uncaught exception: ") + e.what();
  } catch (...) {
    what = "uncaught exception of unknown type";
  }
  return false;
}

// Tokens of the formats the parsers read (YAML, XML, JSON, CSV) and values at the edges of
// their ranges.
const char* const kTokens[] = {"nan",
                               ".nan",
                               "inf",
                               ".inf",
                               "-.inf",
                               "1e308",
                               "-1e308",
                               "1e-300",
                               "1e400",
                               "0",
                               "-0",
                               "-1",
                               "2147483648",
                               "9223372036854775808",
                               "1e6",
                               "0.005",
                               "1e-9",
                               "\"",
                               "'",
                               "[",
                               "]",
                               "{",
                               "}",
                               ":",
                               ",",
                               "\n",
                               "\r\n",
                               "- ",
                               "  ",
                               "&a ",
                               "*a",
                               "!!str ",
                               "null",
                               "true",
                               "~",
                               "#",
                               "<",
                               ">",
                               "/>",
                               "</",
                               "<link name=\"l\">",
                               "<joint",
                               "=\"",
                               "xyz=\"",
                               "<!--",
                               "-->",
                               "<![CDATA[",
                               "\\u0000",
                               "# end: completed\n",
                               "# end: interrupted\n",
                               "t,",
                               ",nan",
                               "\t"};

struct Mutator {
  std::mt19937_64 rng;
  const std::vector<Bytes>* seeds;
  size_t max_len;

  size_t pick(size_t n) { return n == 0 ? 0 : static_cast<size_t>(rng() % n); }

  // A number's digits near position i, replaced by an edge value.
  void replaceNumber(Bytes& b) {
    if (b.empty()) return;
    size_t i = pick(b.size());
    size_t tries = 0;
    while (tries++ < b.size() && !std::isdigit(b[i])) i = (i + 1) % b.size();
    if (!std::isdigit(b[i])) return;
    size_t s = i, e = i;
    auto numChar = [](std::uint8_t c) { return std::isdigit(c) || c == '.' || c == 'e' || c == 'E' || c == '-' || c == '+'; };
    while (s > 0 && numChar(b[s - 1])) --s;
    while (e < b.size() && numChar(b[e])) ++e;
    const char* t = kTokens[pick(17)];  // the numeric tokens come first
    b.erase(b.begin() + static_cast<long>(s), b.begin() + static_cast<long>(e));
    b.insert(b.begin() + static_cast<long>(s), t, t + std::strlen(t));
  }

  Bytes mutate(Bytes b) {
    const int steps = 1 + static_cast<int>(pick(4));
    for (int k = 0; k < steps; ++k) {
      switch (pick(9)) {
        case 0:  // flip a bit
          if (!b.empty()) b[pick(b.size())] ^= static_cast<std::uint8_t>(1u << pick(8));
          break;
        case 1:  // a random byte
          if (!b.empty()) b[pick(b.size())] = static_cast<std::uint8_t>(rng());
          break;
        case 2:  // insert a byte
          b.insert(b.begin() + static_cast<long>(pick(b.size() + 1)), static_cast<std::uint8_t>(rng()));
          break;
        case 3: {  // delete a range
          if (b.empty()) break;
          const size_t s = pick(b.size()), n = 1 + pick(std::min<size_t>(64, b.size() - s));
          b.erase(b.begin() + static_cast<long>(s), b.begin() + static_cast<long>(std::min(b.size(), s + n)));
          break;
        }
        case 4: {  // duplicate a range
          if (b.empty()) break;
          const size_t s = pick(b.size()), n = 1 + pick(std::min<size_t>(256, b.size() - s));
          const Bytes part(b.begin() + static_cast<long>(s), b.begin() + static_cast<long>(std::min(b.size(), s + n)));
          b.insert(b.begin() + static_cast<long>(pick(b.size() + 1)), part.begin(), part.end());
          break;
        }
        case 5:
        case 6: {  // a token
          const char* t = kTokens[pick(sizeof(kTokens) / sizeof(kTokens[0]))];
          b.insert(b.begin() + static_cast<long>(pick(b.size() + 1)), t, t + std::strlen(t));
          break;
        }
        case 7:  // a number at an edge of its range
          replaceNumber(b);
          break;
        case 8: {  // splice with another seed
          const Bytes& o = (*seeds)[pick(seeds->size())];
          if (o.empty() || b.empty()) break;
          const size_t cut = pick(b.size()), from = pick(o.size());
          b.resize(cut);
          b.insert(b.end(), o.begin() + static_cast<long>(from), o.end());
          break;
        }
      }
    }
    if (b.size() > max_len) b.resize(max_len);
    return b;
  }
};

int usage() {
  std::fprintf(stderr,
               "usage: lexdyn-fuzz-NAME INPUT_OR_DIR...  (replay)\n"
               "       lexdyn-fuzz-NAME --seconds S [--runs N] [--seed K] [--out DIR] [--timeout T] [--max-len B] SEEDS...\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = -1.0;
  long runs = -1;
  unsigned long long seed = 1;
  unsigned timeout = 10;
  size_t max_len = 1 << 20;
  std::string out_dir;
  std::vector<std::string> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "lexdyn-fuzz: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    try {
      if (a == "--seconds")
        seconds = std::stod(value());
      else if (a == "--runs")
        runs = std::stol(value());
      else if (a == "--seed")
        seed = std::stoull(value());
      else if (a == "--timeout")
        timeout = static_cast<unsigned>(std::stoul(value()));
      else if (a == "--max-len")
        max_len = std::stoul(value());
      else if (a == "--out")
        out_dir = value();
      else if (a.rfind("--", 0) == 0)
        return usage();
      else
        inputs.push_back(a);
    } catch (const std::exception&) {
      return usage();
    }
  }
  const std::vector<fs::path> files = expand(inputs);
  if (files.empty()) return usage();
  std::signal(SIGALRM, SIG_DFL);  // a hang ends the process (exit status 128 + 14)

  if (seconds < 0.0 && runs < 0) {
    int failed = 0;
    for (const fs::path& f : files) {
      std::string what;
      alarm(timeout);
      if (!runOne(readBytes(f), what)) {
        std::fprintf(stderr, "FINDING %s: %s\n", f.c_str(), what.c_str());
        ++failed;
      }
      alarm(0);
    }
    std::fprintf(stderr, "replayed %zu inputs: %ld refused with an input error, %d findings\n", files.size(), lexdyn::fuzz::rejectedCount(),
                 failed);
    return failed == 0 ? 0 : 1;
  }

  std::vector<Bytes> seeds;
  for (const fs::path& f : files) seeds.push_back(readBytes(f));
  if (!out_dir.empty()) fs::create_directories(out_dir);
  Mutator m{std::mt19937_64(seed), &seeds, max_len};
  const auto t0 = std::chrono::steady_clock::now();
  long n = 0, findings = 0;
  for (; runs < 0 || n < runs; ++n) {
    if (seconds >= 0.0 && std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >= seconds) break;
    const Bytes input = m.mutate(seeds[m.pick(seeds.size())]);
    if (!out_dir.empty()) writeBytes(fs::path(out_dir) / "current.bin", input);
    std::string what;
    alarm(timeout);
    const bool ok = runOne(input, what);
    alarm(0);
    if (!ok) {
      ++findings;
      std::fprintf(stderr, "FINDING at run %ld: %s\n", n, what.c_str());
      if (!out_dir.empty()) writeBytes(fs::path(out_dir) / ("finding-" + std::to_string(n) + ".bin"), input);
    }
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::fprintf(stderr,
               "mutation runner: %ld runs in %.1f s (%.0f/s) from %zu seeds, seed %llu: %ld refused with an input error, %ld findings\n", n,
               secs, secs > 0 ? static_cast<double>(n) / secs : 0.0, seeds.size(), seed, lexdyn::fuzz::rejectedCount(), findings);
  if (!out_dir.empty()) fs::remove(fs::path(out_dir) / "current.bin");
  return findings == 0 ? 0 : 1;
}

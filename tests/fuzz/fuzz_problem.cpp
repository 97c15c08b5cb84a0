// Fuzz target: solver problem files (lexdyn/solver/problem_io.cpp) and the solver on what they
// accept: a result the solver calls solved must be finite (docs/solver.md).
#include <cstdlib>
#include <cstdio>

#include "fuzz_target.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/solver/problem_io.hpp"
#include "lexdyn/solver/solver.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    lexdyn::solver::Problem p = lexdyn::solver::parseProblemJson(text, "fuzz.json");
    p.detectBoundsLevel();
    lexdyn::solver::Options o;
    o.max_iterations = 200;
    lexdyn::solver::Solver s;
    s.setup(p, o);
    const lexdyn::solver::Result& r = s.solve(p);
    if (r.status == lexdyn::solver::Status::Solved && (!r.x.allFinite() || !r.violation_norm.allFinite())) {
      std::fprintf(stderr, "fuzz_problem: a non-finite result reported as solved\n");
      std::abort();
    }
  } catch (const lexdyn::InputError& e) {
    lexdyn::fuzz::noteRejected(e.what());
  }
  return 0;
}

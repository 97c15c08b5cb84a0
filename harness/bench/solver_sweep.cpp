// lexdyn-solver-sweep: a heavy randomized verification sweep of the solver (not part of ctest).
// Random hierarchies (rank-deficient, duplicated, zero and conflicting rows, bounds levels,
// equalities and inequalities) are solved and each result is checked against a KKT certificate
// built from x and the multipliers alone; with --brute-force, tiny problems are also compared with
// an enumeration of every active set. Deterministic for a given --seed.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <random>
#include <string>

#include "lexdyn/solver/solver.hpp"
#include "reference.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Randomized verification sweep of the hierarchical least-squares solver"};
  std::uint64_t seed = 1;
  long cases = 100000;
  int maxN = 12, maxLevels = 7, maxRows = 8;
  bool brute = false;
  app.add_option("--seed", seed, "first problem seed");
  app.add_option("--cases", cases, "number of random problems");
  app.add_option("--max-variables", maxN);
  app.add_option("--max-levels", maxLevels);
  app.add_option("--max-rows", maxRows, "maximum rows per level");
  app.add_flag("--brute-force", brute, "compare tiny problems (<= 9 rows) with active-set enumeration");
  CLI11_PARSE(app, argc, argv);

  using namespace lexdyn::solver;
  std::mt19937_64 meta(seed);
  long fails = 0, held = 0, cycles = 0, iters = 0, solved = 0, maxIt = 0;
  for (long c = 0; c < cases; ++c) {
    const std::uint64_t s = seed + static_cast<std::uint64_t>(c);
    test::GenOptions g;
    g.n = 1 + static_cast<int>(meta() % static_cast<unsigned>(maxN));
    g.levels = 1 + static_cast<int>(meta() % static_cast<unsigned>(maxLevels));
    g.maxRows = 1 + static_cast<int>(meta() % static_cast<unsigned>(maxRows));
    g.inequalities = meta() % 4 != 0;
    g.boundsLevel = meta() % 2;
    const double pr[] = {0.0, 0.3, 0.8}, pd[] = {0.0, 0.2, 0.5}, pz[] = {0.0, 0.1}, pe[] = {0.1, 0.4, 0.9};
    g.pRankDeficient = pr[meta() % 3];
    g.pDuplicate = pd[meta() % 3];
    g.pConflict = pd[meta() % 3];
    g.pZeroRow = pz[meta() % 2];
    g.pEquality = pe[meta() % 3];
    const Problem p = test::randomProblem(s, g);
    if (brute && p.totalRows() > 9) continue;
    Solver solver;
    solver.setup(p);
    const Result& r = solver.solve(p);
    ++solved;
    held += r.held_after_reblock;
    cycles += r.cycles_broken;
    iters += r.iterations;
    maxIt = std::max<long>(maxIt, r.iterations);
    std::string err = (r.status != Status::Solved) ? std::string("status ") + toString(r.status) : test::checkKkt(p, r);
    if (err.empty() && brute) {
      const auto ref = test::bruteForce(p);
      for (int l = 0; l < p.levelCount() && err.empty(); ++l)
        if (std::abs(r.violation_norm(l) - ref[static_cast<size_t>(l)]) > 1e-7 * (1 + ref[static_cast<size_t>(l)]))
          err = "level " + std::to_string(l) + " violation " + std::to_string(r.violation_norm(l)) +
                " differs from brute force " + std::to_string(ref[static_cast<size_t>(l)]);
    }
    if (!err.empty() && ++fails <= 10) std::printf("problem seed %llu: %s\n", static_cast<unsigned long long>(s), err.c_str());
    if ((c + 1) % 20000 == 0) std::fprintf(stderr, "lexdyn-solver-sweep: %ld/%ld\n", c + 1, cases);
  }
  std::printf("{\"solved\": %ld, \"failures\": %ld, \"held_after_reblock\": %ld, \"cycles_broken\": %ld, \"mean_iterations\": %.3f, \"max_iterations\": %ld}\n",
              solved, fails, held, cycles, solved ? static_cast<double>(iters) / static_cast<double>(solved) : 0.0, maxIt);
  return fails == 0 ? 0 : 1;
}

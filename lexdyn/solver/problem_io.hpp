// Problem files (docs/file-formats.md):
//   {"variables": n,
//    "levels": [{"name": "...", "A": [[...], ...], "lower": [...], "upper": [...]}, ...]}
// with null for an unbounded side. Parsing is strict: unknown keys, wrong types, wrong sizes,
// lower > upper, non-finite entries of A, magnitudes beyond kMaxProblemMagnitude and sizes beyond
// the guards below are errors (lexdyn::InputError) naming the file, the level and the row.
#pragma once

#include <optional>
#include <string>

#include "lexdyn/solver/problem.hpp"
#include "lexdyn/solver/solver.hpp"

namespace lexdyn::solver {

/// Size guards of problem files (checked before anything is allocated; docs/file-formats.md).
/// The solver's work grows with the cube of the level count and its restart copies with
/// levels x rows x variables: beyond these a file is refused with a clear error instead of
/// running for minutes or exhausting memory (a file of 20000 one-row levels ran past 120 s at
/// 11 GB). At the guards one cold solve takes about 3 s and 0.45 GB (docs/file-formats.md); the
/// paper-shaped problems are far below (about 100 variables, 10 levels).
inline constexpr long kMaxProblemVariables = 2000;
inline constexpr long kMaxProblemLevels = 100;
inline constexpr long kMaxProblemRows = 10000;       ///< all levels together
inline constexpr long kMaxProblemEntries = 1000000;  ///< rows x variables (8 MB of A)
/// |A_ij| and every finite bound are at most this: squares and products of two such numbers stay
/// well inside the double range (beyond, the arithmetic overflows to inf).
inline constexpr double kMaxProblemMagnitude = 1e100;

/// A problem file's content: the problem and, when the file carries them (`solver_options`: a
/// controller's dump does), the solver options it was solved with.
struct ProblemFile {
  Problem problem;
  std::optional<Options> options;
};

/// Parses problem JSON text; `source` names it in error messages. The file's solver_options
/// are checked (unknown keys, types, Options::validate's ranges) and dropped.
Problem parseProblemJson(const std::string& text, const std::string& source);
/// ... keeping the solver options (a key the file does not give has the solver's default).
ProblemFile parseProblemFile(const std::string& text, const std::string& source);
/// Reads and parses a problem file.
Problem readProblemJson(const std::string& path);
ProblemFile readProblemFile(const std::string& path);
/// Problem as JSON text (bounds levels are written as rows with one nonzero), with the solver
/// options when given.
std::string problemToJson(const Problem& problem, const Options* options = nullptr);
/// Writes a problem file atomically (temporary name, then rename).
void writeProblemJson(const Problem& problem, const std::string& path, const Options* options = nullptr);
/// The options as a problem file's solver_options object (JSON text).
std::string solverOptionsToJson(const Options& options);

/// {"status", "reason", "x", "level_violation", "iterations", ...} as JSON text.
/// With `options`, also "solver_options" (the options solved with) and "solver_options_from"
/// (`options_from`: where they came from), as lexdyn-solve prints them.
std::string resultToJson(const Problem& problem, const Result& result, bool withDetails, const Options* options = nullptr,
                         const std::string& options_from = "");

/// Writes `text` to `path` through a temporary file and a rename.
void writeFileAtomic(const std::string& path, const std::string& text);

}  // namespace lexdyn::solver

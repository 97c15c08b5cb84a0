// Problem files (docs/file-formats.md):
//   {"variables": n,
//    "levels": [{"name": "...", "A": [[...], ...], "lower": [...], "upper": [...]}, ...]}
// with null for an unbounded side. Parsing is strict: unknown keys, wrong types, wrong sizes,
// lower > upper and non-finite entries of A are errors (lexdyn::InputError) naming the file, the
// level and the row.
#pragma once

#include <string>

#include "lexdyn/solver/problem.hpp"
#include "lexdyn/solver/solver.hpp"

namespace lexdyn::solver {

/// Parses problem JSON text; `source` names it in error messages.
Problem parseProblemJson(const std::string& text, const std::string& source);
/// Reads and parses a problem file.
Problem readProblemJson(const std::string& path);
/// Problem as JSON text (bounds levels are written as rows with one nonzero).
std::string problemToJson(const Problem& problem);
/// Writes a problem file atomically (temporary name, then rename).
void writeProblemJson(const Problem& problem, const std::string& path);

/// {"status", "reason", "x", "level_violation", "iterations", ...} as JSON text.
std::string resultToJson(const Problem& problem, const Result& result, bool withDetails);

/// Writes `text` to `path` through a temporary file and a rename.
void writeFileAtomic(const std::string& path, const std::string& text);

}  // namespace lexdyn::solver

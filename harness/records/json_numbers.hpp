// How the records write a figure that may not be computed: a finite number as itself, anything
// else (NaN, infinity) as null; and back. And what is wrong with a record file that is no JSON.
#pragma once

#include <nlohmann/json_fwd.hpp>

#include <string>

namespace lexdyn::records {

/// `v` when finite, else null.
nlohmann::json finiteOrNull(double v);
/// A JSON number as a double; anything else (null, a string, missing) as NaN.
double numberOrNaN(const nlohmann::json& v);

/// What is wrong with `text`, a record file that did not parse as JSON (the parser's byte offset
/// `byte`, 1-based, and its message): "line L: KEY: expected a finite number or null, found NaN"
/// for the non-finite numbers another writer may leave (the harness writes null), else
/// "line L, column C: not JSON (MESSAGE)".
std::string jsonSyntaxProblem(const std::string& text, std::size_t byte, const std::string& message);

}  // namespace lexdyn::records

#include "harness/records/json_numbers.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>

namespace lexdyn::records {

using nlohmann::json;

json finiteOrNull(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
double numberOrNaN(const json& v) { return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN(); }

std::string jsonSyntaxProblem(const std::string& text, std::size_t byte, const std::string& message) {
  const std::size_t at = std::min(byte == 0 ? 0 : byte - 1, text.size());
  std::size_t line = 1, line_start = 0;
  for (std::size_t i = 0; i < at; ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  }
  // The literal being read: the letters (and a sign) around the offset.
  std::size_t from = at;
  while (from > line_start && (std::isalpha(static_cast<unsigned char>(text[from - 1])) || text[from - 1] == '-')) --from;
  std::size_t to = from;
  while (to < text.size() && (std::isalpha(static_cast<unsigned char>(text[to])) || text[to] == '-')) ++to;
  const std::string literal = text.substr(from, to - from);
  if (literal == "NaN" || literal == "Infinity" || literal == "-Infinity" || literal == "nan" || literal == "-nan" || literal == "inf" ||
      literal == "-inf") {
    // The key: the last quoted string followed by ':' before the literal.
    std::string key;
    const std::size_t colon = text.rfind(':', from);
    if (colon != std::string::npos) {
      const std::size_t close = text.rfind('"', colon);
      const std::size_t open = close == std::string::npos || close == 0 ? std::string::npos : text.rfind('"', close - 1);
      if (open != std::string::npos) key = text.substr(open + 1, close - open - 1);
    }
    return "line " + std::to_string(line) + ": " + (key.empty() ? "" : key + ": ") + "expected a finite number or null, found " + literal;
  }
  // nlohmann's message without its own position ("[json.exception.parse_error.101] parse error at
  // line 1, column 10: syntax error ...": the part after the position).
  std::string what = message;
  const size_t column = what.find("column ");
  const size_t colon = column == std::string::npos ? std::string::npos : what.find(": ", column);
  if (colon != std::string::npos) what = what.substr(colon + 2);
  return "line " + std::to_string(line) + ", column " + std::to_string(at - line_start + 1) + ": not JSON (" + what + ")";
}

}  // namespace lexdyn::records

// Reading user files as text (docs/architecture.md, "Errors and exit codes"): a size guard and a
// check that the content is text, so that a binary, truncated-to-garbage or huge file is an
// InputError naming the file (and, for binary data, its line and column) instead of a parser's
// puzzling message ("document empty") or an allocation failure.
#pragma once

#include <cstddef>
#include <string>

namespace lexdyn {

/// Size guard of readTextFile: case files, robot files, problem files and manifests are far below.
inline constexpr std::size_t kMaxTextFileBytes = std::size_t{256} << 20;  // 256 MiB

/// Reads a whole file. Throws InputError naming `path` when it cannot be opened, is not a regular
/// file, is larger than max_bytes, or is not text (requireText). `what` names the kind of file in
/// messages ("case", "URDF", "problem").
std::string readTextFile(const std::string& path, const char* what, std::size_t max_bytes = kMaxTextFileBytes);

/// Throws InputError("file:line", ...) at the first NUL byte or byte sequence that is not UTF-8.
void requireText(const std::string& text, const std::string& file, const char* what);

}  // namespace lexdyn

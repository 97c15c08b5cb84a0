#include "lexdyn/common/input_text.hpp"

#include "lexdyn/common/error.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace lexdyn {

namespace {

std::string hexByte(unsigned char c) {
  char buf[8];
  std::snprintf(buf, sizeof(buf), "0x%02x", static_cast<unsigned>(c));
  return buf;
}

// Length of the UTF-8 sequence starting at s[i] (RFC 3629: no overlongs, no surrogates, at most
// U+10FFFF), 0 when it is not valid.
std::size_t utf8Length(const std::string& s, std::size_t i) {
  const auto b = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = b(i);
  if (c < 0x80) return 1;
  std::size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;
  if (c >= 0xC2 && c <= 0xDF) {
    n = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
    if (c == 0xE0) lo = 0xA0;
    if (c == 0xED) hi = 0x9F;
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
    if (c == 0xF0) lo = 0x90;
    if (c == 0xF4) hi = 0x8F;
  } else {
    return 0;
  }
  if (i + n > s.size()) return 0;
  if (b(i + 1) < lo || b(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k) {
    if (b(i + k) < 0x80 || b(i + k) > 0xBF) return 0;
  }
  return n;
}

}  // namespace

void requireText(const std::string& text, const std::string& file, const char* what) {
  std::size_t line = 1, line_start = 0;
  for (std::size_t i = 0; i < text.size();) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      ++line;
      line_start = ++i;
      continue;
    }
    const std::size_t n = c == 0 ? 0 : utf8Length(text, i);
    if (n == 0) {
      throw InputError(file + ":" + std::to_string(line), std::string("expected a text ") + what +
                                                              " file (UTF-8), found binary data: byte " + hexByte(c) + " at column " +
                                                              std::to_string(i - line_start + 1));
    }
    i += n;
  }
}

std::string readTextFile(const std::string& path, const char* what, std::size_t max_bytes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) throw InputError(path, std::string("cannot open the ") + what + " file: it does not exist");
  if (fs::is_directory(st)) throw InputError(path, std::string("expected a ") + what + " file, found a directory");
  if (fs::is_regular_file(st)) {
    const auto size = fs::file_size(path, ec);
    if (!ec && size > max_bytes) {
      throw InputError(path, std::string("the ") + what + " file is " + std::to_string(size) + " bytes, more than the " +
                                 std::to_string(max_bytes) + " bytes accepted");
    }
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, std::string("cannot open the ") + what + " file for reading");
  std::string text;
  char buf[1 << 16];
  while (in.read(buf, sizeof(buf)) || in.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(in.gcount()));
    if (text.size() > max_bytes) {
      throw InputError(path, std::string("the ") + what + " file is larger than the " + std::to_string(max_bytes) + " bytes accepted");
    }
  }
  if (in.bad()) throw InputError(path, std::string("read error in the ") + what + " file");
  requireText(text, path, what);
  return text;
}

}  // namespace lexdyn

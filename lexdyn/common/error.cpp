#include "lexdyn/common/error.hpp"

#include <cstdio>
#include <cstdlib>

namespace lexdyn {

void abortWithMessage(const char* file, int line, const char* cond, const std::string& msg) {
  std::fprintf(stderr, "lexdyn: internal error at %s:%d: (%s) %s\n", file, line, cond, msg.c_str());
  std::abort();
}

}  // namespace lexdyn

#include "lexdyn/common/format.hpp"

#include <cstdio>

namespace lexdyn {

std::string formatNumber(double v, int significant) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*g", significant, v);
  return buf;
}

}  // namespace lexdyn

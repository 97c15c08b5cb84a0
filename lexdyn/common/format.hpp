// Numbers in messages and recorded settings.
#pragma once

#include <string>

namespace lexdyn {

/// `v` with `significant` significant digits (printf's %.Ng): 6 in messages, 10 for the settings a
/// trace header records. inf and nan print as such.
std::string formatNumber(double v, int significant = 6);

}  // namespace lexdyn

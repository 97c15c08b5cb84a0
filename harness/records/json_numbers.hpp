// How the records write a figure that may not be computed: a finite number as itself, anything
// else (NaN, infinity) as null; and back.
#pragma once

#include <nlohmann/json_fwd.hpp>

namespace lexdyn::records {

/// `v` when finite, else null.
nlohmann::json finiteOrNull(double v);
/// A JSON number as a double; anything else (null, a string, missing) as NaN.
double numberOrNaN(const nlohmann::json& v);

}  // namespace lexdyn::records

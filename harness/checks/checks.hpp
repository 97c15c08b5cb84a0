// Checks read traces (channels by name), never live objects, so they run the same on a fresh
// simulation (row by row as the run goes) and on a stored trace file.
//
// Check types (docs/simulator.md, "Checks"):
//   frame_drift     max |p(t) - p(from_s)| of a frame's origin over t >= from_s        [m]
//   force_balance   max |sum of contact normal forces - robot weight| / weight, t >= from_s
//   contact_slip    max horizontal displacement of any contact point of the given surfaces
//                   from its position at from_s, over t >= from_s                     [m]
//   frame_height    lowest height of a frame's origin over t >= from_s (e.g. "has not fallen")
// A check passes when it saw at least one row at t >= from_s and value <= limit (value >= limit
// for frame_height).
#pragma once

#include "harness/checks/trace.hpp"

#include <memory>
#include <string>
#include <vector>

namespace lexdyn::checks {

struct CheckSpec {
  std::string name;
  std::string type;                    ///< frame_drift | force_balance | contact_slip | frame_height
  std::string frame;                   ///< frame_drift, frame_height
  std::vector<std::string> surfaces;   ///< force_balance, contact_slip
  double from_s = 0.0;
  double limit = 0.0;
  std::string where;                   ///< origin in the case file, for messages
};

struct CheckResult {
  std::string name;
  std::string type;
  bool passed = false;
  double value = 0.0;  ///< NaN when no row was seen
  double limit = 0.0;
  std::string unit;
  std::string detail;
};

class Check {
 public:
  virtual ~Check() = default;
  /// Resolves channels; throws lexdyn::InputError (naming spec.where) if the trace lacks them.
  virtual void bind(const TraceSchema& schema, const TraceMetadata& metadata) = 0;
  virtual void consume(const double* row) = 0;
  virtual CheckResult result() const = 0;
};

/// The known check types.
const std::vector<std::string>& checkTypes();
std::unique_ptr<Check> makeCheck(const CheckSpec& spec);

/// Channel names the runner records and the checks read.
std::string frameChannel(const std::string& frame, char axis);               // frame.<F>.<x|y|z>
std::string contactForceChannel(const std::string& surface);                 // contact.<S>.fz
std::string contactPointChannel(const std::string& surface, int point, char axis);  // contact.<S>.p<i>.<x|y>
constexpr const char* kTimeChannel = "t";
constexpr const char* kWeightMetadata = "robot_weight_N";

/// Runs checks over a stored trace.
std::vector<CheckResult> runChecks(const std::vector<CheckSpec>& specs, const TraceTable& trace);

}  // namespace lexdyn::checks

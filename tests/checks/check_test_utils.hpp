// Helpers for tests of check types: one check run on a trace, the params of joint checks, and
// the expectations on a check's result (value, verdict, detail).
#pragma once

#include "harness/checks/checks.hpp"
#include "harness/checks/trace.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace lexdyn::checks::testing {

/// The result of the check `s` on `t`.
inline CheckResult runOne(const CheckSpec& s, const TraceTable& t) {
  const std::vector<CheckResult> r = runChecks({s}, t);
  EXPECT_EQ(r.size(), 1u);
  return r.empty() ? CheckResult{} : r[0];
}

inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// The params P of a joint check on the measured velocities of `joints`, set in `s`.
template <class P>
P& measuredJoints(CheckSpec& s, std::vector<std::string> joints) {
  auto& p = s.params.emplace<P>();
  p.source = "measured";
  p.joints = std::move(joints);
  return p;
}

/// A check's expected value: exactly `value`, within `tol` of it, or no value (kNoValue, NaN).
struct Expected {
  Expected(double value, double tol = 0.0) : value(value), tol(tol) {}  // implicit: a number is an exact value
  double value, tol;
};

enum class Verdict { kPass, kFail, kEither };
constexpr Verdict kPass = Verdict::kPass, kFail = Verdict::kFail, kEither = Verdict::kEither;
const double kNoValue = std::numeric_limits<double>::quiet_NaN();

/// runOne(s, t), expecting its value, its verdict (kEither: not checked) and these parts of its
/// detail. Returns the result.
inline CheckResult expectOutcome(const CheckSpec& s, const TraceTable& t, Expected value, Verdict verdict,
                                 std::initializer_list<std::string> detail = {}) {
  const CheckResult r = runOne(s, t);
  if (std::isnan(value.value)) {
    EXPECT_TRUE(std::isnan(r.value)) << s.type << ": " << r.value;
  } else if (value.tol == 0.0) {
    EXPECT_EQ(r.value, value.value) << s.type << ": " << r.detail;
  } else {
    EXPECT_NEAR(r.value, value.value, value.tol) << s.type << ": " << r.detail;
  }
  if (verdict != kEither) {
    EXPECT_EQ(r.passed, verdict == kPass) << s.type << ": " << r.detail;
  }
  for (const std::string& part : detail) EXPECT_TRUE(contains(r.detail, part)) << s.type << ": " << r.detail;
  return r;
}

}  // namespace lexdyn::checks::testing

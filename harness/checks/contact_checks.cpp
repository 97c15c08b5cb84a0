// Checks on the lexdyn controller's contact wrenches: parsers and evaluators (docs/cases.md,
// "Checks").
#include "harness/checks/contact_checks.hpp"

#include "harness/checks/check_base.hpp"

#include <algorithm>
#include <cmath>

namespace lexdyn::checks {

namespace {

using Polygon = std::vector<std::pair<double, double>>;

/// Convex hull (counter-clockwise, Andrew's monotone chain) of the points' (x, y).
Polygon convexHull(Polygon p) {
  std::sort(p.begin(), p.end());
  p.erase(std::unique(p.begin(), p.end()), p.end());
  if (p.size() < 3) return p;
  auto cross = [](const std::pair<double, double>& o, const std::pair<double, double>& a, const std::pair<double, double>& b) {
    return (a.first - o.first) * (b.second - o.second) - (a.second - o.second) * (b.first - o.first);
  };
  Polygon h(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i - 1]) <= 0) --k;
    h[k++] = p[i - 1];
  }
  h.resize(k - 1);
  return h;
}

// ---------------------------------------------------------------------------------------------
// Parsers.

const CheckContext::Contact& readContact(CheckReader& r, ContactParams& p) {
  const CheckContext::Contact& c = r.contact(&p.source);
  p.contact = c.name;
  p.normal = c.normal;
  return c;
}

double minNormal(CheckReader& r) { return r.number("min_normal_N", 1.0, &yaml::Node::asNonNegativeDouble); }

void readUnilateral(CheckReader& r) {
  ContactParams p;
  readContact(r, p);
  r.spec.params = std::move(p);
  r.spec.limit = r.map.required("min_N").asDouble();
}

void readFriction(CheckReader& r) {
  ContactFrictionParams p;
  const double mu = readContact(r, p).friction;  // the contact's, unless given
  p.friction = r.number("friction", mu, &yaml::Node::asPositiveDouble);
  p.min_normal_N = minNormal(r);
  r.spec.params = std::move(p);
  r.spec.limit = r.number("limit_ratio", 1.0, &yaml::Node::asPositiveDouble);
}

void readCop(CheckReader& r) {
  ContactCopParams p;
  const CheckContext::Contact& c = readContact(r, p);
  if ((c.normal - Eigen::Vector3d::UnitZ()).norm() > 1e-12) {
    r.map.required("contact").fail("contact_cop needs a contact whose normal is the frame's z axis");
  }
  Polygon pts;
  for (const auto& pt : c.points) pts.emplace_back(pt.x(), pt.y());
  p.polygon = convexHull(pts);
  if (p.polygon.size() < 3)
    r.map.required("contact").fail("contact_cop needs a contact with a support polygon (3 points or more, not aligned)");
  p.min_normal_N = minNormal(r);
  r.spec.params = std::move(p);
  r.spec.limit = r.number("limit_m", 0.0, &yaml::Node::asDouble);
}

void readWrenchMatch(CheckReader& r) {
  WrenchMatchParams p;
  p.contact = r.contact(nullptr).name;
  if (auto v = r.map.optional("component")) p.component = v->asEnum({"force", "torque"});
  if (auto v = r.map.optional("statistic")) p.statistic = v->asEnum({"rms", "max"});
  r.spec.params = p;
  r.spec.limit = r.map.required(p.component == "force" ? "limit_N" : "limit_Nm").asPositiveDouble();
}

// ---------------------------------------------------------------------------------------------
// Evaluators. Wrenches are in the contact frame, about its origin (docs/cases.md). Rows where
// the controller's contact is inactive are skipped.

const char* const kWrenchComponents[6] = {"fx", "fy", "fz", "tx", "ty", "tz"};

/// The contact part of the params of a contact check (ContactParams or a struct derived from it).
const ContactParams& contactParamsOf(const CheckSpec& s) {
  if (const auto* p = std::any_cast<ContactFrictionParams>(&s.params)) return *p;
  if (const auto* p = std::any_cast<ContactCopParams>(&s.params)) return *p;
  return s.paramsAs<ContactParams>();
}

class ContactCheck : public CheckBase {
 public:
  ContactCheck(const CheckSpec& s, const CheckType& t) : CheckBase(s, t), c_(contactParamsOf(spec_)) {}

 protected:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override {
    active_ = channel(schema, contactActiveChannel(c_.contact));
    const bool sensed = c_.source == "sensed";
    for (int k = 0; k < 6; ++k) w_[k] = channel(schema, wrenchChannel(c_.contact, sensed, kWrenchComponents[k]));
  }
  bool contactActive(const double* row) const { return active(row) && row[active_] != 0.0; }
  double normalForce(const double* row) const { return row[w_[0]] * c_.normal[0] + row[w_[1]] * c_.normal[1] + row[w_[2]] * c_.normal[2]; }
  double tangentialForce(const double* row) const {
    const double fn = normalForce(row);
    double s = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double ft = row[w_[k]] - fn * c_.normal[k];
      s += ft * ft;
    }
    return std::sqrt(s);
  }
  const char* sourceName() const { return c_.source == "sensed" ? "sensed" : "computed"; }
  std::string noRowDetail() const override { return "no row with contact '" + c_.contact + "' active in the window"; }
  const ContactParams& c_;
  int active_ = 0;
  int w_[6] = {0, 0, 0, 0, 0, 0};
};

// Lowest normal force while the contact is active; passes when every row has
// f_n >= min_N - 1e-9 |f| (round-off of the wrench's frame change, relative to the row's force).
class ContactUnilateral final : public ContactCheck {
 public:
  ContactUnilateral(const CheckSpec& s, const CheckType& t) : ContactCheck(s, t) {}
  void consume(const double* row) override {
    if (!contactActive(row)) return;
    seen_ = true;
    const double fn = normalForce(row);
    const double fnorm = std::sqrt(row[w_[0]] * row[w_[0]] + row[w_[1]] * row[w_[1]] + row[w_[2]] * row[w_[2]]);
    if (!(fn >= spec_.limit - kBoundaryRelTolerance * fnorm)) {
      if (!below_) first_below_ = row[t_];
      below_ = true;
    }
    if (worse(fn)) detail_ = std::string("lowest ") + sourceName() + " normal force at t = " + fmt(row[t_]) + " s";
  }
  void finish(CheckResult& r) const override {
    r.passed = !below_;
    if (below_) r.detail += "; first below " + fmt(spec_.limit) + " N at t = " + fmt(first_below_) + " s";
  }

 private:
  bool below_ = false;
  double first_below_ = 0.0;
};

// A contact check over the rows with f_n >= min_normal_N (the others are counted as skipped).
class ContactLoadedCheck : public ContactCheck {
 public:
  ContactLoadedCheck(const CheckSpec& s, const CheckType& t, double min_normal_N) : ContactCheck(s, t), min_normal_N_(min_normal_N) {}
  std::string noRowDetail() const override {
    return "no row with contact '" + c_.contact + "' active and f_n >= " + fmt(min_normal_N_) + " N";
  }
  void finish(CheckResult& r) const override {
    if (skipped_ > 0) r.detail += "; " + std::to_string(skipped_) + " rows with f_n below " + fmt(min_normal_N_) + " N skipped";
  }

 protected:
  /// True for a row to evaluate (the contact active, f_n >= min_normal_N and > 0).
  bool loaded(double fn) {
    if (!(fn >= min_normal_N_) || fn <= 0.0) {
      ++skipped_;
      return false;
    }
    seen_ = true;
    return true;
  }

 private:
  const double min_normal_N_;
  long skipped_ = 0;
};

// max |f_t| / (mu f_n) over rows with f_n >= min_normal_N (the circular cone). The computed
// wrench lies exactly on the cone when a single generator of the friction pyramid carries it,
// so the ratio may exceed the limit by 1e-9 (round-off).
class ContactFriction final : public ContactLoadedCheck {
 public:
  ContactFriction(const CheckSpec& s, const CheckType& t)
      : ContactLoadedCheck(s, t, s.paramsAs<ContactFrictionParams>().min_normal_N), p_(spec_.paramsAs<ContactFrictionParams>()) {
    tolerance_ = kBoundaryRelTolerance;
  }
  void consume(const double* row) override {
    if (!contactActive(row)) return;
    const double fn = normalForce(row);
    if (!loaded(fn)) return;
    if (worse(tangentialForce(row) / (p_.friction * fn))) {
      detail_ = std::string("largest ") + sourceName() + " ratio at t = " + fmt(row[t_]) + " s (f_n " + fmt(fn) + " N, mu " +
                fmt(p_.friction) + ")";
    }
  }

 private:
  const ContactFrictionParams& p_;
};

// Signed distance (m) of the centre of pressure to the support polygon's boundary: negative
// inside, positive outside. Value = the largest over rows with f_n >= min_normal_N.
double signedDistanceToPolygon(const Polygon& poly, double x, double y) {
  double dmin = kInf;
  bool inside = true;
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const auto& a = poly[i];
    const auto& b = poly[(i + 1) % n];
    const double ex = b.first - a.first, ey = b.second - a.second;
    const double px = x - a.first, py = y - a.second;
    if (ex * py - ey * px < 0.0) inside = false;  // right of a counter-clockwise edge
    const double len2 = ex * ex + ey * ey;
    const double s = len2 > 0.0 ? std::clamp((px * ex + py * ey) / len2, 0.0, 1.0) : 0.0;
    const double dx = px - s * ex, dy = py - s * ey;
    dmin = std::min(dmin, std::sqrt(dx * dx + dy * dy));
  }
  return inside ? -dmin : dmin;
}

// A CoP on the polygon's edge (all the force on one edge or corner) passes a limit of 0: the
// distance may exceed the limit by 1e-9 of the polygon's diameter (round-off).
class ContactCop final : public ContactLoadedCheck {
 public:
  ContactCop(const CheckSpec& s, const CheckType& t)
      : ContactLoadedCheck(s, t, s.paramsAs<ContactCopParams>().min_normal_N), p_(spec_.paramsAs<ContactCopParams>()) {
    worst_ = -kInf;
    double diameter = 0.0;
    for (const auto& a : p_.polygon) {
      for (const auto& b : p_.polygon) diameter = std::max(diameter, std::hypot(a.first - b.first, a.second - b.second));
    }
    tolerance_ = kBoundaryRelTolerance * diameter;
  }
  void consume(const double* row) override {
    if (!contactActive(row)) return;
    const double fz = row[w_[2]];
    if (!loaded(fz)) return;
    // The contact frame's z is the normal; the CoP on the frame's z = 0 plane.
    const double x = 0.0 - row[w_[4]] / fz, y = row[w_[3]] / fz;  // 0.0 - : no "-0" in details
    if (worse(signedDistanceToPolygon(p_.polygon, x, y))) {
      detail_ = std::string(sourceName()) + " CoP (" + fmt(x) + ", " + fmt(y) + ") m in the contact frame at t = " + fmt(row[t_]) + " s";
    }
  }

 private:
  const ContactCopParams& p_;
};

// Computed (from gamma) against sensed wrench, force or torque part: rms or max of the norm of
// the difference over the rows with the contact active.
class ContactWrenchMatch final : public CheckOf<WrenchMatchParams> {
 public:
  ContactWrenchMatch(const CheckSpec& s, const CheckType& t) : CheckOf(s, t) {
    if (p_.component == "torque") unit_ = "N m";
  }

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override {
    active_ = channel(schema, contactActiveChannel(p_.contact));
    const int k0 = p_.component == "torque" ? 3 : 0;
    for (int k = 0; k < 3; ++k) {
      c_[k] = channel(schema, wrenchChannel(p_.contact, false, kWrenchComponents[k0 + k]));
      s_[k] = channel(schema, wrenchChannel(p_.contact, true, kWrenchComponents[k0 + k]));
    }
  }
  void consume(const double* row) override {
    if (!active(row) || row[active_] == 0.0) return;
    seen_ = true;
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += (row[c_[k]] - row[s_[k]]) * (row[c_[k]] - row[s_[k]]);
    const double d = std::sqrt(d2);
    sum2_ += d2;
    ++n_;
    if (d > max_ || std::isnan(d)) {
      max_ = d;
      t_max_ = row[t_];
    }
  }
  std::string noRowDetail() const override { return "no row with contact '" + p_.contact + "' active in the window"; }
  void finish(CheckResult& r) const override {
    r.value = p_.statistic == "max" ? max_ : std::sqrt(sum2_ / static_cast<double>(n_));
    r.passed = r.value <= spec_.limit;
    r.detail = p_.statistic + " of |computed - sensed| " + p_.component + " over " + std::to_string(n_) + " rows; largest " + fmt(max_) +
               " at t = " + fmt(t_max_) + " s";
  }

  int active_ = 0, c_[3] = {0, 0, 0}, s_[3] = {0, 0, 0};
  double sum2_ = 0.0, max_ = 0.0, t_max_ = 0.0;
  long n_ = 0;
};

}  // namespace

CheckType contactUnilateralCheck() {
  return {"contact_unilateral", "N", kControllerChannels | kBoundsBelow, readUnilateral, makeEvaluator<ContactUnilateral>};
}
CheckType contactFrictionCheck() {
  return {"contact_friction", "|f_t| / (mu f_n)", kControllerChannels, readFriction, makeEvaluator<ContactFriction>};
}
CheckType contactCopCheck() {
  return {"contact_cop", "m (signed distance to the sole's edge, < 0 inside)", kControllerChannels, readCop, makeEvaluator<ContactCop>};
}
CheckType contactWrenchMatchCheck() {
  return {"contact_wrench_match", "N", kControllerChannels, readWrenchMatch, makeEvaluator<ContactWrenchMatch>};
}

}  // namespace lexdyn::checks

// Checks on the simulator's channels (docs/simulator.md, "Checks"): parsers and evaluators.
#include "harness/checks/sim_checks.hpp"

#include "harness/checks/check_base.hpp"
#include "lexdyn/common/input_ranges.hpp"

#include <cmath>
#include <cstdlib>
#include <utility>

namespace lexdyn::checks {

namespace {

// ---------------------------------------------------------------------------------------------
// Parsers.

void readFrame(CheckReader& r) { r.spec.params = FrameParams{r.context.frame(r.map.required("frame"))}; }

void readSurfaces(CheckReader& r) {
  SurfacesParams p;
  for (const yaml::Node& sn : atLeastOne(r.map.required("surfaces"), "contact surface")) p.surfaces.push_back(r.context.surface(sn));
  r.spec.params = std::move(p);
}

void readFrameDrift(CheckReader& r) {
  readFrame(r);
  r.spec.limit = r.map.required("limit_m").asPositiveDouble();
}

void readForceBalance(CheckReader& r) {
  readSurfaces(r);
  r.spec.limit = r.map.required("limit_rel").asPositiveDouble();
}

void readContactSlip(CheckReader& r) {
  readSurfaces(r);
  r.spec.limit = r.map.required("limit_m").asPositiveDouble();
}

void readFrameHeight(CheckReader& r) {
  readFrame(r);
  r.spec.limit = r.map.required("min_m").asDoubleIn(-ranges::kMaxPosition_m, ranges::kMaxPosition_m, "m");
}

// ---------------------------------------------------------------------------------------------
// Evaluators.

class FrameDrift final : public CheckOf<FrameParams> {
 public:
  using CheckOf::CheckOf;

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override {
    for (int k = 0; k < 3; ++k) c_[k] = channel(schema, frameChannel(p_.frame, "xyz"[k]));
  }
  void sample(const double* row, bool first) override {
    if (first) {
      for (int k = 0; k < 3; ++k) ref_[k] = row[c_[k]];
    }
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += (row[c_[k]] - ref_[k]) * (row[c_[k]] - ref_[k]);
    if (worse(std::sqrt(d2))) detail_ = "largest at t = " + std::to_string(row[t_]) + " s";
  }
  int c_[3] = {0, 0, 0};
  double ref_[3] = {0, 0, 0};
};

class ForceBalance final : public CheckOf<SurfacesParams> {
 public:
  using CheckOf::CheckOf;

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata& metadata) override {
    for (const auto& s : p_.surfaces) cols_.push_back(channel(schema, contactForceChannel(s)));
    const std::string* w = findMetadata(metadata, kWeightMetadata);
    if (!w) throw InputError(spec_.where, std::string("check '") + spec_.name + "' needs the trace metadata '" + kWeightMetadata + "'");
    weight_ = std::strtod(w->c_str(), nullptr);
    if (!(weight_ > 0.0)) throw InputError(spec_.where, "robot weight in the trace metadata must be > 0");
  }
  void sample(const double* row, bool) override {
    double sum = 0.0;
    for (int c : cols_) sum += row[c];
    if (worse(std::abs(sum - weight_) / weight_)) {
      detail_ =
          "largest at t = " + std::to_string(row[t_]) + " s: sum " + std::to_string(sum) + " N, weight " + std::to_string(weight_) + " N";
    }
  }
  std::vector<int> cols_;
  double weight_ = 0.0;
};

// Lowest height of a frame's origin; passes when it stays at or above the limit.
class FrameHeight final : public CheckOf<FrameParams> {
 public:
  using CheckOf::CheckOf;

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override { z_ = channel(schema, frameChannel(p_.frame, 'z')); }
  void sample(const double* row, bool) override {
    if (worse(row[z_])) detail_ = "lowest at t = " + std::to_string(row[t_]) + " s";
  }
  int z_ = 0;
};

class ContactSlip final : public CheckOf<SurfacesParams> {
 public:
  using CheckOf::CheckOf;

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override {
    for (const auto& s : p_.surfaces) {
      int found = 0;
      for (int i = 0;; ++i) {
        const int cx = schema.find(contactPointChannel(s, i, 'x'));
        const int cy = schema.find(contactPointChannel(s, i, 'y'));
        if (cx < 0 || cy < 0) break;
        cols_.push_back({cx, cy});
        names_.push_back(s + ".p" + std::to_string(i));
        ++found;
      }
      if (found == 0) channel(schema, contactPointChannel(s, 0, 'x'));
    }
    ref_.assign(cols_.size(), {0.0, 0.0});
  }
  void sample(const double* row, bool first) override {
    if (first) {
      for (size_t i = 0; i < cols_.size(); ++i) ref_[i] = {row[cols_[i].first], row[cols_[i].second]};
    }
    for (size_t i = 0; i < cols_.size(); ++i) {
      const double dx = row[cols_[i].first] - ref_[i].first, dy = row[cols_[i].second] - ref_[i].second;
      if (worse(std::sqrt(dx * dx + dy * dy))) detail_ = "largest for " + names_[i] + " at t = " + std::to_string(row[t_]) + " s";
    }
  }
  std::vector<std::pair<int, int>> cols_;
  std::vector<std::string> names_;
  std::vector<std::pair<double, double>> ref_;
};

}  // namespace

CheckType frameDriftCheck() { return {"frame_drift", "m", kSimulatorChannels, readFrameDrift, makeEvaluator<FrameDrift>}; }
CheckType forceBalanceCheck() { return {"force_balance", "relative", kSimulatorChannels, readForceBalance, makeEvaluator<ForceBalance>}; }
CheckType contactSlipCheck() { return {"contact_slip", "m", kSimulatorChannels, readContactSlip, makeEvaluator<ContactSlip>}; }
CheckType frameHeightCheck() { return {"frame_height", "m", kBoundsBelow, readFrameHeight, makeEvaluator<FrameHeight>}; }

std::string frameChannel(const std::string& frame, char axis) { return "frame." + frame + "." + axis; }
std::string contactForceChannel(const std::string& surface) { return "contact." + surface + ".fz"; }
std::string contactPointChannel(const std::string& surface, int point, char axis) {
  return "contact." + surface + ".p" + std::to_string(point) + "." + axis;
}

std::vector<std::string> framesRead(const CheckSpec& spec) {
  if (const auto* p = std::any_cast<FrameParams>(&spec.params)) return {p->frame};
  return {};
}

}  // namespace lexdyn::checks

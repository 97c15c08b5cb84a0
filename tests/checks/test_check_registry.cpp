// The check registry (harness/checks/check_registry.hpp): every built-in type has a parser and an
// evaluator and reads its case-file entry against a CheckContext alone; an unknown type lists the
// known ones; a type registered here (not built in) is parsed from YAML and evaluated on a trace
// like any other.
#include "harness/checks/check_base.hpp"
#include "harness/checks/check_registry.hpp"
#include "harness/checks/health_checks.hpp"
#include "harness/checks/sim_checks.hpp"
#include "harness/checks/task_checks.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/common/yaml_strict.hpp"
#include "../common/expect_text.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <map>
#include <set>
#include <string>

namespace lexdyn::checks {
namespace {

/// A case: robot with frame F, surface S, joint J (effort 10), a lexdyn controller with contact C
/// (a 0.2 x 0.1 sole with a sensor), task T (position, kp 1) on level L of bfgs; ah without a
/// hierarchy.
CheckContext lexdynContext() {
  CheckContext x;
  x.controller = records::ControllerType::Lexdyn;
  x.control_period_s = 0.005;
  x.frames = {"F"};
  x.surfaces = {"S"};
  x.joints = {{"J", 10.0}};
  CheckContext::Contact c;
  c.name = "C";
  c.friction = 0.7;
  c.has_sensor = true;
  c.points = {{-0.1, -0.05, 0.0}, {0.1, -0.05, 0.0}, {0.1, 0.05, 0.0}, {-0.1, 0.05, 0.0}};
  x.contacts = {c};
  x.tasks = {{"T", "position", true, 1.0, std::nullopt}};
  x.methods = {{"bfgs", true, {"T"}, {"L"}}, {"ah", false, {}, {}}};
  return x;
}

/// The first entry of `checks:` in `text`.
yaml::Node firstCheck(const std::string& text) {
  const yaml::Node root = yaml::loadString("checks:\n  - " + text + "\n", "case.yaml");
  return root.entries()[0].second[0];
}

std::string errorOf(const std::function<void()>& f) { return lexdyn::testing::inputErrorOf(f); }

// One entry per built-in type, with its required keys.
const std::map<std::string, std::string>& entries() {
  static const std::map<std::string, std::string> e = {
      {"frame_drift", "{type: frame_drift, frame: F, limit_m: 0.1}"},
      {"force_balance", "{type: force_balance, surfaces: [S], limit_rel: 0.1}"},
      {"contact_slip", "{type: contact_slip, surfaces: [S], limit_m: 0.1}"},
      {"frame_height", "{type: frame_height, frame: F, min_m: 0.1}"},
      {"task_error", "{type: task_error, tasks: [T], statistic: final, limit: 1}"},
      {"torque_limits", "{type: torque_limits, limit_fraction: 1}"},
      {"contact_unilateral", "{type: contact_unilateral, contact: C, min_N: 0}"},
      {"contact_friction", "{type: contact_friction, contact: C}"},
      {"contact_cop", "{type: contact_cop, contact: C}"},
      {"contact_wrench_match", "{type: contact_wrench_match, contact: C, limit_N: 1}"},
      {"joint_acceleration_sign_changes", "{type: joint_acceleration_sign_changes, limit_per_s: 1}"},
      {"joint_velocity_hf_energy", "{type: joint_velocity_hf_energy, cutoff_hz: 5, limit_rad2_per_s2: 1}"},
      {"task_error_rate_sign_changes", "{type: task_error_rate_sign_changes, task: T, limit_per_s: 1}"},
      {"task_error_closed_form", "{type: task_error_closed_form, task: T, limit_rel: 0.1}"},
      {"task_overshoot", "{type: task_overshoot, task: T, limit_rel: 0.1}"},
      {"controller_status", "{type: controller_status}"},
      {"active_set_peak", "{type: active_set_peak, limit_iterations: 10}"},
      {"factorization_peak", "{type: factorization_peak, limit_factorizations: 10}"},
      {"augmented_fraction", "{type: augmented_fraction, level: L, max_fraction: 0.5}"},
      {"tick_time", "{type: tick_time, timer: tick, limit_us: 100}"},
  };
  return e;
}

TEST(CheckRegistry, EveryBuiltInTypeHasAParserAndAnEvaluator) {
  const CheckRegistry& r = builtinChecks();
  EXPECT_EQ(r.names(), checkTypes());
  EXPECT_EQ(r.types().size(), 20u);
  std::set<std::string> names;
  const CheckContext x = lexdynContext();
  for (const CheckType& t : r.types()) {
    SCOPED_TRACE(t.name);
    EXPECT_TRUE(names.insert(t.name).second) << "registered twice";
    ASSERT_NE(t.parse, nullptr);
    ASSERT_NE(t.make, nullptr);
    EXPECT_FALSE(t.unit.empty());
    ASSERT_TRUE(entries().count(t.name)) << "no case-file entry for type " << t.name << " in this test";
    // The parser needs the context only; the evaluator takes what it parsed.
    const CheckSpec s = readCheck(firstCheck(entries().at(t.name)), x);
    EXPECT_EQ(s.type, t.name);
    EXPECT_EQ(s.name, t.name);
    EXPECT_EQ(s.where, "case.yaml:2: checks[0]");
    EXPECT_EQ(s.params.has_value(), t.name != "active_set_peak" && t.name != "factorization_peak");
    EXPECT_NE(makeCheck(s), nullptr);
  }
  // Flags: what reads the controller, the direction of the bound, machine dependence.
  for (const char* sim : {"frame_drift", "force_balance", "contact_slip", "frame_height"})
    EXPECT_FALSE(r.find(sim)->readsController()) << sim;
  EXPECT_TRUE(r.find("task_error")->readsController());
  std::set<std::string> below, machine;
  for (const CheckType& t : r.types()) {
    if (t.boundsBelow()) below.insert(t.name);
    if (t.machineDependent()) machine.insert(t.name);
  }
  EXPECT_EQ(below, (std::set<std::string>{"frame_height", "contact_unilateral"}));
  EXPECT_EQ(machine, (std::set<std::string>{"tick_time"}));
}

TEST(CheckRegistry, ParsersReadTheirParamsFromTheContext) {
  const CheckContext x = lexdynContext();
  // The task's own gains (kv absent: 2 sqrt(kp)).
  CheckSpec s = readCheck(firstCheck(entries().at("task_error_closed_form")), x);
  EXPECT_EQ(s.paramsAs<TaskClosedFormParams>().task, "T");
  EXPECT_EQ(s.paramsAs<TaskClosedFormParams>().kp, 1.0);
  EXPECT_EQ(s.paramsAs<TaskClosedFormParams>().kv, 2.0);
  s = readCheck(firstCheck("{type: frame_height, name: up, frame: F, min_m: 0.5, from_s: 1}"), x);
  EXPECT_EQ(s.name, "up");
  EXPECT_EQ(s.from_s, 1.0);
  EXPECT_EQ(s.limit, 0.5);
  EXPECT_EQ(s.paramsAs<FrameParams>().frame, "F");
  EXPECT_EQ(framesRead(s), std::vector<std::string>{"F"});
  // Common keys: methods (with a hierarchy), to_s (controller checks only).
  s = readCheck(firstCheck("{type: controller_status, methods: [bfgs], to_s: 2}"), x);
  EXPECT_EQ(s.methods, std::vector<std::string>{"bfgs"});
  EXPECT_EQ(s.to_s, 2.0);
  EXPECT_EQ(s.paramsAs<ControllerStatusParams>().allowed, (std::vector<std::string>{"ok", "solver_stopped_early"}));
  EXPECT_NE(errorOf([&] {
              readCheck(firstCheck("{type: controller_status, methods: [ah]}"), x);
            }).find("case.yaml:2: checks[0].methods[0]: the case has no hierarchy for method ah"),
            std::string::npos);
  EXPECT_NE(errorOf([&] {
              readCheck(firstCheck("{type: frame_drift, frame: F, limit_m: 1, to_s: 2}"), x);
            }).find("checks[0].to_s: unknown key 'to_s'"),
            std::string::npos)
      << errorOf([&] { readCheck(firstCheck("{type: frame_drift, frame: F, limit_m: 1, to_s: 2}"), x); });
  // A controller check in a case without the lexdyn controller.
  CheckContext servo;
  servo.controller = records::ControllerType::PostureServo;
  EXPECT_NE(errorOf([&] {
              readCheck(firstCheck(entries().at("task_error")), servo);
            }).find("checks[0].type: check type task_error reads the lexdyn controller's channels; the controller is posture_servo"),
            std::string::npos);
}

TEST(CheckRegistry, AnUnknownTypeListsTheKnownOnes) {
  const std::string e = errorOf([] { builtinChecks().get("nope", "case.yaml:3: checks[1]"); });
  EXPECT_NE(e.find("case.yaml:3: checks[1]: unknown check type 'nope' (known: frame_drift, force_balance,"), std::string::npos) << e;
  EXPECT_NE(e.find(", tick_time)"), std::string::npos) << e;
  CheckSpec s;
  s.name = "x";
  s.type = "nope";
  s.where = "case.yaml:3: checks[1]";
  EXPECT_EQ(errorOf([&] { makeCheck(s); }), e);
  EXPECT_FALSE(machineDependent(s));
  // In a case file: the type key, with the known types.
  const std::string f = errorOf([] { readCheck(firstCheck("{type: nope}"), lexdynContext()); });
  EXPECT_NE(f.find("case.yaml:2: checks[0].type: "), std::string::npos) << f;
  EXPECT_NE(f.find("frame_drift"), std::string::npos) << f;
  EXPECT_NE(f.find("tick_time"), std::string::npos) << f;
}

// A toy check type registered by the test: the largest value of one channel.
struct ChannelMaxParams {
  std::string channel;
};

class ChannelMax final : public CheckOf<ChannelMaxParams> {
 public:
  using CheckOf::CheckOf;

 private:
  void bindChannels(const TraceSchema& schema, const TraceMetadata&) override { col_ = channel(schema, p_.channel); }
  void sample(const double* row, bool) override {
    if (worse(row[col_])) detail_ = "at t = " + fmt(row[t_]) + " s";
  }
  int col_ = 0;
};

void readChannelMax(CheckReader& r) {
  r.spec.params = ChannelMaxParams{r.map.required("channel").asString()};
  r.spec.limit = r.map.required("limit").asDouble();
}

TEST(CheckRegistry, AToyTypeIsParsedFromYamlAndEvaluatedOnATrace) {
  CheckRegistry registry = builtinChecks();
  registry.add({"channel_max", "units", kSimulatorChannels, readChannelMax, makeEvaluator<ChannelMax>});
  EXPECT_EQ(registry.names().back(), "channel_max");
  EXPECT_EQ(builtinChecks().find("channel_max"), nullptr);  // the built-in registry is untouched

  CheckContext servo;
  servo.controller = records::ControllerType::PostureServo;
  const CheckSpec s = readCheck(firstCheck("{type: channel_max, name: peak, channel: x, limit: 2.5, from_s: 0.1}"), servo, registry);
  EXPECT_EQ(s.name, "peak");
  EXPECT_EQ(s.paramsAs<ChannelMaxParams>().channel, "x");
  EXPECT_EQ(s.limit, 2.5);
  // Unknown keys of the toy type are refused like any other's, naming the key path.
  const std::string e = errorOf([&] { readCheck(firstCheck("{type: channel_max, channel: x, limit: 1, colour: red}"), servo, registry); });
  EXPECT_NE(e.find("case.yaml:2: checks[0].colour: unknown key 'colour'"), std::string::npos) << e;
  // Not a built-in type: the default registry does not know it.
  EXPECT_NE(errorOf([&] { readCheck(firstCheck("{type: channel_max, channel: x, limit: 1}"), servo); }).find("checks[0].type"),
            std::string::npos);

  TraceTable t;
  t.names = {kTimeChannel, "x"};
  t.rows = {{0.0, 3.0}, {0.1, 1.0}, {0.2, 2.0}, {0.3, 1.5}};
  TraceSchema schema;
  for (const auto& n : t.names) schema.add(n);
  auto c = makeCheck(s, registry);
  c->bind(schema, t.metadata);
  for (const auto& row : t.rows) c->consume(row.data());
  const CheckResult r = c->result();
  EXPECT_EQ(r.name, "peak");
  EXPECT_EQ(r.type, "channel_max");
  EXPECT_EQ(r.unit, "units");
  EXPECT_EQ(r.value, 2.0);  // the row at 0 s is before from_s
  EXPECT_TRUE(r.passed);
  EXPECT_EQ(r.detail, "at t = 0.2 s");
  EXPECT_DOUBLE_EQ(margin(r), 0.5);
  EXPECT_FALSE(r.machine_dependent);
}

}  // namespace
}  // namespace lexdyn::checks

#include "harness/golden/golden.hpp"

#include "harness/cases/runner.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/common/yaml_strict.hpp"
#include "lexdyn/control/method.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>

namespace lexdyn::golden {

namespace fs = std::filesystem;

namespace {

std::string num(double v) { return formatNumber(v, 10); }

// A tolerance beyond 1e6 (absolute) or 1 (relative) would accept anything a golden can hold.
constexpr double kMaxAbsTolerance = 1e6, kMaxRelTolerance = 1.0;

Tolerance readTolerance(const yaml::Node& n, Tolerance t) {
  yaml::StrictMap m(n);
  if (auto v = m.optional("abs")) t.abs = v->asDoubleIn(0.0, kMaxAbsTolerance);
  if (auto v = m.optional("rel")) t.rel = v->asDoubleIn(0.0, kMaxRelTolerance);
  m.finish();
  return t;
}

/// Glob patterns of a manifest list: non-empty strings, each once.
std::vector<std::string> readPatterns(const yaml::Node& list, bool allow_empty_list, std::vector<yaml::Node>* nodes) {
  std::vector<std::string> out;
  const std::vector<yaml::Node> items = list.elements();
  if (items.empty() && !allow_empty_list)
    list.fail("expected at least one channel pattern (\"t\" is always kept; \"*\" keeps every channel)");
  for (const yaml::Node& n : items) {
    const std::string p = n.asString();
    if (std::find(out.begin(), out.end(), p) != out.end()) n.fail("pattern '" + p + "' listed twice");
    out.push_back(p);
    if (nodes) nodes->push_back(n);
  }
  return out;
}

bool matchesAny(const std::vector<std::string>& patterns, const std::string& name) {
  for (const auto& p : patterns) {
    if (cases::globMatch(p, name)) return true;
  }
  return false;
}

std::string shell(const std::string& cmd) {
  std::string out;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
  if (!pipe) return out;
  std::array<char, 256> buf{};
  while (std::fgets(buf.data(), static_cast<int>(buf.size()), pipe.get())) out += buf.data();
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

}  // namespace

Manifest loadManifest(const std::string& path) {
  const yaml::Node root = yaml::loadFile(path);
  yaml::StrictMap top(root);
  Manifest m;
  m.path = path;
  m.dir = fs::path(path).parent_path().string();
  if (m.dir.empty()) m.dir = ".";
  const yaml::Node format = top.required("format");
  format.asEnum({"lexdyn-golden-manifest/1"});
  if (auto t = top.optional("tolerance")) m.tolerance = readTolerance(*t, m.tolerance);
  // Every pattern (channels, exclude, channel_tolerances) must match a channel of some golden
  // run: a misspelt pattern would silently keep, drop or loosen nothing.
  std::vector<std::pair<std::string, yaml::Node>> patterns;
  if (auto ct = top.optional("channel_tolerances")) {
    for (const yaml::Node& n : ct->elements()) {
      yaml::StrictMap cm(n);
      const yaml::Node match = cm.required("match");
      ChannelTolerance c{match.asString(), m.tolerance};
      patterns.emplace_back(c.match, match);
      if (auto v = cm.optional("abs")) c.tolerance.abs = v->asDoubleIn(0.0, kMaxAbsTolerance);
      if (auto v = cm.optional("rel")) c.tolerance.rel = v->asDoubleIn(0.0, kMaxRelTolerance);
      cm.finish();
      m.channel_tolerances.push_back(c);
    }
  }
  if (auto ch = top.optional("channels")) {
    std::vector<yaml::Node> nodes;
    m.channels = readPatterns(*ch, false, &nodes);
    for (size_t i = 0; i < nodes.size(); ++i) patterns.emplace_back(m.channels[i], nodes[i]);
  }
  if (auto ex = top.optional("exclude")) {
    std::vector<yaml::Node> nodes;
    m.exclude = readPatterns(*ex, true, &nodes);
    for (size_t i = 0; i < nodes.size(); ++i) patterns.emplace_back(m.exclude[i], nodes[i]);
  }
  const yaml::Node entries = top.required("entries");
  const bool patterns_to_check = !patterns.empty();
  std::set<std::string> channel_union;
  if (entries.size() < 1) entries.fail("expected at least one entry");
  for (const yaml::Node& en : entries.elements()) {
    yaml::StrictMap em(en);
    Entry e;
    e.where = en.where();
    const yaml::Node cn = em.required("case");
    const fs::path rel(cn.asString());
    e.case_path = (rel.is_absolute() ? rel : fs::path(m.dir) / rel).lexically_normal().string();
    if (!fs::is_regular_file(e.case_path)) cn.fail("case file not found: " + e.case_path);
    cases::CaseSpec spec = cases::loadCase(e.case_path);
    e.case_name = spec.name;
    if (auto methods = em.optional("methods")) {
      if (!cases::isLexdyn(spec))
        methods->fail(std::string("the case's controller (") + records::toString(spec.controller.type) + ") has no methods");
      for (const yaml::Node& mn : methods->elements()) {
        const std::string method = mn.asEnum(control::methodNames());
        if (std::find(e.methods.begin(), e.methods.end(), method) != e.methods.end()) mn.fail("method " + method + " listed twice");
        try {
          cases::overrideMethod(spec, method, mn.where());
        } catch (const InputError& err) {
          mn.fail(err.detail());
        }
        e.methods.push_back(method);
      }
      if (e.methods.empty()) methods->fail("expected at least one method");
    } else {
      if (cases::isLexdyn(spec)) en.fail("missing required key 'methods' (the case has a lexdyn controller)");
      e.methods.push_back("");
    }
    const yaml::Node d = em.required("duration_s");
    e.duration_s = d.asPositiveDouble();
    if (e.duration_s > spec.duration_s + 1e-12) d.fail("longer than the case (" + num(spec.duration_s) + " s)");
    if (e.duration_s < spec.control_period_s) d.fail("shorter than one control period of the case (" + num(spec.control_period_s) + " s)");
    const long ticks = std::lround(e.duration_s / spec.control_period_s);
    if (auto v = em.optional("every_n_ticks")) {
      e.every_n_ticks = v->asInt();
      if (e.every_n_ticks < 1 || e.every_n_ticks > ticks) {
        v->fail("expected an integer in [1, " + std::to_string(ticks) + "] (the ticks of the golden's horizon), found " +
                v->raw().Scalar());
      }
    }
    if (patterns_to_check) {
      for (const std::string& method : e.methods) {
        cases::CaseSpec ms = spec;
        if (!method.empty()) cases::overrideMethod(ms, method, e.where);
        for (const std::string& c : cases::traceChannels(ms)) channel_union.insert(c);
      }
    }
    em.finish();
    for (const auto& o : m.entries) {
      if (o.case_name == e.case_name) cn.fail("case '" + e.case_name + "' listed twice");
    }
    m.entries.push_back(e);
  }
  top.finish();
  for (const auto& [pattern, node] : patterns) {
    bool matched = false;
    for (const std::string& c : channel_union) {
      if (cases::globMatch(pattern, c)) {
        matched = true;
        break;
      }
    }
    if (!matched) node.fail("pattern '" + pattern + "' matches no channel of any golden run of the manifest");
  }
  return m;
}

std::string goldenId(const std::string& case_name, const std::string& method) {
  return method.empty() ? case_name : case_name + "." + method;
}

std::string goldenPath(const Manifest& m, const std::string& case_name, const std::string& method) {
  return (fs::path(m.dir) / (goldenId(case_name, method) + ".csv")).string();
}

checks::TraceTable selectChannels(const checks::TraceTable& t, const Manifest& m) {
  std::vector<size_t> keep;
  for (size_t i = 0; i < t.names.size(); ++i) {
    const std::string& n = t.names[i];
    if (n.rfind("time.", 0) == 0) continue;
    if (n != checks::kTimeChannel && (!matchesAny(m.channels, n) || matchesAny(m.exclude, n))) continue;
    keep.push_back(i);
  }
  checks::TraceTable out;
  out.metadata = t.metadata;
  for (size_t i : keep) out.names.push_back(t.names[i]);
  out.rows.reserve(t.rows.size());
  for (const auto& row : t.rows) {
    std::vector<double> r;
    r.reserve(keep.size());
    for (size_t i : keep) r.push_back(row[i]);
    out.rows.push_back(std::move(r));
  }
  return out;
}

checks::TraceTable runGolden(const Entry& e, const std::string& method, const Manifest& m, const std::string& work_dir,
                             records::RunStatus& status, bool progress, const std::atomic<bool>* interrupt) {
  cases::CaseSpec spec = cases::loadCase(e.case_path);
  if (!method.empty()) cases::overrideMethod(spec, method, e.where);
  spec.duration_s = std::min(spec.duration_s, e.duration_s);
  spec.trace.every_n_ticks = e.every_n_ticks;
  spec.trace.timings = false;
  // Without the wall-time channels the tick_time checks have nothing to read; a golden compares
  // traces, not check results, so they are left out (every other check keeps the channels it
  // adds, e.g. frames).
  spec.checks.erase(
      std::remove_if(spec.checks.begin(), spec.checks.end(), [](const checks::CheckSpec& c) { return checks::machineDependent(c); }),
      spec.checks.end());
  cases::RunOptions o;
  o.out_dir = (fs::path(work_dir) / goldenId(e.case_name, method)).string();
  o.progress = progress;
  o.interrupt = interrupt;
  const cases::RunSummary s = cases::runCase(spec, o);
  status = s.status;
  const checks::TraceTable full = checks::readTrace(s.trace_path);
  checks::TraceTable t = selectChannels(full, m);
  t.end_status = full.end_status;
  t.end_message = full.end_message;
  t.metadata.emplace_back("golden_run_status", records::toString(status));
  return t;
}

checks::TraceMetadata provenance(const Entry& e, const std::string& method, records::RunStatus status, const std::string& source_dir) {
  checks::TraceMetadata md;
  md.emplace_back("golden_format", "lexdyn-golden/1");
  md.emplace_back("golden_case", e.case_name);
  md.emplace_back("golden_method", method.empty() ? "none" : method);
  md.emplace_back("golden_duration_s", num(e.duration_s));
  md.emplace_back("golden_every_n_ticks", std::to_string(e.every_n_ticks));
  md.emplace_back("golden_run_status", records::toString(status));
  std::string rev = shell("git -C '" + source_dir + "' rev-parse HEAD 2>/dev/null");
  if (rev.empty()) {
    rev = "unknown (not a git checkout)";
  } else if (!shell("git -C '" + source_dir + "' status --porcelain --untracked-files=no 2>/dev/null").empty()) {
    rev += " (with uncommitted changes)";
  }
  md.emplace_back("git_revision", rev);
  md.emplace_back("regenerate", "lexdyn-harness golden update --only " + goldenId(e.case_name, method));
  return md;
}

void writeGolden(const std::string& path, const checks::TraceTable& t, const checks::TraceMetadata& prov) {
  checks::TraceSchema schema;
  for (const auto& n : t.names) schema.add(n);
  checks::TraceMetadata md = prov;
  for (const auto& kv : t.metadata) {
    if (kv.first.rfind("golden_", 0) == 0 || kv.first == "git_revision" || kv.first == "regenerate") continue;
    md.push_back(kv);
  }
  checks::TraceWriter w(path, schema, md, 1 << 30);
  for (const auto& row : t.rows) w.write(row.data());
  w.finish();
}

std::vector<std::string> goldenFileProblems(const checks::TraceTable& golden) {
  if (!golden.end_status) {
    return {"the golden file has no end mark ('# end: completed'): it was cut or damaged after " + std::to_string(golden.rows.size()) +
            " rows; restore it (git checkout) or regenerate it"};
  }
  if (!golden.complete()) {
    return {std::string("the golden file ends with '# end: ") + records::toString(*golden.end_status) +
            "', not written by `golden update`"};
  }
  return {};
}

Comparison compare(const checks::TraceTable& golden, const checks::TraceTable& fresh, const Tolerance& tolerance,
                   const std::vector<ChannelTolerance>& channel_tolerances) {
  Comparison c;
  // Channels.
  std::vector<int> col(golden.names.size(), -1);
  std::vector<Tolerance> tol(golden.names.size(), tolerance);
  for (size_t i = 0; i < golden.names.size(); ++i) {
    if (golden.names[i].rfind("time.", 0) == 0) continue;  // wall-clock times: never compared
    col[i] = fresh.column(golden.names[i]);
    if (col[i] < 0) c.problems.push_back("channel " + golden.names[i] + " is not in the fresh trace");
    for (const auto& ct : channel_tolerances) {
      if (cases::globMatch(ct.match, golden.names[i])) tol[i] = ct.tolerance;
    }
  }
  long extra = 0;
  for (const auto& n : fresh.names) extra += (golden.column(n) < 0 && n.rfind("time.", 0) != 0) ? 1 : 0;
  if (extra > 0) c.notes.push_back(std::to_string(extra) + " channels only in the fresh trace (not compared)");
  const int gt = golden.column(checks::kTimeChannel), ft = fresh.column(checks::kTimeChannel);
  if (gt < 0 || ft < 0) c.problems.push_back("no time channel 't'");
  // Run status and build.
  const std::string* gs = checks::findMetadata(golden.metadata, "golden_run_status");
  const std::string* fs_ = checks::findMetadata(fresh.metadata, "golden_run_status");
  if (gs && fs_ && *gs != *fs_) c.problems.push_back("run status: golden " + *gs + ", fresh " + *fs_);
  for (const char* key : {"compiler", "build_type", "cxx_flags", "eigen", "simbody", "sundials"}) {
    const std::string* a = checks::findMetadata(golden.metadata, key);
    const std::string* b = checks::findMetadata(fresh.metadata, key);
    if (a && b && *a != *b) c.notes.push_back(std::string("built differently: ") + key + " golden '" + *a + "', fresh '" + *b + "'");
  }
  const size_t n = std::min(golden.rows.size(), fresh.rows.size());
  if (golden.rows.size() != fresh.rows.size()) {
    auto span = [](const checks::TraceTable& t, int tc) {
      if (t.rows.empty() || tc < 0) return std::string("no rows");
      return std::to_string(t.rows.size()) + " rows, t = " + num(t.rows.front()[static_cast<size_t>(tc)]) + " .. " +
             num(t.rows.back()[static_cast<size_t>(tc)]) + " s";
    };
    c.problems.push_back("row count: golden " + span(golden, gt) + "; fresh " + span(fresh, ft));
  }
  c.rows = static_cast<long>(n);
  c.channels = 0;
  for (const auto& name : golden.names) c.channels += name.rfind("time.", 0) == 0 ? 0 : 1;
  bool found = false;
  for (size_t r = 0; r < n && gt >= 0 && ft >= 0; ++r) {
    const std::vector<double>& g = golden.rows[r];
    const std::vector<double>& f = fresh.rows[r];
    const double tg = g[static_cast<size_t>(gt)], tf = f[static_cast<size_t>(ft)];
    if (std::abs(tg - tf) > 1e-9) {
      c.problems.push_back("row " + std::to_string(r) + ": golden time " + num(tg) + " s, fresh " + num(tf) + " s");
      c.rows = static_cast<long>(r);
      break;
    }
    int at_row = 0;
    for (size_t i = 0; i < golden.names.size(); ++i) {
      if (col[i] < 0) continue;
      const double a = g[i], b = f[static_cast<size_t>(col[i])];
      bool same;
      double diff = 0.0;
      const double allowed = tol[i].abs + tol[i].rel * std::abs(a);
      if (std::isnan(a) || std::isnan(b)) {
        same = std::isnan(a) && std::isnan(b);
      } else if (std::isinf(a) || std::isinf(b)) {
        same = a == b;
      } else {
        diff = std::abs(a - b);
        same = diff <= allowed;
        if (diff > c.max_abs_diff) {
          c.max_abs_diff = diff;
          c.max_abs_channel = golden.names[i];
        }
      }
      if (same) continue;
      ++c.diverging_values;
      if (!found) {
        found = true;
        c.first_t = tg;
        c.first_channel = golden.names[i];
        c.golden_value = a;
        c.fresh_value = b;
        c.allowed = allowed;
      }
      if (found && tg == c.first_t) ++at_row;
    }
    if (found && tg == c.first_t) c.diverging_at_first_t = at_row;
  }
  c.ok = !found && c.problems.empty();
  return c;
}

std::string Comparison::report() const {
  std::string s;
  if (ok) {
    s = "ok: " + std::to_string(rows) + " rows x " + std::to_string(channels) + " channels within tolerance (largest |diff| " +
        num(max_abs_diff) + (max_abs_channel.empty() ? "" : " in " + max_abs_channel) + ")";
  } else {
    s = "MISMATCH";
    if (!first_channel.empty()) {
      s += ": first divergence at t = " + num(first_t) + " s in channel " + first_channel + " (golden " + num(golden_value) + ", fresh " +
           num(fresh_value) + ", allowed |diff| " + num(allowed) + "); " + std::to_string(diverging_at_first_t) +
           " channels diverge at that time, " + std::to_string(diverging_values) + " values in all";
    }
    for (const auto& p : problems) s += "; " + p;
  }
  for (const auto& n : notes) s += "; note: " + n;
  return s;
}

}  // namespace lexdyn::golden

// lexdyn._core: the compiled part of the lexdyn Python package (docs/python.md, "Bindings").
//
//   solver   Problem, Options, Solver, Result, solve(), load_problem(), result_to_json()
//   model    RobotModel.load(urdf, data): sizes, neutral configuration, update(q, u), frame and
//            point positions and Jacobians, centre of mass and its Jacobian, M, N
//   cases    _run_case(): the harness's `run` (loadCase, overrides, overrideMethod, runCase);
//            lexdyn.runs.run_case wraps it (temporary directory, summary and trace read back)
//
// numpy in, numpy out (copies). The GIL is released around solves, model loading and case runs.
// One translation unit; everything here is glue over the public C++ API.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "harness/cases/case_file.hpp"
#include "harness/cases/case_overrides.hpp"
#include "harness/cases/runner.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/model/robot_model.hpp"
#include "lexdyn/solver/problem.hpp"
#include "lexdyn/solver/problem_io.hpp"
#include "lexdyn/solver/solver.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

namespace ls = lexdyn::solver;
namespace lm = lexdyn::model;

[[noreturn]] void valueError(const std::string& what) { throw py::value_error(what); }

// ------------------------------------------------------------------------------------------------
// Solver
// ------------------------------------------------------------------------------------------------

// A bound vector: None is +-inf on every row (sign), else one number per row.
Eigen::VectorXd boundVector(const py::object& v, long rows, double none_value, const char* what) {
  if (v.is_none()) return Eigen::VectorXd::Constant(rows, none_value);
  Eigen::VectorXd out = v.cast<Eigen::VectorXd>();
  if (out.size() != rows) {
    valueError(std::string(what) + ": expected " + std::to_string(rows) + " entries (one per row), found " + std::to_string(out.size()));
  }
  return out;
}

Eigen::MatrixXd levelMatrix(const py::object& A, int variables) {
  Eigen::MatrixXd out = A.cast<Eigen::MatrixXd>();
  if (out.cols() != variables) {
    valueError("A: expected " + std::to_string(variables) + " columns (the problem's variables), found " + std::to_string(out.cols()));
  }
  return out;
}

int addLevel(ls::Problem& p, const py::object& A, const py::object& lower, const py::object& upper, const std::string& name) {
  Eigen::MatrixXd M = levelMatrix(A, p.variables());
  const long rows = M.rows();
  Eigen::VectorXd lo = boundVector(lower, rows, -ls::kInf, "lower");
  Eigen::VectorXd up = boundVector(upper, rows, ls::kInf, "upper");
  return p.addLevel(name, std::move(M), std::move(lo), std::move(up));
}

const char* kindName(ls::LevelKind k) { return k == ls::LevelKind::Bounds ? "bounds" : "general"; }

py::dict levelDict(const ls::Level& lv) {
  py::dict d;
  d["name"] = lv.name;
  d["kind"] = kindName(lv.kind);
  d["A"] = Eigen::MatrixXd(lv.A);
  d["lower"] = Eigen::VectorXd(lv.lower);
  d["upper"] = Eigen::VectorXd(lv.upper);
  d["variable"] = lv.variable;
  d["coefficient"] = Eigen::VectorXd(lv.coefficient);
  d["columns"] = lv.columns;
  return d;
}

ls::ActiveSet activeSetFrom(const py::object& obj) {
  ls::ActiveSet a;
  for (const py::handle level : obj) {
    const Eigen::VectorXi codes = py::cast<Eigen::VectorXi>(level);
    std::vector<ls::RowState> row;
    row.reserve(static_cast<size_t>(codes.size()));
    for (int i = 0; i < codes.size(); ++i) {
      if (codes(i) < 0 || codes(i) > 3) {
        valueError("active set: expected row states 0 (inactive), 1 (lower), 2 (upper), 3 (equality), found " + std::to_string(codes(i)));
      }
      row.push_back(static_cast<ls::RowState>(codes(i)));
    }
    a.level.push_back(std::move(row));
  }
  return a;
}

py::list activeSetList(const ls::ActiveSet& a) {
  py::list out;
  for (const auto& level : a.level) {
    py::array_t<std::int8_t> codes(static_cast<py::ssize_t>(level.size()));
    auto w = codes.mutable_unchecked<1>();
    for (size_t i = 0; i < level.size(); ++i) w(static_cast<py::ssize_t>(i)) = static_cast<std::int8_t>(level[i]);
    out.append(codes);
  }
  return out;
}

// A Python Result: the solver's result and the wall time of the C++ solve inside the call (the
// GIL released), as `lexdyn-solve --bench` times it (a first solve's setup left out): the call's
// own cost is the difference.
struct SolveResult : ls::Result {
  double solve_us = std::numeric_limits<double>::quiet_NaN();
};

// Result buffers that freed Python Results give back to the solver that made them: its next
// solve computes into them (Solver::swapResult), so a solve allocates and copies nothing for the
// Result it returns. Shared with the Results, which may outlive their solver.
struct ResultPool {
  static constexpr size_t kMaxSpare = 4;
  std::mutex mutex;
  std::vector<std::unique_ptr<SolveResult>> spare;

  // A Result for Python: a spare one (or a new, empty one), given back here when Python frees it.
  static std::shared_ptr<SolveResult> take(const std::shared_ptr<ResultPool>& pool) {
    std::unique_ptr<SolveResult> r;
    {
      const std::lock_guard<std::mutex> lock(pool->mutex);
      if (!pool->spare.empty()) {
        r = std::move(pool->spare.back());
        pool->spare.pop_back();
      }
    }
    if (!r) r = std::make_unique<SolveResult>();
    return std::shared_ptr<SolveResult>(r.release(), [home = std::weak_ptr<ResultPool>(pool)](SolveResult* freed) {
      std::unique_ptr<SolveResult> owned(freed);
      if (const std::shared_ptr<ResultPool> pl = home.lock()) {
        const std::lock_guard<std::mutex> lock(pl->mutex);
        if (pl->spare.size() < kMaxSpare) pl->spare.push_back(std::move(owned));
      }
    });
  }
};

// A Python solver: the C++ solver, set up at the first solve (or by setup()). The mutex keeps
// two Python threads (the GIL released) from solving with it at once.
struct PySolver {
  ls::Solver solver;
  ls::Options options;
  bool is_setup = false;
  std::mutex mutex;
  std::shared_ptr<ResultPool> pool = std::make_shared<ResultPool>();
};

// A warm start given as a pair (active set, x); a Result warm-starts in place (solveWith).
struct WarmStart {
  ls::ActiveSet active;
  Eigen::VectorXd x;
};

std::optional<WarmStart> warmStartFrom(const py::object& warm) {
  if (warm.is_none()) return std::nullopt;
  const py::tuple t = warm.cast<py::tuple>();
  if (t.size() != 2) valueError("warm: expected a Result or a pair (active set, x)");
  return WarmStart{activeSetFrom(t[0]), t[1].cast<Eigen::VectorXd>()};
}

std::shared_ptr<SolveResult> solveWith(PySolver& s, const ls::Problem& problem, const py::object& warm) {
  // A Result warm-starts in place (`warm` keeps it alive, and Python cannot change it): no copy
  // of its active set and x, as a C++ caller passes them.
  const SolveResult* from = !warm.is_none() && py::isinstance<SolveResult>(warm) ? &warm.cast<const SolveResult&>() : nullptr;
  const std::optional<WarmStart> w = from ? std::nullopt : warmStartFrom(warm);
  // A warm start of another problem's shape is a mistake, not a cold start.
  if (from || w) {
    const ls::ActiveSet& a = from ? from->active : w->active;
    const Eigen::VectorXd& x = from ? from->x : w->x;
    bool same = static_cast<int>(a.level.size()) == problem.levelCount() && x.size() == problem.variables();
    for (int l = 0; same && l < problem.levelCount(); ++l)
      same = static_cast<int>(a.level[static_cast<size_t>(l)].size()) == problem.level(l).rows();
    if (!same) {
      std::string rows;
      for (const auto& lv : a.level) rows += (rows.empty() ? "" : ", ") + std::to_string(lv.size());
      valueError("warm: a start of " + std::to_string(x.size()) + " variables and levels of [" + rows + "] rows, but the problem has " +
                 std::to_string(problem.variables()) + " variables and " + std::to_string(problem.levelCount()) + " levels");
    }
  }
  py::gil_scoped_release nogil;
  const std::lock_guard<std::mutex> lock(s.mutex);
  if (!s.is_setup) {
    s.solver.setup(problem, s.options);
    s.is_setup = true;
  }
  const auto start = std::chrono::steady_clock::now();
  if (from)
    s.solver.solve(problem, from->active, from->x);
  else if (w)
    s.solver.solve(problem, w->active, w->x);
  else
    s.solver.solve(problem);
  const auto end = std::chrono::steady_clock::now();
  // The Result Python keeps is the solver's own, swapped out; the solver keeps a spare Result's
  // buffers for its next solve.
  std::shared_ptr<SolveResult> out = ResultPool::take(s.pool);
  s.solver.swapResult(*out);
  out->solve_us = std::chrono::duration<double, std::micro>(end - start).count();
  return out;
}

// ------------------------------------------------------------------------------------------------
// Model
// ------------------------------------------------------------------------------------------------

// A model with its own workspace, updated by update(q, u). Flat configuration q (size nq):
// free-flyer [base position (3), base orientation quaternion w, x, y, z (4), joints], fixed base
// [joints].
struct PyModel {
  lm::RobotModel model;
  lm::ModelData data;
  Eigen::VectorXd q, u;

  explicit PyModel(lm::RobotModel&& m) : model(std::move(m)), data(model.createData()) {
    q = flat(model.neutralConfiguration());
    u = Eigen::VectorXd::Zero(model.nv());
    model.update(data, model.neutralConfiguration(), u);
  }

  int baseSize() const { return model.hasFreeFlyer() ? 7 : 0; }
  int nq() const { return baseSize() + model.numJoints(); }

  Eigen::VectorXd flat(const lm::Configuration& c) const {
    Eigen::VectorXd out(nq());
    if (model.hasFreeFlyer()) {
      Eigen::Quaterniond quat(c.base_rotation);
      quat.normalize();
      if (quat.w() < 0) quat.coeffs() *= -1.0;
      out.head<3>() = c.base_position;
      out(3) = quat.w();
      out(4) = quat.x();
      out(5) = quat.y();
      out(6) = quat.z();
    }
    out.tail(model.numJoints()) = c.joints;
    return out;
  }

  lm::Configuration configuration(const Eigen::VectorXd& qv) const {
    if (qv.size() != nq()) {
      valueError("q: expected " + std::to_string(nq()) + " entries (" +
                 (model.hasFreeFlyer() ? "base position 3, quaternion w x y z 4, joints " : "joints ") + std::to_string(model.numJoints()) +
                 "), found " + std::to_string(qv.size()));
    }
    if (!qv.allFinite()) valueError("q: expected finite numbers");
    lm::Configuration c;
    if (model.hasFreeFlyer()) {
      Eigen::Quaterniond quat(qv(3), qv(4), qv(5), qv(6));
      const double n = quat.norm();
      if (!(n > 1e-12)) valueError("q: the base quaternion (entries 3..6) is zero");
      quat.coeffs() /= n;
      c.base_rotation = quat.toRotationMatrix();
      c.base_position = qv.head<3>();
    }
    c.joints = qv.tail(model.numJoints());
    return c;
  }

  Eigen::VectorXd velocity(const py::object& uo) const {
    if (uo.is_none()) return Eigen::VectorXd::Zero(model.nv());
    Eigen::VectorXd out = uo.cast<Eigen::VectorXd>();
    if (out.size() != model.nv()) {
      valueError("u: expected " + std::to_string(model.nv()) + " entries (nv), found " + std::to_string(out.size()));
    }
    if (!out.allFinite()) valueError("u: expected finite numbers");
    return out;
  }

  lm::FrameId frame(const py::object& f) const {
    if (py::isinstance<py::str>(f)) return model.frameId(f.cast<std::string>());
    const int id = f.cast<int>();
    lexdyn::checkIndex("frame", id, model.numFrames());
    return id;
  }

  void update(const Eigen::VectorXd& qv, const py::object& uo) {
    const lm::Configuration c = configuration(qv);
    Eigen::VectorXd uv = velocity(uo);
    model.update(data, c, uv);
    q = qv;
    u = std::move(uv);
  }
};

Eigen::Matrix4d homogeneous(const Eigen::Isometry3d& T) { return T.matrix(); }

// ------------------------------------------------------------------------------------------------
// Cases
// ------------------------------------------------------------------------------------------------

// (path, YAML value, label naming it in errors)
using CaseOverride = std::tuple<std::string, std::string, std::string>;

// Runs the case on a worker thread while this (the calling) thread, with the GIL, looks for
// Python's signals every 100 ms: Ctrl-C stops the run after its current tick (the trace gets the
// end mark of an interrupted run, the summary is written) and is raised once the run has ended.
py::dict runCaseBound(const std::string& case_path, const std::string& method, const std::vector<CaseOverride>& overrides,
                      const std::string& out_dir, bool progress, bool wall_clock_checks, const std::string& dump_dir, double dump_from,
                      double dump_to) {
  std::vector<lexdyn::cases::Override> ov;
  ov.reserve(overrides.size());
  for (const CaseOverride& o : overrides) ov.push_back({std::get<0>(o), std::get<1>(o), std::get<2>(o)});

  std::atomic<bool> interrupt{false};
  std::atomic<int> interrupt_signal{0};
  lexdyn::cases::RunOptions options;
  options.out_dir = out_dir;
  options.progress = progress;
  options.interrupt = &interrupt;
  options.interrupt_signal = &interrupt_signal;
  options.wall_clock_checks = wall_clock_checks;
  options.dump_problems_dir = dump_dir;
  options.dump_from_s = dump_from;
  options.dump_to_s = dump_to;

  lexdyn::cases::RunSummary summary;
  std::exception_ptr failure;
  std::mutex mutex;
  std::condition_variable cv;
  bool done = false;
  std::optional<py::error_already_set> python_error;
  {
    py::gil_scoped_release nogil;
    std::thread worker([&] {
      try {
        lexdyn::cases::CaseSpec spec = lexdyn::cases::loadCase(case_path, ov);
        if (!method.empty()) lexdyn::cases::overrideMethod(spec, method, "method");
        summary = lexdyn::cases::runCase(spec, options);
      } catch (...) {
        failure = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex);
      done = true;
      cv.notify_all();
    });
    std::unique_lock<std::mutex> lock(mutex);
    while (!done) {
      cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return done; });
      if (done || python_error) continue;
      lock.unlock();
      {
        py::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() != 0) {
          python_error.emplace();  // fetches (and clears) the error the signal's handler raised
          interrupt_signal.store(SIGINT);
          interrupt.store(true);
        }
      }
      lock.lock();
    }
    lock.unlock();
    worker.join();
  }
  if (python_error) throw std::move(*python_error);
  if (failure) std::rethrow_exception(failure);
  py::dict out;
  out["exit_code"] = lexdyn::cases::exitCode(summary);
  out["status"] = lexdyn::records::toString(summary.status);
  out["message"] = summary.message;
  out["method"] = summary.method;
  out["trace_path"] = summary.trace_path;
  out["summary_path"] = summary.summary_path;
  out["case_path"] = summary.case_path;
  return out;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "lexdyn's C++ solver, robot model and case runner (docs/python.md, \"Bindings\")";

  py::register_exception<lexdyn::InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception<lexdyn::OutputError>(m, "OutputError", PyExc_OSError);

  // ---------------------------------------------------------------- solver
  py::class_<ls::Options>(m, "Options", "Solver options (lexdyn/solver/solver.hpp, docs/solver.md); keyword arguments set fields.")
      .def(py::init([](const py::kwargs& kw) {
        auto o = std::make_unique<ls::Options>();
        py::object self = py::cast(o.get(), py::return_value_policy::reference);
        for (const auto& item : kw) {
          const std::string key = item.first.cast<std::string>();
          if (!py::hasattr(self, key.c_str()) || key.rfind("_", 0) == 0) valueError("Options: unknown field '" + key + "'");
          py::setattr(self, key.c_str(), item.second);
        }
        return o;
      }))
      .def_static("paper", &ls::Options::paper, "dt"_a,
                  "The paper's termination rules for a control period dt: slack 1e-12 dt^2, 10 optimality-phase "
                  "iterations, 30 in total.")
      .def("validate", &ls::Options::validate, "Raises InputError unless every field is within its range.")
      .def_readwrite("rank_tolerance", &ls::Options::rank_tolerance)
      .def_readwrite("feasibility_tolerance", &ls::Options::feasibility_tolerance)
      .def_readwrite("zero_tolerance", &ls::Options::zero_tolerance)
      .def_readwrite("dual_tolerance", &ls::Options::dual_tolerance)
      .def_readwrite("eliminate_first_level", &ls::Options::eliminate_first_level)
      .def_readwrite("elimination_tolerance", &ls::Options::elimination_tolerance)
      .def_readwrite("split_from_variable", &ls::Options::split_from_variable)
      .def_property(
          "last_level_projection",
          [](const ls::Options& o) {
            switch (o.last_level_projection) {
              case ls::Options::LastLevel::Never:
                return "never";
              case ls::Options::LastLevel::Always:
                return "always";
              default:
                return "auto";
            }
          },
          [](ls::Options& o, const std::string& v) {
            if (v == "auto")
              o.last_level_projection = ls::Options::LastLevel::Auto;
            else if (v == "never")
              o.last_level_projection = ls::Options::LastLevel::Never;
            else if (v == "always")
              o.last_level_projection = ls::Options::LastLevel::Always;
            else
              valueError("last_level_projection: expected auto, never or always, found '" + v + "'");
          },
          "auto | never | always")
      .def_readwrite("spanning_stages", &ls::Options::spanning_stages)
      .def_readwrite("spanning_any_rows", &ls::Options::spanning_any_rows)
      .def_readwrite("spanning_structured", &ls::Options::spanning_structured)
      .def_readwrite("lazy_snapshots", &ls::Options::lazy_snapshots)
      .def_readwrite("restart_after_bound_change", &ls::Options::restart_after_bound_change)
      .def_readwrite("swap_reflectors", &ls::Options::swap_reflectors)
      .def_readwrite("project_unit_suffix", &ls::Options::project_unit_suffix)
      .def_readwrite("max_iterations", &ls::Options::max_iterations)
      .def_readwrite("bland_after_degenerate_steps", &ls::Options::bland_after_degenerate_steps)
      .def_readwrite("cycle_tolerance_factor", &ls::Options::cycle_tolerance_factor)
      .def_readwrite("stop_slack_norm", &ls::Options::stop_slack_norm)
      .def_readwrite("stop_optimality_iterations", &ls::Options::stop_optimality_iterations)
      .def_readwrite("stop_total_iterations", &ls::Options::stop_total_iterations)
      .def_readwrite("stop_after_level", &ls::Options::stop_after_level)
      .def_readwrite("compute_multipliers", &ls::Options::compute_multipliers)
      .def("__repr__", [](const ls::Options& o) {
        return "Options(max_iterations=" + std::to_string(o.max_iterations) +
               ", rank_tolerance=" + py::repr(py::float_(o.rank_tolerance)).cast<std::string>() + ", ...)";
      });

  py::class_<ls::Problem>(m, "Problem",
                          "A lexicographic least-squares problem: levels of rows lower <= A x <= upper, the first "
                          "level the most important (docs/solver.md).\n\n"
                          "Problem(variables, levels=None): levels is a list of (A, lower, upper) or (name, A, lower, "
                          "upper); None for a bound is -inf / +inf on every row, lower == upper an equality.")
      .def(py::init([](int variables, const py::object& levels) {
             if (variables <= 0) valueError("variables: expected a positive number, found " + std::to_string(variables));
             auto p = std::make_unique<ls::Problem>(variables);
             if (!levels.is_none()) {
               int i = 0;
               for (const py::handle h : levels) {
                 const py::tuple t = py::reinterpret_borrow<py::object>(h).cast<py::tuple>();
                 if (t.size() == 3) {
                   addLevel(*p, t[0], t[1], t[2], "level" + std::to_string(i));
                 } else if (t.size() == 4) {
                   addLevel(*p, t[1], t[2], t[3], t[0].cast<std::string>());
                 } else {
                   valueError("levels[" + std::to_string(i) + "]: expected (A, lower, upper) or (name, A, lower, upper)");
                 }
                 ++i;
               }
             }
             return p;
           }),
           "variables"_a, "levels"_a = py::none())
      .def_property_readonly("variables", &ls::Problem::variables)
      .def_property_readonly("level_count", &ls::Problem::levelCount)
      .def_property_readonly("total_rows", &ls::Problem::totalRows)
      .def("__len__", &ls::Problem::levelCount)
      .def(
          "add_level",
          [](ls::Problem& p, const py::object& A, const py::object& lower, const py::object& upper, const std::string& name) {
            return addLevel(p, A, lower, upper, name.empty() ? "level" + std::to_string(p.levelCount()) : name);
          },
          "A"_a, "lower"_a = py::none(), "upper"_a = py::none(), "name"_a = "",
          "Appends a general level lower <= A x <= upper (None: unbounded side); returns its index.")
      .def(
          "add_bounds_level",
          [](ls::Problem& p, std::vector<int> variable, const py::object& coefficient, const py::object& lower, const py::object& upper,
             const std::string& name) {
            const long rows = static_cast<long>(variable.size());
            Eigen::VectorXd c = coefficient.is_none() ? Eigen::VectorXd::Ones(rows) : boundVector(coefficient, rows, 1.0, "coefficient");
            return p.addBoundsLevel(name.empty() ? "bounds" : name, std::move(variable), std::move(c),
                                    boundVector(lower, rows, -ls::kInf, "lower"), boundVector(upper, rows, ls::kInf, "upper"));
          },
          "variable"_a, "coefficient"_a = py::none(), "lower"_a = py::none(), "upper"_a = py::none(), "name"_a = "",
          "Appends a bounds level (first level only): row r reads coefficient[r] * x[variable[r]].")
      .def(
          "update_level",
          [](ls::Problem& p, int i, const py::object& A, const py::object& lower, const py::object& upper) {
            ls::Level& lv = p.level(i);
            if (!A.is_none()) {
              if (lv.kind == ls::LevelKind::Bounds) valueError("update_level: a bounds level has no A");
              Eigen::MatrixXd M = levelMatrix(A, p.variables());
              if (M.rows() != lv.rows())
                valueError("A: expected " + std::to_string(lv.rows()) + " rows (the level's), found " + std::to_string(M.rows()));
              lv.A = std::move(M);
            }
            if (!lower.is_none()) lv.lower = boundVector(lower, lv.rows(), -ls::kInf, "lower");
            if (!upper.is_none()) lv.upper = boundVector(upper, lv.rows(), ls::kInf, "upper");
          },
          "index"_a, "A"_a = py::none(), "lower"_a = py::none(), "upper"_a = py::none(),
          "Replaces values of level `index` (same sizes), e.g. the next tick of a sequence.")
      .def("set_level_columns", &ls::Problem::setLevelColumns, "index"_a, "columns"_a)
      .def("validate", &ls::Problem::validate, "source"_a = "problem",
           "Raises InputError (sizes, bounds order, non-finite entries, bounds-level rules).")
      .def("detect_bounds_level", &ls::Problem::detectBoundsLevel,
           "Turns a first level of single-variable rows into a bounds level (as lexdyn-solve does); True if so.")
      .def(
          "level", [](const ls::Problem& p, int i) { return levelDict(p.level(i)); }, "index"_a,
          "Level `index` as a dict: name, kind (general | bounds), A, lower, upper, variable, coefficient, columns.")
      .def_property_readonly("levels",
                             [](const ls::Problem& p) {
                               py::list out;
                               for (int i = 0; i < p.levelCount(); ++i) out.append(levelDict(p.level(i)));
                               return out;
                             })
      .def(
          "to_json", [](const ls::Problem& p) { return ls::problemToJson(p); }, "The problem file's text (docs/file-formats.md).")
      .def(
          "save", [](const ls::Problem& p, const std::string& path) { ls::writeProblemJson(p, path); }, "path"_a,
          "Writes the problem file (atomically), for lexdyn-solve.")
      .def("__repr__", [](const ls::Problem& p) {
        return "Problem(variables=" + std::to_string(p.variables()) + ", levels=" + std::to_string(p.levelCount()) +
               ", rows=" + std::to_string(p.totalRows()) + ")";
      });

  py::class_<SolveResult, std::shared_ptr<SolveResult>>(m, "Result", "A solve's result (lexdyn/solver/solver.hpp); arrays are copies.")
      .def_property_readonly(
          "status", [](const SolveResult& r) { return ls::toString(r.status); },
          "solved | stopped_early | iteration_limit | non_finite_input | non_finite_result")
      .def_property_readonly("reason", [](const SolveResult& r) { return ls::toString(r.reason); })
      .def_property_readonly("x", [](const SolveResult& r) { return Eigen::VectorXd(r.x); })
      .def_property_readonly(
          "level_violation", [](const SolveResult& r) { return Eigen::VectorXd(r.violation_norm); },
          "per level: the Euclidean norm of its violation")
      .def_property_readonly(
          "violation", [](const SolveResult& r) { return r.violation; }, "per level: a x - clamp(a x, lower, upper) of each row")
      .def_property_readonly(
          "multipliers", [](const SolveResult& r) { return Eigen::MatrixXd(r.lambda); },
          "all rows x levels: column l the multipliers of the level-l problem")
      .def_property_readonly(
          "active", [](const SolveResult& r) { return activeSetList(r.active); },
          "per level: int8 row states 0 inactive, 1 lower, 2 upper, 3 equality")
      .def_property_readonly("active_names",
                             [](const SolveResult& r) {
                               std::vector<std::vector<std::string>> out;
                               for (const auto& lv : r.active.level) {
                                 out.emplace_back();
                                 for (ls::RowState s : lv) out.back().push_back(ls::toString(s));
                               }
                               return out;
                             })
      .def_readonly("rank", &SolveResult::rank)
      .def_readonly("iterations", &SolveResult::iterations)
      .def_readonly("factorizations", &SolveResult::factorizations)
      .def_readonly("bound_change_restarts", &SolveResult::bound_change_restarts)
      .def_readonly("optimality_iterations", &SolveResult::optimality_iterations)
      .def_readonly("activations", &SolveResult::activations)
      .def_readonly("deactivations", &SolveResult::deactivations)
      .def_readonly("held_after_reblock", &SolveResult::held_after_reblock)
      .def_readonly("optimal_through", &SolveResult::optimal_through)
      .def_readonly("cycles_broken", &SolveResult::cycles_broken)
      .def_readonly("cold_restarts", &SolveResult::cold_restarts)
      .def_readonly("bad_level", &SolveResult::bad_level)
      .def_readonly("bad_row", &SolveResult::bad_row)
      .def_readonly("solve_us", &SolveResult::solve_us,
                    "wall time of the C++ solve inside the call, microseconds (a first solve's setup left out; the rest of the call is the "
                    "binding's)")
      .def("__repr__", [](const SolveResult& r) {
        return std::string("Result(status=") + ls::toString(r.status) + ", iterations=" + std::to_string(r.iterations) + ")";
      });

  py::class_<PySolver>(m, "Solver",
                       "The active-set solver. Set up for a problem's sizes at the first solve (or by setup()); later "
                       "solves of problems of the same sizes reuse its memory. Threads may share a Solver (one solve "
                       "at a time) but not a Problem that one of them changes while another solves it.")
      .def(py::init([](const py::object& options) {
             auto s = std::make_unique<PySolver>();
             if (!options.is_none()) s->options = options.cast<ls::Options>();
             s->options.validate();
             return s;
           }),
           "options"_a = py::none())
      .def_property(
          "options", [](const PySolver& s) { return s.options; },
          [](PySolver& s, const ls::Options& o) {
            o.validate();
            const std::lock_guard<std::mutex> lock(s.mutex);
            s.options = o;
            if (s.is_setup) s.solver.setOptions(o);
          })
      .def(
          "setup",
          [](PySolver& s, const ls::Problem& p, const py::object& options) {
            if (!options.is_none()) s.options = options.cast<ls::Options>();
            py::gil_scoped_release nogil;
            const std::lock_guard<std::mutex> lock(s.mutex);
            s.solver.setup(p, s.options);
            s.is_setup = true;
          },
          "problem"_a, "options"_a = py::none(), "Validates the problem and allocates for its sizes.")
      .def("solve", &solveWith, "problem"_a, "warm"_a = py::none(),
           "Solves (the GIL released): cold, or warm-started from a previous Result (its active set and x) or "
           "from a pair (active set, x). Returns a Result.");

  m.def(
      "solve",
      [](const ls::Problem& p, const py::object& options, const py::object& warm) {
        PySolver s;
        if (!options.is_none()) s.options = options.cast<ls::Options>();
        return solveWith(s, p, warm);
      },
      "problem"_a, "options"_a = py::none(), "warm"_a = py::none(),
      "One solve by a new Solver (default Options unless given; the GIL released). lexdyn-solve FILE is "
      "solve(load_problem(FILE)).");
  m.def(
      "load_problem",
      [](const std::string& path, bool detect_bounds_level) {
        py::gil_scoped_release nogil;
        ls::Problem p = ls::readProblemJson(path);
        if (detect_bounds_level) p.detectBoundsLevel();
        return p;
      },
      "path"_a, "detect_bounds_level"_a = true,
      "Reads a problem file (lexdyn-harness run --dump-problems, Problem.save; docs/file-formats.md). As "
      "lexdyn-solve reads it: a first level of single-variable rows becomes a bounds level unless "
      "detect_bounds_level=False (its --no-bounds-level).");
  m.def("parse_problem", &ls::parseProblemJson, "text"_a, "source"_a = "problem", "A problem from problem-file text.");
  m.def(
      "result_to_json",
      [](const ls::Problem& p, const SolveResult& r, bool details, std::optional<ls::Options> options, const std::string& from) {
        return ls::resultToJson(p, r, details, options ? &*options : nullptr, from);
      },
      "problem"_a, "result"_a, "details"_a = false, "options"_a = py::none(), "options_from"_a = "",
      "The JSON text lexdyn-solve [--details] prints for this result; with options, also the options it ran and where "
      "they came from (options_from: \"the problem file\" or \"the solver's defaults\"), as lexdyn-solve prints them.");
  m.def(
      "load_solver_options",
      [](const std::string& path) -> std::optional<ls::Options> {
        py::gil_scoped_release nogil;
        return ls::readProblemFile(path).options;
      },
      "path"_a,
      "The solver options a problem file carries (a controller's dump: the options it solved the tick with), or None; "
      "lexdyn-solve runs them by default.");

  // ---------------------------------------------------------------- model
  py::class_<PyModel>(m, "RobotModel",
                      "The controller's robot model (lexdyn/model/robot_model.hpp, docs/model.md) with its own "
                      "workspace. q (nq): free-flyer [base position 3, base quaternion w x y z 4, joints], fixed base "
                      "[joints]; u (nv): free-flyer [omega_world 3, v_base_world 3, joint rates], fixed base [joint "
                      "rates]. Queries read the state of the last update(q, u) (at load: neutral(), u = 0). Jacobian "
                      "rows are [linear; angular] in the world frame, with respect to u.")
      .def_static(
          "load",
          [](const std::string& urdf, const std::string& data, bool strict, std::vector<std::string> package_paths) {
            lm::LoadOptions o;
            o.strict = strict;
            o.package_paths = std::move(package_paths);
            std::unique_ptr<PyModel> out;
            {
              py::gil_scoped_release nogil;
              out = std::make_unique<PyModel>(lm::RobotModel::fromFiles(urdf, data, o));
            }
            return out;
          },
          "urdf"_a, "data"_a, "strict"_a = false, "package_paths"_a = std::vector<std::string>{},
          "Loads a URDF and its data file (YAML), as the harness does; raises InputError naming file and element.")
      .def_property_readonly("name", [](const PyModel& p) { return p.model.name(); })
      .def_property_readonly("has_free_flyer", [](const PyModel& p) { return p.model.hasFreeFlyer(); })
      .def_property_readonly("nq", &PyModel::nq)
      .def_property_readonly("nv", [](const PyModel& p) { return p.model.nv(); })
      .def_property_readonly("num_joints", [](const PyModel& p) { return p.model.numJoints(); })
      .def_property_readonly("joint_velocity_offset", [](const PyModel& p) { return p.model.jointVelocityOffset(); })
      .def_property_readonly("num_bodies", [](const PyModel& p) { return p.model.numBodies(); })
      .def_property_readonly("total_mass", [](const PyModel& p) { return p.model.totalMass(); })
      .def_property_readonly("gravity", [](const PyModel& p) { return Eigen::Vector3d(p.model.gravity()); })
      .def_property_readonly("joint_names", [](const PyModel& p) { return p.model.jointNames(); })
      .def_property_readonly("frame_names",
                             [](const PyModel& p) {
                               std::vector<std::string> out;
                               for (int f = 0; f < p.model.numFrames(); ++f) out.push_back(p.model.frameName(f));
                               return out;
                             })
      .def_property_readonly("posture_names",
                             [](const PyModel& p) {
                               std::vector<std::string> out;
                               for (const auto& kv : p.model.description().postures) out.push_back(kv.first);
                               return out;
                             })
      .def_property_readonly("joint_lower_limits", [](const PyModel& p) { return Eigen::VectorXd(p.model.jointLowerLimits()); })
      .def_property_readonly("joint_upper_limits", [](const PyModel& p) { return Eigen::VectorXd(p.model.jointUpperLimits()); })
      .def_property_readonly("joint_velocity_limits", [](const PyModel& p) { return Eigen::VectorXd(p.model.jointVelocityLimits()); })
      .def_property_readonly("joint_torque_limits", [](const PyModel& p) { return Eigen::VectorXd(p.model.jointTorqueLimits()); })
      .def_property_readonly(
          "q", [](const PyModel& p) { return Eigen::VectorXd(p.q); }, "q of the last update")
      .def_property_readonly(
          "u", [](const PyModel& p) { return Eigen::VectorXd(p.u); }, "u of the last update")
      .def(
          "frame_id", [](const PyModel& p, const std::string& name) { return p.model.frameId(name); }, "name"_a)
      .def(
          "joint_index", [](const PyModel& p, const std::string& name) { return p.model.jointIndex(name); }, "name"_a)
      .def(
          "neutral", [](const PyModel& p) { return p.flat(p.model.neutralConfiguration()); },
          "The neutral configuration: identity base at the origin, joints 0.")
      .def(
          "posture",
          [](const PyModel& p, const std::string& name) {
            lm::Configuration c = p.model.neutralConfiguration();
            c.joints = p.model.posture(name);
            return p.flat(c);
          },
          "name"_a, "q of a named posture of the data file (base as in neutral()).")
      .def(
          "integrate",
          [](const PyModel& p, const Eigen::VectorXd& q, const Eigen::VectorXd& u, double dt) {
            if (u.size() != p.model.nv()) valueError("u: expected " + std::to_string(p.model.nv()) + " entries (nv)");
            lm::Configuration out;
            out.joints.resize(p.model.numJoints());
            p.model.integrate(p.configuration(q), u, dt, out);
            return p.flat(out);
          },
          "q"_a, "u"_a, "dt"_a, "q \"+\" dt u, as the controller integrates (docs/model.md).")
      .def(
          "difference",
          [](const PyModel& p, const Eigen::VectorXd& q0, const Eigen::VectorXd& q1) {
            Eigen::VectorXd out(p.model.nv());
            p.model.difference(p.configuration(q0), p.configuration(q1), out);
            return out;
          },
          "q0"_a, "q1"_a, "u such that integrate(q0, u, 1) == q1.")
      .def("update", &PyModel::update, "q"_a, "u"_a = py::none(),
           "Sets the state (u: None for zero) and computes the kinematics every query reads.")
      .def(
          "mass_matrix",
          [](PyModel& p) {
            Eigen::MatrixXd M(p.model.nv(), p.model.nv());
            p.model.massMatrix(p.data, M);
            return M;
          },
          "M(q) (nv x nv).")
      .def(
          "nonlinear_effects",
          [](PyModel& p) {
            Eigen::VectorXd N(p.model.nv());
            p.model.nonlinearEffects(p.data, N);
            return N;
          },
          "N(q, u): Coriolis, centrifugal and gravity generalized forces (nv); M udot + N = S^T tau + J^T f.")
      .def(
          "frame_placement", [](const PyModel& p, const py::object& f) { return homogeneous(p.model.framePlacement(p.data, p.frame(f))); },
          "frame"_a, "The frame's pose in the world, a 4 x 4 homogeneous matrix (frame: name or id).")
      .def(
          "frame_position",
          [](const PyModel& p, const py::object& f) { return Eigen::Vector3d(p.model.framePlacement(p.data, p.frame(f)).translation()); },
          "frame"_a)
      .def(
          "frame_rotation",
          [](const PyModel& p, const py::object& f) { return Eigen::Matrix3d(p.model.framePlacement(p.data, p.frame(f)).linear()); },
          "frame"_a)
      .def(
          "frame_velocity", [](const PyModel& p, const py::object& f) { return lm::Vector6d(p.model.frameVelocity(p.data, p.frame(f))); },
          "frame"_a, "[v_origin_world; omega_world].")
      .def(
          "frame_jacobian",
          [](const PyModel& p, const py::object& f) {
            Eigen::MatrixXd J(6, p.model.nv());
            p.model.frameJacobian(p.data, p.frame(f), J);
            return J;
          },
          "frame"_a, "6 x nv: [linear velocity of the frame origin; angular velocity], world frame.")
      .def(
          "frame_bias", [](const PyModel& p, const py::object& f) { return lm::Vector6d(p.model.frameBias(p.data, p.frame(f))); },
          "frame"_a, "Jdot u of frame_jacobian.")
      .def(
          "point_position",
          [](const PyModel& p, const py::object& f, const Eigen::Vector3d& point) {
            return Eigen::Vector3d(p.model.pointPosition(p.data, p.frame(f), point));
          },
          "frame"_a, "point"_a = Eigen::Vector3d::Zero().eval(), "World position of a point given in the frame.")
      .def(
          "point_velocity",
          [](const PyModel& p, const py::object& f, const Eigen::Vector3d& point) {
            return Eigen::Vector3d(p.model.pointVelocity(p.data, p.frame(f), point));
          },
          "frame"_a, "point"_a = Eigen::Vector3d::Zero().eval())
      .def(
          "point_jacobian",
          [](const PyModel& p, const py::object& f, const Eigen::Vector3d& point) {
            Eigen::MatrixXd J(3, p.model.nv());
            p.model.pointJacobian(p.data, p.frame(f), point, J);
            return J;
          },
          "frame"_a, "point"_a = Eigen::Vector3d::Zero().eval(), "3 x nv Jacobian of a point given in the frame.")
      .def(
          "com", [](const PyModel& p) { return Eigen::Vector3d(p.model.centerOfMass(p.data)); }, "Centre of mass, world.")
      .def("com_velocity", [](const PyModel& p) { return Eigen::Vector3d(p.model.centerOfMassVelocity(p.data)); })
      .def(
          "com_jacobian",
          [](const PyModel& p) {
            Eigen::MatrixXd J(3, p.model.nv());
            p.model.centerOfMassJacobian(p.data, J);
            return J;
          },
          "3 x nv Jacobian of the centre of mass.")
      .def("com_bias", [](const PyModel& p) { return Eigen::Vector3d(p.model.centerOfMassBias(p.data)); })
      .def("__repr__", [](const PyModel& p) {
        return "RobotModel(" + p.model.name() + ", nq=" + std::to_string(p.nq()) + ", nv=" + std::to_string(p.model.nv()) + ")";
      });

  // ---------------------------------------------------------------- cases
  m.def("_run_case", &runCaseBound, "case_path"_a, "method"_a, "overrides"_a, "out_dir"_a, "progress"_a, "wall_clock_checks"_a,
        "dump_dir"_a, "dump_from"_a, "dump_to"_a,
        "lexdyn-harness run CASE --out OUT_DIR (lexdyn.run_case wraps it); returns exit_code, status, message, "
        "method and the paths written.");
}

"""Readers of every file lexdyn's harness writes (docs/python.md, docs/file-formats.md):

    read_trace(path)          trace.csv / trace.csv.partial / golden traces -> Trace
                              (.array: numpy structured array, .dataframe(): pandas DataFrame)
    read_summary(path)        a run's summary.json -> RunSummary (a dict with the run's verdict)
    read_check_results(path)  saved `lexdyn-harness check --json` / `compare --json` -> CheckResults
    read_sweep(dir)           a sweep's output directory -> Sweep (summary, records, dataframe())
    read_sweep_summary(path)  a sweep's summary.json
    read_sweep_results(path)  a sweep's results.jsonl -> point records
    read_history(path)        the nightly job's history (JSON Lines) -> History
    read_night(path)          a night's nightly.json -> dict (night_info / write_night make one)

Every reader raises FormatError (a ValueError) naming the file, the line and the field of the
first thing that is not what the format says.

The compiled module lexdyn._core (built with the package: build/python/lexdyn, or installed)
adds the C++ side (docs/python.md, "Bindings"):

    Problem, Options, Solver, Result, solve(problem), load_problem(path), result_to_json(...)
    RobotModel.load(urdf, data)   update(q, u), com(), com_jacobian(), mass_matrix(), Jacobians
    run_case(case_path, method=None, overrides=None, duration=None, out_dir=None) -> CaseRun
    InputError, OutputError       what the C++ side raises for bad input / an unwritable output

Without it (the source tree's python/ on PYTHONPATH) the readers work alone and `BINDINGS` is
False.
"""
import importlib.util

from .errors import FormatError
from .history import HISTORY_FORMAT, NIGHT_FORMAT, History, night_info, read_history, read_night, write_night
from .summary import CHECK_RESULTS_FORMAT, SUMMARY_FORMAT, Check, CheckResults, RunSummary, read_check_results, read_summary
from .sweeps import SWEEP_SUMMARY_FORMAT, Sweep, read_sweep, read_sweep_results, read_sweep_summary, sweep_dataframe
from .trace import TRACE_VERSION, Trace, read_trace, read_trace_header, trace_array, trace_dataframe

if importlib.util.find_spec(__name__ + "._core") is not None:
    from . import _core  # a module that is there but does not load is an error, not "no bindings"
else:  # the pure-Python package (the source tree's python/): readers only
    _core = None

__version__ = "0.1.0"
BINDINGS = _core is not None

__all__ = [
    "FormatError", "Trace", "read_trace", "read_trace_header", "trace_array", "trace_dataframe", "TRACE_VERSION",
    "RunSummary", "Check", "read_summary", "SUMMARY_FORMAT", "CheckResults", "read_check_results", "CHECK_RESULTS_FORMAT", "Sweep", "read_sweep", "read_sweep_summary", "read_sweep_results",
    "sweep_dataframe", "SWEEP_SUMMARY_FORMAT", "History", "read_history", "HISTORY_FORMAT", "NIGHT_FORMAT", "night_info",
    "read_night", "write_night",
]

if BINDINGS:
    from ._core import InputError, Options, OutputError, Problem, Result, RobotModel, Solver, load_problem, \
        load_solver_options, parse_problem, result_to_json, solve
    from .runs import CaseRun, run_case

    __all__ += ["InputError", "OutputError", "Problem", "Options", "Solver", "Result", "solve", "load_problem",
                "load_solver_options", "parse_problem", "result_to_json", "RobotModel", "run_case", "CaseRun"]

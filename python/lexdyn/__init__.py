"""Readers of every file lexdyn's harness writes (docs/python.md, docs/file-formats.md):

    read_trace(path)          trace.csv / trace.csv.partial / golden traces -> Trace
                              (.array: numpy structured array, .dataframe(): pandas DataFrame)
    read_summary(path)        a run's summary.json -> RunSummary (a dict with the run's verdict)
    read_sweep(dir)           a sweep's output directory -> Sweep (summary, records, dataframe())
    read_sweep_summary(path)  a sweep's summary.json
    read_sweep_results(path)  a sweep's results.jsonl -> point records
    read_history(path)        the nightly job's history (JSON Lines) -> History

Every reader raises FormatError (a ValueError) naming the file, the line and the field of the
first thing that is not what the format says.
"""
from .errors import FormatError
from .history import HISTORY_FORMAT, History, read_history
from .summary import SUMMARY_FORMAT, Check, RunSummary, read_summary
from .sweeps import SWEEP_SUMMARY_FORMAT, Sweep, read_sweep, read_sweep_results, read_sweep_summary, sweep_dataframe
from .trace import TRACE_VERSION, Trace, read_trace, read_trace_header, trace_array, trace_dataframe

__version__ = "0.1.0"

__all__ = [
    "FormatError", "Trace", "read_trace", "read_trace_header", "trace_array", "trace_dataframe", "TRACE_VERSION",
    "RunSummary", "Check", "read_summary", "SUMMARY_FORMAT", "Sweep", "read_sweep", "read_sweep_summary", "read_sweep_results",
    "sweep_dataframe", "SWEEP_SUMMARY_FORMAT", "History", "read_history", "HISTORY_FORMAT",
]

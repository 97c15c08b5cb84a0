"""Sweep outputs (docs/report.md, "Sweeps"): SWEEP_OUT/summary.json
(format lexdyn-sweep-summary/1) and SWEEP_OUT/results.jsonl, one record per point, read by
lexdyn.read_sweep. --sweeps names one such directory or a directory whose subdirectories are."""
import os

import lexdyn

from .common import ReportInputError, json_constant

FORMAT = lexdyn.SWEEP_SUMMARY_FORMAT


class Sweep(lexdyn.Sweep):
    """A sweep as lexdyn reads it, figures stored as NaN or Infinity kept as DamagedNumbers (shown
    as "not a number (damaged)")."""

    def __init__(self, directory):
        super().__init__(directory, constant=json_constant)

    def method_status_counts(self):
        """{method: {status: count}} of the runs of results.jsonl (each record's `runs`)."""
        return self.status_counts()


def load_sweeps(path):
    if not path:
        return []
    if not os.path.isdir(path):
        raise ReportInputError(path, "expected a sweep output directory (--sweeps), found none")
    if os.path.isfile(os.path.join(path, "summary.json")):
        return [Sweep(path)]
    out = []
    for name in sorted(os.listdir(path)):
        d = os.path.join(path, name)
        if not name.startswith(".") and os.path.isfile(os.path.join(d, "summary.json")):
            out.append(Sweep(d))
    return out

"""Trace files (`trace.csv`, `trace.csv.partial`, golden traces; docs/file-formats.md, "Trace
files"): `# key: value` header lines, one line of channel names, one row per recorded tick, and
the end mark `# end: STATUS[: why]` of a finished run.

    tr = lexdyn.read_trace("out/run/trace.csv")
    tr.names, tr.metadata, tr.end_status
    tr["task.position.error"]          # one channel (numpy array)
    tr.array                           # numpy structured array, one field per channel
    tr.dataframe()                     # pandas DataFrame (needs pandas)

The checks are the C++ reader's (lexdyn::checks::readTrace): LF lines, no NUL byte, header lines
before the names, unique channel names, one number per channel and row as the writer writes them
(`inf`, `-inf`, `nan` included), the time `t` finite, >= 0, strictly increasing, on the tick grid
of `control_period_s` (the last row of a failed run excepted) and within `duration_s`. A
`.partial` file (a killed run) may end in a cut line, which is dropped; in a finished file that
is an error. Every error is a FormatError naming the file, the line and the channel.
"""
import math
import os
import re
import warnings

import numpy as np

from .errors import FormatError

# The version of the trace format this reader knows (header line `# lexdyn_trace: 1`; a trace
# without it is read as this version).
TRACE_VERSION = "1"
MAX_CHANNELS = 200000
_NUMBER = re.compile(r"-?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|-?inf|-?nan")
_OTHER_CHARACTERS = re.compile(r"[^0-9.eE+\-,\ninfa]")
_BAD_NAME = re.compile(r"[\s\"]")
_TINY = (re.compile(r"e-\d{3,}"), re.compile(r"E-\d{3,}"))  # a literal prefix: a fast scan


def _token_at(body, at):
    """The value of BODY (comma and newline separated) that holds position AT."""
    start = max(body.rfind(",", 0, at), body.rfind("\n", 0, at)) + 1
    ends = [e for e in (body.find(",", at), body.find("\n", at)) if e >= 0]
    return body[start:min(ends) if ends else len(body)]


def _value_problem(v):
    """None when V is a value as the harness writes it (a decimal number in the double range, inf,
    -inf or nan: what the C++ reader takes), else what is wrong with it."""
    if not _NUMBER.fullmatch(v):
        return f"expected a number, found '{v}'"
    if v.lstrip("-") in ("inf", "nan"):
        return None
    f = float(v)
    mantissa = re.split(r"[eE]", v)[0]
    if math.isinf(f) or (f == 0.0 and re.search(r"[1-9]", mantissa)):
        return f"expected a number in the double range, found '{v}'"
    return None


class Trace:
    """A trace as read: `path`, `metadata` (header lines, in order), `names` (channels), `data`
    (rows x channels, float64), `end_status` and `end_message` (None without an end mark: a
    killed run's `.partial` file), `partial` (read as a `.partial` file)."""

    def __init__(self, path, metadata, names, data, end_status=None, end_message=None, partial=False):
        self.path = path
        self.metadata = metadata
        self.names = list(names)
        self.index = {n: i for i, n in enumerate(self.names)}
        self.data = data
        self.end_status = end_status
        self.end_message = end_message
        self.partial = partial

    @property
    def rows(self):
        return self.data.shape[0]

    def __len__(self):
        return self.rows

    @property
    def ended(self):
        """True when the trace has its end mark (the run finished, in any status)."""
        return self.end_status is not None

    @property
    def completed(self):
        return self.end_status == "completed"

    @property
    def t(self):
        return self.col("t") if "t" in self.index else np.zeros(self.rows)

    def has(self, name):
        return name in self.index

    def __contains__(self, name):
        return name in self.index

    def col(self, name):
        """The values of one channel (a view into `data`)."""
        if name not in self.index:
            raise FormatError(self.path, "expected this channel, the trace has none", field=name)
        return self.data[:, self.index[name]]

    __getitem__ = col

    def cols(self, names):
        """rows x len(NAMES) array of the channels NAMES."""
        names = list(names)
        for n in names:
            if n not in self.index:
                raise FormatError(self.path, "expected this channel, the trace has none", field=n)
        return self.data[:, [self.index[n] for n in names]] if names else np.zeros((self.rows, 0))

    def matching(self, prefix, suffix=""):
        """Channel names starting with PREFIX and ending with SUFFIX, in trace order."""
        return [n for n in self.names if n.startswith(prefix) and n.endswith(suffix)]

    @property
    def dtype(self):
        return np.dtype([(n, np.float64) for n in self.names])

    @property
    def array(self):
        """The rows as a numpy structured array, one float64 field per channel (a view of
        `data`: no copy)."""
        if self.rows == 0:
            return np.zeros(0, dtype=self.dtype)
        return np.ascontiguousarray(self.data).view(self.dtype).reshape(self.rows)

    def dataframe(self):
        """The rows as a pandas DataFrame, one column per channel (needs pandas)."""
        import pandas as pd
        return pd.DataFrame(self.data, columns=self.names)


def _line_of(text, offset):
    return text.count("\n", 0, offset) + 1


def _header_number(metadata, key, path):
    s = metadata.get(key)
    if s is None:
        return 0.0
    try:
        v = float(s) if _NUMBER.fullmatch(s) else math.nan
    except ValueError:
        v = math.nan
    if not (math.isfinite(v) and v > 0):
        raise FormatError(path, f"expected a positive number, found '{s}'", field=key)
    return v


def _keep(names, channels):
    if channels is None:
        return list(range(len(names)))
    if callable(channels):
        return [i for i, n in enumerate(names) if n == "t" or channels(n)]
    wanted = set(channels)
    return [i for i, n in enumerate(names) if n == "t" or n in wanted]


def read_trace_header(path):
    """(metadata dict, channel names) of a trace, without reading its rows."""
    path = os.fspath(path)
    metadata = {}
    if os.path.isdir(path):
        raise FormatError(path, "expected a trace file, found a folder")
    if not os.path.exists(path):
        raise FormatError(path, "expected a trace file, found no such file")
    with open(path, encoding="utf-8", errors="replace", newline="\n") as f:
        for lineno, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if not line:
                continue
            if line.startswith("#"):
                key, sep, value = line[2:].partition(": ")
                if not line.startswith("# ") or not sep:
                    raise FormatError(path, "expected a header line '# key: value'", line=lineno)
                metadata[key] = value
                continue
            return metadata, line.split(",")
    raise FormatError(path, "expected a line of channel names after the header, found the end of the file")


def read_trace(path, channels=None):
    """Reads the trace PATH (see the module's doc). CHANNELS: None for all, a list of names or a
    predicate on a name; `t` is always kept."""
    path = os.fspath(path)
    partial = path.endswith(".partial")
    if os.path.isdir(path):
        raise FormatError(path, "expected a trace file, found a folder")
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except FileNotFoundError:
        raise FormatError(path, "expected a trace file, found no such file") from None
    nul = raw.find(b"\0")
    if nul >= 0:
        line = raw.count(b"\n", 0, nul) + 1
        column = nul - (raw.rfind(b"\n", 0, nul) + 1) + 1
        raise FormatError(path, f"expected a text trace file, found binary data (a NUL byte) at column {column}", line=line)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise FormatError(path, f"expected a text trace file (UTF-8), found binary data (byte {e.start + 1})",
                          line=raw.count(b"\n", 0, e.start) + 1) from None
    cr = text.find("\r")
    if cr >= 0:
        raise FormatError(path, "the line ends with a carriage return (CRLF line endings); trace files use LF only",
                          line=_line_of(text, cr))
    lines = text.split("\n")
    cut = lines.pop()   # the text after the last newline: '' for a whole file

    # Header lines, then the channel names.
    metadata = {}
    k = 0
    while k < len(lines) and (not lines[k] or lines[k].startswith("#")):
        line = lines[k]
        k += 1
        if not line:
            continue
        key, sep, value = line[2:].partition(": ")
        if not line.startswith("# ") or not sep:
            raise FormatError(path, "expected a header line '# key: value'", line=k)
        if key == "end":
            raise FormatError(path, "an end mark before the channel names", line=k)
        metadata[key] = value
    if k == len(lines):
        if cut:
            raise FormatError(path, "the last line has no newline: the file was cut short", line=k + 1)
        raise FormatError(path, "expected a line of channel names after the header, found the end of the file")
    version = metadata.get("lexdyn_trace", TRACE_VERSION)
    if version != TRACE_VERSION:
        raise FormatError(path, f"expected trace format version {TRACE_VERSION}, found '{version}'", field="lexdyn_trace")
    names_line = k + 1
    names = lines[k].split(",")
    if len(names) > MAX_CHANNELS:
        raise FormatError(path, f"more than {MAX_CHANNELS} channels (size guard)", line=names_line)
    seen = set()
    for i, n in enumerate(names):
        if not n or _BAD_NAME.search(n):
            raise FormatError(path, f"invalid channel name '{n}' in column {i + 1}", line=names_line)
        if n in seen:
            raise FormatError(path, f"duplicate channel name '{n}'", line=names_line, field=n)
        seen.add(n)
    period = _header_number(metadata, "control_period_s", path)
    duration = _header_number(metadata, "duration_s", path)

    # Rows, then the end mark.
    rows, row_lines = [], []
    end_status = end_message = None
    for j in range(k + 1, len(lines)):
        line = lines[j]
        if not line:
            continue
        if end_status is not None:
            raise FormatError(path, f"a line after the end mark ('# end: {end_status}')", line=j + 1)
        if line.startswith("#"):
            if not line.startswith("# end: "):
                raise FormatError(path, "a header line after the channel names (only '# end: STATUS' may follow the rows)", line=j + 1)
            end_status, _, end_message = line[7:].partition(": ")
            end_message = end_message or None
            if not end_status:
                raise FormatError(path, "empty end mark", line=j + 1)
            continue
        rows.append(line)
        row_lines.append(j + 1)
    if cut:
        if not partial:
            raise FormatError(path, "the last line has no newline: the file was cut short", line=len(lines) + 1)
        if end_status is not None:
            raise FormatError(path, f"a line after the end mark ('# end: {end_status}')", line=len(lines) + 1)
        # A killed run's .partial trace: the cut last row is dropped.

    width = len(names)
    data = _parse_rows(path, rows, row_lines, names)
    _check_time(path, names, data, row_lines, period, duration, end_status)
    keep = _keep(names, channels)
    if len(keep) != width:
        data = data[:, keep]
    return Trace(path, metadata, [names[i] for i in keep], np.ascontiguousarray(data), end_status, end_message, partial)


def _parse_rows(path, rows, row_lines, names):
    width = len(names)
    if not rows:
        return np.zeros((0, width))
    body = "\n".join(rows)
    values = None
    if not _OTHER_CHARACTERS.search(body) and all(r.count(",") == width - 1 for r in rows):
        # Every value in one C-level parse (exact: strtod); a count that does not fit the rows
        # sends us to the row-by-row check, which names the line and the channel.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            values = np.fromstring(body.replace("\n", ","), sep=",")
        if values.size != len(rows) * width:
            values = None
        # What strtod takes and the harness never writes: a leading +, a number beyond the double
        # range (read as inf, or as 0 below the smallest subnormal): the row-by-row check names it.
        elif (body.startswith("+") or ",+" in body or "\n+" in body or np.count_nonzero(np.isinf(values)) != body.count("inf")
              or any(_value_problem(_token_at(body, m.start())) for tiny in _TINY for m in tiny.finditer(body))):
            values = None
    if values is None:
        for r, lineno in zip(rows, row_lines):
            fields = r.split(",")
            if len(fields) != width:
                raise FormatError(path, f"expected {width} values, found {len(fields)}", line=lineno)
            for name, v in zip(names, fields):
                problem = _value_problem(v)
                if problem:
                    raise FormatError(path, problem, line=lineno, field=name)
        raise FormatError(path, "expected one number per channel and row, found a malformed row")
    return values.reshape(len(rows), width)


def _check_time(path, names, data, row_lines, period, duration, end_status):
    if "t" not in names or data.shape[0] == 0:
        return
    t = data[:, names.index("t")]
    bad = np.nonzero(~np.isfinite(t) | (t < 0))[0]
    if bad.size:
        raise FormatError(path, f"expected a finite time >= 0 s, found {t[bad[0]]!r}", line=row_lines[bad[0]], field="t")
    back = np.nonzero(np.diff(t) <= 0)[0]
    if back.size:
        i = back[0] + 1
        raise FormatError(path, f"expected rows in strictly increasing time, found {t[i]!r} s after {t[i - 1]!r} s",
                          line=row_lines[i], field="t")
    if period > 0:
        kk = t / period
        off = np.nonzero(np.abs(kk - np.round(kk)) > 1e-6 * np.maximum(1.0, kk))[0]
        if off.size:
            i = off[0]
            if i != len(t) - 1:
                raise FormatError(path, f"expected a tick of the header's control period ({period:g} s), found {t[i]!r} s "
                                  "(only the last row of a failed run may fall between ticks)", line=row_lines[i], field="t")
            if end_status in (None, "completed", "interrupted"):
                raise FormatError(path, f"expected a tick of the header's control period ({period:g} s), found {t[i]!r} s "
                                  "in the last row, which only the last state of a failed run may be", line=row_lines[i], field="t")
    if duration > 0:
        over = np.nonzero(t > duration + max(period, 1e-9))[0]
        if over.size:
            i = over[0]
            raise FormatError(path, f"expected a time within the header's duration ({duration:g} s), found {t[i]!r} s",
                              line=row_lines[i], field="t")


def trace_array(path, channels=None):
    """The rows of the trace PATH as a numpy structured array (read_trace(...).array)."""
    return read_trace(path, channels).array


def trace_dataframe(path, channels=None):
    """The rows of the trace PATH as a pandas DataFrame (read_trace(...).dataframe())."""
    return read_trace(path, channels).dataframe()

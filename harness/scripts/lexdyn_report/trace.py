"""Reading trace files (docs/file-formats.md, "Trace files") with numpy.

A trace is `# key: value` header lines, one line of channel names, then one row per recorded
tick. A `.partial` trace (a killed run) may end in a cut line, which is dropped; in a finished
file a malformed row is an error naming the file and the line.
"""
import numpy as np

from .common import ReportInputError


class Trace:
    def __init__(self, path, metadata, names, data):
        self.path = path
        self.metadata = metadata
        self.names = names
        self.index = {n: i for i, n in enumerate(names)}
        self.data = data  # rows x channels (float64)
        self.t = self.col("t") if "t" in self.index else np.zeros(len(data))

    @property
    def rows(self):
        return self.data.shape[0]

    def has(self, name):
        return name in self.index

    def col(self, name):
        if name not in self.index:
            raise ReportInputError(self.path, f"expected a channel '{name}', the trace has none")
        return self.data[:, self.index[name]]

    def cols(self, names):
        return self.data[:, [self.index[n] for n in names]] if names else np.zeros((self.rows, 0))

    def matching(self, prefix, suffix=""):
        """Channel names starting with PREFIX and ending with SUFFIX, in trace order."""
        return [n for n in self.names if n.startswith(prefix) and n.endswith(suffix)]


def read_header(path):
    """(metadata dict, channel names) without reading the rows."""
    metadata = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                key, _, value = line[1:].strip().partition(":")
                metadata[key.strip()] = value.strip()
                continue
            return metadata, line.rstrip("\n").split(",")
    raise ReportInputError(path, "expected a line of channel names after the header, found the end of the file")


def read_trace(path, wanted=None):
    """Reads a trace; WANTED (a predicate on channel names) keeps only some channels. 't' is
    always kept."""
    partial = path.endswith(".partial")
    metadata, names = read_header(path)
    keep = [i for i, n in enumerate(names) if n == "t" or wanted is None or wanted(n)]
    width = len(names)
    with open(path) as f:
        lines = [l for l in f if not l.startswith("#")][1:]
    first = len(metadata) + 2  # file line number of the first row
    if lines and partial and (not lines[-1].endswith("\n") or lines[-1].count(",") != width - 1):
        lines.pop()  # the cut last row of a killed run
    # Fast path: every value of every row in one C-level parse (strtod: exact, inf and nan
    # included); a count that does not fit the rows sends us to the row-by-row check below.
    body = "".join(lines)
    values = np.fromstring(body.replace("\n", ","), sep=",") if lines else np.zeros(0)
    if values.size != len(lines) * width or any(l.count(",") != width - 1 for l in lines):
        for k, line in enumerate(lines):
            fields = line.rstrip("\n").split(",")
            where = f"{path}:{first + k}"
            if len(fields) != width:
                raise ReportInputError(where, f"expected {width} values, found {len(fields)}")
            for name, v in zip(names, fields):
                try:
                    float(v)
                except ValueError:
                    raise ReportInputError(where, f"channel {name}: expected a number, found '{v}'")
        raise ReportInputError(path, "expected one number per channel and row, found a malformed row")
    if lines and not lines[-1].endswith("\n"):
        raise ReportInputError(f"{path}:{first + len(lines) - 1}", "unterminated last line in a finished trace")
    data = values.reshape(len(lines), width)[:, keep] if lines else np.zeros((0, len(keep)))
    return Trace(path, metadata, [names[i] for i in keep], np.ascontiguousarray(data))

"""Shared pieces: atomic writes, the method colours, number formatting, input errors, YAML files."""
import html
import math
import os

try:
    import yaml
except ImportError:  # pragma: no cover
    yaml = None

# One colour per method across every figure and table of the report (matplotlib's tab10
# entries, colour-blind distinguishable in pairs). A run without a method (posture servo) is grey.
METHOD_COLOURS = {"bfgs": "#1f77b4", "ah": "#ff7f0e", "gn": "#d62728", "wls": "#2ca02c", "": "#7f7f7f"}
EXTRA_COLOURS = ["#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22"]
METHOD_ORDER = ["bfgs", "ah", "gn", "wls", ""]
METHOD_LABELS = {"bfgs": "LexDynBFGS", "ah": "LexDynAH", "gn": "GN", "wls": "WLS", "": "posture servo"}


class ReportInputError(Exception):
    """Bad input: what was expected, what was found, where (file, line, key)."""

    def __init__(self, where, what):
        super().__init__(f"{where}: {what}")


def read_yaml(path, what):
    """The YAML document of PATH ({} when it is empty); a file that cannot be read or parsed is a
    ReportInputError saying that WHAT ("case file") was expected. Needs python3-yaml."""
    try:
        with open(path) as f:
            return yaml.safe_load(f) or {}
    except (OSError, yaml.YAMLError) as e:
        raise ReportInputError(path, f"expected a readable {what} ({e})")


def method_colour(method):
    if method in METHOD_COLOURS:
        return METHOD_COLOURS[method]
    # Unknown methods get a stable colour of their own (sorted name order is not stable across
    # reports, so hash the name deterministically).
    h = sum((i + 1) * ord(c) for i, c in enumerate(method))
    return EXTRA_COLOURS[h % len(EXTRA_COLOURS)]


def method_label(method):
    return METHOD_LABELS.get(method, method)


def method_sort_key(method):
    return (METHOD_ORDER.index(method) if method in METHOD_ORDER else len(METHOD_ORDER), method)


def write_atomic(path, data):
    """Writes bytes or text to PATH through a temporary name in the same directory."""
    tmp = f"{path}.partial.{os.getpid()}"
    mode = "wb" if isinstance(data, (bytes, bytearray)) else "w"
    with open(tmp, mode) as f:
        f.write(data)
    os.replace(tmp, path)


def copy_atomic(src, dst):
    """Copies SRC to DST through a temporary name in DST's directory."""
    with open(src, "rb") as f:
        write_atomic(dst, f.read())


def esc(x):
    return html.escape(str(x), quote=True)


def fnum(v, spec=".4g", none="-"):
    if v is None:
        return none
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    try:
        return format(v, spec)
    except (TypeError, ValueError):
        return str(v)


def finite(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)

"""Shared pieces: atomic writes, the method colours, number formatting, input and output errors,
YAML files, damaged numbers."""
import html
import math
import os

from lexdyn import FormatError

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


class ReportInputError(FormatError):
    """Bad input: what was expected, what was found, where (file, line, key). Exit code 2, as
    for a FormatError of the readers (lexdyn), of which it is one."""

    def __init__(self, where, what):
        super().__init__(where, what)


class ReportOutputError(Exception):
    """A file or folder that cannot be written (a full disk, a read-only or unwritable folder, a
    file-size limit): WHERE names it, WHAT is the operating system's reason. A run failure (exit
    code 3), never bad input."""

    def __init__(self, where, what):
        super().__init__(f"{where}: {what}")


def os_reason(e):
    """The operating system's reason of an OSError ("No space left on device")."""
    return e.strerror or (os.strerror(e.errno) if e.errno else str(e))


# How the page shows a figure that is not a finite number (NaN or Infinity in a stored file, a
# string where a number belongs): never "nan", never averaged into a trend or a band.
DAMAGED = "not a number (damaged)"


class DamagedNumber(float):
    """NaN, Infinity or -Infinity read from a JSON file (which JSON has not; Python's json reads
    them unless told otherwise): a non-finite float that prints as DAMAGED and remembers the
    text it was read from."""

    def __new__(cls, text):
        x = super().__new__(cls, text)
        x.text = text
        return x

    def __str__(self):
        return DAMAGED

    __repr__ = __str__

    def __format__(self, spec):
        return DAMAGED


def non_finite_fields(x, where=""):
    """[(FIELD, TEXT)] of every DamagedNumber in a document read with json_constant: FIELD as
    'checks[2].value'."""
    out = []
    if isinstance(x, DamagedNumber):
        out.append((where or "(top level)", x.text))
    elif isinstance(x, dict):
        for k, v in x.items():
            out += non_finite_fields(v, f"{where}.{k}" if where else str(k))
    elif isinstance(x, list):
        for i, v in enumerate(x):
            out += non_finite_fields(v, f"{where}[{i}]")
    return out


def json_constant(text):
    """json.load's parse_constant: NaN, Infinity, -Infinity as DamagedNumbers."""
    return DamagedNumber(text)


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


def write_atomic(path, data, durable=False):
    """Writes bytes or text to PATH through a temporary name in the same directory (PATH.partial.PID,
    renamed when whole). DURABLE: also synced to the disk, the file then its folder. A failure is a
    ReportOutputError with the operating system's reason, and leaves no temporary file."""
    tmp = f"{path}.partial.{os.getpid()}"
    mode = "wb" if isinstance(data, (bytes, bytearray)) else "w"
    try:
        with open(tmp, mode) as f:
            f.write(data)
            if durable:
                f.flush()
                os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as e:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise ReportOutputError(path, os_reason(e)) from e
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    if durable:
        sync_folder(os.path.dirname(os.path.abspath(path)))


def sync_folder(path):
    """fsync of a folder, so that a rename in it survives a crash of the machine (a file system
    that refuses it is no failure)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def copy_atomic(src, dst):
    """Copies SRC to DST through a temporary name in DST's directory."""
    with open(src, "rb") as f:
        write_atomic(dst, f.read())


def esc(x):
    return html.escape(str(x), quote=True)


def fnum(v, spec=".4g", none="-"):
    """A figure as text: NONE for None, DAMAGED for anything that is not a finite number (NaN or
    Infinity read from a damaged file, a string)."""
    if v is None:
        return none
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        return DAMAGED
    try:
        return format(v, spec)
    except (TypeError, ValueError):
        return DAMAGED


def fpercent(fraction, spec=".1f"):
    """A fraction as a percentage ('75.0 %'), '-' for None, DAMAGED when not a finite number."""
    if fraction is None:
        return "-"
    return f"{fnum(100 * fraction, spec)} %" if finite(fraction) else DAMAGED


def finite(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)

"""JSON documents and JSON Lines as the harness writes them: UTF-8, a figure that is not a finite
number written as null. NaN, Infinity and -Infinity (not JSON, but accepted by Python's json)
are refused naming the field, unless the caller asks to keep them (`constant`)."""
import json
import math

from .errors import FormatError


class NonFiniteNumber(float):
    """NaN, Infinity or -Infinity as read from a file, with the text it was read from."""

    def __new__(cls, text):
        x = super().__new__(cls, text)
        x.text = text
        return x


def kind(x):
    """How a JSON value looks, for messages: 'a string', 'a list', ..."""
    if x is None:
        return "null"
    if isinstance(x, bool):
        return "true / false"
    if isinstance(x, (int, float)):
        return "a number"
    if isinstance(x, str):
        return "a string"
    if isinstance(x, list):
        return "a list"
    if isinstance(x, dict):
        return "an object"
    return type(x).__name__


def first_non_finite(x, where=""):
    """(field, text) of the first float of X that is not finite, or None."""
    if isinstance(x, float) and not math.isfinite(x):
        return where or "(top level)", getattr(x, "text", repr(x))
    if isinstance(x, dict):
        for k, v in x.items():
            found = first_non_finite(v, f"{where}.{k}" if where else str(k))
            if found:
                return found
    elif isinstance(x, list):
        for i, v in enumerate(x):
            found = first_non_finite(v, f"{where}[{i}]")
            if found:
                return found
    return None


def syntax_error(e):
    """json's message of E with its column ("Unterminated string starting at column 12")."""
    msg = e.msg[:-3] if e.msg.endswith(" at") else e.msg
    return f"{msg} at column {e.colno}"


def parse(text, path, what, line=None, constant=None, cut=False):
    """The JSON value of TEXT (one document, or one line of a JSON Lines file: LINE). CONSTANT:
    json's parse_constant for NaN and Infinity (kept as the values it makes); None refuses them.
    CUT: TEXT is a file's last line without its end (a syntax error there says the file was cut)."""
    try:
        doc = json.loads(text, parse_constant=constant or NonFiniteNumber)
    except json.JSONDecodeError as e:
        at = line if line is not None else e.lineno
        more = "; the file's last line has no end: it was cut short" if cut else ""
        raise FormatError(path, f"expected {what}, found a syntax error ({syntax_error(e)}){more}", line=at) from None
    if constant is None:
        bad = first_non_finite(doc)
        if bad:
            raise FormatError(path, f"expected a finite number or null, found {bad[1]}", line=line, field=bad[0])
    return doc


def read_text(path, what):
    """The UTF-8 text of PATH; a folder, a missing file or binary data is a FormatError (a file
    that cannot be read for another reason raises OSError)."""
    path = str(path)
    try:
        with open(path, "rb") as f:
            data = f.read()
    except IsADirectoryError:
        raise FormatError(path, f"expected {what}, found a folder") from None
    except FileNotFoundError:
        raise FormatError(path, f"expected {what}, found no such file") from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        line = data[:e.start].count(b"\n") + 1
        raise FormatError(path, f"expected {what} (UTF-8 text), found binary data (byte {e.start + 1})", line=line) from None


def load(path, what, constant=None):
    """The JSON document of the file PATH (see parse)."""
    return parse(read_text(path, what), path, what, constant=constant)


def load_lines(path, what, constant=None):
    """[(line number, value)] of a JSON Lines file (blank lines skipped)."""
    out = []
    lines = read_text(path, what).split("\n")
    for lineno, line in enumerate(lines, 1):
        if line.strip():
            out.append((lineno, parse(line, path, what, line=lineno, constant=constant, cut=lineno == len(lines))))
    return out


def need(cond, path, field, what, line=None):
    if not cond:
        raise FormatError(path, what, line=line, field=field)

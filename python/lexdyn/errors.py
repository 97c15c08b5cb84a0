"""The one error of the readers: a file that is not what its format says."""


class FormatError(ValueError):
    """A file that does not hold what its format says: `path`, `line` (1-based, None when the
    file has no lines to speak of, e.g. a JSON document as a whole), `field` (the key path or
    channel, None when the problem is not one field's) and `what` (what was expected and what
    was found). The message reads `PATH:LINE: FIELD: WHAT`."""

    def __init__(self, path, what, line=None, field=None):
        self.path = str(path)
        self.line = line
        self.field = field
        self.what = what
        where = self.path + (f":{line}" if line is not None else "")
        super().__init__(f"{where}: {field}: {what}" if field else f"{where}: {what}")

"""Locks of lexdyn's jobs (docs/report.md, "Locks"), in the format every lexdyn tool uses.

A folder DIR that a job writes is locked by the file DIR/.lexdyn.lock: opened read-write
(created 0644, close-on-exec), held with flock(LOCK_EX | LOCK_NB) for the job's lifetime, and
holding one line naming its holder:

  pid=<pid> started=<UTC time, 2026-11-28T07:01:02Z> host=<hostname> command=<what>

A second job on the same folder is refused at once (exit code 2) with that holder. The kernel
releases a flock when its process ends, so the file of a job that died is simply taken over. The
file is never removed: a third job would lock a new file of the same name while the second still
holds the old one.

A file shared by many jobs (the history of nights) is locked by FILE.lock, the same line, held
with a blocking flock while a job reads, changes and writes the file.
"""
import datetime
import fcntl
import os
import socket

from .common import ReportInputError, ReportOutputError, os_reason

LOCK_NAME = ".lexdyn.lock"


def holder_line(command):
    """The line a lock's holder writes into its lock file."""
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    try:
        host = socket.gethostname() or "unknown"
    except OSError:
        host = "unknown"
    return f"pid={os.getpid()} started={now} host={host} command={command}\n"


def describe_holder(text):
    """'pid 1234, report.py, started 2026-11-28T07:01:02Z on HOST' from a lock file's first line,
    or 'holder unknown' when the line names no pid."""
    line = text.split("\n", 1)[0]
    fields = {}
    rest = line
    for key in ("pid", "started", "host"):
        if not rest.startswith(key + "="):
            break
        value, _, rest = rest[len(key) + 1:].partition(" ")
        fields[key] = value
    if rest.startswith("command="):
        fields["command"] = rest[len("command="):]
    pid = fields.get("pid", "")
    if not pid.isdigit():
        return "holder unknown"
    out = f"pid {pid}"
    if fields.get("command"):
        out += f", {fields['command']}"
    if fields.get("started"):
        out += f", started {fields['started']}"
    if fields.get("host"):
        out += f" on {fields['host']}"
    return out


def create_folder(path, option="--out"):
    """Creates the folder PATH and its parents. An existing PATH (or a parent) that is not a
    folder is bad input (ReportInputError); a refusal of the system (permissions, a full or
    read-only file system) is a ReportOutputError with its reason."""
    if not path:
        raise ReportInputError(option, "expected a folder, found an empty path")
    if os.path.isdir(path):
        return
    p = os.path.abspath(path)
    while True:
        if os.path.lexists(p):
            if not os.path.isdir(p):
                raise ReportInputError(path, f"cannot create the output folder: {p} exists and is not a folder")
            break
        parent = os.path.dirname(p)
        if parent == p:
            break
        p = parent
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as e:
        raise ReportOutputError(e.filename or path, os_reason(e)) from e


def _open_lock_file(path):
    try:
        return os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    except OSError as e:
        raise ReportOutputError(path, os_reason(e)) from e


def _record_holder(fd, command):
    # Best effort: the lock is the flock; the line only names the holder in others' messages.
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, holder_line(command).encode(), 0)
    except OSError:
        pass


def _read_holder(fd):
    try:
        return os.pread(fd, 1024, 0).decode("utf-8", "replace")
    except OSError:
        return ""


class _HeldLock:
    """A lock file held open; closing it releases the flock (the file stays)."""

    fd = None

    def release(self):
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()


class FolderLock(_HeldLock):
    """The lock of an output folder, held until release() (or the end of the process). Creates
    the folder. Another job holding it: ReportInputError (exit code 2) 'DIR: in use by another
    lexdyn job (pid P, C, started T on H); wait for it to end or give another --out'."""

    def __init__(self, folder, command):
        create_folder(folder)
        self.folder = folder
        self.path = os.path.join(folder, LOCK_NAME)
        fd = _open_lock_file(self.path)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = describe_holder(_read_holder(fd))
            os.close(fd)
            raise ReportInputError(folder, f"in use by another lexdyn job ({holder}); wait for it to end or give another --out")
        except OSError as e:
            os.close(fd)
            raise ReportOutputError(self.path, os_reason(e)) from e
        _record_holder(fd, command)
        self.fd = fd


class FileLock(_HeldLock):
    """The lock of a file shared by many jobs (FILE.lock), waited for, held until release()."""

    def __init__(self, file, command):
        parent = os.path.dirname(os.path.abspath(file))
        create_folder(parent)
        self.path = file + ".lock"
        fd = _open_lock_file(self.path)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
        except OSError as e:
            os.close(fd)
            raise ReportOutputError(self.path, os_reason(e)) from e
        _record_holder(fd, command)
        self.fd = fd

"""How every part reads the files a user names and writes its results.

Reading: one function, `read_input`, so that every input (mission, plan, model, scenario,
ocean and run files) is refused alike when it is missing, a directory, a device or a named
pipe, or larger than `MAX_INPUT_BYTES`, with one line naming the file. Every data file
(TOML or JSON) is then parsed by one function, `parse_data` (`read_data` does both), which
bounds its nesting (`MAX_DATA_DEPTH`) and refuses a number that is not finite.

Writing: atomically. A crash, a full disk or Ctrl-C leaves either the old file or the new
one, never half of one (the promise README.md makes).
"""

from __future__ import annotations

import codecs
import errno
import json
import math
import os
import stat
import tempfile
from pathlib import Path

from gliderplan.contract import MAX_DATA_DEPTH, MAX_INPUT_BYTES
from gliderplan.contract.errors import GliderplanError, UsageError


class InputFileError(GliderplanError):
    """A file that cannot be read as the input it should be; `usage` when the path names
    no file that could be one (missing, a directory, a device or pipe, unreadable). Its
    message starts with the file's name."""

    def __init__(self, message: str, *, usage: bool = False, details: str = "",
                 file: str | None = None) -> None:
        super().__init__(message, usage=usage, details=details, file=file)


class DataFileError(InputFileError):
    """A data file (TOML or JSON) that does not parse or breaks the bounds of `parse_data`:
    the file `where`, the dotted `key` at fault (None: the whole file) and the `problem`."""

    def __init__(self, where: str, key: str | None, problem: str) -> None:
        self.where, self.key, self.problem = where, key, problem
        super().__init__(f"{where}: {key}: {problem}" if key else f"{where}: {problem}",
                         file=where)


class OutputFileError(UsageError):
    """A result file that cannot be written where the user asked (`-o`)."""


def read_input(path: str | Path, what: str, *, head: int | None = None) -> bytes:
    """The bytes of the input file `path` (`what` it should be: "mission file", ...).

    Opened without blocking (a named pipe with no writer would hang) and checked to be a
    regular file of at most MAX_INPUT_BYTES before it is read: a device such as /dev/zero
    never ends. `head`: only the first `head` bytes, whatever the file's size (of a file
    that another library reads, such as a Slocum log, looked at before it is handed on)."""
    shown = str(path)
    wanted = MAX_INPUT_BYTES + 1 if head is None else head
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except OSError as err:
        raise InputFileError(f"{shown}: {_open_problem(err, what)}", usage=True,
                             file=shown) from None
    try:
        info = os.fstat(fd)
        if stat.S_ISDIR(info.st_mode):
            raise InputFileError(f"{shown}: is a directory, not a {what}", usage=True, file=shown)
        if not stat.S_ISREG(info.st_mode):
            raise InputFileError(f"{shown}: is not a regular file (a device, pipe or "
                                 f"socket), not a {what}", usage=True, file=shown)
        data = b""
        if head is not None or info.st_size <= MAX_INPUT_BYTES:
            chunk = b"-"
            while chunk and len(data) < wanted:  # it may grow while it is read
                chunk = os.read(fd, wanted - len(data))
                data += chunk
    except OSError as err:
        raise InputFileError(f"{shown}: cannot read: {err.strerror}", usage=True,
                             file=shown) from None
    finally:
        os.close(fd)
    if head is None and max(info.st_size, len(data)) > MAX_INPUT_BYTES:
        raise InputFileError(f"{shown}: more than {MAX_INPUT_BYTES} bytes is too large for a "
                             f"{what} (the limit of every file gliderplan reads)", file=shown)
    return data


def read_input_text(path: str | Path, what: str) -> str:
    """The text (UTF-8, a leading byte-order mark dropped) of the input file `path`."""
    data = read_input(path, what)
    if b"\0" in data:
        raise InputFileError(f"{path}: binary file (contains NUL bytes), not a {what}",
                             file=str(path))
    if data.startswith(codecs.BOM_UTF8):  # a spreadsheet or an editor on Windows adds one
        data = data[len(codecs.BOM_UTF8):]
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        line = data[: err.start].count(b"\n") + 1
        raise InputFileError(f"{path}:{line}: not UTF-8 text (byte 0x{data[err.start]:02x}), "
                             f"not a {what}", file=str(path)) from None


def read_data(path: str | Path, what: str, *, finite: bool = True) -> dict:
    """The table a TOML (or, for a name ending in .json, JSON) data file `path` holds,
    read by `read_input_text` and checked by `parse_data`; InputFileError naming the file."""
    syntax = "json" if str(path).endswith(".json") else "toml"
    return parse_data(read_input_text(path, what), str(path), syntax, finite=finite)


def parse_data(text: str, where: str, syntax: str = "toml", *, finite: bool = True) -> dict:
    """The top-level table of data `text` ("toml" or "json" `syntax`), refused with
    InputFileError naming `where` (the file) and the key when it does not parse, is not a
    table, nests tables or arrays more than MAX_DATA_DEPTH deep, or (`finite`) holds a
    number that is not finite: the one parser of every data file gliderplan reads."""
    import tomllib

    try:
        data = json.loads(text) if syntax == "json" else tomllib.loads(text)
    except RecursionError:
        raise DataFileError(where, None, f"tables or arrays nested more than "
                            f"{MAX_DATA_DEPTH} deep") from None
    except (tomllib.TOMLDecodeError, ValueError) as err:
        raise DataFileError(where, None, f"not valid {syntax.upper()}: {err}") from None
    if not isinstance(data, dict):
        raise DataFileError(where, None, f"expected a {syntax.upper()} table (object), got "
                            f"{type(data).__name__}")
    _check_data(data, where, finite)
    return data


def _check_data(data: dict, where: str, finite: bool) -> None:
    """Walk `data` without recursion: its depth, and (`finite`) its numbers."""
    pending: list[tuple[str, object, int]] = [("", data, 0)]
    while pending:
        key, value, depth = pending.pop()
        if isinstance(value, dict | list):
            if depth > MAX_DATA_DEPTH:
                shown = key if len(key) <= 60 else f"{key[:57]}..."
                raise DataFileError(where, shown, f"tables or arrays nested more than "
                                    f"{MAX_DATA_DEPTH} deep")
            items = value.items() if isinstance(value, dict) else \
                ((f"[{i}]", v) for i, v in enumerate(value))
            for name, item in items:
                inner = f"{key}{name}" if name.startswith("[") else \
                    f"{key}.{name}" if key else str(name)
                pending.append((inner, item, depth + 1))
        elif finite and isinstance(value, float) and not math.isfinite(value):
            parent, _, leaf = key.rpartition(".")
            raise DataFileError(where, parent or None,
                                f"{leaf} must be a finite number, got {value!r}")


def _open_problem(err: OSError, what: str) -> str:
    if err.errno in (errno.ENOENT, errno.ENOTDIR):
        return "no such file"
    if err.errno == errno.ENAMETOOLONG:
        return f"file name too long for a {what}"
    return f"cannot open: {err.strerror}"


def output_directory(path: str | Path) -> Path:
    """`path`, made a directory for results (with its parents), or OutputFileError."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputFileError(f"{path}: cannot write: {err.strerror}") from None
    return path


def write_atomically(path: str | Path, data: str | bytes, *, private: bool = False,
                     replace: bool = True) -> None:
    """Write a result file so that a crash leaves either the old file or the new one;
    OutputFileError, naming the file, if it cannot be written there.

    A symbolic link stays a link: the file it points to is replaced. A file that exists
    keeps its permissions, and one that is read-only (no write permission for us, or no
    write bit at all, which root would override) is refused, not replaced: a rename
    would bypass its permissions. A new file gets the umask's (mkstemp alone: 0600).
    `private`: readable by its owner only (mode 0600: a key). `replace=False`: an existing
    file is left alone and FileExistsError raised (the new file appears whole or not at
    all; a hard link is how an atomic no-clobber create is done on POSIX)."""
    shown = Path(path)
    path = Path(os.path.realpath(path))
    output_directory(path.parent)
    try:
        try:
            permissions = stat.S_IMODE(path.stat().st_mode)
        except FileNotFoundError:
            permissions = 0o666 & ~_umask()
        else:
            if not (permissions & 0o222 and os.access(path, os.W_OK)):
                raise OutputFileError(f"{shown}: read-only (mode {permissions:03o}): not "
                                      "replaced; make it writable (chmod u+w) to replace it")
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:32]}.", dir=path.parent)
    except OSError as err:
        raise OutputFileError(f"{shown}: cannot write: {err.strerror}") from None
    mode = "wb" if isinstance(data, bytes) else "w"
    try:
        with os.fdopen(fd, mode) as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(tmp, 0o600 if private else permissions)
        if replace:
            os.replace(tmp, path)
        else:
            os.link(tmp, path)
    except FileExistsError:  # replace=False and the file is there: the caller's to say
        Path(tmp).unlink(missing_ok=True)
        raise
    except OSError as err:
        Path(tmp).unlink(missing_ok=True)
        raise OutputFileError(f"{shown}: cannot write: {err.strerror}") from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    if not replace:
        Path(tmp).unlink()


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask

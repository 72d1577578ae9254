"""How every part reads the files a user names and writes its results.

Reading: one function, `read_input`, so that every input (mission, plan, model, scenario,
ocean and run files) is refused alike when it is missing, a directory, a device or a named
pipe, or larger than `MAX_INPUT_BYTES`, with one line naming the file. Every data file
(TOML or JSON) is then parsed by one function, `parse_data` (`read_data` does both), which
bounds its nesting (`MAX_DATA_DEPTH`) and refuses a number that is not finite.

Writing: atomically. A crash, a full disk or Ctrl-C leaves either the old file or the new
one, never half of one (the promise README.md makes): `write_atomically` for one file,
`write_files_atomically` for files that go together (a plan and its report). A command
that writes a folder of results (`sim`, `montecarlo`, `plan --sweep`, `export -o`,
`report`, `compare-sbc`, `compile`) writes it with `output_folder`: into a new hidden
folder beside the target, moved into place whole, under a lock, so that the folder holds
one run, never files of two.
"""

from __future__ import annotations

import codecs
import errno
import json
import math
import os
import re
import shutil
import stat
import tempfile
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
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


def write_files_atomically(files: dict[str | Path, str | bytes]) -> None:
    """Write files that go together (a plan and its report): each to a temporary file
    beside it first, then all renamed into place one after the other, where a stop signal
    waits (contract.interrupts.deferred). A file that cannot be written leaves every one
    as it was: never a new plan beside an old report."""
    from gliderplan.contract import interrupts

    staged: list[tuple[str, Path, Path]] = []
    try:
        for path, data in files.items():
            real = Path(os.path.realpath(path))
            name = f".{real.name[:32]}.new"
            tmp = Path(tempfile.mkdtemp(prefix=name, dir=output_directory(real.parent)))
            staged.append((str(path), tmp, real))
            try:
                mode = stat.S_IMODE(real.stat().st_mode)
            except FileNotFoundError:
                mode = None
            write_atomically(tmp / real.name, data)
            if mode is not None:
                if not (mode & 0o222 and os.access(real, os.W_OK)):
                    raise OutputFileError(f"{path}: read-only (mode {mode:03o}): not "
                                          "replaced; make it writable (chmod u+w) to replace "
                                          "it")
                os.chmod(tmp / real.name, mode)
        for _, tmp, real in staged:  # the files replaced, kept until all are in place
            if real.exists():
                os.link(real, tmp / ".previous")
        with interrupts.deferred(reraise=True):
            done: list[tuple[Path, Path]] = []
            for shown, tmp, real in staged:
                try:
                    os.replace(tmp / real.name, real)
                    done.append((tmp, real))
                except OSError as err:
                    for put_tmp, put in done:  # put back what was replaced
                        if (put_tmp / ".previous").exists():
                            os.replace(put_tmp / ".previous", put)
                        else:
                            put.unlink(missing_ok=True)
                    raise OutputFileError(f"{shown}: cannot write: {err.strerror}") from None
    except OSError as err:
        raise OutputFileError(f"cannot write: {err.strerror or err}") from None
    finally:
        for _, tmp, _ in staged:
            shutil.rmtree(tmp, ignore_errors=True)


# ---- a folder of results --------------------------------------------------------------

RUN_MARKER = ".gliderplan-run"  # in every folder output_folder writes: what wrote it
_LEFTOVER = re.compile(r"^\..+\.[a-z0-9_]{8}$")  # write_atomically's temporary file
_OWN = re.compile(r"^\.gliderplan\.(lock|(new|old)-[a-z0-9_]{8})$")  # in a mount point


class OutputFolder:
    """A folder of results being written (`output_folder`): write its files into `path`
    (a hidden folder beside the target); `final(name)` is where a file will be. Set
    `complete` False for a run that was cut short: the folder's RUN_MARKER says so."""

    def __init__(self, path: Path, target: Path, command: str) -> None:
        self.path, self.target, self.command = path, target, command
        self.complete = True

    def write(self, name: str, data: str | bytes) -> Path:
        """Write the file `name` of the run; where it will be once the run is in place."""
        write_atomically(self.path / name, data)
        return self.final(name)

    def final(self, name: str) -> Path:
        return self.target / name

    def sub(self, name: str) -> OutputFolder:
        """The folder `name` inside this one (a fleet's plan, a glider's run): written
        with it, moved into place with it."""
        return OutputFolder(output_directory(self.path / name), self.target / name,
                            self.command)


@contextmanager
def output_folder(path: str | Path, *, command: str, force: bool = False,
                  keep: bool = False, recognised: Iterable[str] = (),
                  inputs: Iterable[str | Path | None] = ()) -> Iterator[OutputFolder]:
    """The folder `path` (`-o`) for one run of `command`, written whole or not at all.

    Inside the block the files go into a new hidden folder beside `path`; when the block
    ends they replace the folder at `path` in one rename (the previous run is then
    deleted); if it raises (an error, a full disk, Ctrl-C), the new folder is removed and
    the previous run stays as it was. A symbolic link to a folder stays a link: the
    folder it points to is replaced. A lock beside the folder refuses a second run into
    it while one is writing it. A mount point (or a folder whose parent cannot be
    written) cannot be replaced: the run is staged inside it and moved in entry by entry
    (`_commit_in_place`).

    OutputFileError (exit 2), before anything is computed, for a folder that holds
    anything but a previous gliderplan run (the files its RUN_MARKER lists, the names
    `recognised`: those of a run written before folders had a marker, and folders of
    results) unless `force` (what it holds is then deleted with the previous run); for
    the working folder, one above it, the home folder or the root; for an `inputs` path
    inside the folder (it would be deleted with it); for a folder another run is writing.
    `keep`: the new folder starts as a copy (hard links) of the previous one, which it
    then extends (`export` into its own run)."""
    shown = str(path)
    real = Path(os.path.realpath(path))
    if real.exists() and not real.is_dir():
        raise OutputFileError(f"-o {shown}: not a directory")
    home = Path(os.path.realpath(Path.home())) if "HOME" in os.environ else None
    if real == Path(real.anchor) or real == home or _within(Path.cwd(), real):
        raise OutputFileError(f"-o {shown}: is the working folder, one above it, the home "
                              "folder or the root; a run's folder is replaced whole: name a "
                              f"folder of its own (e.g. {Path(shown) / 'run'})")
    if not keep:
        for given in inputs:
            if given is not None and _within(Path(os.path.realpath(given)), real):
                raise OutputFileError(f"{given}: lies inside -o {shown}, which this run "
                                      "replaces whole: move it out, or write elsewhere")
    parent = output_directory(real.parent)
    key = _folder_key(real.name)
    # a mount point (a container's volume), or a folder in one that cannot be written,
    # stays where it is: the run is staged inside it
    mounted = real.is_dir() and (os.path.ismount(real) or not os.access(parent, os.W_OK))
    if mounted:
        parent, key = real, "gliderplan"
    lock = _lock(parent / f".{key}.lock", shown)
    staging = None
    try:
        if real.is_dir() and not keep and not force:
            foreign = _foreign(real, set(recognised))
            if foreign:
                listed = ", ".join(foreign[:3]) + (", ..." if len(foreign) > 3 else "")
                raise OutputFileError(
                    f"-o {shown}: not empty and not a gliderplan run's folder (it holds "
                    f"{listed}): name a new or empty folder, or add --force to replace it "
                    "(its files are deleted)")
        _remove_stale(parent, key)
        try:
            staging = Path(tempfile.mkdtemp(prefix=f".{key}.new-", dir=parent))
            if keep and real.is_dir():
                _copy_linked(real, staging)
        except OSError as err:
            raise OutputFileError(f"-o {shown}: cannot write: {err.strerror}") from None
        folder = OutputFolder(staging, Path(shown), command)
        yield folder
        if mounted:
            _commit_in_place(folder, real, shown)
        else:
            _commit(folder, real, parent, key, shown)
        staging = None
    finally:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)
        _unlock(*lock)


def _within(inner: Path, outer: Path) -> bool:
    """Whether `inner` is `outer` or lies inside it (both resolved)."""
    return inner == outer or outer in inner.parents


def _folder_key(name: str) -> str:
    """The target's name in the names of its lock and its hidden folders."""
    if len(name.encode()) <= 200:
        return name
    import hashlib

    return f"{name[:100]}~{hashlib.sha256(name.encode()).hexdigest()[:12]}"


def _foreign(folder: Path, recognised: set[str]) -> list[str]:
    """What in `folder` is no gliderplan run's: not a file its RUN_MARKER lists (or,
    without one, a name `recognised`), nor a folder of results of its own (empty: a run,
    or an empty folder)."""
    try:
        names = sorted(os.listdir(folder))
    except OSError as err:
        raise OutputFileError(f"-o {folder}: cannot read: {err.strerror}") from None
    allowed = set(recognised) | {RUN_MARKER}
    names = [name for name in names if not _OWN.match(name)]
    if RUN_MARKER in names:
        try:
            listed = json.loads((folder / RUN_MARKER).read_text()).get("files", [])
            allowed |= {name for name in listed if isinstance(name, str)}
        except (OSError, ValueError, AttributeError):
            pass
    return [name for name in names if name not in allowed and not _LEFTOVER.match(name)
            and not (folder / name / RUN_MARKER).is_file()]


def _remove_stale(parent: Path, key: str) -> None:
    """Remove the hidden folders of runs into this target that were killed (the lock is
    ours: no live run owns them)."""
    stale = re.compile(rf"^\.{re.escape(key)}\.(new|old)-[a-z0-9_]{{8}}$")
    for name in os.listdir(parent):
        if stale.match(name):
            shutil.rmtree(parent / name, ignore_errors=True)


def _copy_linked(source: Path, destination: Path) -> None:
    """The contents of `source` into `destination`, hard-linked where they can be."""
    def link(src: str, dst: str) -> None:
        try:
            os.link(src, dst)
        except OSError:
            shutil.copy2(src, dst)

    for entry in os.scandir(source):
        if entry.name == RUN_MARKER or _OWN.match(entry.name):
            continue
        target = destination / entry.name
        if entry.is_dir(follow_symlinks=False):
            shutil.copytree(entry.path, target, symlinks=True, copy_function=link)
        elif entry.is_symlink():
            os.symlink(os.readlink(entry.path), target)
        else:
            link(entry.path, str(target))


def _commit(folder: OutputFolder, real: Path, parent: Path, key: str, shown: str) -> None:
    """Move the new folder into place whole; delete the previous run. Cut short by a
    stop signal, it leaves the new run in place or the previous one (output_folder then
    removes what is left of the other)."""
    staging = folder.path
    try:
        names = sorted(n for n in os.listdir(staging) if not _LEFTOVER.match(n))
        marker = {"command": folder.command, "complete": folder.complete, "files": names}
        write_atomically(staging / RUN_MARKER, json.dumps(marker, indent=2) + "\n")
        try:
            mode = stat.S_IMODE(real.stat().st_mode)
        except FileNotFoundError:
            mode = 0o777 & ~_umask()
        os.chmod(staging, mode)
        _fsync(staging)
        old = _move_into_place(staging, real, parent, key)
        _fsync(parent)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except OSError as err:
        raise OutputFileError(f"-o {shown}: cannot write: {err.strerror or err}") from None


def _commit_in_place(folder: OutputFolder, real: Path, shown: str) -> None:
    """Move the new run into `real`, a mount point that cannot be replaced: its entries
    aside into a hidden folder, the new ones in (the marker last, so that a folder cut
    half-way by a crash has none and is refused, not taken for a run), then the old ones
    deleted. Not one rename, as elsewhere, but a failure puts the previous run back."""
    staging = folder.path
    moved: list[str] = []
    kept: list[str] = []
    old = None
    try:
        names = sorted(n for n in os.listdir(staging) if not _LEFTOVER.match(n))
        marker = {"command": folder.command, "complete": folder.complete, "files": names}
        write_atomically(staging / RUN_MARKER, json.dumps(marker, indent=2) + "\n")
        _fsync(staging)
        old = Path(tempfile.mkdtemp(prefix=".gliderplan.old-", dir=real))
        try:
            for name in sorted(os.listdir(real)):
                if not _OWN.match(name):
                    os.rename(real / name, old / name)
                    kept.append(name)
            for name in [*names, RUN_MARKER]:
                os.rename(staging / name, real / name)
                moved.append(name)
        except BaseException:
            for name in moved:
                os.rename(real / name, staging / name)
            for name in kept:
                os.rename(old / name, real / name)
            raise
        _fsync(real)
        shutil.rmtree(old, ignore_errors=True)
        shutil.rmtree(staging, ignore_errors=True)
    except OSError as err:
        try:
            if old is not None:
                os.rmdir(old)  # emptied by the rollback (else it holds the previous run)
        except OSError:
            pass
        raise OutputFileError(f"-o {shown}: cannot write: {err.strerror or err}") from None


def _move_into_place(staging: Path, real: Path, parent: Path, key: str) -> Path | None:
    """Rename `staging` to `real`; where `real` is a folder that is not empty, exchange
    the two (one rename on Linux, two elsewhere); the previous folder's new name, if any."""
    try:
        os.rename(staging, real)  # no folder there, or an empty one
        return None
    except OSError as err:
        if err.errno not in (errno.ENOTEMPTY, errno.EEXIST):
            raise
    if _exchange(staging, real):
        return staging
    old = Path(tempfile.mkdtemp(prefix=f".{key}.old-", dir=parent))
    os.rename(real, old / "run")
    try:
        os.rename(staging, real)
    except BaseException:
        os.rename(old / "run", real)
        raise
    return old


def _exchange(first: Path, second: Path) -> bool:
    """Swap two paths atomically (Linux renameat2 RENAME_EXCHANGE); False where this
    system or file system cannot."""
    import ctypes

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]
    at_fdcwd, rename_exchange = -100, 2
    if renameat2(at_fdcwd, os.fsencode(first), at_fdcwd, os.fsencode(second),
                 rename_exchange) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP, errno.ENOTSUP):
        return False
    raise OSError(code, os.strerror(code), str(second))


def _fsync(directory: Path) -> None:
    """Flush a folder's entries to disk (where the system lets a folder be opened)."""
    try:
        fd = os.open(directory, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _lock(path: Path, shown: str) -> tuple[Path, int]:
    """Hold the lock file `path` (flock, released if the process dies), or OutputFileError
    naming the process that holds it."""
    import fcntl

    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o644)
        except OSError as err:
            raise OutputFileError(f"-o {shown}: cannot write: {err.strerror}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            holder = b""
            if err.errno in (errno.EAGAIN, errno.EWOULDBLOCK, errno.EACCES):
                holder = os.read(fd, 32).strip()
            os.close(fd)
            if not holder and err.errno not in (errno.EAGAIN, errno.EWOULDBLOCK,
                                                errno.EACCES):
                raise OutputFileError(f"-o {shown}: cannot lock: {err.strerror}") from None
            said = f" (process {holder.decode(errors='replace')})" if holder else ""
            raise OutputFileError(f"-o {shown}: another gliderplan run is writing this "
                                  f"folder{said}: wait for it to end, or name another "
                                  "folder") from None
        try:  # the file may have been removed by the run that held it, as we opened it
            same = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()}\n".encode())
            return path, fd
        os.close(fd)


def _unlock(path: Path, fd: int) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass
    os.close(fd)

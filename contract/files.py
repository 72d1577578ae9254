"""How every part writes a result file: atomically. A crash, a full disk or Ctrl-C leaves
either the old file or the new one, never half of one (the promise README.md makes)."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def write_atomically(path: str | Path, data: str | bytes, *, private: bool = False,
                     replace: bool = True) -> None:
    """Write a result file so that a crash leaves either the old file or the new one.

    `private`: readable by its owner only (mode 0600: a key). `replace=False`: an existing
    file is left alone and FileExistsError raised (the new file appears whole or not at
    all; a hard link is how an atomic no-clobber create is done on POSIX)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    mode = "wb" if isinstance(data, bytes) else "w"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, mode) as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        if not private:
            os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; results are for sharing
        if replace:
            os.replace(tmp, path)
        else:
            os.link(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    if not replace:
        Path(tmp).unlink()


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask

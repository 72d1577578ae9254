"""Signed plans (docs/plan-format.md, "Signed plans"): a plan sent to a glider at the surface
travels over a satellite link anyone can send on, so it carries a sequence number and an
HMAC-SHA256 tag under a key provisioned on the vehicle. The runtime flies a plan only if
the tag matches and the sequence number is newer than the plan in force.

The key file holds the 32-byte key as 64 lowercase hex digits and a LF, mode 0600,
exactly what the runtime's `--key FILE` reads (runtime/src/gp_key.c).
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import stat
import time
from pathlib import Path

from gliderplan.contract import MAX_PLAN_SEQUENCE, PLAN_KEY_BYTES
from gliderplan.contract.errors import GliderplanError
from gliderplan.contract.files import write_atomically
from gliderplan.planner.planfile import PlanFileError, PlanRejected, read_plan_bytes

KEY_FILE_BYTES = 2 * PLAN_KEY_BYTES + 1


class KeyFileError(GliderplanError):
    """A key file that is missing, shared with others or not a key."""


def write_new_key(path: str | Path) -> None:
    """Write a fresh random key to `path` (mode 0600, atomically); never over an existing
    file, whose key may be the one a vehicle holds."""
    try:
        write_atomically(path, secrets.token_bytes(PLAN_KEY_BYTES).hex() + "\n", private=True,
                         replace=False)
    except FileExistsError:
        raise KeyFileError(f"{path}: exists; a new key would not match the one provisioned "
                           "with it: remove it first, or write elsewhere", usage=True) from None
    except OSError as err:
        raise KeyFileError(f"{path}: cannot write the key: {err.strerror}", usage=True) from None


def read_key(path: str | Path) -> bytes:
    """The key in `path`, refused as the runtime refuses it: missing, not a regular file,
    readable by group or others, or not 64 lowercase hex digits and a LF."""
    try:
        # Opened without blocking: a named pipe with no writer would hang (contract.files).
        with os.fdopen(os.open(path, os.O_RDONLY | os.O_NONBLOCK), "rb") as handle:
            mode = os.fstat(handle.fileno()).st_mode
            if not stat.S_ISREG(mode):
                raise KeyFileError(f"{path}: the key file is not a regular file", usage=True)
            text = handle.read(KEY_FILE_BYTES + 1)
    except FileNotFoundError:
        raise KeyFileError(f"{path}: no such key file (gliderplan keygen -o {path} makes one)",
                           usage=True) from None
    except OSError as err:
        raise KeyFileError(f"{path}: cannot read the key file: {err.strerror}",
                           usage=True) from None
    if mode & 0o077:
        raise KeyFileError(f"{path}: the key file may be read by others (mode "
                           f"{stat.S_IMODE(mode):03o}): chmod 600 it")
    hex_digits = text[:-1].decode("ascii", errors="replace")
    if (len(text) != KEY_FILE_BYTES or not text.endswith(b"\n")
            or any(c not in "0123456789abcdef" for c in hex_digits)):
        raise KeyFileError(f"{path}: not a key file ({2 * PLAN_KEY_BYTES} lowercase hex "
                           "digits and a LF; gliderplan keygen writes one)")
    return bytes.fromhex(hex_digits)


def unsigned_part(data: bytes) -> bytes:
    """The plan file without its `seq` and `hmac` lines, if it has them."""
    lines = data.split(b"\n")
    if len(lines) >= 3 and lines[-2].startswith(b"hmac ") and lines[-3].startswith(b"seq "):
        return b"\n".join(lines[:-3]) + b"\n"
    return data


def tag(signed_part: bytes, key: bytes) -> str:
    """HMAC-SHA256 of every byte before the `hmac` line, in lowercase hex."""
    return hmac.new(key, signed_part, hashlib.sha256).hexdigest()


def default_sequence() -> int:
    """A sequence number that grows between signings without a counter to keep: the time
    of signing in whole seconds since 1970 (a u32 until 2106)."""
    return int(time.time())


def sign_plan(data: bytes, key: bytes, seq: int) -> bytes:
    """The plan file `data` signed with `key` as plan number `seq` (any earlier signature
    is replaced). PlanFileError if `data` is not a plan file."""
    if not 1 <= seq <= MAX_PLAN_SEQUENCE:
        raise PlanFileError(0, f"seq {seq}: must lie in 1..{MAX_PLAN_SEQUENCE}")
    body = unsigned_part(data)
    read_plan_bytes(body)
    signed = body + f"seq {seq}\n".encode("ascii")
    return signed + f"hmac {tag(signed, key)}\n".encode("ascii")


def check_signature(data: bytes, key: bytes, path: str = "") -> int:
    """The sequence number of a plan file signed with `key`; PlanRejected, naming the line
    as the runtime does, if it is unsigned or its tag does not match."""
    where = f"{path}:" if path else ""
    lines = data.split(b"\n")
    body = unsigned_part(data)
    if body == data:
        raise PlanRejected(f"{where}{len(lines) - 1}: the plan is not signed, and the vehicle "
                           "holds a key: it flies signed plans only (gliderplan plan --sign)")
    stated = lines[-2][len(b"hmac "):].decode("ascii", errors="replace")
    signed_part = data[:len(data) - len(lines[-2]) - 1]
    if not hmac.compare_digest(stated, tag(signed_part, key)):
        raise PlanRejected(f"{where}{len(lines) - 1}: the signature does not match: the plan "
                           "was changed after it was signed, or signed with another key")
    return int(lines[-3][len(b"seq "):])

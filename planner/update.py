"""Plan updates (docs/plan-update.md): a signed binary delta against the plan a glider holds,
small enough for one short Iridium message down (contract.MAX_UPDATE_BYTES, 270 bytes).

An update names the plan it was made against (its sequence number and the first bytes of
the SHA-256 of its file) and the plan it makes (the new sequence number and the first
bytes of the SHA-256 of the new file), lists the changes (a field of a line of the plan
file: a sensor's on-time, a profile's share, ...; `contract.UpdateField`), each value a
decimal mantissa and exponent, and ends in an HMAC-SHA256 tag over everything before it,
under the vehicle's key. The vehicle checks the tag first, then the sequence numbers and
the plan it holds, makes the change in the plan file's text, checksums and signs the
result with its key (as the shore did), and reads it strictly as any plan before it flies
it: the new plan is a signed plan file like any other, the one it stores and resumes.

This module is both sides: `make_updates` on the shore, `apply_update` as the runtime does
it (runtime/src/gp_update.c follows it line for line; tests hold the two to the same
bytes, the same verdicts and the same messages).
"""

from __future__ import annotations

import hashlib
import hmac
import struct
import zlib
from dataclasses import dataclass
from decimal import ROUND_HALF_EVEN, Decimal

from gliderplan.contract import (
    MAX_PLAN_BYTES,
    MAX_PLAN_SEQUENCE,
    MAX_UPDATE_BYTES,
    UPDATE_FIELD_LINES,
    UPDATE_FORMAT_VERSION,
    UPDATE_HASH_BYTES,
    UPDATE_HEADER_BYTES,
    UPDATE_MAX_DIGITS,
    UPDATE_MAX_EXPONENT,
    UPDATE_OPTIONAL_FIELDS,
    UpdateField,
    UpdateStatus,
)
from gliderplan.contract.errors import GliderplanError
from gliderplan.planner.planfile import Plan, PlanFileError, read_plan_bytes
from gliderplan.planner.signing import unsigned_part

MAGIC = b"GU"
TAG_BYTES = 32
# the smallest update: header and tag, no change
MIN_UPDATE_BYTES = UPDATE_HEADER_BYTES + TAG_BYTES
_MAX_MANTISSA = 10**UPDATE_MAX_DIGITS - 1
_HEADER = struct.Struct(f"<2sBII{UPDATE_HASH_BYTES}s{UPDATE_HASH_BYTES}sB")
assert _HEADER.size == UPDATE_HEADER_BYTES


class UpdateError(GliderplanError):
    """No update can carry what was asked (too large, or a plan that is not the one held);
    the message says what to cut."""


# ---- values ----------------------------------------------------------------------------

def decimal(value: float | Decimal, digits: int = 9) -> tuple[int, int]:
    """(mantissa, exponent) of `value` rounded to `digits` significant digits, canonical: no
    trailing zero in the mantissa, and 0 is (0, 0)."""
    number = Decimal(value) if not isinstance(value, Decimal) else value
    if not number.is_finite():
        raise ValueError(f"an update carries finite values, not {value!r}")
    if number == 0:
        return 0, 0
    adjusted = number.adjusted()
    number = number.quantize(Decimal(1).scaleb(adjusted - digits + 1), ROUND_HALF_EVEN)
    sign, numerals, exponent = number.as_tuple()
    mantissa = int("".join(map(str, numerals)))
    while mantissa and mantissa % 10 == 0:
        mantissa //= 10
        exponent += 1
    if mantissa > _MAX_MANTISSA or abs(exponent) > UPDATE_MAX_EXPONENT:
        raise ValueError(f"{value} has no decimal an update carries ({UPDATE_MAX_DIGITS} digits "
                         f"at most, times 10^-{UPDATE_MAX_EXPONENT}..10^{UPDATE_MAX_EXPONENT})")
    return (-mantissa if sign else mantissa), int(exponent)


def decimal_text(mantissa: int, exponent: int) -> str:
    """The plan-file NUMBER of mantissa x 10^exponent, as the runtime writes it: its digits,
    with trailing zeros for a positive exponent and a point for a negative one."""
    digits = str(abs(mantissa))
    sign = "-" if mantissa < 0 else ""
    if exponent >= 0:
        return sign + digits + "0" * exponent if mantissa else "0"
    point = len(digits) + exponent
    if point > 0:
        return f"{sign}{digits[:point]}.{digits[point:]}"
    return f"{sign}0.{'0' * -point}{digits}"


# ---- the format -------------------------------------------------------------------------

@dataclass(frozen=True)
class Change:
    """Set field `field` of line `line` (1-based) of the plan file to mantissa x 10^exponent."""

    line: int
    field: UpdateField
    mantissa: int
    exponent: int

    @property
    def text(self) -> str:
        return decimal_text(self.mantissa, self.exponent)

    @property
    def value(self) -> float:
        return float(self.text)


@dataclass(frozen=True)
class PlanUpdate:
    """The fields of an update, as it travels (`pack`) and as it is read (`read_update`)."""

    base_seq: int  # the plan it was made against
    new_seq: int  # the plan it makes
    base_hash: bytes  # first UPDATE_HASH_BYTES of the SHA-256 of the base plan file
    result_hash: bytes  # the same of the plan file it makes
    changes: tuple[Change, ...]
    tag: bytes = b""  # HMAC-SHA256 of everything before it

    def body(self) -> bytes:
        """Every byte before the tag."""
        out = bytearray(_HEADER.pack(MAGIC, UPDATE_FORMAT_VERSION, self.base_seq,
                                     self.new_seq, self.base_hash, self.result_hash,
                                     len(self.changes)))
        line = 0
        for change in self.changes:
            out.append(int(change.field))
            out += _varint(change.line - line)
            out += _varint(_zigzag(change.mantissa))
            out += struct.pack("<b", change.exponent)
            line = change.line
        return bytes(out)

    def pack(self, key: bytes) -> bytes:
        """The update's bytes, signed with `key`."""
        body = self.body()
        return body + hmac.new(key, body, hashlib.sha256).digest()


def _varint(n: int) -> bytes:
    """LEB128: seven bits a byte, low first, the high bit set on every byte but the last."""
    out = bytearray()
    while True:
        byte = n & 0x7F
        n >>= 7
        out.append(byte | (0x80 if n else 0))
        if not n:
            return bytes(out)


def _zigzag(n: int) -> int:
    return 2 * n if n >= 0 else -2 * n - 1


def _unzigzag(n: int) -> int:
    return n // 2 if n % 2 == 0 else -(n + 1) // 2


def plan_hash(data: bytes) -> bytes:
    """The first UPDATE_HASH_BYTES of the SHA-256 of a plan file's bytes."""
    return hashlib.sha256(data).digest()[:UPDATE_HASH_BYTES]


class Refused(Exception):
    """What the vehicle answers an update it does not apply (`status`, `message`)."""

    def __init__(self, status: UpdateStatus, message: str) -> None:
        super().__init__(message)
        self.status, self.message = status, message


_VARINT_BYTES = 8  # 56 bits: a line or a mantissa fits with room


def _read_varint(data: bytes, at: int, end: int, what: str, most: int) -> tuple[int, int]:
    value = shift = 0
    for i in range(_VARINT_BYTES):
        if at + i >= end:
            raise Refused(UpdateStatus.MALFORMED, f"{what}: the update ends inside it")
        byte = data[at + i]
        value |= (byte & 0x7F) << shift
        shift += 7
        if not byte & 0x80:
            if value > most:
                raise Refused(UpdateStatus.MALFORMED, f"{what}: more than {most}")
            return value, at + i + 1
    raise Refused(UpdateStatus.MALFORMED, f"{what}: a number longer than {_VARINT_BYTES} bytes")


def read_update(data: bytes) -> PlanUpdate:
    """The fields of an update, checked for their form only (not the tag): Refused
    (MALFORMED) naming what is wrong, as the runtime says it."""
    if len(data) > MAX_UPDATE_BYTES:
        raise Refused(UpdateStatus.MALFORMED, f"the update has {len(data)} bytes, more than "
                      f"{MAX_UPDATE_BYTES}")
    if len(data) < MIN_UPDATE_BYTES or data[:2] != MAGIC:
        raise Refused(UpdateStatus.MALFORMED, f"not a plan update ({len(data)} bytes"
                      + (", no GU magic)" if len(data) >= 2 else ")"))
    magic, version, base_seq, new_seq, base_hash, result_hash, count = \
        _HEADER.unpack_from(data)
    if version != UPDATE_FORMAT_VERSION:
        raise Refused(UpdateStatus.MALFORMED, f"update version {version}: this vehicle reads "
                      f"version {UPDATE_FORMAT_VERSION}")
    end = len(data) - TAG_BYTES
    at, line, changes = UPDATE_HEADER_BYTES, 0, []
    for k in range(1, count + 1):
        if at >= end:
            raise Refused(UpdateStatus.MALFORMED, f"change {k}: the update ends before it")
        code = data[at]
        if code not in UPDATE_FIELD_LINES:
            raise Refused(UpdateStatus.MALFORMED, f"change {k}: no field has code {code}")
        advance, at = _read_varint(data, at + 1, end, f"change {k}: line", MAX_PLAN_BYTES)
        raw, at = _read_varint(data, at, end, f"change {k}: value", 2 * _MAX_MANTISSA)
        if at >= end:
            raise Refused(UpdateStatus.MALFORMED, f"change {k}: the update ends inside it")
        exponent = struct.unpack_from("<b", data, at)[0]
        at += 1
        mantissa = _unzigzag(raw)
        field = UpdateField(code)
        if not -UPDATE_MAX_EXPONENT <= exponent <= UPDATE_MAX_EXPONENT \
                or (mantissa == 0 and exponent != 0) or (mantissa and mantissa % 10 == 0):
            raise Refused(UpdateStatus.MALFORMED, f"change {k}: the value is not a canonical "
                          "decimal")
        if (advance == 0 and (k == 1 or code <= changes[-1].field)):
            raise Refused(UpdateStatus.MALFORMED, f"change {k}: changes must come in the "
                          "order of the plan's lines and fields")
        line += advance
        changes.append(Change(line, field, mantissa, exponent))
    if at != end:
        raise Refused(UpdateStatus.MALFORMED, f"{end - at} bytes after the last change")
    return PlanUpdate(base_seq, new_seq, base_hash, result_hash, tuple(changes),
                      bytes(data[end:]))


# ---- the new plan file ------------------------------------------------------------------

def _signed_seq(data: bytes) -> int:
    """The `seq` of a signed plan file, 0 if it is unsigned."""
    lines = data.split(b"\n")
    if len(lines) >= 3 and lines[-3].startswith(b"seq ") and lines[-2].startswith(b"hmac "):
        return int(lines[-3][4:])
    return 0


def changed_plan(held: bytes, changes: tuple[Change, ...] | list[Change], new_seq: int,
                 key: bytes) -> bytes:
    """The plan file `held` with `changes` made in its text, its checksum line anew, signed
    with `key` as plan `new_seq`: the bytes the runtime makes of an update. Refused
    (MALFORMED) for a change the plan's lines cannot take."""
    lines = unsigned_part(held).split(b"\n")[:-1]  # the last is the empty one after LF
    body_lines = len(lines) - 1  # up to the crc32 line
    for k, change in enumerate(changes, 1):
        keyword, place = UPDATE_FIELD_LINES[change.field]
        if not 1 <= change.line <= body_lines:
            raise Refused(UpdateStatus.MALFORMED, f"change {k}: line {change.line} is not "
                          f"in the plan's body (lines 1..{body_lines})")
        fields = lines[change.line - 1].split(b" ")
        appended = place == len(fields) and change.field in UPDATE_OPTIONAL_FIELDS
        if fields[0].decode("ascii", "replace") != keyword or \
                (place >= len(fields) and not appended):
            raise Refused(UpdateStatus.MALFORMED, f"change {k}: line {change.line} is no "
                          f"'{keyword}' line with a field {place}")
        if appended:  # an optional last field the line left out
            fields.append(b"")
        fields[place] = change.text.encode("ascii")
        lines[change.line - 1] = b" ".join(fields)
    body = b"".join(line + b"\n" for line in lines[:body_lines])
    signed = body + f"crc32 {zlib.crc32(body):08x}\nseq {new_seq}\n".encode("ascii")
    return signed + f"hmac {hmac.new(key, signed, hashlib.sha256).hexdigest()}\n".encode()


@dataclass(frozen=True)
class Applied:
    """What the vehicle makes of an update: its verdict, the message it says, and the plan
    file in force after it (the new one when applied, else the one it held)."""

    status: UpdateStatus
    message: str
    plan_file: bytes
    seq: int  # of the plan in force after it

    @property
    def accepted(self) -> bool:
        return self.status in (UpdateStatus.APPLIED, UpdateStatus.DUPLICATE)


def apply_update(held: bytes, data: bytes, key: bytes | None, *, check=None) -> Applied:
    """Apply the update `data` to the signed plan file `held` as the runtime does, in the
    runtime's order: the key, the form, the tag, the sequence numbers, the plan it was made
    against, the changes, the plan they make (its hash, then `check(new_file)`, which
    raises PlanFileError when the plan cannot be flown: the runtime's strict reader)."""
    seq = _signed_seq(held)

    def refused(status: UpdateStatus, message: str) -> Applied:
        return Applied(status, message, held, seq)

    if key is None:
        return refused(UpdateStatus.NO_KEY, "no key is provisioned on this vehicle: plan "
                       "updates are refused (start the runtime with --key FILE)")
    try:
        update = read_update(data)
    except Refused as err:
        return refused(err.status, err.message)
    body = data[:len(data) - TAG_BYTES]
    if not hmac.compare_digest(update.tag, hmac.new(key, body, hashlib.sha256).digest()):
        return refused(UpdateStatus.FORGED, "the signature does not match: the update was "
                       "changed after it was signed, or signed with another key")
    if seq == 0:
        return refused(UpdateStatus.NOT_HELD, "no signed plan is in force: send a whole plan "
                       "first")
    if update.new_seq <= seq:
        if update.new_seq == seq and update.result_hash == plan_hash(held):
            return refused(UpdateStatus.DUPLICATE, f"update to plan {seq} already applied: "
                           f"plan {seq} is in force")
        return refused(UpdateStatus.STALE, f"update to plan {update.new_seq} is not newer "
                       f"than plan {seq} in force: replayed or stale")
    if update.base_seq > seq:
        return refused(UpdateStatus.OUT_OF_ORDER, f"the update was made against plan "
                       f"{update.base_seq}, newer than plan {seq} in force: an update before "
                       "it has not arrived")
    if update.base_seq < seq:
        return refused(UpdateStatus.NOT_HELD, f"the update was made against plan "
                       f"{update.base_seq}; plan {seq} is in force")
    if update.base_hash != plan_hash(held):
        return refused(UpdateStatus.NOT_HELD, f"the update was made against another plan "
                       f"{seq}: its hash differs from the plan in force")
    try:
        new_file = changed_plan(held, update.changes, update.new_seq, key)
    except Refused as err:
        return refused(err.status, err.message)
    if len(new_file) > MAX_PLAN_BYTES:
        return refused(UpdateStatus.BAD_PLAN, f"the updated plan would have more than "
                       f"{MAX_PLAN_BYTES} bytes")
    if plan_hash(new_file) != update.result_hash:
        return refused(UpdateStatus.MALFORMED, "the plan it makes is not the plan it was "
                       "signed for (its hash differs)")
    try:
        (check or read_plan_bytes)(new_file)
    except PlanFileError as err:
        where = f"line {err.line}: " if err.line else ""
        return refused(UpdateStatus.BAD_PLAN, f"the updated plan is refused: {where}"
                       f"{err.message}")
    return Applied(UpdateStatus.APPLIED, f"ok: plan {update.new_seq} in force", new_file,
                   update.new_seq)


# ---- the shore: what to send ---------------------------------------------------------------

@dataclass(frozen=True)
class _Group:
    """Changes that must travel in one update (a state's profile shares sum to one)."""

    what: str  # for messages: "s2 sensor temp", "s3 profiles"
    changes: tuple[Change, ...]

    @property
    def size(self) -> int:
        """[bytes] of its changes in an update: at most (the first one's line advance
        counted from line 0)."""
        return len(PlanUpdate(0, 0, bytes(UPDATE_HASH_BYTES), bytes(UPDATE_HASH_BYTES),
                              self.changes).body()) - UPDATE_HEADER_BYTES


def _fields(line: str) -> list[str]:
    return line.split(" ")


def change_groups(held: bytes, target: Plan, digits: int = 9) -> list[_Group]:
    """The changes that turn the plan file `held` into `target` for what the glider flies
    (the fields of `contract.UpdateField`), each value rounded to `digits` significant
    digits; a value that reads the same is no change. Grouped by what must travel
    together: a sensor line, a state line, a power line, a state's profiles."""
    lines = unsigned_part(held).decode("ascii").split("\n")[:-1]
    groups: list[_Group] = []
    states = iter(target.states)
    state = None
    profiles: list[Change] = []

    def wanted(number: int, field: UpdateField, old: str, new: float) -> list[Change]:
        mantissa, exponent = decimal(new, digits)
        if float(old) == float(decimal_text(mantissa, exponent)):
            return []
        return [Change(number, field, mantissa, exponent)]

    sensor_index = 0
    for number, line in enumerate(lines, 1):
        f = _fields(line)
        if f[0] == "state":
            state = next(states)
            sensor_index = 0
            found = [*wanted(number, UpdateField.STATE_CLOCK, f[2], state.clock_mhz),
                     *wanted(number, UpdateField.STATE_CYCLE, f[3], state.cycle_s)]
            if found:
                groups.append(_Group(f"{state.name} state line", tuple(found)))
        elif f[0] == "power" and state is not None:
            found = [*wanted(number, UpdateField.POWER_SLEEP, f[1], int(state.sleep)),
                     *wanted(number, UpdateField.POWER_CYCLES, f[2], state.cycles_per_tick)]
            if found:
                groups.append(_Group(f"{state.name} power line", tuple(found)))
        elif f[0] == "sensor" and state is not None:
            sensor = state.sensors[sensor_index]
            sensor_index += 1
            found = [*wanted(number, UpdateField.SENSOR_PERIOD, f[2], sensor.period_s),
                     *wanted(number, UpdateField.SENSOR_ON, f[3], sensor.on_s)]
            if found:
                groups.append(_Group(f"{state.name} sensor {sensor.name}", tuple(found)))
        elif f[0] == "profile" and state is not None:
            profile = state.profiles[int(f[1])]
            profiles += [*wanted(number, UpdateField.PROFILE_SHARE, f[2], profile.share),
                         *wanted(number, UpdateField.PROFILE_PITCH, f[3], profile.pitch_rad),
                         *wanted(number, UpdateField.PROFILE_BALLAST, f[4], profile.ballast_cc),
                         *wanted(number, UpdateField.PROFILE_SPEED, f[5], profile.speed_mps),
                         *wanted(number, UpdateField.PROFILE_THRUST, f[6] if len(f) > 6
                                 else "0", profile.thrust_w)]
        elif f[0] == "end" and state is not None:
            if profiles:
                groups.append(_Group(f"{state.name} profiles", tuple(profiles)))
            profiles = []
    return groups


@dataclass(frozen=True)
class UpdateChain:
    """Updates to send in order, and the plan file the glider holds once they are applied."""

    updates: tuple[bytes, ...]
    plan_file: bytes
    plan_files: tuple[bytes, ...] = ()  # the plan file each update makes, in order


def make_updates(held: bytes, target: Plan, key: bytes, *, first_seq: int | None = None,
                 max_updates: int = 1, digits: int = 9,
                 check=None) -> UpdateChain:
    """The updates, each at most MAX_UPDATE_BYTES, that turn the signed plan file `held`
    into `target` for what the glider flies: one if the changes fit, else a chain (each
    made against the plan the one before makes, sequence numbers from `first_seq`, by
    default one more than `held`'s), at most `max_updates`; none when nothing changes.
    UpdateError saying what to cut when they do not fit; `check(plan_file)` reads each
    plan made (PlanFileError: it cannot be flown)."""
    seq = _signed_seq(held)
    if seq == 0:
        raise UpdateError("the plan the glider holds must be signed (gliderplan plan --sign): "
                          "an update names it by its sequence number")
    groups = change_groups(held, target, digits)
    if not groups:
        return UpdateChain((), held)
    room = MAX_UPDATE_BYTES - MIN_UPDATE_BYTES
    too_big = [g for g in groups if g.size > room]
    if too_big:
        raise UpdateError(f"the changes to {too_big[0].what} take {too_big[0].size} bytes, "
                          f"more than the {room} an update holds beside its header and tag: "
                          "send a whole plan (gliderplan plan --sign)")
    batches: list[list[_Group]] = [[]]
    for group in groups:
        if sum(g.size for g in batches[-1]) + group.size > room and batches[-1]:
            batches.append([])
        batches[-1].append(group)
    if len(batches) > max_updates:
        total = sum(g.size for g in groups)
        largest = sorted(groups, key=lambda g: -g.size)[:3]
        raise UpdateError(
            f"the changes take {len(batches)} updates ({total} bytes of changes, "
            f"{room} fit in one beside its header and tag), more than the {max_updates} "
            f"allowed: cut the changes to {', '.join(g.what for g in largest)}, allow "
            "more updates (--max-updates), or send a whole plan (gliderplan plan --sign)")
    new_seq = seq + 1 if first_seq is None else first_seq
    updates, plan_files = [], []
    for batch in batches:
        if not seq < new_seq <= MAX_PLAN_SEQUENCE:
            raise UpdateError(f"sequence number {new_seq}: must lie in {seq + 1}.."
                              f"{MAX_PLAN_SEQUENCE}")
        changes = tuple(sorted((c for g in batch for c in g.changes),
                               key=lambda c: (c.line, c.field)))
        new_file = changed_plan(held, changes, new_seq, key)
        if check is not None:
            check(new_file)
        update = PlanUpdate(seq, new_seq, plan_hash(held), plan_hash(new_file), changes)
        updates.append(update.pack(key))
        assert len(updates[-1]) <= MAX_UPDATE_BYTES, "a batch is sized to fit"
        plan_files.append(new_file)
        held, seq, new_seq = new_file, new_seq, new_seq + 1
    return UpdateChain(tuple(updates), held, tuple(plan_files))


def describe(data: bytes) -> str:
    """An update in a line, for logs: its plans and changes."""
    update = read_update(data)
    return (f"update {update.base_seq} -> {update.new_seq}: {len(update.changes)} change(s), "
            f"{len(data)} bytes")

"""The science-computer side of the runtime link (docs/protocol.md), byte for byte.

Framing (COBS + CRC-16/CCITT-FALSE), the nine messages, and `Link`: a small driver
that plays the science computer over a serial port (pyserial's, or `FdPort` over a pty
master) for the simulator's emulator and the end-to-end tests. A COMMAND travels as the
changes against a COMMAND the science computer holds (`CommandUpdate`); `Link` keeps
the last ones it received and applies each update to its base.
"""

from __future__ import annotations

import binascii
import functools
import math
import os
import select
import struct
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple, Protocol, cast

from gliderplan.contract import (
    BAUD,
    COMMAND_FIELD_FORMATS,
    COMMAND_MAX_SIZE,
    FLAG_DONE,
    HELLO_FIXED_BYTES,
    MAX_LINK_PLAN,
    MAX_PAYLOAD,
    MAX_UPDATE_BYTES,
    MAX_WIRE,
    MISSION_HASH_BYTES,
    N_SENSORS,
    PLAN_PIECE,
    PROTOCOL_VERSION,
    RETRANSMIT_MS,
    SENSORS_MASK,
    SENSORS_RESYNC,
    CommandField,
    MessageType,
    ReleaseReason,
    UpdateStatus,
)

HEADER = struct.Struct("<BBBBH")  # version, type, seq, ack, length
READ_CHUNK = 4096  # [bytes] taken from the port at once: whatever has arrived


# ---- errors ------------------------------------------------------------------------


class ProtocolError(Exception):
    """A frame or payload that breaks docs/protocol.md."""


class CobsError(ProtocolError):
    """The bytes are not a valid COBS encoding."""


class FrameTooLongError(ProtocolError):
    """More than MAX_WIRE bytes before the delimiter."""


class CrcError(ProtocolError):
    """The CRC-16 does not match."""


class VersionError(ProtocolError):
    """A protocol version other than 1."""


class LengthError(ProtocolError):
    """The header's length disagrees with the packet, or a payload has the wrong size."""


class UnknownTypeError(ProtocolError):
    """A message type this version does not define."""


class LinkError(Exception):
    """The peer did not answer as the protocol requires."""


class LinkTimeoutError(LinkError):
    """No valid answer after every retransmission."""


class LinkClosedError(LinkError):
    """The line is gone: the runtime closed its end (it ended, or was killed)."""


class LinkReleasedError(LinkError):
    """The runtime sent RELEASE: it gave control back to the glider."""

    def __init__(self, reason: int) -> None:
        super().__init__(f"runtime released control (reason {reason})")
        self.reason = reason


# ---- checksum and COBS -------------------------------------------------------------


def crc16_ccitt_false(data: bytes) -> int:
    """CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, not reflected, xorout 0.

    binascii's CRC-CCITT is this polynomial, unreflected, from a given initial value: the
    same checksum at C speed (the simulator's closed loop checks two frames per tick).
    """
    return binascii.crc_hqx(data, 0xFFFF)


def cobs_encode(data: bytes) -> bytes:
    """Consistent Overhead Byte Stuffing: the result holds no zero byte."""
    out = bytearray()
    for block in bytes(data).split(b"\x00"):  # whole blocks at C speed, not byte by byte
        while len(block) >= 0xFE:
            out.append(0xFF)
            out += block[:0xFE]
            block = block[0xFE:]
        out.append(len(block) + 1)
        out += block
    return bytes(out)


def cobs_decode(data: bytes) -> bytes:
    """Inverse of cobs_encode; raises CobsError on a zero byte or a block past the end."""
    if 0 in data:
        raise CobsError("zero byte inside a COBS frame")
    out = bytearray()
    i, size = 0, len(data)
    while i < size:  # one round per block: its bytes are copied at C speed
        code = data[i]
        end = i + code
        out += data[i + 1:end]
        i = end
        if code != 0xFF and i < size:
            out.append(0)
    if i != size:
        raise CobsError("COBS block runs past the end of the frame")
    return bytes(out)


# ---- frames ------------------------------------------------------------------------


class Frame(NamedTuple):  # a tuple: the closed loop makes two per tick
    type: int
    seq: int
    ack: int
    payload: bytes = b""


def build_packet(frame: Frame) -> bytes:
    """The decoded packet: header, payload, CRC-16 (big-endian)."""
    if len(frame.payload) > MAX_PAYLOAD:
        raise LengthError(f"payload of {len(frame.payload)} bytes exceeds {MAX_PAYLOAD}")
    body = HEADER.pack(PROTOCOL_VERSION, frame.type, frame.seq & 0xFF, frame.ack & 0xFF,
                       len(frame.payload)) + frame.payload
    return body + struct.pack(">H", crc16_ccitt_false(body))


def build_frame(frame: Frame) -> bytes:
    """Bytes on the wire: COBS(packet) + 0x00."""
    return cobs_encode(build_packet(frame)) + b"\x00"


def parse_packet(packet: bytes) -> Frame:
    """Check a decoded packet and return its frame; raises a ProtocolError subclass."""
    if len(packet) < HEADER.size + 2:
        raise LengthError(f"packet of {len(packet)} bytes is shorter than a header and CRC")
    body = packet[:-2]
    if crc16_ccitt_false(body) != int.from_bytes(packet[-2:], "big"):
        raise CrcError("CRC-16 mismatch")
    version, kind, seq, ack, length = HEADER.unpack_from(body)
    if version != PROTOCOL_VERSION:
        raise VersionError(f"protocol version {version}, expected {PROTOCOL_VERSION}")
    if length > MAX_PAYLOAD or HEADER.size + length != len(body):
        raise LengthError(f"length field {length} disagrees with a {len(packet)}-byte packet")
    if kind not in MessageType._value2member_map_:
        raise UnknownTypeError(f"unknown message type 0x{kind:02x}")
    return Frame(kind, seq, ack, bytes(body[HEADER.size:]))


def parse_frame(wire: bytes) -> Frame:
    """Parse one frame's wire bytes (with or without its trailing 0x00 delimiter)."""
    if wire.endswith(b"\x00"):
        wire = wire[:-1]
    if len(wire) > MAX_WIRE:
        raise FrameTooLongError(f"{len(wire)} bytes before the delimiter (max {MAX_WIRE})")
    return parse_packet(cobs_decode(wire))


class FrameReader:
    """Splits a byte stream at 0x00 delimiters; yields Frames or the ProtocolError of each
    dropped frame. Bytes past MAX_WIRE are discarded up to the next delimiter."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self._overlong = False

    def feed(self, data: bytes) -> Iterator[Frame | ProtocolError]:
        start = 0
        while True:  # one slice per frame, not one append per byte
            end = data.find(0, start)
            chunk = data[start:] if end < 0 else data[start:end]
            room = MAX_WIRE - len(self._buffer)
            if len(chunk) > room:
                self._overlong = True
                chunk = chunk[:room]
            self._buffer += chunk
            if end < 0:
                return
            start = end + 1
            wire, overlong = bytes(self._buffer), self._overlong
            self._buffer.clear()
            self._overlong = False
            if overlong:
                yield FrameTooLongError(f"frame longer than {MAX_WIRE} bytes")
            elif wire:
                try:
                    yield parse_frame(wire)
                except ProtocolError as error:
                    yield error


# ---- messages ----------------------------------------------------------------------


def _expect_size(name: str, payload: bytes, size: int) -> None:
    if len(payload) != size:
        raise LengthError(f"{name} payload of {len(payload)} bytes, expected {size}")


@dataclass(frozen=True)
class Hello:
    read_mask: int
    mission_hash: bytes  # MISSION_HASH_BYTES raw bytes of SHA-256
    name: str
    n_sensors: int = N_SENSORS
    protocol: int = PROTOCOL_VERSION

    TYPE = MessageType.HELLO

    def pack(self) -> bytes:
        name = self.name.encode("ascii")
        if len(self.mission_hash) != MISSION_HASH_BYTES:
            raise LengthError(f"mission hash must be {MISSION_HASH_BYTES} bytes")
        return (struct.pack("<BBI", self.protocol, self.n_sensors, self.read_mask)
                + self.mission_hash + bytes([len(name)]) + name)

    @classmethod
    def unpack(cls, payload: bytes) -> Hello:
        if len(payload) < HELLO_FIXED_BYTES:
            raise LengthError(f"HELLO payload of {len(payload)} bytes is too short")
        protocol, n_sensors, read_mask = struct.unpack_from("<BBI", payload)
        name_len = payload[HELLO_FIXED_BYTES - 1]
        _expect_size("HELLO", payload, HELLO_FIXED_BYTES + name_len)
        name = payload[HELLO_FIXED_BYTES:].decode("ascii", errors="replace")
        return cls(read_mask, bytes(payload[6:6 + MISSION_HASH_BYTES]), name, n_sensors,
                   protocol)


@functools.cache
def _indices(mask: int) -> tuple[int, ...]:
    """The set bits of a mask, lowest first."""
    return tuple(i for i in range(32) if mask >> i & 1)


@functools.cache
def _f32s(count: int) -> struct.Struct:
    return struct.Struct(f"<{count}f")


_SENSORS_HEAD = struct.Struct("<IB")  # tick, flags
_MASK = struct.Struct("<I")


class Sensors(NamedTuple):
    """One tick's readings: sensor index -> value (f32 on the wire, in increasing index
    order). The frame leaves the mask out when the readings are exactly the sensors of
    HELLO's `read_mask`. `resync`: ask for a whole COMMAND (the last update had no base)."""

    tick: int
    values: Mapping[int, float]
    resync: bool = False

    TYPE = MessageType.SENSORS

    @property
    def mask(self) -> int:
        return sum(1 << i for i in self.values)

    def pack(self, read_mask: int | None = None) -> bytes:
        """The payload; `read_mask` is the runtime's (HELLO), None: always send the mask."""
        mask = self.mask
        if mask >> 32:
            raise ValueError("sensor indices must lie in 0..31")
        flags = SENSORS_RESYNC if self.resync else 0
        indices = _indices(mask)
        values = _f32s(len(indices)).pack(*(self.values[i] for i in indices))
        if mask == read_mask:
            return _SENSORS_HEAD.pack(self.tick, flags) + values
        return _SENSORS_HEAD.pack(self.tick, flags | SENSORS_MASK) + _MASK.pack(mask) + values

    @classmethod
    def unpack(cls, payload: bytes, read_mask: int | None = None) -> Sensors:
        if len(payload) < _SENSORS_HEAD.size:
            raise LengthError(f"SENSORS payload of {len(payload)} bytes is too short")
        tick, flags = _SENSORS_HEAD.unpack_from(payload)
        if flags & ~(SENSORS_MASK | SENSORS_RESYNC):
            raise LengthError(f"SENSORS with reserved flags 0x{flags:02x}")
        at = _SENSORS_HEAD.size
        if flags & SENSORS_MASK:
            if len(payload) < at + 4:
                raise LengthError(f"SENSORS payload of {len(payload)} bytes is too short")
            mask = _MASK.unpack_from(payload, at)[0]
            at += 4
        elif read_mask is None:
            raise LengthError("SENSORS without a mask, and no read mask to read it by")
        else:
            mask = read_mask
        indices = _indices(mask)
        _expect_size("SENSORS", payload, at + 4 * len(indices))
        values = _f32s(len(indices)).unpack_from(payload, at)
        return cls(tick, dict(zip(indices, values, strict=True)), bool(flags & SENSORS_RESYNC))


class Command(NamedTuple):  # a tuple: the simulator builds one per tick
    """A COMMAND whole: the runtime's answer to one tick (docs/protocol.md)."""

    tick: int
    state: int  # NO_STATE once exited
    stack_depth: int
    transition: int  # a TransitionKind
    from_state: int
    to_state: int
    profile: int
    flags: int  # FLAG_SURFACE, FLAG_DONE, FLAG_CLIMBING, FLAG_HEADING
    depth_target_m: float
    pitch_rad: float
    ballast_cc: float
    heading_rad: float
    sensor_power: int
    event_count: int
    speed_mps: float = 0.0  # through the water on the propeller; 0: a glide
    thrust_w: float = 0.0  # a glider's thruster assisting a yo; 0: off

    TYPE = MessageType.COMMAND

    def pack(self, base: Command | None = None) -> bytes:
        """The payload of this COMMAND as its changes against `base` (None: the zero
        COMMAND, i.e. sent whole)."""
        return CommandUpdate.between(self, base).pack()

    @property
    def done(self) -> bool:
        return bool(self.flags & FLAG_DONE)


assert tuple(field.name.lower() for field in CommandField) == Command._fields[1:]
ZERO_COMMAND = Command(0, *(0.0 if f == "f" else 0 for f in COMMAND_FIELD_FORMATS))
_FIELDS = tuple(struct.Struct("<" + f) for f in COMMAND_FIELD_FORMATS)
_COMMAND_HEAD = struct.Struct("<IBH")  # tick, base, fields
assert _COMMAND_HEAD.size + sum(f.size for f in _FIELDS) == COMMAND_MAX_SIZE


@functools.cache
def _fields_struct(fields: int) -> struct.Struct:
    """The values of the fields a `fields` mask names, in field order."""
    return struct.Struct("<" + "".join(COMMAND_FIELD_FORMATS[i] for i in _indices(fields)))


class CommandUpdate(NamedTuple):
    """A COMMAND as it travels: the fields that differ from a base COMMAND, `base` ticks
    back (0: from the zero COMMAND, which makes it a whole one)."""

    tick: int
    base: int
    fields: int  # bit i: CommandField i follows
    values: tuple[int | float, ...]  # of those fields, in field order

    TYPE = MessageType.COMMAND

    @classmethod
    def between(cls, command: Command, base: Command | None = None) -> CommandUpdate:
        """The update that turns `base` (None: the zero COMMAND) into `command`; fields are
        compared as they travel (f32 bits)."""
        back = 0 if base is None else command.tick - base.tick
        if not 0 <= back <= 0xFF or (base is not None and back == 0):
            raise ValueError(f"a base {back} ticks back cannot be named (1..255)")
        old = ZERO_COMMAND if base is None else base
        fields, values = 0, []
        for i, field in enumerate(_FIELDS):
            new = command[i + 1]
            if field.pack(new) != field.pack(old[i + 1]):
                fields |= 1 << i
                values.append(new)
        return cls(command.tick, back, fields, tuple(values))

    def pack(self) -> bytes:
        return (_COMMAND_HEAD.pack(self.tick, self.base, self.fields)
                + _fields_struct(self.fields).pack(*self.values))

    @classmethod
    def unpack(cls, payload: bytes) -> CommandUpdate:
        if len(payload) < _COMMAND_HEAD.size:
            raise LengthError(f"COMMAND payload of {len(payload)} bytes is too short")
        tick, base, fields = _COMMAND_HEAD.unpack_from(payload)
        if fields >> len(_FIELDS):
            raise LengthError(f"COMMAND with unknown fields 0x{fields:04x}")
        values = _fields_struct(fields)
        _expect_size("COMMAND", payload, _COMMAND_HEAD.size + values.size)
        return cls(tick, base, fields, values.unpack_from(payload, _COMMAND_HEAD.size))

    def apply(self, base: Command) -> Command:
        """The COMMAND this update makes of `base` (the zero COMMAND when `base` is 0)."""
        whole = list(base)
        whole[0] = self.tick
        for i, value in zip(_indices(self.fields), self.values, strict=True):
            whole[i + 1] = value
        return Command._make(whole)


class Unresolved(NamedTuple):
    """A COMMAND update for `tick` whose base this side does not hold."""

    tick: int


@dataclass(frozen=True)
class Release:
    reason: int

    TYPE = MessageType.RELEASE

    def pack(self) -> bytes:
        return bytes([self.reason])

    @classmethod
    def unpack(cls, payload: bytes) -> Release:
        _expect_size("RELEASE", payload, 1)
        return cls(payload[0])


@dataclass(frozen=True)
class PlanPiece:
    """A PLAN frame: `data`, the bytes of a plan file from `offset`, of `total` in all (the
    plan itself is `planner.planfile.Plan`)."""

    offset: int
    total: int
    data: bytes

    TYPE = MessageType.PLAN

    def pack(self) -> bytes:
        if len(self.data) > PLAN_PIECE:
            raise LengthError(f"PLAN piece of {len(self.data)} bytes exceeds {PLAN_PIECE}")
        return struct.pack("<HH", self.offset, self.total) + self.data

    @classmethod
    def unpack(cls, payload: bytes) -> PlanPiece:
        if not 4 <= len(payload) <= 4 + PLAN_PIECE:
            raise LengthError(f"PLAN payload of {len(payload)} bytes")
        offset, total = struct.unpack_from("<HH", payload)
        return cls(offset, total, bytes(payload[4:]))


@dataclass(frozen=True)
class PlanStatus:
    accepted: bool
    message: str

    TYPE = MessageType.PLAN_STATUS

    def pack(self) -> bytes:
        text = self.message.encode("ascii")[:MAX_PAYLOAD - 2]
        return bytes([int(self.accepted), len(text)]) + text

    @classmethod
    def unpack(cls, payload: bytes) -> PlanStatus:
        if len(payload) < 2:
            raise LengthError("PLAN_STATUS payload is too short")
        _expect_size("PLAN_STATUS", payload, 2 + payload[1])
        return cls(bool(payload[0]), payload[2:].decode("ascii", errors="replace"))


@dataclass(frozen=True)
class UpdatePiece(PlanPiece):
    """A PLAN_UPDATE frame: a piece of a plan update (docs/plan-update.md), laid out as a
    PLAN piece."""

    TYPE = MessageType.PLAN_UPDATE


@dataclass(frozen=True)
class UpdateStatusMessage:
    """UPDATE_STATUS: what became of a plan update (`contract.UpdateStatus`), the sequence
    number of the plan in force after it (0: none), and the runtime's words."""

    status: int
    seq: int
    message: str

    TYPE = MessageType.UPDATE_STATUS

    @property
    def accepted(self) -> bool:
        return self.status in (UpdateStatus.APPLIED, UpdateStatus.DUPLICATE)

    def pack(self) -> bytes:
        text = self.message.encode("ascii")[:MAX_PAYLOAD - 6]
        return struct.pack("<BIB", self.status, self.seq, len(text)) + text

    @classmethod
    def unpack(cls, payload: bytes) -> UpdateStatusMessage:
        if len(payload) < 6:
            raise LengthError("UPDATE_STATUS payload is too short")
        _expect_size("UPDATE_STATUS", payload, 6 + payload[5])
        status, seq, _ = struct.unpack_from("<BIB", payload)
        return cls(status, seq, payload[6:].decode("ascii", errors="replace"))


@dataclass(frozen=True)
class Nak:
    TYPE = MessageType.NAK

    def pack(self) -> bytes:
        return b""

    @classmethod
    def unpack(cls, payload: bytes) -> Nak:
        _expect_size("NAK", payload, 0)
        return cls()


Message = (Hello | Sensors | CommandUpdate | Release | PlanPiece | PlanStatus | UpdatePiece
           | UpdateStatusMessage | Nak)
MESSAGES: dict[int, type] = {m.TYPE: m for m in (Hello, Sensors, CommandUpdate, Release, PlanPiece,
                                                 PlanStatus, UpdatePiece, UpdateStatusMessage,
                                                 Nak)}


def unpack_message(frame: Frame) -> Message:
    """The typed message a frame carries; raises LengthError on a malformed payload."""
    return MESSAGES[frame.type].unpack(frame.payload)


def plan_pieces(plan: bytes, kind: type[PlanPiece] = PlanPiece) -> list[PlanPiece]:
    """A plan file (or with `kind` UpdatePiece, a plan update) cut into PLAN (PLAN_UPDATE)
    messages of at most PLAN_PIECE bytes, in order."""
    if not 0 < len(plan) <= MAX_LINK_PLAN:
        raise ValueError(f"a plan file has 1..{MAX_LINK_PLAN} bytes, not {len(plan)}")
    return [kind(offset, len(plan), plan[offset:offset + PLAN_PIECE])
            for offset in range(0, len(plan), PLAN_PIECE)]


# ---- the science-computer side -----------------------------------------------------


class Port(Protocol):
    """What Link needs of a serial port (pyserial's Serial has it)."""

    def fileno(self) -> int: ...

    def read(self, size: int = 1) -> bytes: ...

    def write(self, data: bytes) -> int | None: ...


class FdPort:
    """A Port over a raw file descriptor, e.g. the master side of os.openpty(), or the
    descriptor of a port pyserial opened (non-blocking: a read takes what is there in
    one system call, where pyserial's own read makes three)."""

    def __init__(self, fd: int, timeout: float | None = None) -> None:
        self.fd = fd
        self.timeout = timeout
        self._nonblocking = not os.get_blocking(fd)

    def fileno(self) -> int:
        return self.fd

    def read(self, size: int = 1) -> bytes:
        """Up to `size` bytes: what is there, else what arrives within the timeout."""
        if self._nonblocking:
            try:
                return os.read(self.fd, size)
            except BlockingIOError:
                pass
            except OSError:  # pty master with no slave open: nothing to read yet
                return b""
        ready, _, _ = select.select([self.fd], [], [], self.timeout)
        if not ready:
            return b""
        try:
            return os.read(self.fd, size)
        except OSError:
            return b""

    def write(self, data: bytes) -> int:
        """Write all of `data`; LinkClosedError once the other end has closed the line (a
        pty whose runtime has ended answers EIO)."""
        view = memoryview(data)
        while view:
            try:
                written = os.write(self.fd, view)
            except BlockingIOError:  # a non-blocking line that is full: wait for room
                select.select([], [self.fd], [])
                continue
            except OSError as err:
                raise LinkClosedError(f"the line is closed ({err.strerror})") from None
            view = view[written:]
        return len(data)


class Link:
    """The science computer: one SENSORS per tick, waits for the COMMAND of that tick.

    Re-sends the same frame (same seq) on a NAK or after `retransmit_s` without an
    answer; gives up (LinkTimeoutError) after `max_retries` + 1 timeouts without one.
    Answers every dropped frame with NAK. Applies each COMMAND update to the COMMAND it
    names as its base (the last two received are kept); for an update whose base it
    does not hold it sends the tick's SENSORS again asking for a whole COMMAND (resync).
    """

    def __init__(self, port: Port, retransmit_s: float = RETRANSMIT_MS / 1000,
                 max_retries: int = 25) -> None:
        self.port = port
        self.retransmit_s = retransmit_s
        self.max_retries = max_retries
        self.seq = 0
        self.ack = 0
        self.dropped = 0  # frames received that failed to parse
        self.resyncs = 0  # COMMAND updates whose base was missing
        self.naks = 0  # NAKs received: frames of ours the runtime dropped
        self.resends = 0  # frames sent again after a retransmission timeout without answer
        self.recovered = 0  # exchanges answered after at least one re-send
        self.hello: Hello | None = None
        self.release: Release | None = None
        self.plan_status: PlanStatus | None = None
        self.update_status: UpdateStatusMessage | None = None  # the last one received
        self.command: Command | None = None  # the newest COMMAND received
        self._recent: dict[int, Command] = {}  # tick -> COMMAND: the bases updates may name
        self._reader = FrameReader()
        self._inbox: list[Message] = []

    # -- low level

    def send(self, message: Message) -> bytes:
        """Send a new frame (next seq); return its wire bytes for re-sending."""
        self.seq = (self.seq + 1) & 0xFF
        wire = build_frame(Frame(message.TYPE, self.seq, self.ack, message.pack()))
        self.port.write(wire)
        return wire

    def receive(self, timeout_s: float) -> Message | Command | Unresolved | None:
        """The next valid message within timeout_s, or None. NAKs every dropped frame.
        A COMMAND comes whole (`Command`), applied to its base, or as `Unresolved`; a late
        copy of an older COMMAND whose base is gone is passed over."""
        deadline = time.monotonic() + timeout_s
        while True:
            while not self._inbox:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return None
                self._read(remaining)
            message = self._note(self._inbox.pop(0))
            if message is not None:
                return message

    def _read(self, timeout_s: float) -> None:
        """Whatever arrives within timeout_s, parsed into the inbox."""
        # wait here rather than in read(): a pyserial port reconfigures the line (a
        # tcsetattr) on every change of its timeout
        ready, _, _ = select.select([self.port], [], [], timeout_s)
        if not ready:
            return
        try:
            data = self.port.read(READ_CHUNK)
        except OSError as err:  # pyserial's SerialException: the other end hung up
            raise LinkError(f"the serial line hung up ({err})") from None
        for item in self._reader.feed(data):
            if isinstance(item, ProtocolError):
                self._drop()
                continue
            try:
                message = unpack_message(item)
            except ProtocolError:
                self._drop()
                continue
            self.ack = item.seq
            self._inbox.append(message)

    def _drop(self) -> None:
        self.dropped += 1
        self.send(Nak())

    def _note(self, message: Message) -> Message | Command | Unresolved | None:
        if isinstance(message, CommandUpdate):
            return self._apply(message)
        if isinstance(message, Hello):
            self.hello = message
        elif isinstance(message, Release):
            self.release = message
        elif isinstance(message, PlanStatus):
            self.plan_status = message
        elif isinstance(message, UpdateStatusMessage):
            self.update_status = message
        return message

    def _apply(self, update: CommandUpdate) -> Command | Unresolved | None:
        base = ZERO_COMMAND if update.base == 0 else self._recent.get(update.tick - update.base)
        newest = self.command
        if base is None:
            if newest is not None and update.tick <= newest.tick:
                return None  # a late copy of an answer already applied
            self.resyncs += 1
            return Unresolved(update.tick)
        command = update.apply(base)
        if newest is None or command.tick > newest.tick:
            self._recent = {command.tick: command}
            if newest is not None:
                self._recent[newest.tick] = newest
            self.command = command
        return command

    # -- the science computer's dialogue

    def wait_hello(self, timeout_s: float = 10.0) -> Hello:
        """Wait for the runtime's HELLO (it repeats it until the first SENSORS)."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            message = self.receive(deadline - time.monotonic())
            if isinstance(message, Hello):
                return message
            if isinstance(message, Release):
                raise LinkReleasedError(message.reason)
        raise LinkTimeoutError(f"no HELLO within {timeout_s:g} s")

    def _exchange(self, wire: bytes, answered: type, match=lambda message: True,
                  resync=None) -> Message:
        """Write `wire`, re-send it on NAK or silence, until an `answered` message matches.
        An unresolved COMMAND update for a matching tick makes `resync()` the wire.

        Gives up after `max_retries` + 1 retransmission timeouts in all: NAKs re-send at
        once but do not use up the budget, since a burst of them (one per damaged frame
        the runtime dropped) says nothing about whether this frame arrived.
        """
        wait_s = self.retransmit_s + len(wire) * 10 / BAUD  # time to put it on the line
        give_up = time.monotonic() + (self.max_retries + 1) * wait_s
        sent = 0
        while True:
            self.port.write(wire)
            sent += 1
            deadline = min(time.monotonic() + wait_s, give_up)
            while (remaining := deadline - time.monotonic()) > 0:
                message = self.receive(remaining)
                if message is None:
                    self.resends += 1
                    break
                if isinstance(message, answered) and match(message):
                    self.recovered += sent > 1
                    return message
                if isinstance(message, Release):
                    if message.reason not in (ReleaseReason.MISSION_EXITED,
                                              ReleaseReason.ENERGY_RESERVE):
                        raise LinkReleasedError(message.reason)
                    break  # the mission's last COMMAND went first and was lost: ask again
                if isinstance(message, Nak):
                    self.naks += 1
                    break
                if isinstance(message, Unresolved) and resync is not None and match(message):
                    wire = resync()
                    break
            if time.monotonic() >= give_up:
                raise LinkTimeoutError(f"no {answered.__name__} within {self.max_retries + 1} "
                                       f"retransmission timeouts")

    def step(self, tick: int, values: Mapping[int, float] | Sequence[float]) -> Command:
        """Send one tick's SENSORS and return the runtime's COMMAND for that tick.

        `values`: sensor index -> value, or a sequence indexed by sensor (NaN: not sent).
        """
        if not isinstance(values, Mapping):
            values = {i: v for i, v in enumerate(values) if not math.isnan(v)}
        read_mask = self.hello.read_mask if self.hello is not None else None

        def frame(resync: bool = False) -> bytes:
            self.seq = (self.seq + 1) & 0xFF
            payload = Sensors(tick, values, resync).pack(read_mask)
            return build_frame(Frame(MessageType.SENSORS, self.seq, self.ack, payload))

        command = self._exchange(frame(), Command, lambda answer: answer.tick == tick,
                                 resync=lambda: frame(resync=True))
        return cast(Command, command)

    def send_plan(self, plan: bytes) -> PlanStatus:
        """Send a plan file in PLAN pieces; return the runtime's PLAN_STATUS.

        A re-send repeats every piece from offset 0: the runtime only assembles pieces
        that arrive in order.
        """
        pieces = []
        for piece in plan_pieces(plan):
            self.seq = (self.seq + 1) & 0xFF
            pieces.append(build_frame(Frame(MessageType.PLAN, self.seq, self.ack, piece.pack())))
        status = self._exchange(b"".join(pieces), PlanStatus)
        return cast(PlanStatus, status)

    def send_update(self, update: bytes) -> UpdateStatusMessage:
        """Send a plan update in PLAN_UPDATE pieces; return the runtime's UPDATE_STATUS.
        A re-send repeats every piece from offset 0, as for plans. An update longer than
        one may be (MAX_UPDATE_BYTES) goes too: the runtime refuses it at its first piece."""
        if len(update) > 2 * MAX_UPDATE_BYTES:
            raise ValueError(f"an update of {len(update)} bytes: the runtime reads its first "
                             "piece only")
        pieces = []
        for piece in plan_pieces(update, UpdatePiece):
            self.seq = (self.seq + 1) & 0xFF
            pieces.append(build_frame(Frame(MessageType.PLAN_UPDATE, self.seq, self.ack,
                                            piece.pack())))
        status = self._exchange(b"".join(pieces), UpdateStatusMessage)
        return cast(UpdateStatusMessage, status)

    def wait_release(self, timeout_s: float = 5.0) -> int:
        """Wait for the runtime's RELEASE and return its reason."""
        if self.release is not None:
            return self.release.reason
        deadline = time.monotonic() + timeout_s
        while (remaining := deadline - time.monotonic()) > 0:
            message = self.receive(remaining)
            if isinstance(message, Release):
                return message.reason
        raise LinkTimeoutError(f"no RELEASE within {timeout_s:g} s")

"""The science-computer side of the runtime link (docs/protocol.md), byte for byte.

Framing (COBS + CRC-16/CCITT-FALSE), the seven messages, and `Link`: a small driver
that plays the science computer over a serial port (pyserial's, or `FdPort` over a pty
master) for the simulator's emulator and the end-to-end tests.
"""

from __future__ import annotations

import binascii
import fcntl
import math
import os
import select
import struct
import termios
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple, Protocol, cast

from gliderplan.contract import (
    BAUD,
    COMMAND_SIZE,
    FLAG_DONE,
    MAX_LINK_PLAN,
    MAX_PAYLOAD,
    MAX_WIRE,
    N_SENSORS,
    PLAN_PIECE,
    PROTOCOL_VERSION,
    MessageType,
)

HEADER = struct.Struct("<BBBBH")  # version, type, seq, ack, length
MAX_PACKET = HEADER.size + MAX_PAYLOAD + 2  # 248 bytes decoded


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
    out = bytearray()
    i, size = 0, len(data)
    while i < size:
        code = data[i]
        if code == 0:
            raise CobsError("zero byte inside a COBS frame")
        end = i + code
        if end > size:
            raise CobsError("COBS block runs past the end of the frame")
        block = data[i + 1:end]
        if 0 in block:
            raise CobsError("zero byte inside a COBS frame")
        out += block
        i = end
        if code != 0xFF and i < size:
            out.append(0)
    return bytes(out)


# ---- frames ------------------------------------------------------------------------


@dataclass(frozen=True)
class Frame:
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
    body, crc = packet[:-2], struct.unpack(">H", packet[-2:])[0]
    if crc16_ccitt_false(body) != crc:
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
    mission_hash: bytes  # 32 raw bytes of SHA-256
    name: str
    n_sensors: int = N_SENSORS
    protocol: int = PROTOCOL_VERSION

    TYPE = MessageType.HELLO

    def pack(self) -> bytes:
        name = self.name.encode("ascii")
        if len(self.mission_hash) != 32:
            raise LengthError("mission hash must be 32 bytes")
        return (struct.pack("<BBI", self.protocol, self.n_sensors, self.read_mask)
                + self.mission_hash + bytes([len(name)]) + name)

    @classmethod
    def unpack(cls, payload: bytes) -> Hello:
        if len(payload) < 6 + 32 + 1:
            raise LengthError(f"HELLO payload of {len(payload)} bytes is too short")
        protocol, n_sensors, read_mask = struct.unpack_from("<BBI", payload)
        name_len = payload[38]
        _expect_size("HELLO", payload, 39 + name_len)
        name = payload[39:].decode("ascii", errors="replace")
        return cls(read_mask, bytes(payload[6:38]), name, n_sensors, protocol)


@dataclass(frozen=True)
class Sensors:
    """One tick's readings: sensor index -> value (sent as f32, in increasing index order)."""

    tick: int
    values: Mapping[int, float]

    TYPE = MessageType.SENSORS

    @property
    def mask(self) -> int:
        return sum(1 << i for i in self.values)

    def pack(self) -> bytes:
        indices = sorted(self.values)
        if indices and not 0 <= indices[0] <= indices[-1] < 32:
            raise ValueError("sensor indices must lie in 0..31")
        return (struct.pack("<II", self.tick, self.mask)
                + struct.pack(f"<{len(indices)}f", *(self.values[i] for i in indices)))

    @classmethod
    def unpack(cls, payload: bytes) -> Sensors:
        if len(payload) < 8:
            raise LengthError(f"SENSORS payload of {len(payload)} bytes is too short")
        tick, mask = struct.unpack_from("<II", payload)
        indices = [i for i in range(32) if mask >> i & 1]
        _expect_size("SENSORS", payload, 8 + 4 * len(indices))
        values = struct.unpack_from(f"<{len(indices)}f", payload, 8)
        return cls(tick, dict(zip(indices, values, strict=True)))


_COMMAND = struct.Struct("<IBBBBBBBBffffII")
assert _COMMAND.size == COMMAND_SIZE


class Command(NamedTuple):  # a tuple: the simulator builds one per tick
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

    TYPE = MessageType.COMMAND

    def pack(self) -> bytes:
        return _COMMAND.pack(self.tick, self.state, self.stack_depth, self.transition,
                             self.from_state, self.to_state, self.profile, self.flags, 0,
                             self.depth_target_m, self.pitch_rad, self.ballast_cc,
                             self.heading_rad, self.sensor_power, self.event_count)

    @classmethod
    def unpack(cls, payload: bytes) -> Command:
        _expect_size("COMMAND", payload, _COMMAND.size)
        (tick, state, depth, transition, source, target, profile, flags, _reserved,
         depth_target, pitch, ballast, heading, power, events) = _COMMAND.unpack(payload)
        return cls(tick, state, depth, transition, source, target, profile, flags,
                   depth_target, pitch, ballast, heading, power, events)

    @property
    def done(self) -> bool:
        return bool(self.flags & FLAG_DONE)


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
class Plan:
    offset: int
    total: int
    data: bytes

    TYPE = MessageType.PLAN

    def pack(self) -> bytes:
        if len(self.data) > PLAN_PIECE:
            raise LengthError(f"PLAN piece of {len(self.data)} bytes exceeds {PLAN_PIECE}")
        return struct.pack("<HH", self.offset, self.total) + self.data

    @classmethod
    def unpack(cls, payload: bytes) -> Plan:
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
class Nak:
    TYPE = MessageType.NAK

    def pack(self) -> bytes:
        return b""

    @classmethod
    def unpack(cls, payload: bytes) -> Nak:
        _expect_size("NAK", payload, 0)
        return cls()


Message = Hello | Sensors | Command | Release | Plan | PlanStatus | Nak
MESSAGES: dict[int, type] = {m.TYPE: m for m in (Hello, Sensors, Command, Release, Plan,
                                                 PlanStatus, Nak)}


def unpack_message(frame: Frame) -> Message:
    """The typed message a frame carries; raises LengthError on a malformed payload."""
    return MESSAGES[frame.type].unpack(frame.payload)


def plan_pieces(plan: bytes) -> list[Plan]:
    """A plan file cut into PLAN messages of at most PLAN_PIECE bytes, in order."""
    if not 0 < len(plan) <= MAX_LINK_PLAN:
        raise ValueError(f"a plan file has 1..{MAX_LINK_PLAN} bytes, not {len(plan)}")
    return [Plan(offset, len(plan), plan[offset:offset + PLAN_PIECE])
            for offset in range(0, len(plan), PLAN_PIECE)]


# ---- the science-computer side -----------------------------------------------------


class Port(Protocol):
    """What Link needs of a serial port (pyserial's Serial has it)."""

    def fileno(self) -> int: ...

    @property
    def in_waiting(self) -> int: ...

    def read(self, size: int = 1) -> bytes: ...

    def write(self, data: bytes) -> int | None: ...


class FdPort:
    """A Port over a raw file descriptor, e.g. the master side of os.openpty()."""

    def __init__(self, fd: int, timeout: float | None = None) -> None:
        self.fd = fd
        self.timeout = timeout

    def fileno(self) -> int:
        return self.fd

    @property
    def in_waiting(self) -> int:
        """Bytes ready to read (0 on a pty master with no slave open)."""
        try:
            count = fcntl.ioctl(self.fd, termios.FIONREAD, b"\0\0\0\0")
        except OSError:
            return 0
        return struct.unpack("i", count)[0]

    def read(self, size: int = 1) -> bytes:
        ready, _, _ = select.select([self.fd], [], [], self.timeout)
        if not ready:
            return b""
        try:
            return os.read(self.fd, size)
        except OSError:  # pty master with no slave open: nothing to read yet
            return b""

    def write(self, data: bytes) -> int:
        view = memoryview(data)
        while view:
            written = os.write(self.fd, view)
            view = view[written:]
        return len(data)


class Link:
    """The science computer: one SENSORS per tick, waits for the COMMAND of that tick.

    Re-sends the same frame (same seq) on a NAK or after `retransmit_s` without an
    answer; gives up (LinkTimeoutError) after `max_retries` + 1 timeouts without one.
    Answers every dropped frame with NAK.
    """

    def __init__(self, port: Port, retransmit_s: float = 0.2, max_retries: int = 25) -> None:
        self.port = port
        self.retransmit_s = retransmit_s
        self.max_retries = max_retries
        self.seq = 0
        self.ack = 0
        self.dropped = 0  # frames received that failed to parse
        self.hello: Hello | None = None
        self.release: Release | None = None
        self.plan_status: PlanStatus | None = None
        self._reader = FrameReader()
        self._inbox: list[tuple[Frame, Message]] = []

    # -- low level

    def send(self, message: Message) -> bytes:
        """Send a new frame (next seq); return its wire bytes for re-sending."""
        self.seq = (self.seq + 1) & 0xFF
        wire = build_frame(Frame(message.TYPE, self.seq, self.ack, message.pack()))
        self.port.write(wire)
        return wire

    def receive(self, timeout_s: float) -> Message | None:
        """The next valid message within timeout_s, or None. NAKs every dropped frame."""
        deadline = time.monotonic() + timeout_s
        while not self._inbox:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return None
            # wait here rather than in read(): a pyserial port reconfigures the line (a
            # tcsetattr) on every change of its timeout
            ready, _, _ = select.select([self.port], [], [], remaining)
            if not ready:
                continue
            try:
                data = self.port.read(max(1, self.port.in_waiting))
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
                self._inbox.append((item, message))
        _, message = self._inbox.pop(0)
        self._note(message)
        return message

    def _drop(self) -> None:
        self.dropped += 1
        self.send(Nak())

    def _note(self, message: Message) -> None:
        if isinstance(message, Hello):
            self.hello = message
        elif isinstance(message, Release):
            self.release = message
        elif isinstance(message, PlanStatus):
            self.plan_status = message

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

    def _exchange(self, wire: bytes, answered: type, match=lambda message: True) -> Message:
        """Write `wire`, re-send it on NAK or silence, until an `answered` message matches.

        Gives up after `max_retries` + 1 retransmission timeouts in all: NAKs re-send at
        once but do not use up the budget, since a burst of them (one per damaged frame
        the runtime dropped) says nothing about whether this frame arrived.
        """
        wait_s = self.retransmit_s + len(wire) * 10 / BAUD  # time to put it on the line
        give_up = time.monotonic() + (self.max_retries + 1) * wait_s
        while True:
            self.port.write(wire)
            deadline = min(time.monotonic() + wait_s, give_up)
            while (remaining := deadline - time.monotonic()) > 0:
                message = self.receive(remaining)
                if message is None:
                    break
                if isinstance(message, answered) and match(message):
                    return message
                if isinstance(message, Release):
                    raise LinkReleasedError(message.reason)
                if isinstance(message, Nak):
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
        self.seq = (self.seq + 1) & 0xFF
        wire = build_frame(Frame(MessageType.SENSORS, self.seq, self.ack,
                                 Sensors(tick, values).pack()))
        return self._exchange(wire, Command, lambda command: command.tick == tick)

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

"""The link protocol's Python side (docs/protocol.md): framing, messages, the Link driver."""

from __future__ import annotations

import os
import struct
import threading

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gliderplan.contract import (
    COMMAND_MAX_SIZE,
    FLAG_CLIMBING,
    FLAG_HEADING,
    PROTOCOL_VERSION,
    SENSORS_MASK,
    SENSORS_RESYNC,
    ReleaseReason,
    TransitionKind,
)
from gliderplan.runtime import protocol as p


def test_crc16_matches_the_catalogue_check_value():
    # CRC-16/CCITT-FALSE of "123456789" is 0x29B1 (CRC RevEng catalogue).
    assert p.crc16_ccitt_false(b"123456789") == 0x29B1


@pytest.mark.parametrize(
    ("raw", "encoded"),
    [  # the examples of Cheshire & Baker's COBS paper / Wikipedia
        (b"\x00", b"\x01\x01"),
        (b"\x00\x00", b"\x01\x01\x01"),
        (b"\x11\x22\x00\x33", b"\x03\x11\x22\x02\x33"),
        (b"\x11\x22\x33\x44", b"\x05\x11\x22\x33\x44"),
        (b"\x11\x00\x00\x00", b"\x02\x11\x01\x01\x01"),
        (bytes(range(1, 255)), b"\xff" + bytes(range(1, 255)) + b"\x01"),
    ],
)
def test_cobs_encodes_the_reference_examples(raw, encoded):
    assert p.cobs_encode(raw) == encoded
    assert p.cobs_decode(encoded) == raw


@given(st.binary(max_size=600))
def test_cobs_round_trips_without_zero_bytes(raw):
    encoded = p.cobs_encode(raw)
    assert 0 not in encoded
    assert p.cobs_decode(encoded) == raw


def test_frame_layout_is_byte_exact():
    frame = p.Frame(p.MessageType.RELEASE, seq=7, ack=3, payload=b"\x01")
    packet = p.build_packet(frame)
    body = bytes([PROTOCOL_VERSION, 0x04, 7, 3, 1, 0, 1])
    assert packet == body + struct.pack(">H", p.crc16_ccitt_false(body))
    wire = p.build_frame(frame)
    assert wire.endswith(b"\x00") and 0 not in wire[:-1]
    assert p.parse_frame(wire) == frame


CALL = p.Command(tick=42, state=1, stack_depth=1, transition=TransitionKind.CALL, from_state=0,
                 to_state=1, profile=0, flags=FLAG_CLIMBING | FLAG_HEADING,
                 depth_target_m=5.0, pitch_rad=0.5, ballast_cc=230.0, heading_rad=1.5,
                 sensor_power=0x207, event_count=3)
MESSAGES = [
    p.Hello(read_mask=0b111, mission_hash=bytes(range(32)), name="sampleMission"),
    p.Sensors(tick=42, values={0: 500.0, 1: 12.5, 9: 14.25}),
    p.Sensors(tick=42, values={0: 500.0}, resync=True),
    p.CommandUpdate.between(CALL),
    p.Release(ReleaseReason.MISSION_EXITED),
    p.PlanPiece(offset=200, total=450, data=b"x" * 200),
    p.PlanStatus(False, "plan line 3: hash does not match the mission"),
    p.Nak(),
]


@pytest.mark.parametrize("message", MESSAGES, ids=lambda m: type(m).__name__)
def test_every_message_round_trips_through_a_frame(message):
    wire = p.build_frame(p.Frame(message.TYPE, 1, 0, message.pack()))
    frame = p.parse_frame(wire)
    assert p.unpack_message(frame) == message


def test_a_whole_command_carries_every_field_that_is_not_zero():
    every = CALL._replace(state=2, transition=TransitionKind.GOTO, from_state=1, to_state=2,
                          profile=1, speed_mps=1.25, thrust_w=3.0)
    assert len(every.pack()) == COMMAND_MAX_SIZE == 46
    assert p.CommandUpdate.unpack(every.pack()).apply(p.ZERO_COMMAND) == every
    update = p.CommandUpdate.unpack(CALL.pack())
    assert update.base == 0
    assert update.fields == (1 << 13) - 1 - (1 << p.CommandField.FROM_STATE) \
        - (1 << p.CommandField.PROFILE)  # from state 0 and profile 0 equal the zero COMMAND
    assert update.apply(p.ZERO_COMMAND) == CALL


def test_a_command_travels_as_its_changes_against_a_base():
    before = CALL._replace(tick=41, transition=0, from_state=0xFF, to_state=0xFF, state=0,
                           stack_depth=0, event_count=2)
    update = p.CommandUpdate.unpack(CALL.pack(before))
    assert (update.tick, update.base) == (42, 1)
    assert update.fields == sum(1 << f for f in (
        p.CommandField.STATE, p.CommandField.STACK_DEPTH, p.CommandField.TRANSITION,
        p.CommandField.FROM_STATE, p.CommandField.TO_STATE, p.CommandField.EVENT_COUNT))
    assert len(CALL.pack(before)) == 7 + 5 + 4
    assert update.apply(before) == CALL
    steady = CALL._replace(tick=43)
    assert len(steady.pack(CALL)) == 7  # nothing changed: the tick and its base
    assert p.CommandUpdate.unpack(steady.pack(CALL)).apply(CALL) == steady
    # floats compare as they travel: -0.0 is a change, an f32-equal value is not
    assert p.CommandUpdate.between(CALL._replace(tick=43, ballast_cc=-0.0),
                                   CALL._replace(ballast_cc=0.0)).fields == \
        1 << p.CommandField.BALLAST_CC
    assert p.CommandUpdate.between(steady._replace(pitch_rad=0.5 + 1e-12), CALL).fields == 0
    with pytest.raises(ValueError):
        p.CommandUpdate.between(CALL._replace(tick=42 + 256), CALL)  # too far back to name


_f32 = st.floats(width=32, allow_nan=False)
_u8 = st.integers(0, 255)
_commands = st.builds(p.Command, st.integers(0, 2**32 - 1), _u8, _u8, _u8, _u8, _u8, _u8, _u8,
                      _f32, _f32, _f32, _f32, st.integers(0, 2**32 - 1),
                      st.integers(0, 2**32 - 1), _f32, _f32)


@given(_commands, _commands, st.integers(1, 255))
def test_any_command_comes_back_from_its_changes_against_any_base(command, base, back):
    base = base._replace(tick=(command.tick - back) % 2**32)
    if base.tick > command.tick:
        base = base._replace(tick=command.tick - 1) if command.tick else None
    wire = p.build_frame(p.Frame(p.MessageType.COMMAND, 1, 0, command.pack(base)))
    update = p.unpack_message(p.parse_frame(wire))
    assert update.apply(base or p.ZERO_COMMAND) == command


def test_sensors_are_sent_in_increasing_index_order_as_f32():
    payload = p.Sensors(tick=1, values={9: 2.0, 0: 1.0}).pack()
    assert payload == struct.pack("<IBIff", 1, SENSORS_MASK, (1 << 0) | (1 << 9), 1.0, 2.0)
    # exactly the runtime's read mask (HELLO): the mask stays off the wire
    payload = p.Sensors(tick=1, values={9: 2.0, 0: 1.0}).pack(read_mask=(1 << 0) | (1 << 9))
    assert payload == struct.pack("<IBff", 1, 0, 1.0, 2.0)
    assert p.Sensors.unpack(payload, read_mask=(1 << 0) | (1 << 9)).values == {0: 1.0, 9: 2.0}
    resync = p.Sensors(tick=1, values={0: 1.0}, resync=True).pack(read_mask=1)
    assert resync == struct.pack("<IBf", 1, SENSORS_RESYNC, 1.0)


def _packet(version: int, rest: bytes) -> bytes:
    """COBS of a packet with a good CRC: version, then the rest of the header and payload."""
    body = bytes([version]) + rest
    return p.cobs_encode(body + struct.pack(">H", p.crc16_ccitt_false(body)))


def _corrupt(wire: bytes, index: int) -> bytes:
    data = bytearray(wire)
    data[index] ^= 0x40
    if data[index] == 0:
        data[index] = 0x55
    return bytes(data)


@pytest.mark.parametrize(
    ("wire", "error"),
    [
        (_corrupt(p.build_frame(p.Frame(4, 1, 0, b"\x01")), 5), p.CrcError),
        (_packet(PROTOCOL_VERSION + 1, b"\x04\x01\x00\x01\x00\x01"), p.VersionError),
        (_packet(PROTOCOL_VERSION, b"\x04\x01\x00\x05\x00\x01"), p.LengthError),
        (_packet(PROTOCOL_VERSION, b"\x42\x01\x00\x00\x00"), p.UnknownTypeError),
        (b"\x05\x11\x22", p.CobsError),
        (b"\x01" * 251, p.FrameTooLongError),
        (b"\x03\x01\x02", p.LengthError),
    ],
    ids=["crc", "version", "length", "type", "cobs", "too-long", "short"],
)
def test_bad_frames_raise_typed_errors(wire, error):
    with pytest.raises(error):
        p.parse_frame(wire)


@pytest.mark.parametrize(
    ("message_type", "payload"),
    [(p.CommandUpdate, b"\x00" * 6), (p.CommandUpdate, struct.pack("<IBH", 0, 0, 1)),
     (p.CommandUpdate, struct.pack("<IBHB", 0, 0, 1 << 15, 0)),
     (p.Sensors, struct.pack("<IBI", 0, SENSORS_MASK, 3) + b"\x00" * 4),
     (p.Sensors, struct.pack("<IB", 0, 0x80)),
     (p.Hello, b"\x01" * 10), (p.Release, b""), (p.PlanStatus, b"\x01\x05ok"),
     (p.Nak, b"\x00"), (p.PlanPiece, b"\x00")],
)
def test_payloads_of_the_wrong_size_are_refused(message_type, payload):
    with pytest.raises(p.LengthError):
        message_type.unpack(payload)


@settings(max_examples=300)
@given(st.binary(max_size=1200))
def test_random_bytes_never_crash_the_reader(data):
    reader = p.FrameReader()
    for item in reader.feed(data):
        if isinstance(item, p.Frame):
            p.build_packet(item)  # a frame that parsed is a well-formed frame
        else:
            assert isinstance(item, p.ProtocolError)


def test_reader_recovers_after_garbage_and_an_overlong_frame():
    good = p.build_frame(p.Frame(p.MessageType.NAK, 9, 0))
    items = list(p.FrameReader().feed(b"\x07" * 400 + b"\x00" + b"\x13\x37\x00" + good))
    assert isinstance(items[0], p.FrameTooLongError)
    assert isinstance(items[1], p.ProtocolError)
    assert items[2] == p.Frame(p.MessageType.NAK, 9, 0)


def test_plan_pieces_cover_the_file_in_order():
    plan = bytes(range(256)) * 2
    pieces = p.plan_pieces(plan)
    assert [piece.offset for piece in pieces] == [0, 200, 400]
    assert b"".join(piece.data for piece in pieces) == plan
    assert {piece.total for piece in pieces} == {512}
    with pytest.raises(ValueError):
        p.plan_pieces(b"")


# ---- Link against a scripted runtime on a pty pair ---------------------------------


class ScriptedRuntime(threading.Thread):
    """A fake runtime: HELLO, then answers SENSORS with COMMAND updates against the tick
    before; corrupts chosen answers, leaves others unanswered, and names for others a base
    three ticks back (the science computer keeps two) until asked to resync."""

    def __init__(self, fd: int, corrupt_ticks: set[int], silent_ticks: set[int],
                 far_base_ticks: frozenset[int] = frozenset()) -> None:
        super().__init__(daemon=True)
        self.port = p.FdPort(fd, timeout=0.05)
        self.corrupt_ticks, self.silent_ticks = corrupt_ticks, silent_ticks
        self.far_base_ticks = far_base_ticks
        self.seq = 0
        self.answered: list[int] = []
        self.resyncs: list[int] = []
        self.sent: dict[int, p.Command] = {}
        self.naks = 0
        self.stop = threading.Event()

    def send(self, message, corrupt=False):
        self.seq = (self.seq + 1) & 0xFF
        wire = p.build_frame(p.Frame(message.TYPE, self.seq, 0, message.pack()))
        self.port.write(_corrupt(wire, 3) if corrupt else wire)

    def answer(self, sensors: p.Sensors) -> p.CommandUpdate:
        tick = sensors.tick
        command = p.Command(tick, 0, 0, 0, 255, 255, 0, 0, 1.0, 0.0, 0.0, 0.25 * tick, 0, tick)
        self.sent[tick] = command
        back = 3 if tick in self.far_base_ticks and not sensors.resync else 1
        return p.CommandUpdate.between(command, None if sensors.resync
                                       else self.sent.get(tick - back))

    def run(self):
        reader = p.FrameReader()
        self.send(p.Hello(1, bytes(32), "scripted"))
        while not self.stop.is_set():
            for item in reader.feed(self.port.read(256)):
                if not isinstance(item, p.Frame):
                    continue
                if item.type == p.MessageType.SENSORS:
                    message = p.Sensors.unpack(item.payload, read_mask=1)
                else:
                    message = p.unpack_message(item)
                if isinstance(message, p.Nak):
                    self.naks += 1
                    continue
                if isinstance(message, p.PlanPiece):
                    if message.offset + len(message.data) == message.total:
                        self.send(p.PlanStatus(True, "ok"))
                    continue
                tick = message.tick
                self.answered.append(tick)
                if message.resync:
                    self.resyncs.append(tick)
                if tick in self.silent_ticks:
                    self.silent_ticks.discard(tick)
                    continue
                corrupt = tick in self.corrupt_ticks
                self.corrupt_ticks.discard(tick)
                self.send(self.answer(message), corrupt=corrupt)


@pytest.fixture
def pty_pair():
    master, slave = os.openpty()
    yield master, slave
    os.close(master)
    os.close(slave)


def test_link_retransmits_on_silence_and_naks_corrupted_answers(pty_pair):
    master, slave = pty_pair
    import tty

    tty.setraw(slave)
    runtime = ScriptedRuntime(slave, corrupt_ticks={1}, silent_ticks={2})
    runtime.start()
    link = p.Link(p.FdPort(master), retransmit_s=0.1)
    try:
        assert link.wait_hello(2.0).name == "scripted"
        commands = [link.step(tick, {0: float(tick)}) for tick in range(4)]
        assert commands == [runtime.sent[tick] for tick in range(4)]
        assert link.dropped == 1  # the corrupted COMMAND of tick 1
        assert runtime.naks == 1
        assert runtime.answered.count(2) == 2  # tick 2 was sent again after silence
        assert link.send_plan(b"GPPLAN 1\n" * 50).accepted
    finally:
        runtime.stop.set()
        runtime.join(1.0)


def test_link_gives_up_after_its_retries(pty_pair):
    master, _slave = pty_pair
    link = p.Link(p.FdPort(master), retransmit_s=0.02, max_retries=2)
    with pytest.raises(p.LinkTimeoutError):
        link.step(0, {0: 0.0})


def test_link_asks_for_a_whole_command_when_it_lacks_the_base(pty_pair):
    master, slave = pty_pair
    import tty

    tty.setraw(slave)
    runtime = ScriptedRuntime(slave, set(), set(), far_base_ticks=frozenset({5}))
    runtime.start()
    link = p.Link(p.FdPort(master), retransmit_s=0.5)
    try:
        link.wait_hello(2.0)
        commands = [link.step(tick, {0: float(tick)}) for tick in range(8)]
        assert commands == [runtime.sent[tick] for tick in range(8)]
        assert (link.resyncs, runtime.resyncs) == (1, [5])  # the SENSORS of tick 5, again
        assert link.dropped == 0 and runtime.answered.count(5) == 2
    finally:
        runtime.stop.set()
        runtime.join(1.0)

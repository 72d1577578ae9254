"""The link protocol's Python side (docs/protocol.md): framing, messages, the Link driver."""

from __future__ import annotations

import os
import struct
import threading

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gliderplan.contract import FLAG_CLIMBING, FLAG_HEADING, ReleaseReason, TransitionKind
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
    body = bytes([1, 0x04, 7, 3, 1, 0, 1])
    assert packet == body + struct.pack(">H", p.crc16_ccitt_false(body))
    wire = p.build_frame(frame)
    assert wire.endswith(b"\x00") and 0 not in wire[:-1]
    assert p.parse_frame(wire) == frame


MESSAGES = [
    p.Hello(read_mask=0b111, mission_hash=bytes(range(32)), name="sampleMission"),
    p.Sensors(tick=42, values={0: 500.0, 1: 12.5, 9: 14.25}),
    p.Command(tick=42, state=1, stack_depth=1, transition=TransitionKind.CALL, from_state=0,
              to_state=1, profile=0, flags=FLAG_CLIMBING | FLAG_HEADING,
              depth_target_m=5.0, pitch_rad=0.5, ballast_cc=230.0, heading_rad=1.5,
              sensor_power=0x207, event_count=3),
    p.Release(ReleaseReason.MISSION_EXITED),
    p.Plan(offset=200, total=450, data=b"x" * 200),
    p.PlanStatus(False, "plan line 3: hash does not match the mission"),
    p.Nak(),
]


@pytest.mark.parametrize("message", MESSAGES, ids=lambda m: type(m).__name__)
def test_every_message_round_trips_through_a_frame(message):
    wire = p.build_frame(p.Frame(message.TYPE, 1, 0, message.pack()))
    frame = p.parse_frame(wire)
    assert p.unpack_message(frame) == message


def test_command_is_36_bytes():
    assert len(MESSAGES[2].pack()) == 36


def test_sensors_are_sent_in_increasing_index_order_as_f32():
    payload = p.Sensors(tick=1, values={9: 2.0, 0: 1.0}).pack()
    assert payload == struct.pack("<IIff", 1, (1 << 0) | (1 << 9), 1.0, 2.0)


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
        (p.cobs_encode(b"\x02\x04\x01\x00\x01\x00\x01"
                       + struct.pack(">H", p.crc16_ccitt_false(b"\x02\x04\x01\x00\x01\x00\x01"))),
         p.VersionError),
        (p.cobs_encode(b"\x01\x04\x01\x00\x05\x00\x01"
                       + struct.pack(">H", p.crc16_ccitt_false(b"\x01\x04\x01\x00\x05\x00\x01"))),
         p.LengthError),
        (p.cobs_encode(b"\x01\x42\x01\x00\x00\x00"
                       + struct.pack(">H", p.crc16_ccitt_false(b"\x01\x42\x01\x00\x00\x00"))),
         p.UnknownTypeError),
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
    [(p.Command, b"\x00" * 35), (p.Sensors, struct.pack("<II", 0, 3) + b"\x00" * 4),
     (p.Hello, b"\x01" * 10), (p.Release, b""), (p.PlanStatus, b"\x01\x05ok"),
     (p.Nak, b"\x00"), (p.Plan, b"\x00")],
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
    """A fake runtime: HELLO, then answers SENSORS with COMMAND; corrupts chosen answers."""

    def __init__(self, fd: int, corrupt_ticks: set[int], silent_ticks: set[int]) -> None:
        super().__init__(daemon=True)
        self.port = p.FdPort(fd, timeout=0.05)
        self.corrupt_ticks, self.silent_ticks = corrupt_ticks, silent_ticks
        self.seq = 0
        self.answered: list[int] = []
        self.naks = 0
        self.stop = threading.Event()

    def send(self, message, corrupt=False):
        self.seq = (self.seq + 1) & 0xFF
        wire = p.build_frame(p.Frame(message.TYPE, self.seq, 0, message.pack()))
        self.port.write(_corrupt(wire, 3) if corrupt else wire)

    def run(self):
        reader = p.FrameReader()
        self.send(p.Hello(1, bytes(32), "scripted"))
        while not self.stop.is_set():
            for item in reader.feed(self.port.read(256)):
                if not isinstance(item, p.Frame):
                    continue
                message = p.unpack_message(item)
                if isinstance(message, p.Nak):
                    self.naks += 1
                    continue
                if isinstance(message, p.Plan):
                    if message.offset + len(message.data) == message.total:
                        self.send(p.PlanStatus(True, "ok"))
                    continue
                tick = message.tick
                self.answered.append(tick)
                if tick in self.silent_ticks:
                    self.silent_ticks.discard(tick)
                    continue
                corrupt = tick in self.corrupt_ticks
                self.corrupt_ticks.discard(tick)
                self.send(p.Command(tick, 0, 0, 0, 255, 255, 0, 0, 1.0, 0.0, 0.0, 0.0, 0,
                                    tick), corrupt=corrupt)


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
        assert [c.tick for c in commands] == [0, 1, 2, 3]
        assert [c.event_count for c in commands] == [0, 1, 2, 3]
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

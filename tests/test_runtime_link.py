"""The runtime binary (hand-written Fig. 2 table) against protocol.Link over a pty pair:
the paper's trace, kill and resume from the checkpoint, corrupted frames, plans over
the link, link silence."""

from __future__ import annotations

import os
import random
import select
import shutil
import signal
import subprocess
import tty
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from waiting import wait_until

from gliderplan.contract import N_SENSORS, NO_STATE, ReleaseReason, TransitionKind
from gliderplan.planner.signing import sign_plan
from gliderplan.runtime import protocol as p

RUNTIME = Path(__file__).resolve().parents[1] / "runtime"
FIG2_HASH = "5db9c7f6bccd8ec471713fb8071fb0f3aceb0069b185b69571c5783b1814d1b9"
FIG2_TRACE = ["0 start - s1 0", "500 call s1 s2 1", "1500 return s2 s1 0",
              "2000 goto s1 s3 0", "2500 exit s3 - 0"]
NAMES = {0: "s1", 1: "s2", 2: "s3", NO_STATE: "-"}

pytestmark = pytest.mark.skipif(
    shutil.which("gcc") is None or shutil.which("make") is None,
    reason="gcc and make are needed to build the C runtime (apt-get install gcc make)",
)


SANITIZERS = ("OPT=-O1 -g", "SANITIZE=-fsanitize=address,undefined -fno-sanitize-recover=all")


@pytest.fixture(scope="module", params=["plain", "sanitized"])
def build(request, tmp_path_factory) -> Path:
    """Runtimes of the hand-written tables (fig2-runtime, stacker-runtime), built plain
    and under ASan + UBSan: the link code gets the sanitizers' checks too."""
    build = tmp_path_factory.mktemp(request.param)
    flags = SANITIZERS if request.param == "sanitized" else ()
    subprocess.run(["make", "-C", str(RUNTIME), "fig2", f"BUILD={build}", "CC=gcc", *flags],
                   check=True, capture_output=True, timeout=300)
    return build


@pytest.fixture(scope="module")
def binary(build) -> Path:
    return build / "fig2-runtime"


@dataclass
class Glider:
    """The science computer's end of a pty pair, and the runtime process on the other."""

    master: int
    slave: int
    device: str
    process: subprocess.Popen | None = None

    def start(self, binary: Path, *args: str) -> subprocess.Popen:
        self.process = subprocess.Popen([str(binary), "--device", self.device, *args],
                                        stderr=subprocess.PIPE, text=True)
        return self.process

    def link(self) -> p.Link:
        return p.Link(p.FdPort(self.master), max_retries=20)


@pytest.fixture
def glider() -> Iterator[Glider]:
    master, slave = os.openpty()
    tty.setraw(slave)  # keep the slave open: a restarted runtime finds the line as it was
    g = Glider(master, slave, os.ttyname(slave))
    yield g
    if g.process and g.process.poll() is None:
        g.process.kill()
        g.process.wait(5)
    os.close(master)
    os.close(slave)


def readings(tick: int) -> dict[int, float]:
    """Sensors of one 10-second tick: missiontime, depth, lat, lon, temp."""
    return {0: tick * 10.0, 1: 5.0 + tick % 20, 6: 3910.0, 7: -7349.0, 9: 15.0}


def fly(link: p.Link, first_tick: int, last_tick: int) -> list[p.Command]:
    commands = []
    for tick in range(first_tick, last_tick + 1):
        command = link.step(tick, readings(tick))
        commands.append(command)
        if command.done:
            break
    return commands


def transitions(commands: list[p.Command]) -> list[str]:
    names = {1: "start", 2: "goto", 3: "call", 4: "return", 5: "exit"}
    return [f"{c.tick * 10} {names[c.transition]} {NAMES[c.from_state]} {NAMES[c.to_state]} "
            f"{c.stack_depth}" for c in commands if c.transition]


def make_plan(s2_temp_on_s: float = 15, hash_: str = FIG2_HASH, s1_pitch: float = 0.3,
              budget_j: float = 180000) -> bytes:
    body = (f"GPPLAN 3\nmission sampleMission\nhash {hash_}\ncomputer ts7800 300\n"
            f"budget_j {budget_j:g}\npredicted_j 9876.5\ncomponents hotel\nassumptions 0\n"
            "states 3\n"
            "state s1 300 600 0 1\npredict 1000 2 20\nenergy 3950\n"
            f"profile 0 1 {s1_pitch:g} 150 0.31\nend\n"
            "state s2 300 600 1 1\npredict 1000 1 12\nenergy 3950\n"
            f"sensor temp 60 {s2_temp_on_s:g}\nprofile 0 1 0.4 200 0.3\nend\n"
            "state s3 300 600 0 1\npredict 500 1 5\nenergy 1976.5\n"
            "profile 0 1 0.454 230 0.31\nend\n").encode()
    return body + f"crc32 {zlib.crc32(body):08x}\n".encode()


KEY = bytes(range(32))


@pytest.fixture
def key_file(tmp_path) -> str:
    """The vehicle's key, as `gliderplan keygen` writes one (mode 0600)."""
    path = tmp_path / "vehicle.key"
    path.write_text(KEY.hex() + "\n")
    path.chmod(0o600)
    return str(path)


def signed(seq: int, **changes) -> bytes:
    return sign_plan(make_plan(**changes), KEY, seq)


def test_fig2_over_the_serial_link_gives_the_papers_trace(binary, glider, tmp_path):
    process = glider.start(binary, "--state-dir", str(tmp_path))
    link = glider.link()
    hello = link.wait_hello()
    assert (hello.name, hello.mission_hash.hex(), hello.n_sensors) == (
        "sampleMission", FIG2_HASH, N_SENSORS)
    commands = fly(link, 0, 400)
    assert transitions(commands) == FIG2_TRACE
    assert commands[-1].done and commands[-1].state == NO_STATE
    assert link.wait_release() == ReleaseReason.MISSION_EXITED
    assert process.wait(10) == 0
    assert (tmp_path / "events.log").read_text().splitlines() == FIG2_TRACE


def test_a_killed_runtime_resumes_from_its_checkpoint(binary, glider, tmp_path):
    glider.start(binary, "--state-dir", str(tmp_path))
    link = glider.link()
    link.wait_hello()
    before = fly(link, 0, 100)  # in s2, called from s1
    assert before[-1].state == 1 and before[-1].stack_depth == 1
    glider.process.send_signal(signal.SIGKILL)
    glider.process.wait(5)
    with open(tmp_path / "events.log", "a") as log:  # as if killed between log and checkpoint
        log.write("1010 return s2 s1 0\n")

    tap = Tap(glider.master)
    link = p.Link(tap, max_retries=20)
    process = glider.start(binary, "--state-dir", str(tmp_path))
    link.wait_hello()
    after = fly(link, 101, 400)
    assert after[0].state == 1 and after[0].stack_depth == 1  # not a fresh start
    assert [u.base for u in tap.updates()[:2]] == [0, 1]  # whole after the restart
    assert transitions(before + after) == FIG2_TRACE
    assert process.wait(10) == 0
    assert (tmp_path / "events.log").read_text().splitlines() == FIG2_TRACE


def newest_record(checkpoint: Path) -> int:
    """Offset of the checkpoint's newest record (runtime/README.md: a header, then two
    slots of the size the header gives; a record starts with its sequence number)."""
    data = checkpoint.read_bytes()
    slot = int.from_bytes(data[72:76], "little")
    seqs = [int.from_bytes(data[at:at + 4], "little") for at in (slot, 2 * slot)]
    return slot * (1 + seqs.index(max(seqs)))


def test_a_checkpoint_torn_by_a_crash_gives_way_to_the_one_before(binary, glider, tmp_path):
    """Killed while writing the checkpoint of the call into s2 (tick 50): its COMMAND never
    went out and the record is torn. The science computer, without an answer, moves on to
    tick 51. The restarted runtime resumes from the record before (in s1), drops the
    call's line from the event log and makes the call on tick 51: the log and the
    COMMANDs tell the same story."""
    glider.start(binary, "--state-dir", str(tmp_path))
    link = glider.link()
    link.wait_hello()
    before = fly(link, 0, 50)
    assert before[-1].transition == TransitionKind.CALL
    glider.process.send_signal(signal.SIGKILL)
    glider.process.wait(5)
    checkpoint = tmp_path / "checkpoint"
    data = bytearray(checkpoint.read_bytes())
    torn = newest_record(checkpoint)
    data[torn + 20:torn + 40] = bytes(20)
    checkpoint.write_bytes(bytes(data))

    process = glider.start(binary, "--state-dir", str(tmp_path))
    link.wait_hello()
    after = fly(link, 51, 400)
    assert (after[0].transition, after[0].from_state, after[0].state) == (
        TransitionKind.CALL, 0, 1)
    late_call = ["510 call s1 s2 1", *FIG2_TRACE[2:]]
    assert transitions(before[:-1] + after) == [FIG2_TRACE[0], *late_call]
    assert process.wait(10) == 0
    assert (tmp_path / "events.log").read_text().splitlines() == [FIG2_TRACE[0], *late_call]


def thermocline_readings(tick: int) -> dict[int, float]:
    """A 5-24 m yo through a thermocline at 12 m with +-0.3 C of flicker; every third
    SENSORS leaves the temperature out (the runtime flies on its last reading)."""
    values = readings(tick)
    del values[9]
    if tick % 3:
        values[9] = (22.0 if values[1] < 12.0 else 9.0) + (0.3 if tick % 2 else -0.3)
    return values


def test_a_runtime_killed_between_records_resumes_with_the_same_memory(binary, glider,
                                                                        tmp_path):
    """Killed on ticks in s2 that wrote no record, only a journal entry (twice in a row,
    once right after a restart): each restart steps the journal again, and every COMMAND
    is the one of a run never killed, with the thermocline tracker's band and window and
    the temperature the frames left out as they were."""
    def flight(state_dir: Path, kill_after: set[int]) -> list[p.Command]:
        glider.start(binary, "--state-dir", str(state_dir))
        link = glider.link()
        link.wait_hello()
        commands = []
        for tick in range(401):
            commands.append(link.step(tick, thermocline_readings(tick)))
            if commands[-1].done:
                break
            if tick in kill_after:
                glider.process.send_signal(signal.SIGKILL)
                glider.process.wait(5)
                glider.start(binary, "--state-dir", str(state_dir))
                link.wait_hello()
        assert link.wait_release() == ReleaseReason.MISSION_EXITED  # read: not left on the line
        assert glider.process.wait(10) == 0
        return commands

    never_killed = flight(tmp_path / "never-killed", set())
    killed = flight(tmp_path / "killed", {67, 68, 69, 112, 140})
    assert killed == never_killed
    assert len({(c.depth_target_m, c.flags) for c in never_killed[50:150]}) > 4  # it tracked
    assert (tmp_path / "killed" / "events.log").read_text().splitlines() == FIG2_TRACE


def test_corrupted_frames_are_naked_and_the_trace_survives(binary, glider):
    process = glider.start(binary)
    link = glider.link()
    link.wait_hello()
    commands = fly(link, 0, 10)
    os.write(glider.master, b"\x13\x37garbage\x00" + b"\x05" * 600 + b"\x00")
    wire = bytearray(p.build_frame(p.Frame(p.MessageType.SENSORS, 200, 0,
                                           p.Sensors(11, readings(11)).pack())))
    wire[5] ^= 0x10
    os.write(glider.master, bytes(wire))
    commands += fly(link, 11, 400)
    assert transitions(commands) == FIG2_TRACE
    assert process.wait(10) == 0


class Tap(p.FdPort):
    """The science computer's port, keeping every byte it read."""

    def __init__(self, fd: int) -> None:
        super().__init__(fd)
        self.received = bytearray()

    def read(self, size: int = 1) -> bytes:
        data = super().read(size)
        self.received += data
        return data

    def updates(self) -> list[p.CommandUpdate]:
        """The COMMANDs read so far, as they travelled."""
        frames = p.FrameReader().feed(bytes(self.received))
        return [p.CommandUpdate.unpack(f.payload) for f in frames
                if isinstance(f, p.Frame) and f.type == p.MessageType.COMMAND]


def test_commands_travel_as_their_changes_against_the_tick_before(binary, glider):
    process = glider.start(binary)
    tap = Tap(glider.master)
    link = p.Link(tap, max_retries=20)
    link.wait_hello()
    commands = fly(link, 0, 400)
    assert transitions(commands) == FIG2_TRACE  # the changes applied make the same trace
    updates = tap.updates()
    assert [u.tick for u in updates] == [c.tick for c in commands]
    assert updates[0].base == 0  # the first is whole
    assert {u.base for u in updates[1:]} == {1}
    pairs = zip(commands[:-1], commands[1:], strict=True)
    assert [p.CommandUpdate.between(c, b) for b, c in pairs] == updates[1:]
    sizes = [len(u.pack()) for u in updates[1:]]
    assert min(sizes) == 7  # the tick and its base: nothing changed
    assert sum(sizes) / len(sizes) < 12
    assert process.wait(10) == 0


def _lose_the_answer(link: p.Link, master: int, tick: int) -> None:
    """Send the SENSORS of `tick` and throw its COMMAND away, as a noisy line would."""
    link.seq = (link.seq + 1) & 0xFF
    os.write(master, p.build_frame(p.Frame(p.MessageType.SENSORS, link.seq, link.ack,
                                           p.Sensors(tick, readings(tick)).pack())))
    answer = b""
    while not answer.endswith(b"\x00"):
        ready, _, _ = select.select([master], [], [], 5.0)
        assert ready, "no COMMAND"
        answer += os.read(master, 1)


def test_a_lost_command_is_sent_again_against_what_the_science_computer_holds(binary,
                                                                              glider):
    process = glider.start(binary)
    tap = Tap(glider.master)
    link = p.Link(tap, max_retries=20)
    link.wait_hello()
    commands = fly(link, 0, 49)
    _lose_the_answer(link, glider.master, 50)  # the call into s2
    commands += fly(link, 50, 400)  # tick 50 again: the runtime answers without a step
    assert transitions(commands) == FIG2_TRACE
    assert commands[50].event_count == 1 and link.resyncs == 0
    assert tap.updates()[50].base == 1  # against COMMAND 49, which the science holds
    assert process.wait(10) == 0


def test_a_science_computer_that_lost_its_commands_gets_a_whole_one(binary, glider):
    """A science computer restarted mid-mission holds no COMMAND: the runtime's next
    update names a base it lacks, it asks for a resync, and the runtime sends the COMMAND
    whole."""
    process = glider.start(binary)
    commands = fly(glider.link(), 0, 60)
    tap = Tap(glider.master)
    restarted = p.Link(tap, max_retries=20)
    commands += fly(restarted, 61, 400)
    assert transitions(commands) == FIG2_TRACE
    assert restarted.resyncs == 1
    first, again = tap.updates()[:2]
    # against COMMAND 59, the last one the old science computer acknowledged; then whole
    assert (first.tick, again.tick) == (61, 61) and (first.base, again.base) == (2, 0)
    assert process.wait(10) == 0


def test_a_repeated_sensors_frame_gets_the_same_command_without_a_step(binary, glider):
    glider.start(binary)
    link = glider.link()
    link.wait_hello()
    fly(link, 0, 49)
    wire = p.build_frame(p.Frame(p.MessageType.SENSORS, 77, link.ack,
                                 p.Sensors(50, readings(50)).pack()))
    answers = []
    for _ in range(2):  # tick 50 is the call into s2: stepping twice would call again
        os.write(glider.master, wire)
        while (message := link.receive(2.0)) is not None and not (
                isinstance(message, p.Command) and message.tick == 50):
            pass  # skip late duplicates of earlier answers
        answers.append(message)
    assert answers[0] == answers[1]
    assert answers[0].transition == TransitionKind.CALL and answers[0].event_count == 1


def test_plans_over_the_link_are_checked_and_a_bad_one_keeps_the_last(binary, glider, tmp_path,
                                                                      key_file):
    plan_file = tmp_path / "fig2.plan"
    plan_file.write_bytes(signed(1, s2_temp_on_s=15))
    state = tmp_path / "state"
    process = glider.start(binary, "--plan", str(plan_file), "--key", key_file,
                           "--state-dir", str(state))
    link = glider.link()
    link.wait_hello()
    commands = fly(link, 0, 50)
    assert abs(commands[0].pitch_rad) == pytest.approx(0.3)  # the plan's pitch in s1

    damaged = bytearray(signed(2, s2_temp_on_s=30))
    damaged[40] ^= 1  # line noise, or an attacker's edit: the tag no longer matches
    status = link.send_plan(bytes(damaged))
    assert not status.accepted and "line 28: the signature does not match" in status.message
    status = link.send_plan(signed(2, hash_="0" * 64))  # signed, but for another mission
    assert not status.accepted and "line 3: hash does not match" in status.message
    commands += fly(link, 51, 53)  # s2 entered at 500 s: temp on for 15 s of 60 s
    assert [c.sensor_power >> 9 & 1 for c in commands[50:54]] == [1, 1, 0, 0]

    status = link.send_plan(signed(3, s2_temp_on_s=30))
    assert status.accepted and status.message == "ok"
    commands += fly(link, 54, 400)  # the new window, from t_in 40 s: 30 s of every 60 s
    assert [c.sensor_power >> 9 & 1 for c in commands[54:59]] == [0, 0, 1, 1, 1]
    assert transitions(commands) == FIG2_TRACE
    assert process.wait(10) == 0


def test_a_signed_plan_that_contradicts_itself_is_refused_over_the_link(binary, glider,
                                                                         tmp_path, key_file):
    """Signed with the vehicle's key, a plan predicting more than its budget is still
    refused by the runtime's own check (`gp_plan_check`), naming the line and the field;
    the plan in force flies on."""
    plan_file = tmp_path / "fig2.plan"
    plan_file.write_bytes(signed(1))
    process = glider.start(binary, "--plan", str(plan_file), "--key", key_file,
                           "--state-dir", str(tmp_path / "state"))
    link = glider.link()
    link.wait_hello()
    commands = fly(link, 0, 10)
    status = link.send_plan(signed(2, budget_j=1000))
    assert not status.accepted
    assert status.message.endswith("line 6: predicted_j 9876.5 J exceeds budget_j 1000 J")
    commands += fly(link, 11, 400)
    assert abs(commands[0].pitch_rad) == pytest.approx(0.3)  # the plan in force's pitch
    assert transitions(commands) == FIG2_TRACE
    assert process.wait(10) == 0


@pytest.mark.parametrize(
    ("plan", "message"),
    [
        (make_plan(hash_="1" * 64), "fig2.plan line 3: hash does not match the compiled mission"),
        (make_plan()[:-1], "fig2.plan line 26: no final LF (truncated file)"),
        (make_plan().replace(b"GPPLAN 3", b"GPPLAN 2"), "line 26: checksum mismatch"),
        (None, "fig2.plan: cannot read the plan file (no such file)"),
    ],
    ids=["wrong-hash", "truncated", "edited", "missing"],
)
def test_a_bad_plan_file_refuses_to_start(binary, glider, tmp_path, plan, message):
    plan_file = tmp_path / "fig2.plan"
    if plan is not None:
        plan_file.write_bytes(plan)
    process = glider.start(binary, "--plan", str(plan_file))
    _, err = process.communicate(timeout=10)
    assert process.returncode == 1
    assert message in err and len(err.strip().splitlines()) == 1


def test_bad_arguments_are_a_one_line_error(binary, glider):
    process = glider.start(binary, "--link-timeout-s", "soon")
    _, err = process.communicate(timeout=10)
    assert process.returncode == 1
    assert "--link-timeout-s 'soon'" in err and len(err.strip().splitlines()) == 1


def test_link_silence_releases_control_and_the_returning_link_takes_it_back(binary, glider,
                                                                           tmp_path):
    """Silent past the watchdog, the runtime hands the glider to layered control (RELEASE,
    reason 1) and listens; the link's return hands it back, from the state the mission
    was in, at the mission time the science computer says. Stopped while the link is
    down, it exits 3."""
    process = glider.start(binary, "--link-timeout-s", "1", "--state-dir", str(tmp_path))
    link = glider.link()
    link.wait_hello()
    commands = fly(link, 0, 60)  # into s2; then the science computer falls silent
    assert link.wait_release(timeout_s=10) == ReleaseReason.LINK_SILENT
    link.release = None
    # 40 ticks (400 s) under layered control; s2 returns at 1500 s, whenever that is seen
    commands += fly(link, 101, 400)
    assert transitions(commands) == FIG2_TRACE
    assert commands[61].tick == 101 and commands[61].state == 1  # still in s2
    assert link.wait_release() == ReleaseReason.MISSION_EXITED  # read: not left on the line
    assert process.wait(10) == 0
    said = process.stderr.read()
    assert "link silent past its timeout; releasing control" in said
    assert "link back; taking control again" in said
    assert (tmp_path / "events.log").read_text().splitlines() == FIG2_TRACE

    process = glider.start(binary, "--link-timeout-s", "1")
    link = glider.link()
    link.wait_hello()
    fly(link, 0, 5)
    assert link.wait_release(timeout_s=10) == ReleaseReason.LINK_SILENT
    process.send_signal(signal.SIGTERM)
    assert process.wait(10) == 3


@pytest.mark.parametrize("signal_number", [signal.SIGTERM, signal.SIGSEGV],
                         ids=["stopped", "crashed"])
def test_a_stopped_or_crashed_runtime_releases_control(binary, glider, signal_number):
    process = glider.start(binary)
    link = glider.link()
    link.wait_hello()
    fly(link, 0, 5)
    process.send_signal(signal_number)
    assert link.wait_release(timeout_s=10) == ReleaseReason.INTERNAL_ERROR
    assert process.wait(10) == 4


def test_a_plan_adopted_over_the_link_outlives_a_restart(binary, glider, tmp_path, key_file):
    state = tmp_path / "state"
    glider.start(binary, "--state-dir", str(state), "--key", key_file)
    link = glider.link()
    link.wait_hello()
    commands = fly(link, 0, 3)
    assert abs(commands[-1].pitch_rad) == pytest.approx(0.454)  # no plan: the profile's
    assert link.send_plan(signed(5)).accepted
    commands = fly(link, 4, 60)
    assert abs(commands[0].pitch_rad) == pytest.approx(0.3)
    glider.process.send_signal(signal.SIGKILL)
    glider.process.wait(5)
    process = glider.start(binary, "--state-dir", str(state), "--key", key_file)
    link.wait_hello()
    commands = fly(link, 61, 400)
    # t_in 110, 120, 130, 140, 150 s: the plan powers temp for 15 s of every 60 s
    assert [c.sensor_power >> 9 & 1 for c in commands[:5]] == [0, 1, 1, 0, 0]
    assert transitions(commands) == FIG2_TRACE[2:]
    assert process.wait(10) == 0


def test_hello_repeats_until_the_first_sensors(binary, glider):
    glider.start(binary, "--retransmit-ms", "50")
    link = glider.link()
    hellos = [link.wait_hello(), link.wait_hello(), link.wait_hello()]
    assert len(hellos) == 3 and link.hello.name == "sampleMission"
    assert fly(link, 0, 0)[0].transition == TransitionKind.START


def test_plan_pieces_out_of_order_are_ignored(binary, glider, key_file):
    glider.start(binary, "--key", key_file)
    link = glider.link()
    link.wait_hello()
    fly(link, 0, 2)
    pieces = p.plan_pieces(make_plan())
    assert len(pieces) >= 2
    link.send(pieces[1])  # no piece at offset 0 came first: nothing to continue
    answers = []
    while (message := link.receive(0.5)) is not None:
        answers.append(message)
    assert not any(isinstance(m, (p.PlanStatus, p.Nak)) for m in answers)
    assert link.send_plan(signed(1)).accepted


def test_without_a_key_no_plan_over_the_link_is_flown(binary, glider, tmp_path):
    """A forged plan with its CRC recomputed was once accepted over the link: now a
    runtime without a key refuses every plan that comes over it, and says why."""
    state = tmp_path / "state"
    process = glider.start(binary, "--state-dir", str(state))
    link = glider.link()
    link.wait_hello()
    commands = fly(link, 0, 3)
    for plan in (make_plan(), signed(7)):
        status = link.send_plan(plan)
        assert not status.accepted and "no key is provisioned on this vehicle" in status.message
    commands += fly(link, 4, 400)
    assert all(abs(c.pitch_rad) != pytest.approx(0.3) for c in commands)
    assert transitions(commands) == FIG2_TRACE
    assert process.wait(10) == 0
    assert "plan over the link rejected (seq 0): no key" in process.stderr.read()
    log = (state / "plans.log").read_text().splitlines()
    assert [line.split(" ", 3)[1:3] for line in log] == [["rejected", "0"]] * 2


def test_with_a_key_unsigned_replayed_and_reused_plans_are_refused(binary, glider, tmp_path,
                                                                  key_file):
    state = tmp_path / "state"
    process = glider.start(binary, "--key", key_file, "--state-dir", str(state))
    link = glider.link()
    link.wait_hello()
    commands = fly(link, 0, 3)
    status = link.send_plan(make_plan())  # a forger without the key: CRC right, no tag
    assert not status.accepted and "line 26: the plan is not signed" in status.message
    assert link.send_plan(signed(10)).accepted
    assert link.send_plan(signed(10)).accepted  # the plan in force, sent again
    status = link.send_plan(signed(9, s2_temp_on_s=30))  # an old plan, replayed
    assert not status.accepted and "seq 9 is older than the plan in force (seq 10)" in (
        status.message)
    status = link.send_plan(signed(10, s2_temp_on_s=30))
    assert not status.accepted and "seq 10 is the plan in force's, but this is another" in (
        status.message)
    commands += fly(link, 4, 400)
    assert transitions(commands) == FIG2_TRACE
    assert [c.sensor_power >> 9 & 1 for c in commands[50:54]] == [1, 1, 0, 0]  # seq 10's
    assert process.wait(10) == 0
    log = [line.split(" ", 3)[1:3] for line in (state / "plans.log").read_text().splitlines()]
    assert log == [["rejected", "0"], ["accepted", "10"], ["accepted", "10"], ["rejected", "0"],
                   ["rejected", "0"]]


@pytest.mark.parametrize(("stored", "flown", "said"), [
    (3, 0.3, "newer than --plan (seq 2)"), (1, 0.4, "older than the plan in force"),
    (None, 0.4, "the signature does not match")], ids=["newer", "older", "tampered"])
def test_on_resume_a_stored_plan_replaces_plan_only_if_signed_and_newer(
        binary, glider, tmp_path, key_file, stored, flown, said):
    """`--plan` (seq 2, pitch 0.4 in s1) against the plan the state directory kept from
    the link: a newer one is flown; an older or tampered one gives way, and it says so."""
    state = tmp_path / "state"
    glider.start(binary, "--state-dir", str(state), "--key", key_file)
    link = glider.link()
    link.wait_hello()
    fly(link, 0, 3)
    glider.process.send_signal(signal.SIGKILL)
    glider.process.wait(5)
    on_disk = signed(stored) if stored else bytearray(signed(4))
    if not stored:
        on_disk[200] ^= 1
    (state / "plan").write_bytes(bytes(on_disk))
    plan_file = tmp_path / "fig2.plan"
    plan_file.write_bytes(signed(2, s1_pitch=0.4))
    process = glider.start(binary, "--state-dir", str(state), "--key", key_file,
                           "--plan", str(plan_file))
    link.wait_hello()
    commands = fly(link, 4, 400)
    assert abs(commands[0].pitch_rad) == pytest.approx(flown)
    assert process.wait(10) == 0
    assert said in process.stderr.read()


def test_a_mission_fault_releases_control_and_is_logged(build, glider, tmp_path):
    process = glider.start(build / "stacker-runtime", "--state-dir", str(tmp_path))
    link = glider.link()
    link.wait_hello()
    commands = []
    with pytest.raises(p.LinkReleasedError) as released:
        for tick in range(100):
            commands.append(link.step(tick, {0: float(tick)}))
    assert released.value.reason == ReleaseReason.INTERNAL_ERROR
    assert process.wait(10) == 4
    assert "call overflows the state stack" in process.stderr.read()
    assert [c.stack_depth for c in commands if c.transition] == [0, 1, 2]
    assert (tmp_path / "events.log").read_text().splitlines() == [
        "0 start - a 0", "10 call a b 1", "20 call b a 2", "21 fault a b 2"]


def test_random_frames_and_bytes_never_derail_the_runtime(binary, glider):
    """Garbage, damaged frames and well-formed frames of every type but SENSORS (with
    random payloads) between ticks: the runtime neither crashes nor steps on them."""
    process = glider.start(binary)
    link = glider.link()
    link.wait_hello()
    rng = random.Random(5)
    commands = fly(link, 0, 20)
    for burst in range(40):
        noise = bytearray()
        for _ in range(25):
            kind = rng.choice([t for t in p.MessageType if t != p.MessageType.SENSORS])
            payload = rng.randbytes(rng.randrange(0, p.MAX_PAYLOAD + 1))
            if kind == p.MessageType.PLAN and rng.random() < 0.5:
                payload = b"\x00\x00" + payload[2:]  # offset 0: starts a (bad) plan
            wire = bytearray(p.build_frame(p.Frame(kind, rng.randrange(256), 0, payload)))
            if rng.random() < 0.3:
                wire[rng.randrange(len(wire) - 1)] = rng.randrange(1, 256)
            noise += wire + rng.randbytes(rng.randrange(0, 40))
        os.write(glider.master, bytes(noise))
        commands += fly(link, 21 + burst, 21 + burst)
    commands += fly(link, 61, 400)
    assert transitions(commands) == FIG2_TRACE
    assert process.wait(10) == 0


def test_a_stale_sensors_frame_is_not_stepped_again(binary, glider):
    """A copy of an older tick's SENSORS (delayed or duplicated on the line) arriving with
    a new seq was once stepped again, running mission time backwards: now it is ignored,
    and the mission flies on as if it had never come."""
    process = glider.start(binary)
    link = glider.link()
    link.wait_hello()
    commands = fly(link, 0, 60)  # the call into s2 was tick 50
    for tick in (50, 0, 59):
        os.write(glider.master, p.build_frame(p.Frame(p.MessageType.SENSORS, 200 + tick,
                                                      link.ack,
                                                      p.Sensors(tick, readings(tick)).pack())))
    assert link.receive(1.0) is None  # no answer: nothing stepped, nothing sent
    commands += fly(link, 61, 400)
    assert transitions(commands) == FIG2_TRACE
    assert [c.event_count for c in commands[59:62]] == [1, 1, 1]
    assert process.wait(10) == 0
    assert "3 stale SENSORS ignored" in process.stderr.read()


def test_a_kill_before_the_first_checkpoint_logs_start_once(binary, glider, tmp_path):
    """Killed after tick 0's `start` reached the event log but before its checkpoint:
    the state directory holds the checkpoint written at start-up, before any tick. The
    restarted runtime drops the logged line and starts again: `start` is logged once
    (it was logged twice before the checkpoint came into being at start-up)."""
    glider.start(binary, "--state-dir", str(tmp_path))
    link = glider.link()
    link.wait_hello()
    at_start_up = (tmp_path / "checkpoint").read_bytes()
    before = fly(link, 0, 0)
    glider.process.send_signal(signal.SIGKILL)
    glider.process.wait(5)
    assert (tmp_path / "events.log").read_text().splitlines() == FIG2_TRACE[:1]
    (tmp_path / "checkpoint").write_bytes(at_start_up)  # the tick's record never landed

    process = glider.start(binary, "--state-dir", str(tmp_path))
    link.wait_hello()
    after = fly(link, 1, 400)
    assert after[0].transition == TransitionKind.START  # tick 1 is the mission's first
    assert process.wait(10) == 0
    assert before[0].transition == TransitionKind.START
    restarted_trace = ["10 start - s1 0", *FIG2_TRACE[1:]]
    assert transitions(after) == restarted_trace
    assert (tmp_path / "events.log").read_text().splitlines() == restarted_trace


@pytest.mark.parametrize("link_timeout_s", [2, 600], ids=["released", "flying"])
def test_a_peer_that_stops_reading_never_blocks_the_runtime(binary, glider, link_timeout_s):
    """The science computer stops reading while the runtime keeps writing (HELLO every
    millisecond here) until the line is full. The runtime blocked for good in its write
    once, deaf to its watchdog and to SIGTERM; now a full line costs frames: its watchdog
    still releases control, and SIGTERM stops it at once (exit 3 once released, 4
    before)."""
    process = glider.start(binary, "--retransmit-ms", "1", "--link-timeout-s",
                           str(link_timeout_s))
    said = bytearray()  # the runtime's stderr so far

    def line_full() -> bool:  # nobody reads it: the runtime's end takes no more
        return not select.select([], [glider.slave], [], 0)[1]

    def released() -> bool:  # the watchdog has said so
        if select.select([process.stderr], [], [], 0)[0]:
            said.extend(os.read(process.stderr.fileno(), 4096))
        return b"link silent past its timeout" in said

    wait_until(line_full, 30, "the runtime fills the line")
    if link_timeout_s == 2:
        wait_until(released, 30, "the watchdog releases control on a full line")
    assert process.poll() is None
    process.send_signal(signal.SIGTERM)
    assert process.wait(5) == (3 if link_timeout_s == 2 else 4)
    said.extend(process.stderr.read().encode())
    assert (b"link silent past its timeout" in said) == (link_timeout_s == 2)

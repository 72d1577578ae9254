"""Fig. 2 end to end: `gliderplan compile` builds the runtime from the generated C, and a
scripted science computer (protocol.Link) drives it over a pty pair, feeding missiontime.

    s1 --call (500 s)--> s2 --return (1500 s)--> s1 --goto (2000 s)--> s3 --exit (2500 s)

Also: corrupted frames change nothing, a killed runtime resumes, bad plans stop it
before it starts, a hand-written plan's sensor windows reach the COMMANDs, and the
TS-7800 and TS-5500 builds fly it on the boards' own CPU models under qemu-user.
"""

from __future__ import annotations

import math
import os
import random
import re
import select
import shutil
import signal
import struct
import subprocess
import tty
import zlib
from collections.abc import Iterator
from pathlib import Path

import pytest
import serial
from waiting import wait_until

from gliderplan.cli.main import main
from gliderplan.contract import (
    BAUD,
    FLAG_CLIMBING,
    FLAG_DONE,
    NO_STATE,
    PLAN_FORMAT_VERSION,
    PROTOCOL_VERSION,
    ExitCode,
    ReleaseReason,
    RuntimeExit,
)
from gliderplan.contract.errors import GliderplanError
from gliderplan.language import check_source, semantics
from gliderplan.language.codegen_c import read_mask
from gliderplan.language.registry import SENSOR_BY_NAME, SENSORS
from gliderplan.runtime import build
from gliderplan.runtime import protocol as p

ROOT = Path(__file__).resolve().parents[1]
FIG2 = ROOT / "examples" / "fig2.mission"
ENERGY_LEFT = SENSOR_BY_NAME["energy_left"].index
TICK_S = 10.0
STATES = {0: "s1", 1: "s2", 2: "s3", NO_STATE: "-"}
KINDS = {1: "start", 2: "goto", 3: "call", 4: "return", 5: "exit"}
PAPER_TRACE = ["0 start - s1 0", "500 call s1 s2 1", "1500 return s2 s1 0",
               "2000 goto s1 s3 0", "2500 exit s3 - 0"]

BOARDS = [target for target in build.TARGETS if target != "host"]


pytestmark = pytest.mark.skipif(shutil.which("cc") is None,
                                reason="no C compiler (cc) to build the runtime")


@pytest.fixture(scope="module")
def cache(tmp_path_factory) -> Iterator[Path]:
    """A build cache of this module's own, so the tests never read a stale user cache."""
    directory = tmp_path_factory.mktemp("cache")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("GLIDERPLAN_CACHE_DIR", str(directory))
        yield directory


def compile_fig2(out: Path, *options: str) -> int:
    return main(["compile", str(FIG2), "-o", str(out), *options])


@pytest.fixture(scope="module")
def binary(cache, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("host")
    assert compile_fig2(out) == 0
    return out / "sampleMission"


@pytest.fixture(scope="module")
def fig2_hash(binary) -> str:
    return (binary.parent / "sampleMission.c").read_text().split("Mission hash ")[1][:64]


class Line:
    """A pty pair: the runtime opens the slave by name, the science computer holds the master."""

    def __init__(self) -> None:
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)  # held open so that a restarted runtime finds the same line
        self.device = os.ttyname(self.slave)
        self.process: subprocess.Popen | None = None

    def start(self, command: list[str], *args: str) -> subprocess.Popen:
        self.process = subprocess.Popen([*command, "--device", self.device, *args],
                                        stderr=subprocess.PIPE, text=True)
        return self.process

    def link(self) -> p.Link:
        return p.Link(p.FdPort(self.master), max_retries=20)

    def close(self) -> None:
        if self.process and self.process.poll() is None:
            self.process.kill()
            self.process.wait(10)
        os.close(self.master)
        os.close(self.slave)


@pytest.fixture
def line() -> Iterator[Line]:
    pair = Line()
    yield pair
    pair.close()


def readings(tick: int) -> dict[int, float]:
    """One tick's sensors: missiontime, depth sweeping 5-24 m, position, temperature."""
    return {0: tick * TICK_S, 1: 5.0 + tick % 20, 2: 0.0, 6: 3910.0, 7: -7349.0, 9: 15.0}


def fly(link: p.Link, first: int, last: int = 1000,
        before_step=lambda tick: None) -> list[p.Command]:
    commands = []
    for tick in range(first, last + 1):
        before_step(tick)
        commands.append(link.step(tick, readings(tick)))
        if commands[-1].done:
            break
    return commands


def trace(commands: list[p.Command]) -> list[str]:
    return [f"{c.tick * TICK_S:g} {KINDS[c.transition]} {STATES[c.from_state]} "
            f"{STATES[c.to_state]} {c.stack_depth}" for c in commands if c.transition]


def run_to_end(line: Line, command: list[str], state_dir: Path) -> list[p.Command]:
    process = line.start(command, "--state-dir", str(state_dir))
    link = line.link()
    assert link.wait_hello(30).name == "sampleMission"
    commands = fly(link, 0)
    assert link.wait_release() == ReleaseReason.MISSION_EXITED
    assert process.wait(30) == 0, process.stderr.read()
    return commands


def test_compiled_fig2_flies_the_papers_trace(binary, line, tmp_path):
    commands = run_to_end(line, [str(binary)], tmp_path)
    assert trace(commands) == PAPER_TRACE
    assert (tmp_path / "events.log").read_text().splitlines() == PAPER_TRACE


def test_fig2_over_a_line_the_runtime_makes_with_a_pyserial_peer(binary, tmp_path):
    """`--device pty`: the runtime creates the pseudo-terminal and names its other end;
    the science computer opens that with pyserial at 115200 8N1, as a real port."""
    process = subprocess.Popen([str(binary), "--device", "pty", "--state-dir", str(tmp_path)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        ready, _, _ = select.select([process.stdout], [], [], 30)
        device = process.stdout.readline().strip() if ready else ""
        assert device.startswith("/dev/pts/"), process.stderr.read()
        with serial.Serial(device, BAUD, timeout=0) as port:
            link = p.Link(port, max_retries=20)
            assert link.wait_hello(30).name == "sampleMission"
            commands = fly(link, 0)
            assert link.wait_release() == ReleaseReason.MISSION_EXITED
        assert process.wait(30) == 0, process.stderr.read()  # it waited for us to hang up
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert trace(commands) == PAPER_TRACE


def test_a_simulated_run_cut_short_stops_the_runtime_cleanly(cache):
    """The simulator's end of the line closes, then it stops the runtime (SIGTERM): the
    runtime, which saw its peer hang up, releases and exits 4 instead of napping through
    the stop signal until the simulator kills it."""
    from gliderplan.planner.limits import flight_limits
    from gliderplan.sim.emulator import start_c_runtime

    mission = check_source(FIG2.read_text(), str(FIG2)).mission
    for _ in range(5):  # the signal can land anywhere in the runtime's wait
        runtime = start_c_runtime(mission, None, flight_limits(mission))
        for tick in range(3):
            runtime.step(tick, 0x2C3, [tick * TICK_S, 5.0, 0.0, 0, 0, 0, 3910.0, -7349.0, 0,
                                       15.0, *[0.0] * 7])
        runtime.close()
        assert runtime.process.returncode == RuntimeExit.INTERNAL, runtime.stderr_text()
        assert "stopped by a signal" in runtime.stderr_text()


def test_a_second_compile_comes_from_the_cache(binary, cache, tmp_path):
    entries = sorted(cache.rglob("sampleMission"))
    assert compile_fig2(tmp_path) == 0
    assert sorted(cache.rglob("sampleMission")) == entries  # nothing new was built
    assert (tmp_path / "sampleMission").read_bytes() == binary.read_bytes()


def _touched(path: Path) -> int:
    """The modification time [ns] the file system gives a file written now."""
    path.touch()
    return path.stat().st_mtime_ns


def test_the_cache_keeps_the_most_recently_used_builds(monkeypatch, tmp_path):
    monkeypatch.setenv("GLIDERPLAN_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(build, "CACHED_BUILDS", 2)
    # A cache directory shared with others: their old directories are none of ours,
    # even one named like a build, and neither is a link to a build elsewhere.
    elsewhere = tmp_path / "elsewhere"
    (elsewhere / build.CACHE_MARKER).parent.mkdir()
    (elsewhere / build.CACHE_MARKER).write_text("not in the cache\n")
    foreign = [tmp_path / "cache" / "ab" / "notes", tmp_path / "cache" / "cd" / ("cd" * 32)]
    for directory in foreign:
        directory.mkdir(parents=True)
        (directory / "keep.txt").write_text("someone else's\n")
        os.utime(directory, (0, 0))  # older than every build
    (tmp_path / "cache" / "ab" / "link").symlink_to(elsewhere)
    text = FIG2.read_text()
    for horizon in (2500, 2600, 2500, 2700):  # the third is a cache hit that refreshes 2500
        source = tmp_path / "m.mission"
        source.write_text(text.replace("2500", str(horizon)))
        assert main(["compile", str(source), "-o", str(tmp_path / str(horizon))]) == 0
        # the cache orders builds by modification time: the next one's must be later
        newest = max(m.parent.stat().st_mtime_ns
                     for m in (tmp_path / "cache").glob(f"??/*/{build.CACHE_MARKER}"))
        wait_until(lambda newest=newest: _touched(tmp_path / "clock") > newest, 5,
                   "the file system's clock passes the newest build's")
    built = [b.read_bytes() for b in (tmp_path / "cache").rglob("sampleMission")]
    assert len(built) == 2
    assert (tmp_path / "2500" / "sampleMission").read_bytes() in built
    assert (tmp_path / "2700" / "sampleMission").read_bytes() in built
    assert (tmp_path / "2600" / "sampleMission").read_bytes() not in built
    assert all((directory / "keep.txt").is_file() for directory in foreign)
    assert (elsewhere / build.CACHE_MARKER).is_file()


def test_the_cache_key_changes_with_every_input_of_the_build(tmp_path):
    (tmp_path / "include").mkdir()
    (tmp_path / "include" / "gp_mission.h").write_text("/* header */\n")
    source = tmp_path / "gp_a.c"
    source.write_text("int a;\n")
    host, arm = build.TARGETS["host"], build.TARGETS["ts7800"]

    def key(mission_c="m", board=host, command=("true",)):
        return build.build_key(mission_c, tmp_path / "include", [source], board, list(command))

    first = key()
    assert key() == first
    assert key(mission_c="m2") != first
    assert key(board=arm) != first
    assert key(command=("echo",)) != first  # another compiler (its --version differs too)
    source.write_text("int b;\n")
    assert key() != first


def test_the_cache_key_changes_when_the_c_library_is_rebuilt(tmp_path):
    # musl rebuilt for the i486 keeps the compiler's --version: the key must still move.
    (tmp_path / "include").mkdir()
    source = tmp_path / "gp_a.c"
    source.write_text("int a;\n")
    libc = tmp_path / "libc.a"
    libc.write_bytes(b"!<arch>\nold")
    compiler = tmp_path / "cc"  # links nothing, traces what a real link would read
    compiler.write_text(f'#!/bin/sh\n[ "$1" = --version ] && echo cc 1.0 || echo {libc}\n')
    compiler.chmod(0o755)

    def key():
        return build.build_key("m", tmp_path / "include", [source], build.TARGETS["host"],
                               [str(compiler)])

    first = key()
    assert key() == first
    libc.write_bytes(b"!<arch>\nnew")
    assert key() != first


def test_a_missing_cross_compiler_names_the_debian_package(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv("PATH", str(tmp_path))  # no compiler of any kind
    assert compile_fig2(tmp_path / "out", "--target", "ts7800") == 1
    assert "sudo apt-get install gcc-arm-linux-gnueabi" in capsys.readouterr().err


def test_a_ts5500_build_needs_musl_for_the_i486_and_says_how_to_build_it(monkeypatch, tmp_path,
                                                                         capsys):
    # The i686 toolchain alone (or gcc -m32) would link a C library the board cannot run.
    (tmp_path / "bin").mkdir()
    for tool in ("gcc", "i686-linux-gnu-gcc"):
        if shutil.which(tool):
            (tmp_path / "bin" / tool).symlink_to(shutil.which(tool))
    monkeypatch.setenv("PATH", str(tmp_path / "bin"))
    assert compile_fig2(tmp_path / "out", "--target", "ts5500") == 1
    said = capsys.readouterr().err
    assert "needs i486-linux-musl-gcc, which is not installed" in said
    script = said.split("sudo sh ")[1].split()[0]
    assert Path(script).is_file() and script.endswith("musl-i486.sh")


def test_compile_takes_the_default_ballast_from_the_mission_s_vehicle(tmp_path, capsys):
    broken = tmp_path / "glider.toml"
    broken.write_text("kind = 'vehicle'\n")
    mission = tmp_path / "m.mission"
    mission.write_text(FIG2.read_text().replace("mission sampleMission\n",
                                                f'mission sampleMission\nvehicle "{broken}"\n'))
    assert main(["compile", str(mission), "-o", str(tmp_path / "out")]) == 1
    assert "glider.toml" in capsys.readouterr().err
    assert not (tmp_path / "out" / "sampleMission").exists()


def test_a_compiler_failure_is_a_clear_error_and_caches_nothing(monkeypatch, tmp_path, capsys):
    (tmp_path / "bin").mkdir()
    fake = tmp_path / "bin" / "cc"
    fake.write_text('#!/bin/sh\n[ "$1" = --version ] && { echo "fake cc 1.0"; exit 0; }\n'
                    'echo "mission.c:1:1: error: out of cheese" >&2\nexit 1\n')
    fake.chmod(0o755)
    monkeypatch.setenv("PATH", f"{tmp_path / 'bin'}:{os.environ['PATH']}")
    monkeypatch.setenv("GLIDERPLAN_CACHE_DIR", str(tmp_path / "cache"))
    assert compile_fig2(tmp_path / "out") == 1
    message = capsys.readouterr().err
    assert "cc failed for target host" in message and "out of cheese" in message
    assert not (tmp_path / "out" / "sampleMission").exists()
    assert not [p for p in (tmp_path / "cache").rglob("*") if p.is_file()]


def test_a_stack_beyond_the_runtime_limit_is_refused_before_compiling(tmp_path, capsys):
    assert compile_fig2(tmp_path, "--max-stack", "40") == 2
    assert "--max-stack must be between 1 and 32" in capsys.readouterr().err
    deep = tmp_path / "deep.mission"
    deep.write_text(FIG2.read_text().replace("mission sampleMission\n",
                                             "mission sampleMission\nstack 40\n"))
    assert main(["compile", str(deep), "-o", str(tmp_path)]) == 1
    assert f"{deep}:2:7: error: stack depth must be a whole number from 1 to 32" \
        in capsys.readouterr().err
    assert not (tmp_path / "sampleMission").exists()


def _sensors_frame(link: p.Link, tick: int) -> bytes:
    """A SENSORS frame for `tick` with the seq the next real frame would use."""
    frame = p.Frame(p.MessageType.SENSORS, (link.seq + 1) & 0xFF, link.ack,
                    p.Sensors(tick, readings(tick)).pack())
    return p.build_packet(frame)


def test_corrupted_frames_are_rejected_and_change_nothing(binary, line, tmp_path):
    process = line.start([str(binary)], "--state-dir", str(tmp_path))
    link = line.link()
    link.wait_hello(30)

    def inject(tick: int) -> None:
        if tick % 25:
            return
        # Each would be tick 250 (missiontime 2500: exit) if the runtime believed it.
        packet = bytearray(_sensors_frame(link, 250))
        bad_crc = bytes(packet[:-1]) + bytes([packet[-1] ^ 0x01])
        bad_version = bytes([PROTOCOL_VERSION + 1]) + bytes(packet[1:-2])
        bad_version += p.crc16_ccitt_false(bad_version).to_bytes(2, "big")
        truncated = bytes(packet[:-5])
        for wire in (bad_crc, bad_version, truncated):
            os.write(line.master, p.cobs_encode(wire) + b"\x00")
        os.write(line.master, b"\x13\x37 not a frame\x00")

    commands = fly(link, 0, before_step=inject)
    assert trace(commands) == PAPER_TRACE
    assert link.wait_release() == ReleaseReason.MISSION_EXITED
    assert process.wait(30) == 0


def test_a_killed_runtime_resumes_with_the_same_trace(binary, line, tmp_path):
    line.start([str(binary)], "--state-dir", str(tmp_path))
    link = line.link()
    link.wait_hello(30)
    before = fly(link, 0, 120)  # in s2, called from s1
    assert (before[-1].state, before[-1].stack_depth) == (1, 1)
    line.process.send_signal(signal.SIGKILL)
    line.process.wait(10)

    process = line.start([str(binary)], "--state-dir", str(tmp_path))
    link.wait_hello(30)
    after = fly(link, 121)
    assert (after[0].state, after[0].stack_depth, after[0].transition) == (1, 1, 0)
    assert trace(before + after) == PAPER_TRACE
    assert process.wait(30) == 0
    assert (tmp_path / "events.log").read_text().splitlines() == PAPER_TRACE


# ---- plans ---------------------------------------------------------------------------


def make_plan(mission_hash: str, version: int = PLAN_FORMAT_VERSION,
              temp_period_s: float = 60, temp_on_s: float = 15, s2_clock_mhz: int = 300,
              s3_ballast: str = "230") -> bytes:
    """A plan for Fig. 2 written by hand from docs/plan-format.md."""
    body = (f"GPPLAN {version}\nmission sampleMission\nhash {mission_hash}\n"
            "computer ts7800 300\nbudget_j 6630000\npredicted_j 9876.5\ncomponents hotel\n"
            "assumptions 0\nstates 3\n"
            "state s1 300 600 0 1\npredict 1000 2 20\nenergy 3950\nprofile 0 1 0.3 150 0.31\nend\n"
            f"state s2 {s2_clock_mhz} 600 1 1\npredict 1000 1 12\nenergy 3950\n"
            f"sensor temp {temp_period_s:g} {temp_on_s:g}\nprofile 0 1 0.4 200 0.3\nend\n"
            "state s3 300 600 0 1\npredict 500 1 5\nenergy 1976.5\n"
            f"profile 0 1 0.454 {s3_ballast} 0.31\nend\n").encode()
    return body + f"crc32 {zlib.crc32(body):08x}\n".encode()


def bad_plans(mission_hash: str) -> dict[str, tuple[bytes, str]]:
    good = make_plan(mission_hash)
    other = make_plan("0" * 64)
    wrong_version = make_plan(mission_hash, version=1)
    bad_crc = good[:-3] + (b"00\n" if good[-3:] != b"00\n" else b"11\n")
    return {
        "truncated": (good[: len(good) // 2], "truncated"),
        "bad-crc": (bad_crc, "checksum"),
        "other-mission": (other, "hash"),
        "wrong-version": (wrong_version, "version"),
        # absurd values: the vehicle's pump is +-233 cc, the TS-7800 runs at 300 or 500 MHz
        "ballast-1e300": (make_plan(mission_hash, s3_ballast="1e300"), "exceeds the vehicle's"),
        "ballast-5000": (make_plan(mission_hash, s3_ballast="5000"), "5000 exceeds the vehicle"),
        "clock-133": (make_plan(mission_hash, s2_clock_mhz=133), "clock 133 mhz: the board"),
    }


BAD_PLANS = ["truncated", "bad-crc", "other-mission", "wrong-version", "ballast-1e300",
             "ballast-5000", "clock-133"]


@pytest.mark.parametrize("case", BAD_PLANS)
def test_the_runtime_refuses_to_start_on_a_bad_plan(binary, fig2_hash, line, tmp_path, case):
    plan, word = bad_plans(fig2_hash)[case]
    (tmp_path / "bad.plan").write_bytes(plan)
    process = line.start([str(binary)], "--plan", str(tmp_path / "bad.plan"),
                         "--state-dir", str(tmp_path / "state"))
    assert process.wait(30) == 1
    message = process.stderr.read()
    assert "bad.plan" in message and word in message.lower(), message
    assert not (tmp_path / "state" / "events.log").exists()


@pytest.mark.parametrize("case", BAD_PLANS)
def test_compile_rejects_a_bad_plan(binary, fig2_hash, tmp_path, capsys, case):
    plan, word = bad_plans(fig2_hash)[case]
    (tmp_path / "bad.plan").write_bytes(plan)
    assert compile_fig2(tmp_path / "out", "--plan", str(tmp_path / "bad.plan")) == 1
    message = capsys.readouterr().err
    assert "plan rejected" in message and "bad.plan line" in message, message
    assert word in message.lower(), message
    assert not (tmp_path / "out" / "bad.plan").exists()


def test_compile_mission_checks_the_plan_with_the_runtime_and_ships_it(binary, fig2_hash,
                                                                      tmp_path):
    from gliderplan.language import check_file
    from gliderplan.planner.planfile import PlanRejected
    from gliderplan.runtime.build import compile_mission

    mission = check_file(str(FIG2)).checked()
    (tmp_path / "fig2.plan").write_bytes(make_plan(fig2_hash))
    built = compile_mission(mission, tmp_path / "out", plan_path=tmp_path / "fig2.plan")
    assert built == tmp_path / "out" / "sampleMission" and built.is_file()
    assert (tmp_path / "out" / "fig2.plan").read_bytes() == make_plan(fig2_hash)
    (tmp_path / "bad.plan").write_bytes(bad_plans(fig2_hash)["bad-crc"][0])
    with pytest.raises(PlanRejected, match="plan rejected: .*bad.plan line"):
        compile_mission(mission, tmp_path / "out2", plan_path=tmp_path / "bad.plan")
    assert not (tmp_path / "out2").exists()
    (tmp_path / "file").write_text("a file, not a directory\n")
    with pytest.raises(GliderplanError, match="not a directory") as refused:
        compile_mission(mission, tmp_path / "file")  # the command's error, exit 2
    assert refused.value.exit_code == ExitCode.USAGE


def test_a_hand_written_plan_switches_sensors_on_their_windows(binary, fig2_hash, line,
                                                              tmp_path, capsys):
    (tmp_path / "fig2.plan").write_bytes(make_plan(fig2_hash))
    out = tmp_path / "out"
    assert compile_fig2(out, "--plan", str(tmp_path / "fig2.plan")) == 0
    assert (out / "fig2.plan").read_bytes() == make_plan(fig2_hash)

    commands = run_to_end(line, [str(out / "sampleMission"), "--plan", str(out / "fig2.plan")],
                          tmp_path / "state")
    assert trace(commands) == PAPER_TRACE
    temp_bit, always = 1 << 9, 0b111  # temp (CTD) is planned; missiontime, depth, pitch not
    in_s2 = [c for c in commands if c.state == 1]
    assert len(in_s2) == 100
    for command in in_s2:
        t_in = command.tick * TICK_S - 500.0
        assert bool(command.sensor_power & temp_bit) == (math.fmod(t_in, 60.0) < 15.0), t_in
        assert command.sensor_power & always == always
    in_s1 = [c for c in commands if c.state == 0]
    assert all(not c.sensor_power & temp_bit for c in in_s1)
    # The planned pitch and ballast replace the profile's own and the vehicle default.
    assert {round(abs(c.pitch_rad), 6) for c in in_s1} == {0.3}
    assert {abs(c.ballast_cc) for c in in_s1} == {150.0}


def clocks_by_state(link: p.Link, speed: Path) -> dict[int, set[str]]:
    """Fly to the end: state -> what the clock file held after each of its ticks."""
    link.wait_hello(30)
    clocks: dict[int, set[str]] = {}
    for tick in range(1000):
        command = link.step(tick, readings(tick))
        clocks.setdefault(command.state, set()).add(speed.read_text())
        if command.done:
            return clocks
    return clocks


def test_the_runtime_sets_each_states_planned_clock(binary, fig2_hash, line, tmp_path):
    (tmp_path / "fig2.plan").write_bytes(make_plan(fig2_hash, s2_clock_mhz=500))
    speed = tmp_path / "scaling_setspeed"  # what cpufreq's userspace governor reads, in kHz
    speed.write_text("")
    process = line.start([str(binary), "--plan", str(tmp_path / "fig2.plan"),
                          "--clock-file", str(speed)])
    clocks = clocks_by_state(line.link(), speed)
    assert process.wait(30) == 0, process.stderr.read()
    assert clocks[0] == {"300000\n"} and clocks[2] == {"300000\n"}
    assert clocks[1] == {"500000\n"}


def test_without_a_plan_the_runtime_follows_the_missions_own_power_settings(
        cache, line, tmp_path):
    # Fig. 2 with s2 at 500 MHz, asleep between ticks: the tables the compiler writes
    # carry both, and the runtime acts on them through its clock and suspend files.
    source = FIG2.read_text().replace(
        "  sensors missiontime, depth, pitch, temp\n",
        "  sensors missiontime, depth, pitch, temp\n  computer clock 500 MHz\n"
        "  computer sleep between ticks\n")
    (tmp_path / "power.mission").write_text(source)
    build = tmp_path / "build"
    assert main(["compile", str(tmp_path / "power.mission"), "-o", str(build)]) == 0
    speed, suspend = tmp_path / "scaling_setspeed", tmp_path / "power_state"
    speed.write_text("")
    suspend.write_text("")
    process = line.start([str(build / "sampleMission"), "--clock-file", str(speed),
                          "--suspend-file", str(suspend)])
    clocks = clocks_by_state(line.link(), speed)
    assert process.wait(30) == 0, process.stderr.read()
    assert clocks[1] == {"500000\n"}
    assert clocks[0] <= {"", "500000\n"}  # s1 has no clock of its own: left as it was
    in_s2 = 1000 / TICK_S  # ticks from 500 s to 1500 s, each followed by a sleep
    assert suspend.read_text().count("mem\n") == in_s2


def test_a_clock_that_cannot_be_set_is_said_once_and_the_mission_flies_on(
        binary, fig2_hash, line, tmp_path):
    (tmp_path / "fig2.plan").write_bytes(make_plan(fig2_hash, s2_clock_mhz=500))
    process = line.start([str(binary), "--plan", str(tmp_path / "fig2.plan"),
                          "--clock-file", str(tmp_path / "no" / "such" / "file")])
    link = line.link()
    link.wait_hello(30)
    assert trace(fly(link, 0)) == PAPER_TRACE
    assert process.wait(30) == 0
    said = process.stderr.read()
    assert said.count("cannot set the clock to 300 MHz") == 1, said
    assert "500 MHz" not in said


# ---- a mission with variables, against the reference semantics ---------------------


def f32(value: float) -> float:
    """The value as the link carries it (binary32), so both sides see the same reading."""
    return struct.unpack("<f", struct.pack("<f", value))[0]


@pytest.mark.parametrize(("target", "seed"), [("host", 1), ("host", 2), ("host", 3),
                                            ("ts7800", 4), ("ts5500", 5)])
def test_compiled_survey_follows_the_reference_semantics(cache, line, tmp_path, target, seed,
                                                        board_runner):
    # A mission with variables, assignments that read sensors, call and return, checked
    # tick by tick on random readings against language.semantics.
    runner = board_runner(target)
    source = ROOT / "examples" / "thermocline_survey.mission"
    mission = check_source(source.read_text(), str(source)).mission
    assert main(["compile", str(source), "-o", str(tmp_path / "bin"), "--target", target]) == 0
    names = {i: s.name for i, s in enumerate(mission.states)} | {NO_STATE: ""}
    mask = read_mask(mission)
    rng = random.Random(seed)

    process = line.start([*runner, str(tmp_path / "bin" / mission.name)],
                         "--state-dir", str(tmp_path / "state"))
    link = line.link()
    link.wait_hello(30)
    machine, first = semantics.start(mission)
    expected, actual = [first], []
    for tick in range(100_000):
        values = {s.index: f32(rng.uniform(-5.0, 90.0)) for s in SENSORS if mask >> s.index & 1}
        values[0] = tick * 60.0
        values[ENERGY_LEFT] = mission.battery.energy_j  # a full battery: the guard sleeps
        command = link.step(tick, values)
        if command.transition:
            actual.append(semantics.Transition(
                values[0], KINDS[command.transition], names[command.from_state],
                names[command.to_state], command.stack_depth))
        readings = {s.name: values[s.index] for s in SENSORS if s.index in values}
        machine, transition = semantics.step(mission, machine, readings, values[0])
        if transition:
            expected.append(transition)
        if command.done:
            break
    assert link.wait_release() == ReleaseReason.MISSION_EXITED
    assert process.wait(30) == 0
    assert machine.exited
    assert actual == expected
    assert len(expected) > 10  # the readings make the survey move between its states


@pytest.mark.parametrize("seed", [1, 2])
def test_compiled_altimeter_stop_turns_the_dives_as_the_python_executor_does(cache, line,
                                                                            tmp_path, seed):
    # yo and thermotrackyo with an altimeter stop, then a yo without one, fed the same
    # frames: depths up and down, altitude readings near the stop, missing (NaN) or far
    from gliderplan.power_models import load_vehicle
    from gliderplan.sim.executor import PythonRuntime

    source = ROOT / "tests" / "missions" / "sim_altimeter.mission"
    mission = check_source(source.read_text(), str(source)).mission
    assert main(["compile", str(source), "-o", str(tmp_path / "bin"), "--target", "host"]) == 0
    mask = read_mask(mission)
    assert mask >> SENSOR_BY_NAME["altitude"].index & 1  # the routine reads the altimeter
    vehicle = load_vehicle(mission.vehicle)
    reference = PythonRuntime(mission, None, vehicle.unplanned_ballast_cc, True,
                              vehicle.max_ballast_cc, vehicle.envelope)
    process = line.start([str(tmp_path / "bin" / mission.name)])
    link = line.link()
    link.wait_hello(30)
    rng = random.Random(seed)
    depth, turns = 3.0, 0
    for tick in range(4000):
        # near the floor (40 m) readings about the stop; above it, none or the floor's: a
        # floor within the stop of the yo's top would turn it every tick (the envelope)
        altitude = rng.choice([math.nan, 40.0 - depth, 4.0, 3.99, 4.01, rng.uniform(0, 9)]
                              if depth > 30.0 else [math.nan, 40.0 - depth])
        values = {0: tick * TICK_S, 1: f32(depth), 5: f32(altitude), 6: 5441.0, 7: 647.0,
                  9: f32(rng.uniform(8.0, 20.0))}
        values = {i: v for i, v in values.items() if mask >> i & 1}
        command = link.step(tick, values)
        array = [values.get(i, math.nan) for i in range(len(SENSORS))]
        expected = reference.step(tick, mask, array)
        expected = expected._replace(**{k: f32(getattr(expected, k)) for k in (
            "depth_target_m", "pitch_rad", "ballast_cc", "heading_rad")})  # as the link has it
        assert command == expected, tick
        climbing = command.flags & FLAG_CLIMBING
        turns += climbing and depth < 30.0 and command.depth_target_m == 3.0 \
            and command.state == 0  # a dive the altimeter turned, well above 50 m
        depth = min(max(depth + (-1.5 if climbing else 1.5) * rng.uniform(0.5, 1.5), 0.0), 55.0)
        if command.flags & FLAG_DONE:
            break
    assert link.wait_release() == ReleaseReason.MISSION_EXITED
    assert process.wait(30) == 0
    assert turns > 0


# ---- the boards' CPU models under qemu-user (-cpu arm926, -cpu 486) -----------------

@pytest.mark.parametrize("target", BOARDS)
def test_board_builds_fly_fig2_on_the_boards_cpus(cache, line, tmp_path, target, board_runner):
    runner = board_runner(target)
    assert compile_fig2(tmp_path / target, "--target", target) == 0
    commands = run_to_end(line, [*runner, str(tmp_path / target / "sampleMission")],
                          tmp_path / "state")
    assert trace(commands) == PAPER_TRACE


# Instructions the i486 does not have: the P6's conditional moves and x87 compares that set
# EFLAGS, the Pentium's cmpxchg8b, rdtsc and model registers, fast system calls, MMX/SSE.
I686_ONLY = re.compile(r"\s(cmov\w+|fcmov\w+|fu?comip?|cmpxchg8b|rdtsc|rdmsr|wrmsr|rdpmc|"
                       r"sysenter|sysexit|syscall|fisttp\w*|[lms]fence|clflush|prefetch\w*|"
                       r"emms|ldmxcsr|stmxcsr)\s|%x?mm\d")
OBJDUMP = "i686-linux-gnu-objdump"


def i686_only_instructions(binary: Path) -> list[str]:
    """Disassembled lines of `binary` that an i486 cannot execute."""
    listing = subprocess.run([OBJDUMP, "-d", str(binary)], capture_output=True, text=True,
                             check=True).stdout
    return [line.strip() for line in listing.splitlines() if I686_ONLY.search(line)]


def test_the_ts5500_binary_has_no_instruction_the_i486_lacks(cache, tmp_path, board_runner):
    board_runner("ts5500")
    if shutil.which(OBJDUMP) is None:
        pytest.skip(f"{OBJDUMP} not installed (make sysdeps)")
    # The scan finds what an i686 build of the same kind of code contains.
    probe = tmp_path / "probe.c"
    probe.write_text("int least(int a, int b) { return a < b ? a : b; }\n"
                     "int below(double a, double b) { return a < b; }\n")
    subprocess.run(["i686-linux-gnu-gcc", "-O2", "-march=i686", "-c", str(probe), "-o",
                    str(tmp_path / "probe.o")], check=True)
    found = " ".join(i686_only_instructions(tmp_path / "probe.o"))
    assert "cmov" in found and "fcomip" in found

    assert compile_fig2(tmp_path / "ts5500", "--target", "ts5500") == 0
    assert i686_only_instructions(tmp_path / "ts5500" / "sampleMission") == []


def test_the_ts5500_build_rounds_each_result_to_double_once(tmp_path, board_runner):
    # x87 registers hold 64-bit mantissas; -mpc64 sets the precision to double's 53 bits at
    # start-up, or a difference is rounded twice and lands one unit off the reference. The
    # C library's strtod and printf still read and print every double exactly.
    emulator = board_runner("ts5500")
    board = build.TARGETS["ts5500"]
    source = tmp_path / "difference.c"
    source.write_text("#include <stdio.h>\n#include <stdlib.h>\n"
                      "int main(int argc, char **argv) {\n"
                      "    for (int i = 1; i + 1 < argc; i += 2) {\n"
                      "        volatile double a = strtod(argv[i], NULL);\n"
                      "        volatile double b = strtod(argv[i + 1], NULL);\n"
                      "        printf(\"%a %.17g\\n\", a - b, a - b);\n"
                      "    }\n"
                      "    return 0;\n"
                      "}\n")
    subprocess.run([board.compiler, *board.flags, str(source), "-o", str(tmp_path / "difference")],
                   check=True)
    pairs = [(-3.256479851258976e16, 2.00001), (0.454, 0.0), (1.7976931348623157e308, 1e292),
             (5e-324, 0.0), (123456.789, 0.001), (-7349.8058, 3910.5)]
    done = subprocess.run([*emulator, str(tmp_path / "difference"),
                           *(repr(x) for pair in pairs for x in pair)],
                          capture_output=True, text=True, check=True)
    for (a, b), line in zip(pairs, done.stdout.splitlines(), strict=True):
        exact, decimal = line.split()
        assert float.fromhex(exact) == float(decimal) == a - b, (a, b, line)

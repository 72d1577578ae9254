"""The science computer behind a real serial line: the compiled C runtime runs as its own
process and creates a pseudo-terminal (`--device pty`); the simulator opens the other end
with pyserial, as it would a serial port, and speaks docs/protocol.md over it
(gliderplan.runtime.protocol.Link). The simulator sends each tick's SENSORS
frame and waits for that tick's COMMAND, so the run is lock-step: as fast as the two
processes can talk, and deterministic."""

from __future__ import annotations

import functools
import os
import select
import shutil
import signal
import subprocess
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING

from gliderplan.contract import RETRANSMIT_MS, ExitCode, FlightLimits
from gliderplan.contract.errors import GliderplanError
from gliderplan.language import ir
from gliderplan.language.semantics import MissionFault

if TYPE_CHECKING:
    import serial

    from gliderplan.runtime.protocol import Command
    from gliderplan.sim.faults import FaultSchedule, FaultyLine

HELLO_TIMEOUT_S = 10.0
# under line faults: a HELLO is a long frame, and a heavily noisy line damages most of them
FAULT_HELLO_TIMEOUT_S = 60.0
EXIT_TIMEOUT_S = 5.0
FAULT_WATCHDOG_S = 10 * RETRANSMIT_MS / 1000  # [s] the runtime's link timeout under faults
# exchanges of one tick (each of the link's retransmission budget) before the link is
# declared failed: a tick is never skipped, so a run flies the fault-free flight or ends
LINK_FAILURE_EXCHANGES = 3
KILL_DELAY_S = 0.0003  # [s] mean wait before a kill that lands while the runtime works
LINK_COUNTS = ("dropped", "naks", "resends", "recovered", "resyncs")  # a Link's counters


class EmulatorError(GliderplanError):
    """The C runtime could not be built or started, or broke the link."""


class LinkFailure(EmulatorError):
    """Under line faults, the runtime's HELLO never came through: the link has failed."""

    exit_code = ExitCode.LINK_FAILED


class CRuntime:
    """The compiled runtime over a pty, answering one SENSORS frame per `step`.

    With `faults` (sim/faults.py) the line runs through the fault layer, the runtime keeps
    a state directory (its checkpoint and event log) and a short watchdog, is killed and
    restarted at the ticks the faults draw, and the glider flies under its own layered
    control while the line is cut. A tick is exchanged until it completes (the mission
    clock waits) or the link is declared failed (a MissionFault: the run ends there);
    a runtime that ended while its last COMMAND was lost ends the run as it ended.
    `report()` counts all of it."""

    superseded: tuple = ()  # a COMMAND carries one transition: the trace is events.log's

    def __init__(self, binary: Path, mission: ir.CheckedMission, plan_path: str | None,
                 naive_tracker: bool, work_dir: Path, key_path: str | None = None,
                 state_dir: str | Path | None = None,
                 faults: FaultSchedule | None = None) -> None:
        self._work = work_dir
        self._mission = mission
        self.faults = faults
        self.exited = False
        self.port: serial.Serial | None = None
        self.line: FaultyLine | None = None
        self.process: subprocess.Popen | None = None
        self._closed = False
        self._stderr: str | None = None
        self._last: Command | None = None  # the last COMMAND flown: layered control's
        self._cut = False  # the line is cut (a disconnect)
        self._counts: Counter[str] = Counter()
        self._downtime_s = 0.0  # [s] wall time from each kill to the restarted runtime's HELLO
        self.events_log: str | None = None  # the runtime's event log, once closed
        self.suspends = 0  # counted when the runtime has ended (close)
        # The platform's suspend interface, simulated: a file the runtime appends "mem" to
        # each time it would suspend the board between ticks (a restarted runtime too).
        self._suspend_file = work_dir / "power-state"
        self._suspend_file.touch()
        # the runtime makes the pty and names its other end; a state directory only when
        # asked for or under faults: a simulated run needs no checkpoint to resume from
        if state_dir is None and faults is not None:
            state_dir = work_dir / "state"
        self._state_dir = None if state_dir is None else Path(state_dir).resolve()
        self._command = [str(binary), "--device", "pty", "--suspend-file",
                         str(self._suspend_file)]
        if key_path is not None:  # the key provisioned on the vehicle: the plan is uploaded
            self._command += ["--key", str(Path(key_path).resolve())]
        elif plan_path is not None:
            self._command += ["--plan", str(Path(plan_path).resolve())]
        if self._state_dir is not None:
            self._command += ["--state-dir", str(self._state_dir)]
        if naive_tracker:
            self._command.append("--naive-tracker")
        if faults is not None:
            self._command += ["--link-timeout-s", f"{FAULT_WATCHDOG_S:g}"]
        self._start()
        if key_path is not None and plan_path is not None:
            self._upload(plan_path)

    def _start(self) -> None:
        """Start the runtime, open its line, wait for its HELLO."""
        import serial

        from gliderplan.contract import BAUD
        from gliderplan.runtime.protocol import FdPort, Link, LinkError
        from gliderplan.sim.faults import FaultyLine

        self.process = subprocess.Popen(self._command, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        try:
            # pyserial opens and sets up the line (raw 115200 8N1, non-blocking); the link
            # reads and writes its descriptor directly: one system call each way per
            # frame, where pyserial's read and write add two select calls and an ioctl
            self.port = serial.Serial(self._peer_path(), BAUD, timeout=0)
            port = FdPort(self.port.fileno())
            self.line = None if self.faults is None else FaultyLine(port, self.faults)
            self.link = Link(port if self.line is None else self.line)
            hello = self.link.wait_hello(HELLO_TIMEOUT_S if self.line is None
                                         else FAULT_HELLO_TIMEOUT_S)
        except (EmulatorError, LinkError, serial.SerialException) as err:
            self.close()
            failed = LinkFailure if self.line is not None and isinstance(err, LinkError) \
                else EmulatorError
            raise failed(f"the runtime did not say HELLO ({err}): "
                         f"{self.stderr_text()}") from None
        if hello.mission_hash.hex() != self._mission.hash:
            self.close()
            raise EmulatorError("the runtime was compiled for another mission (hash differs)")
        self._read_mask = hello.read_mask

    def _upload(self, plan_path: str) -> None:
        """Send the plan over the link, as at the surface, before the first tick; the
        vehicle's verdict decides (PlanRejected with its reason)."""
        from gliderplan.planner.planfile import PlanRejected, read_plan_data
        from gliderplan.runtime.protocol import LinkError

        try:
            status = self.link.send_plan(read_plan_data(plan_path))
        except LinkError as err:
            self.close()
            raise EmulatorError(f"the runtime did not answer the plan ({err}): "
                                f"{self.stderr_text()}") from None
        if not status.accepted:
            self.close()
            raise PlanRejected(f"{plan_path} {status.message} (said the vehicle)")

    def deliver_update(self, update: bytes) -> tuple[int, int, str]:
        """Send a plan update over the link, as at a surfacing, between two ticks; the
        runtime's verdict (contract.UpdateStatus, the plan in force after it, its words)."""
        from gliderplan.contract import UpdateStatus
        from gliderplan.runtime.protocol import LinkError

        try:
            status = self.link.send_update(update)
        except LinkError as err:
            raise EmulatorError(f"the runtime did not answer the plan update ({err}): "
                                f"{self.stderr_text()}") from None
        return UpdateStatus(status.status), status.seq, status.message

    def step(self, tick: int, mask: int, values: list[float]) -> Command:
        """Send one tick's SENSORS (those of `mask` the runtime reads: HELLO's read mask),
        return the runtime's COMMAND (with faults: layered control's while the line is
        cut)."""
        from gliderplan.contract import NO_STATE

        carried = {i: values[i] for i in _indices(mask & self._read_mask)}
        if self.faults is not None:
            command = self._faulted_step(tick, carried, values[0])
        else:
            command = self._exchange(tick, carried)
        self.exited = command.state == NO_STATE
        self._last = command
        return command

    def _exchange(self, tick: int, carried: dict[int, float]) -> Command:
        from gliderplan.runtime.protocol import LinkError, LinkReleasedError

        try:
            return self.link.step(tick, carried)
        except LinkReleasedError as err:
            raise MissionFault(f"tick {tick}: the runtime released the glider ({err}): "
                               f"{self.stderr_text()}") from None
        except LinkError as err:  # timed out, or hung up
            raise MissionFault(f"tick {tick}: the runtime stopped answering ({err}): "
                               f"{self.stderr_text()}") from None

    def _faulted_step(self, tick: int, carried: dict[int, float], time_s: float) -> Command:
        from gliderplan.contract import ReleaseReason
        from gliderplan.runtime.protocol import (
            LinkClosedError,
            LinkReleasedError,
            LinkTimeoutError,
        )

        faults = self.faults
        if faults.kill_due(tick):
            self._kill_and_restart(tick, carried)
        if faults.spec.link_down(time_s):
            return self._layered(tick, cut=True)
        if self._cut:  # the line is back: what the runtime said into it is lost
            self._cut = self.line.down = False
            self.line.discard_input()
        for _ in range(LINK_FAILURE_EXCHANGES):
            try:
                return self.link.step(tick, carried)
            except LinkReleasedError as err:
                if err.reason != ReleaseReason.LINK_SILENT:
                    raise MissionFault(f"tick {tick}: the runtime released the glider "
                                       f"({err}): {self.stderr_text()}") from None
                # its watchdog fired while frames were lost; it takes control back as
                # soon as it hears this tick's SENSORS again
                self._counts["releases"] += 1
                self.link.release = None
            except LinkClosedError:
                return self._ended(tick)
            except LinkTimeoutError:
                if self.process.poll() is not None or self.link.release is not None:
                    return self._ended(tick)
                self._counts["lost_exchanges"] += 1
        raise MissionFault(f"tick {tick}: link failure: no COMMAND in {LINK_FAILURE_EXCHANGES} "
                           "exchanges of every retransmission; the glider flies on under its "
                           "layered control")

    def _ended(self, tick: int) -> Command:
        """The runtime ended while this tick's COMMAND was lost on the line: the mission's
        end (its exit, or a guard's: the runtime's exit status says which) as a COMMAND,
        or a MissionFault for any other end. Its event log holds the transition."""
        from gliderplan.contract import FLAG_DONE, NO_STATE, RuntimeExit, TransitionKind
        from gliderplan.runtime.protocol import ZERO_COMMAND

        try:
            status = self.process.wait(timeout=EXIT_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            status = None
        kind = {RuntimeExit.DONE: TransitionKind.EXIT, RuntimeExit.RESERVE: TransitionKind.RESERVE,
                }.get(status)
        if kind is None:
            raise MissionFault(f"tick {tick}: the runtime ended (exit {status}) while the "
                               f"line lost its answers: {self.stderr_text()}")
        last = self._last or ZERO_COMMAND
        self.exited = True
        # as the runtime's last COMMAND: no state, no flight, no sensor powered
        return ZERO_COMMAND._replace(tick=tick, state=NO_STATE, transition=kind,
                                     from_state=last.state if last.state != NO_STATE else 0,
                                     to_state=NO_STATE, flags=FLAG_DONE,
                                     event_count=last.event_count)

    def _layered(self, tick: int, cut: bool = False) -> Command:
        """A tick flown by the glider's layered control: the last COMMAND's flight goes on,
        no transition; with `cut`, the line is cut (the first such tick waits until the
        runtime's watchdog has handed control over)."""
        from gliderplan.contract import NO_STATE
        from gliderplan.runtime.protocol import ZERO_COMMAND

        if cut and not self._cut:
            self._cut = self.line.down = True
            self._counts["disconnects"] += 1
            self._counts["releases"] += self._await_release()
        self._counts["layered_ticks"] += 1
        last = self._last or ZERO_COMMAND
        return last._replace(tick=tick, transition=0, from_state=NO_STATE, to_state=NO_STATE)

    def _await_release(self) -> int:
        """Watch the runtime's side of a cut line until its watchdog sends RELEASE (1), or
        twice the watchdog has passed without one (0)."""
        from gliderplan.contract import MessageType
        from gliderplan.runtime.protocol import Frame, FrameReader

        reader, fd = FrameReader(), self.port.fileno()
        deadline = time.monotonic() + 2 * FAULT_WATCHDOG_S + 1.0
        while (remaining := deadline - time.monotonic()) > 0:
            if not select.select([fd], [], [], remaining)[0]:
                break
            for item in reader.feed(os.read(fd, 4096)):
                if isinstance(item, Frame) and item.type == MessageType.RELEASE:
                    return 1
        return 0

    def _kill_and_restart(self, tick: int, carried: dict[int, float]) -> None:
        """SIGKILL the runtime at a random moment (idle between ticks, or while it works on
        this tick's SENSORS), then start it again on its state directory."""
        from gliderplan.runtime.protocol import Sensors

        rng = self.faults.rng
        if rng.random() < 0.5:
            self.link.send(Sensors(tick, carried))
            time.sleep(rng.expovariate(1 / KILL_DELAY_S))
        self.process.kill()
        self.process.wait()
        self._retire()
        began = time.monotonic()
        try:
            self._start()
        except LinkFailure as err:
            raise MissionFault(f"tick {tick}: link failure: {err}") from None
        self._counts["restarts"] += 1
        self._downtime_s += time.monotonic() - began

    def _retire(self) -> None:
        """Close a killed runtime's line and pipes, keeping its link's counts."""
        self.port.close()
        self.port = None
        self._count_link()
        self.process.stdout.close()
        self.process.stderr.close()

    def _count_link(self) -> None:
        link = getattr(self, "link", None)
        for name in LINK_COUNTS:
            self._counts[name] += getattr(link, name, 0)

    def report(self) -> dict:
        """What the faults did (summary.json's `faults`): injected by kind; detected (frames
        each side dropped as damaged, re-sends after silence, COMMANDs resynchronised);
        recovered (exchanges answered after a re-send); ticks lost to layered control;
        the runtime's releases and restarts; the time under layered control."""
        count = self._counts
        return {
            "spec": self.faults.spec.text,
            "injected": dict(sorted(self.faults.injected.items())),
            "detected": {"damaged_at_science_computer": count["dropped"],
                         "damaged_at_runtime": count["naks"],
                         "timeouts": count["resends"], "resyncs": count["resyncs"]},
            "recovered": count["recovered"],
            "lost_exchanges": count["lost_exchanges"],
            "disconnects": count["disconnects"],
            "releases": count["releases"],
            "layered_control_s": count["layered_ticks"] * self.faults.tick_s,
            "kills": count["restarts"],
            "kills_asked": self.faults.spec.kills,
            "restart_downtime_s": round(self._downtime_s, 3),
        }

    def _peer_path(self) -> str:
        """The pty path the runtime prints first, once it has opened the line."""
        ready, _, _ = select.select([self.process.stdout], [], [], HELLO_TIMEOUT_S)
        line = self.process.stdout.readline().decode(errors="replace").strip() if ready else ""
        if not line:
            raise EmulatorError("it opened no serial line")
        return line

    def envelope_notes(self) -> list[str]:
        """What the runtime's envelope guard said it did (its stderr's `envelope:` lines),
        once it has ended."""
        return [line.split(": ", 1)[1] for line in self.stderr_text().splitlines()
                if ": envelope: " in line]

    def stderr_text(self) -> str:
        """What the runtime said on stderr, once it has ended."""
        if self._stderr is None and self.process.poll() is not None:
            self._stderr = self.process.stderr.read().decode(errors="replace").strip()
        return self._stderr or ""

    def close(self) -> None:
        """Let an exited runtime finish (RELEASE, exit 0); stop one that is still flying.
        Our end of the line closes first: the runtime waits for that before it closes its
        own, which would discard what we had not read. With faults, the runtime's event
        log is kept (`events_log`). Once: a failed restart has closed it already."""
        if self._closed:
            return
        self._closed = True
        if self.port is not None:
            self.port.close()
        try:
            if not self.exited:
                self.process.send_signal(signal.SIGTERM)
            self.process.wait(timeout=EXIT_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        finally:
            self.stderr_text()  # kept for the error message
            self.process.stdout.close()
            self.process.stderr.close()
            self._count_link()
            log = None if self._state_dir is None else self._state_dir / "events.log"
            if self.faults is not None and log.exists():
                self.events_log = log.read_text()
            self.suspends = self._suspend_file.read_text().count("mem\n")
            shutil.rmtree(self._work, ignore_errors=True)


@functools.cache
def _indices(mask: int) -> tuple[int, ...]:
    """Sensor indices of the set bits of a mask."""
    return tuple(i for i in range(32) if mask >> i & 1)


def start_c_runtime(mission: ir.CheckedMission, plan_path: str | None, limits: FlightLimits,
                    naive_tracker: bool = False, key_path: str | None = None,
                    state_dir: str | Path | None = None,
                    faults: FaultSchedule | None = None) -> CRuntime:
    """Compile the mission for the host (cached) with the vehicle's and board's `limits` and
    start it against the emulator. With `key_path` the key is provisioned on the runtime
    and the plan is uploaded over the link, signed, rather than read at start-up. The
    runtime keeps its checkpoints and event log in `state_dir` if given; with `faults`,
    they are injected (CRuntime)."""
    from gliderplan.language.codegen_c import CodegenError
    from gliderplan.runtime.build import BuildError, compile_mission

    work = Path(tempfile.mkdtemp(prefix="gliderplan-sim-"))
    try:
        binary = compile_mission(mission, work, "host", limits=limits)
    except (CodegenError, BuildError) as err:
        shutil.rmtree(work, ignore_errors=True)
        raise EmulatorError(str(err)) from None
    return CRuntime(binary, mission, plan_path, naive_tracker, work, key_path, state_dir,
                    faults)

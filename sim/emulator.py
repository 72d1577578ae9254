"""The science computer behind a real serial line: the compiled C runtime runs as its own
process and creates a pseudo-terminal (`--device pty`); the simulator opens the other end
with pyserial, as it would a serial port, and speaks docs/protocol.md over it
(gliderplan.runtime.protocol.Link). The simulator sends each tick's SENSORS
frame and waits for that tick's COMMAND, so the run is lock-step: as fast as the two
processes can talk, and deterministic."""

from __future__ import annotations

import functools
import select
import shutil
import signal
import subprocess
import tempfile
from pathlib import Path

from gliderplan.contract import FlightLimits
from gliderplan.contract.errors import GliderplanError
from gliderplan.language import ir
from gliderplan.language.semantics import MissionFault

HELLO_TIMEOUT_S = 10.0
EXIT_TIMEOUT_S = 5.0


class EmulatorError(GliderplanError):
    """The C runtime could not be built or started, or broke the link."""


class CRuntime:
    """The compiled runtime over a pty, answering one SENSORS frame per `step`."""

    def __init__(self, binary: Path, mission: ir.CheckedMission, plan_path: str | None,
                 naive_tracker: bool, work_dir: Path, key_path: str | None = None,
                 state_dir: str | Path | None = None) -> None:
        import serial

        from gliderplan.contract import BAUD
        from gliderplan.runtime.protocol import FdPort, Link, LinkError

        self._work = work_dir
        self.exited = False
        self.port: serial.Serial | None = None
        self._stderr: str | None = None
        # the runtime makes the pty and names its other end; a state directory only when
        # asked for: a simulated run needs no checkpoint to resume from
        command = [str(binary), "--device", "pty"]
        if key_path is not None:  # the key provisioned on the vehicle: the plan is uploaded
            command += ["--key", str(Path(key_path).resolve())]
        elif plan_path is not None:
            command += ["--plan", str(Path(plan_path).resolve())]
        if state_dir is not None:
            command += ["--state-dir", str(Path(state_dir).resolve())]
        if naive_tracker:
            command.append("--naive-tracker")
        self.process = subprocess.Popen(command, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        try:
            # pyserial opens and sets up the line (raw 115200 8N1, non-blocking); the link
            # reads and writes its descriptor directly: one system call each way per
            # frame, where pyserial's read and write add two select calls and an ioctl
            self.port = serial.Serial(self._peer_path(), BAUD, timeout=0)
            self.link = Link(FdPort(self.port.fileno()))
            hello = self.link.wait_hello(HELLO_TIMEOUT_S)
        except (EmulatorError, LinkError, serial.SerialException) as err:
            self.close()
            raise EmulatorError(f"the runtime did not say HELLO ({err}): "
                                f"{self.stderr_text()}") from None
        if hello.mission_hash.hex() != mission.hash:
            self.close()
            raise EmulatorError("the runtime was compiled for another mission (hash differs)")
        self._read_mask = hello.read_mask
        if key_path is not None and plan_path is not None:
            self._upload(plan_path)

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

    def step(self, tick: int, mask: int, values: list[float]):
        """Send one tick's SENSORS (those of `mask` the runtime reads: HELLO's read mask),
        return the runtime's COMMAND."""
        from gliderplan.contract import NO_STATE
        from gliderplan.runtime.protocol import LinkError, LinkReleasedError

        carried = {i: values[i] for i in _indices(mask & self._read_mask)}
        try:
            command = self.link.step(tick, carried)
            self.exited = command.state == NO_STATE
            return command
        except LinkReleasedError as err:
            raise MissionFault(f"tick {tick}: the runtime released the glider ({err}): "
                               f"{self.stderr_text()}") from None
        except LinkError as err:  # timed out, or hung up
            raise MissionFault(f"tick {tick}: the runtime stopped answering ({err}): "
                               f"{self.stderr_text()}") from None

    def _peer_path(self) -> str:
        """The pty path the runtime prints first, once it has opened the line."""
        ready, _, _ = select.select([self.process.stdout], [], [], HELLO_TIMEOUT_S)
        line = self.process.stdout.readline().decode(errors="replace").strip() if ready else ""
        if not line:
            raise EmulatorError("it opened no serial line")
        return line

    def stderr_text(self) -> str:
        """What the runtime said on stderr, once it has ended."""
        if self._stderr is None and self.process.poll() is not None:
            self._stderr = self.process.stderr.read().decode(errors="replace").strip()
        return self._stderr or ""

    def close(self) -> None:
        """Let an exited runtime finish (RELEASE, exit 0); stop one that is still flying.
        Our end of the line closes first: the runtime waits for that before it closes its
        own, which would discard what we had not read."""
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
            shutil.rmtree(self._work, ignore_errors=True)


@functools.cache
def _indices(mask: int) -> tuple[int, ...]:
    """Sensor indices of the set bits of a mask."""
    return tuple(i for i in range(32) if mask >> i & 1)


def start_c_runtime(mission: ir.CheckedMission, plan_path: str | None, limits: FlightLimits,
                    naive_tracker: bool = False, key_path: str | None = None,
                    state_dir: str | Path | None = None) -> CRuntime:
    """Compile the mission for the host (cached) with the vehicle's and board's `limits` and
    start it against the emulator. With `key_path` the key is provisioned on the runtime
    and the plan is uploaded over the link, signed, rather than read at start-up. The
    runtime keeps its checkpoints and event log in `state_dir` if given."""
    from gliderplan.language.codegen_c import CodegenError
    from gliderplan.runtime.build import BuildError, compile_mission

    work = Path(tempfile.mkdtemp(prefix="gliderplan-sim-"))
    try:
        binary = compile_mission(mission, work, "host", limits=limits)
    except (CodegenError, BuildError) as err:
        shutil.rmtree(work, ignore_errors=True)
        raise EmulatorError(str(err)) from None
    return CRuntime(binary, mission, plan_path, naive_tracker, work, key_path, state_dir)

"""The science computer behind a real serial line: the compiled C runtime runs as its own
process on one end of a pseudo-terminal pair, the simulator speaks docs/protocol.md on
the other (gliderplan.runtime.protocol.Link). The simulator sends each tick's SENSORS
frame and waits for that tick's COMMAND, so the run is lock-step: as fast as the two
processes can talk, and deterministic."""

from __future__ import annotations

import functools
import os
import shutil
import signal
import subprocess
import tempfile
import tty
from pathlib import Path

from gliderplan.language import ir
from gliderplan.language.semantics import MissionFault

HELLO_TIMEOUT_S = 10.0
EXIT_TIMEOUT_S = 5.0


class EmulatorError(Exception):
    """The C runtime could not be built or started, or broke the link."""


class CRuntime:
    """The compiled runtime over a pty, answering one SENSORS frame per `step`."""

    def __init__(self, binary: Path, mission: ir.CheckedMission, plan_path: str | None,
                 naive_tracker: bool, work_dir: Path) -> None:
        from gliderplan.runtime.protocol import FdPort, Link, LinkError

        self._work = work_dir
        self.exited = False
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)  # the runtime sets raw mode too; no echo before it does
        # no --state-dir: a simulated run needs no checkpoint to resume from
        command = [str(binary), "--device", os.ttyname(self.slave)]
        if plan_path is not None:
            command += ["--plan", str(Path(plan_path).resolve())]
        if naive_tracker:
            command.append("--naive-tracker")
        self.process = subprocess.Popen(command, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        self.link = Link(FdPort(self.master))
        try:
            hello = self.link.wait_hello(HELLO_TIMEOUT_S)
        except LinkError as err:
            self.close()
            raise EmulatorError(f"the runtime did not say HELLO ({err}): "
                                f"{self.stderr_text()}") from None
        if hello.mission_hash.hex() != mission.hash:
            self.close()
            raise EmulatorError("the runtime was compiled for another mission (hash differs)")

    def step(self, tick: int, mask: int, values: list[float]):
        """Send one tick's SENSORS (the sensors in `mask`), return the runtime's COMMAND."""
        from gliderplan.runtime.protocol import NO_STATE, LinkReleasedError, LinkTimeoutError

        carried = {i: values[i] for i in _indices(mask)}
        try:
            command = self.link.step(tick, carried)
            self.exited = command.state == NO_STATE
            return command
        except LinkReleasedError as err:
            raise MissionFault(f"tick {tick}: the runtime released the glider ({err}): "
                               f"{self.stderr_text()}") from None
        except LinkTimeoutError as err:
            raise MissionFault(f"tick {tick}: the runtime stopped answering ({err})") from None

    def stderr_text(self) -> str:
        if self.process.poll() is None:
            return ""
        return self.process.stderr.read().decode(errors="replace").strip()

    def close(self) -> None:
        """Let an exited runtime finish (RELEASE, exit 0); stop one that is still flying."""
        try:
            if not self.exited:
                self.process.send_signal(signal.SIGTERM)
            self.process.wait(timeout=EXIT_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        finally:
            self.process.stderr.close()
            os.close(self.master)
            os.close(self.slave)
            shutil.rmtree(self._work, ignore_errors=True)


@functools.cache
def _indices(mask: int) -> tuple[int, ...]:
    """Sensor indices of the set bits of a mask."""
    return tuple(i for i in range(32) if mask >> i & 1)


def start_c_runtime(mission: ir.CheckedMission, plan_path: str | None,
                    naive_tracker: bool = False) -> CRuntime:
    """Compile the mission for the host (cached) and start it against the emulator."""
    from gliderplan.language.codegen_c import CodegenError
    from gliderplan.runtime.build import BuildError, compile_mission

    work = Path(tempfile.mkdtemp(prefix="gliderplan-sim-"))
    try:
        binary = compile_mission(mission, work, "host")
    except (CodegenError, BuildError) as err:
        shutil.rmtree(work, ignore_errors=True)
        raise EmulatorError(str(err)) from None
    return CRuntime(binary, mission, plan_path, naive_tracker, work)

"""Building a mission binary: the runtime's C sources plus one generated mission file.

The runtime sources ship inside the package (`gliderplan.runtime`: `include/*.h`,
`src/*.c`), so a compile works after `pip install`. Three targets: the host, the
TS-7800's ARMv5TE (ARM9) and the TS-5500's i486-class AMD Elan SC520, both static so
the binary runs on the boards' old C libraries; the TS-5500's links musl built for the
i486 (`musl-i486.sh`). Builds are cached by everything that
determines the binary: the generated source, the runtime sources, the target, the
compiler's version and the C library it links.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from gliderplan.contract import NO_BOARD, FlightLimits
from gliderplan.contract.errors import GliderplanError, UsageError
from gliderplan.contract.files import OutputFileError, output_directory, write_atomically
from gliderplan.language.codegen_c import generate_c
from gliderplan.language.ir import CheckedMission

# The contract of runtime/include/gp_mission.h: every runtime source and the mission.
C_FLAGS = ("-std=c11", "-O2", "-Wall", "-Wextra", "-Werror")
LINK_FLAGS = ("-lm",)
CACHED_BUILDS = 64  # at most ~40 MB: a static board binary is 0.6-0.7 MB, a host one 70 kB
# Written into every cache entry this module builds: the clean-up removes only entries
# that hold it, never what others keep in a cache directory they share with us.
CACHE_MARKER = ".gliderplan-build"


class BuildError(GliderplanError):
    """A build that cannot run or failed; the message says what to do."""


# How to get musl built for the i486 (the distribution's 32-bit C libraries use i686
# instructions the TS-5500 does not have).
MUSL_I486 = (f"sudo sh {Path(__file__).with_name('musl-i486.sh')} /usr/local/lib/musl-i486 "
             "/usr/local/bin  (it needs gcc-i686-linux-gnu)")


@dataclass(frozen=True)
class Target:
    """A board: its compiler command and flags, how to install the compiler, and the
    qemu-user command that runs its binaries on the board's own CPU model."""

    name: str
    compiler: str
    flags: tuple[str, ...]
    install: str
    description: str
    emulator: tuple[str, ...] = ()


TARGETS: dict[str, Target] = {
    t.name: t
    for t in (
        Target("host", "cc", (), "sudo apt-get install gcc", "this machine"),
        Target("ts7800", "arm-linux-gnueabi-gcc", ("-march=armv5te", "-static"),
               "sudo apt-get install gcc-arm-linux-gnueabi", "TS-7800, ARMv5TE (ARM9)",
               emulator=("qemu-arm", "-cpu", "arm926")),
        # musl compiled for the i486, linked statically: no i686 instruction anywhere.
        # -mpc64: the x87 rounds each result to double once, as the reference does (but
        # a subnormal result, below 2.2e-308, twice: to 53 bits, then to its fewer bits).
        Target("ts5500", "i486-linux-musl-gcc", ("-march=i486", "-mpc64", "-static"),
               MUSL_I486, "TS-5500, i486-class AMD Elan SC520",
               emulator=("qemu-i386", "-cpu", "486")),
    )
}


def find_target(name: str) -> Target:
    try:
        return TARGETS[name]
    except KeyError:
        raise BuildError(f"unknown target {name!r}; choose one of "
                         f"{', '.join(TARGETS)}") from None


def compiler_command(board: Target) -> list[str]:
    """The compiler to run, or a BuildError saying how to install it."""
    if shutil.which(board.compiler):
        return [board.compiler]
    raise BuildError(f"target {board.name} ({board.description}) needs {board.compiler}, "
                     f"which is not installed; on Debian/Ubuntu: {board.install}")


@contextmanager
def runtime_sources() -> Iterator[tuple[Path, list[Path]]]:
    """(include directory, sorted C sources) of the runtime shipped with the package."""
    with resources.as_file(resources.files("gliderplan.runtime")) as root:
        include, sources = root / "include", sorted((root / "src").glob("*.c"))
        if not (include / "gp_mission.h").is_file() or not sources:
            raise BuildError(f"the runtime's C sources are missing from {root}: "
                             "reinstall gliderplan")
        yield include, sources


def compiler_version(command: list[str]) -> str:
    try:
        done = subprocess.run([*command, "--version"], capture_output=True, text=True,
                              check=True, timeout=60)
    except (OSError, subprocess.SubprocessError) as err:
        raise BuildError(f"{command[0]} --version failed: {err}") from err
    return done.stdout


def linked_libraries_digest(command: list[str], board: Target) -> str:
    """SHA-256 of every library and start-up file the compiler links for `board`, found by
    linking an empty program with the linker's trace on: musl rebuilt for the i486, or a
    distribution's C library updated, changes the binary while the compiler's version
    stays the same. A compiler that cannot link counts as none (the build itself then
    fails with the compiler's own message)."""
    digest = hashlib.sha256()
    with tempfile.TemporaryDirectory(prefix="gliderplan-libs-") as scratch:
        program = Path(scratch) / "empty.c"
        program.write_text("int main(void) { return 0; }\n")
        try:
            traced = subprocess.run([*command, *board.flags, str(program), *LINK_FLAGS,
                                     "-o", str(Path(scratch) / "empty"), "-Wl,-t"],
                                    capture_output=True, text=True, timeout=120).stdout
        except (OSError, subprocess.SubprocessError):
            traced = ""
        for line in sorted(set(traced.split())):
            linked = Path(line.strip("()"))
            if linked.is_absolute() and linked.is_file() and scratch not in line:
                digest.update(f"{linked}:".encode())
                digest.update(hashlib.sha256(linked.read_bytes()).digest())
    return digest.hexdigest()


def build_mission(c_source_path: str | Path, out_dir: str | Path, target: str = "host") -> Path:
    """Compile the runtime with one mission's C file into `out_dir`; the binary's path.

    The binary is named after the C file (`fig2.c` -> `fig2`). Uncached: see
    `compile_mission` for the cached path from a checked mission.
    """
    c_source = Path(c_source_path)
    out = output_directory(out_dir)
    board = find_target(target)
    command = compiler_command(board)
    with runtime_sources() as (include, sources):
        _compile(command, board, include, [*sources, c_source], out / c_source.stem)
    return out / c_source.stem


def _compile(command: list[str], board: Target, include: Path, sources: list[Path],
             binary: Path) -> None:
    """Run the compiler into a temporary file, then rename: a failed build leaves nothing."""
    fd, tmp = tempfile.mkstemp(prefix=f".{binary.name}.", dir=binary.parent)
    os.close(fd)
    args = [*command, *C_FLAGS, *board.flags, f"-I{include}", *map(str, sources),
            "-o", tmp, *LINK_FLAGS]
    try:
        done = subprocess.run(args, capture_output=True, text=True, timeout=600)
        if done.returncode != 0:
            raise BuildError(f"{command[0]} failed for target {board.name} "
                             f"(exit {done.returncode}):\n{done.stderr.strip()}")
        os.chmod(tmp, 0o755)
        os.replace(tmp, binary)
    except OSError as err:
        raise BuildError(f"cannot run {command[0]}: {err}") from err
    finally:
        Path(tmp).unlink(missing_ok=True)


# ---- cached builds from a checked mission -------------------------------------------


def cache_dir() -> Path:
    """$GLIDERPLAN_CACHE_DIR, else ~/.cache/gliderplan/builds; the newest
    `CACHED_BUILDS` builds are kept."""
    configured = os.environ.get("GLIDERPLAN_CACHE_DIR")
    if configured:
        return Path(configured)
    return Path.home() / ".cache" / "gliderplan" / "builds"


def build_key(mission_c: str, include: Path, sources: list[Path], board: Target,
              command: list[str]) -> str:
    """SHA-256 over everything that determines the binary."""
    digest = hashlib.sha256()

    def part(label: str, data: bytes) -> None:
        digest.update(f"{label}:{len(data)}:".encode())
        digest.update(data)

    part("mission", mission_c.encode())
    for path in [*sorted(include.glob("*.h")), *sources]:
        part(path.name, path.read_bytes())
    part("target", repr(board).encode())
    part("flags", " ".join(C_FLAGS + LINK_FLAGS).encode())
    part("compiler", " ".join(command).encode())
    part("version", compiler_version(command).encode())
    part("libraries", linked_libraries_digest(command, board).encode())
    return digest.hexdigest()


def build_target(mission: CheckedMission, target: str | None) -> str:
    """The target to build `mission` for: `target`, else the host; UsageError for a
    mission without a board (`computer none`) and no `target`, which has nothing to
    build for unless told."""
    if target is not None:
        return target
    if mission.computer.is_none:
        raise UsageError(f"mission {mission.name} names no board (computer {NO_BOARD}): "
                         f"there is no board to build for; give --target "
                         f"{'|'.join(TARGETS)}")
    return "host"


def target_board(mission: CheckedMission, target: str) -> str:
    """The board spec a build for `target` runs on: the board of that name, or for the
    host the mission's own computer (the host stands in for it)."""
    return mission.computer.board if target == "host" else target


def refuse_missing_features(mission: CheckedMission, target: str) -> None:
    """BuildError naming the state when one of the mission's states asks the board it is
    built for for something that board's data file says it cannot do: a clock it lacks
    (`computer clock`), a sleep between ticks it cannot wake from on the serial line, a
    workload none of its clocks runs within the tick. `check` holds a
    mission to its own computer; a build for another board (`--target`) is held here."""
    if mission.computer.is_none:  # no board to set: the per-state settings are refused
        return                    # by check, the clocks are all 0
    from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, TICK_S
    from gliderplan.power_models import load_board

    spec = target_board(mission, target)
    board = load_board(spec)
    if board.is_none:
        return
    clocks = [m.clock_mhz for m in board.clock_modes]
    problems = []  # (the mission's `computer NAME @ MHZ` is the board it is planned on:
    for state in mission.states:  # building for another, to compare, is no error)
        use = state.computer
        if use.clock_mhz is not None and not board.has_clock(use.clock_mhz):
            problems.append(f"state {state.name} asks for 'computer clock "
                            f"{use.clock_mhz:g} MHz'")
        if use.sleep and (board.sleep is None or "serial" not in board.sleep.wakes_on):
            problems.append(f"state {state.name} asks to 'sleep between ticks', which the "
                            "board cannot (no sleep it wakes from on the serial line)")
        fastest = max([use.clock_mhz] if use.clock_mhz else clocks)
        capacity = fastest * 1e6 * board.cycles_per_clock * TICK_S
        if (use.cycles_per_tick or RUNTIME_CYCLES_PER_TICK) > capacity:
            problems.append(f"state {state.name}'s workload of {use.cycles_per_tick:,.0f} "
                            f"cycles is more than {capacity:,.0f} in a {TICK_S:g} s tick")
    if problems:
        raise BuildError(f"mission {mission.name} cannot run on board {board.name} (target "
                         f"{target}; clocks {board.clocks_text()} MHz): "
                         + "; ".join(problems) + ": change the mission's computer settings "
                         "or build for its own board")


def compile_mission(mission: CheckedMission, out_dir: str | Path, target: str | None = None,
                    plan_path: str | Path | None = None,
                    limits: FlightLimits | None = None,
                    key_path: str | Path | None = None) -> Path:
    """Generate the mission's C into `out_dir`/<name>.c and build `out_dir`/<name>: the
    pipeline of `gliderplan compile`, for `target` (default: `build_target`, the host).
    With `plan_path`, the plan is first checked by the runtime's own reader
    (`runtime_accepts`; with `key_path`, the key provisioned on the vehicle, its signature
    too, as the runtime checks it, and `gp_plan_check`: a plan made for another board is
    refused) and then copied beside the binary. A mission that asks the target's board for
    a clock, a sleep or a workload it cannot give is refused before anything is built.

    `limits` (the default ballast, the pump's volume, the board's clocks) are by default
    those of the mission's vehicle on the target's board (the mission's computer for the
    host). A build with the same inputs is copied from the cache instead of compiled
    again. Raises CodegenError for a mission the runtime cannot hold, PlanRejected for a
    plan it would refuse, ModelFileError for a vehicle or board that cannot be loaded,
    BuildError otherwise.
    """
    if Path(out_dir).exists() and not Path(out_dir).is_dir():
        raise UsageError(f"-o {out_dir}: not a directory")
    target = build_target(mission, target)
    board = find_target(target)
    if key_path is not None and plan_path is None:
        raise UsageError("--key: the key checks a plan's signature; give --plan too")
    refuse_missing_features(mission, target)
    if limits is None:
        from gliderplan.planner.limits import flight_limits

        limits = flight_limits(mission, None if target == "host" else target)
    if plan_path is not None:
        from gliderplan.planner.planfile import read_plan_data

        plan = read_plan_data(plan_path)
        if key_path is not None:
            from gliderplan.planner.signing import read_key

            read_key(key_path)  # a key the runtime would refuse: said here, in its words
        runtime_accepts(mission, plan_path, limits, key_path=key_path)
    source = generate_c(mission, limits)
    out = output_directory(out_dir)
    c_path = out / f"{mission.name}.c"
    if not (c_path.is_file() and c_path.read_text() == source):  # keep make's timestamps
        write_atomically(c_path, source)
    with runtime_sources() as (include, sources):
        key = build_key(source, include, sources, board, compiler_command(board))
    cached = cache_dir() / key[:2] / key / mission.name
    if cached.is_file():
        os.utime(cached.parent)  # recently used: kept longest
    else:
        build_mission(c_path, cached.parent, target)
        write_atomically(cached.parent / CACHE_MARKER, f"gliderplan build {key}\n")
        _prune_cache(cache_dir(), CACHED_BUILDS)
    binary = out / mission.name
    _copy_atomically(cached, binary)
    if plan_path is not None:
        write_atomically(out / Path(plan_path).name, plan)
    return binary


def _prune_cache(root: Path, keep: int) -> None:
    """Remove all but the `keep` most recently used builds under `root`: only entries
    this module made (they hold CACHE_MARKER), never a link or another's directory."""
    used: list[tuple[float, Path]] = []
    for entry in root.glob("??/*"):
        try:
            if not entry.is_symlink() and (entry / CACHE_MARKER).is_file():
                used.append((entry.stat().st_mtime, entry))
        except OSError:  # another process removed it meanwhile
            continue
    for _, stale in sorted(used, reverse=True)[keep:]:
        shutil.rmtree(stale, ignore_errors=True)  # another process may be removing it too


def _copy_atomically(source: Path, destination: Path) -> None:
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{destination.name[:32]}.", dir=destination.parent)
        os.close(fd)
        try:
            shutil.copy2(source, tmp)
            os.replace(tmp, destination)
        finally:
            Path(tmp).unlink(missing_ok=True)
    except OSError as err:
        raise OutputFileError(f"{destination}: cannot write: {err.strerror}") from None


# ---- checking a plan with the runtime's own reader ----------------------------------


def runtime_accepts(mission: CheckedMission, plan_path: str | Path, limits: FlightLimits,
                    timeout_s: float = 10.0, key_path: str | Path | None = None) -> None:
    """Start the mission's host binary (`limits` as for `compile_mission`; with
    `key_path`, holding that key, so that it flies signed plans only) on the plan over a
    pty; it must get as far as HELLO, else PlanRejected with the runtime's own message.

    The runtime reads its plan before it talks to the science computer, so the same
    strict reader that will run on the board decides, not a second implementation, and
    its message names the plan file and line.
    """
    import signal

    from gliderplan.planner.planfile import PlanRejected
    from gliderplan.runtime.protocol import FdPort, Link, LinkError

    with tempfile.TemporaryDirectory(prefix="gliderplan-plan-") as tmp:
        work = Path(tmp)
        binary = compile_mission(mission, work, "host", limits=limits)
        master, slave = os.openpty()
        try:
            key = [] if key_path is None else ["--key", str(Path(key_path).resolve())]
            process = subprocess.Popen(
                [str(binary), "--device", os.ttyname(slave), "--plan", str(plan_path),
                 "--state-dir", str(work / "state"), *key],
                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            link = Link(FdPort(master))
            deadline = time.monotonic() + timeout_s
            hello = False
            while not hello and process.poll() is None and time.monotonic() < deadline:
                try:
                    link.wait_hello(0.1)
                    hello = True
                except LinkError:
                    pass
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
            _, stderr = process.communicate(timeout=timeout_s)
        finally:
            os.close(master)
            os.close(slave)
    if hello:
        return
    message = stderr.decode(errors="replace").strip()
    if process.returncode == 1:
        raise PlanRejected(message or "rejected without a message")
    raise BuildError(f"the runtime neither accepted nor rejected the plan "
                     f"(exit {process.returncode}): {message}")

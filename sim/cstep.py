"""The compiled runtime's own step in this process: the simulator's default runtime.

Two shared objects, each built once with the machine's C compiler (as `compile` builds
mission binaries) and cached like them (`runtime.build.cache_dir`):
- the step library: the runtime's step sources (runtime/src: the tick, the event
  system, the pilot, the routes, the plan reader) and the simulator's C side
  (sim/flight.c), keyed by their sources, the compiler and its flags;
- a mission's tables (language/codegen_c.py), keyed by the generated source. The
  vehicle's rating is not in them but given to the step at init: the scenarios of a Monte
  Carlo draw a vehicle each, and fly one build of the mission's tables.
The library steps the mission through ctypes: a SENSORS frame's readings in, the
COMMAND out, with nothing between them but a function call. The serial link's closed
loop (sim/emulator.py, `sim --runtime c`) runs the same tick in the board binary.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import struct
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import replace
from importlib import resources
from pathlib import Path

from gliderplan.contract import (
    MAX_VARIABLES,
    N_SENSORS,
    Envelope,
    EnvelopeAction,
    FlightLimits,
    TransitionKind,
)
from gliderplan.contract.errors import GliderplanError
from gliderplan.language import ir
from gliderplan.language.codegen_c import envelope_figures
from gliderplan.language.semantics import MissionFault
from gliderplan.runtime.protocol import Command

PLAN_ERROR_LEN = 160  # GP_PLAN_ERROR_LEN
NOTE_LEN = 256  # GPS_NOTE_LEN
UPDATE_MESSAGE_LEN = 224  # GP_UPDATE_MESSAGE_LEN
SHARED_FLAGS = ("-fPIC", "-shared", "-ffp-contract=off", "-fno-builtin-sin",
                "-fno-builtin-cos")
# The runtime's sources the step needs (the tick, its envelope, the plan and its updates):
# not its link, serial line, store or main.
STEP_SOURCES = ("gp_crc.c", "gp_envelope.c", "gp_machine.c", "gp_pilot.c", "gp_plan.c",
                "gp_route.c", "gp_runtime.c", "gp_sha256.c", "gp_update.c")
SIM_SOURCES = ("step.c", "flight.c")  # the simulator's side: the step's context, the loop
LIBRARY_NAME = "gpstep"
FAULTS = {3: "overflow", 4: "underflow", 5: "bad table"}  # gp_step_result of a refusal
# the envelope compiled into a mission's tables, one the check accepts: the step flies
# the flight's own (`CStep`'s limits), so that the tables do not depend on the vehicle's
# rating
TABLES_ENVELOPE = Envelope(max_depth_m=1.0, max_pitch_rad=1.0, min_yo_band_m=0.0,
                           min_inflection_s=0.0, action=EnvelopeAction.FAULT)


class StepBuildError(GliderplanError):
    """The step library or a mission's tables could not be built (no compiler, or it
    failed); the message says what to do."""


# ---- building -----------------------------------------------------------------------

@functools.cache
def _compiler() -> tuple[tuple[str, ...], str]:
    """(the host's compiler command, its version text)."""
    from gliderplan.runtime.build import TARGETS, compiler_command, compiler_version

    command = compiler_command(TARGETS["host"])
    return tuple(command), compiler_version(command)


def _runtime_root() -> Path:
    return Path(str(resources.files("gliderplan.runtime")))


def _key(parts: Sequence[tuple[str, bytes]]) -> str:
    """SHA-256 over labelled parts: everything that determines a shared object."""
    from gliderplan.runtime.build import C_FLAGS

    command, version = _compiler()
    digest = hashlib.sha256()
    for label, data in (*parts, ("flags", " ".join(C_FLAGS + SHARED_FLAGS).encode()),
                        ("compiler", " ".join(command).encode()),
                        ("version", version.encode())):
        digest.update(f"{label}:{len(data)}:".encode())
        digest.update(data)
    return digest.hexdigest()


def build_shared(name: str, sources: Sequence[Path], out: Path, optimize: bool = True) -> Path:
    """Compile `sources` with the runtime's headers into the shared object `out`/lib`name`.so
    (a temporary file renamed: a failed build leaves nothing). StepBuildError on failure.
    `optimize` False: -O0, for code compiled once and run briefly (the same doubles: no
    contraction, no excess precision on the host)."""
    import subprocess

    from gliderplan.runtime.build import LINK_FLAGS

    command, _ = _compiler()
    out.mkdir(parents=True, exist_ok=True)
    target = out / f"lib{name}.so"
    fd, tmp = tempfile.mkstemp(prefix=f".{name}.", dir=out)
    os.close(fd)
    args = [*command, *_c_flags(optimize), *SHARED_FLAGS, f"-I{_runtime_root() / 'include'}",
            f"-I{_sim_root()}", *map(str, sources), "-o", tmp, *LINK_FLAGS]
    try:
        done = subprocess.run(args, capture_output=True, text=True, timeout=600)
        if done.returncode != 0:
            raise StepBuildError(f"{command[0]} failed to build {target.name} "
                                 f"(exit {done.returncode}):\n{done.stderr.strip()}")
        os.replace(tmp, target)
    except OSError as err:
        raise StepBuildError(f"cannot run {command[0]}: {err}") from err
    finally:
        Path(tmp).unlink(missing_ok=True)
    return target


def _c_flags(optimize: bool) -> list[str]:
    from gliderplan.runtime.build import C_FLAGS

    return [flag if optimize or not flag.startswith("-O") else "-O0" for flag in C_FLAGS]


def _cached(name: str, key: str, sources: Callable[[Path], Sequence[Path]]) -> Path:
    """The cached shared object of `key`, built from `sources(directory)` if missing."""
    from gliderplan.contract.files import write_atomically
    from gliderplan.runtime.build import (
        CACHE_MARKER,
        CACHED_BUILDS,
        _prune_cache,
        cache_dir,
    )

    entry = cache_dir() / key[:2] / key
    library = entry / f"lib{name}.so"
    if library.is_file():
        os.utime(entry)  # recently used: kept longest
        return library
    build_shared(name, sources(entry), entry)
    write_atomically(entry / CACHE_MARKER, f"gliderplan build {key}\n")
    _prune_cache(cache_dir(), CACHED_BUILDS)
    return library


def _sim_root() -> Path:
    return Path(str(resources.files("gliderplan.sim")))


def step_sources() -> list[Path]:
    """The C sources of the step library, in a fixed order."""
    root = _runtime_root()
    return [*(root / "src" / name for name in STEP_SOURCES),
            *(_sim_root() / name for name in SIM_SOURCES)]


@functools.cache
def step_library() -> ctypes.CDLL:
    """The step library, built (or found in the cache) and loaded once per process."""
    headers = [*sorted((_runtime_root() / "include").glob("*.h")),
               *sorted(_sim_root().glob("*.h"))]
    parts = [(p.name, p.read_bytes()) for p in [*headers, *step_sources()]]
    path = _cached(LIBRARY_NAME, _key(parts), lambda _: step_sources())
    return _declare(ctypes.CDLL(str(path)))


def _declare(library: ctypes.CDLL) -> ctypes.CDLL:
    pointer, size = ctypes.c_void_p, ctypes.c_size_t
    library.gps_step_size.restype, library.gps_step_size.argtypes = size, []
    library.gps_step_init.restype = ctypes.c_int
    library.gps_step_init.argtypes = [pointer, pointer, pointer, ctypes.c_char_p, size,
                                      ctypes.c_int, ctypes.c_char_p]
    library.gps_step_tick.restype = None
    library.gps_step_tick.argtypes = [pointer, ctypes.c_uint32, ctypes.c_uint32, pointer,
                                      pointer, pointer]
    for name in ("gps_step_events", "gps_step_suspends", "gps_step_plan_seq"):
        getattr(library, name).restype = ctypes.c_uint32
        getattr(library, name).argtypes = [pointer]
    for name in ("gps_step_variables", "gps_step_own_readings"):
        getattr(library, name).restype = None
        getattr(library, name).argtypes = [pointer, pointer]
    library.gps_step_entered.restype = ctypes.c_int
    library.gps_step_entered.argtypes = [pointer, ctypes.c_int, pointer]
    library.gps_step_releases.restype = ctypes.c_int
    library.gps_step_releases.argtypes = [pointer, pointer]
    library.gps_step_envelope_note.restype = None
    library.gps_step_envelope_note.argtypes = [pointer, ctypes.c_char_p]
    library.gps_step_update.restype = ctypes.c_int
    library.gps_step_update.argtypes = [pointer, ctypes.c_char_p, size, ctypes.c_char_p, size,
                                        ctypes.c_char_p, ctypes.c_char_p,
                                        ctypes.POINTER(size), ctypes.c_char_p]
    return library


def mission_tables(mission: ir.CheckedMission, limits: FlightLimits) -> int:
    """The address of the mission's compiled tables (a `gp_mission`), built with `limits`
    (the vehicle's ballast and pump, the board's clocks) but its envelope, which the step
    is given (`TABLES_ENVELOPE` in its place), or found in the cache."""
    from gliderplan.language.codegen_c import generate_c

    return _tables_address(generate_c(mission, replace(limits, envelope=TABLES_ENVELOPE)))


@functools.cache
def _tables_address(source: str) -> int:
    include = _runtime_root() / "include"
    parts = [(p.name, p.read_bytes()) for p in sorted(include.glob("*.h"))]

    def write(entry: Path) -> list[Path]:
        entry.mkdir(parents=True, exist_ok=True)
        path = entry / "mission.c"
        path.write_text(source)
        return [path]

    path = _cached("mission", _key([*parts, ("mission", source.encode())]), write)
    return tables_in(ctypes.CDLL(str(path)))


def tables_in(library: ctypes.CDLL, symbol: str = "gp_mission_table") -> int:
    """The address of the `gp_mission` named `symbol` in a loaded shared object."""
    return ctypes.addressof(ctypes.c_char.in_dll(library, symbol))


# ---- the runtime's structures (runtime/include/gp_frame.h, gp_runtime.h) ---------------

class _Command(ctypes.Structure):
    _fields_ = [("tick", ctypes.c_uint32), ("state", ctypes.c_uint8),
                ("stack_depth", ctypes.c_uint8), ("transition", ctypes.c_uint8),
                ("from_state", ctypes.c_uint8), ("to_state", ctypes.c_uint8),
                ("profile", ctypes.c_uint8), ("flags", ctypes.c_uint8),
                ("depth_target_m", ctypes.c_float), ("pitch_rad", ctypes.c_float),
                ("ballast_cc", ctypes.c_float), ("heading_rad", ctypes.c_float),
                ("sensor_power", ctypes.c_uint32), ("event_count", ctypes.c_uint32),
                ("speed_mps", ctypes.c_float), ("thrust_w", ctypes.c_float)]


class _Transition(ctypes.Structure):
    _fields_ = [("kind", ctypes.c_uint8), ("from_state", ctypes.c_uint8),
                ("to_state", ctypes.c_uint8), ("depth", ctypes.c_uint8)]


class _Breach(ctypes.Structure):
    _fields_ = [("limit", ctypes.c_uint8), ("value", ctypes.c_double),
                ("bound", ctypes.c_double)]


class _Envelope(ctypes.Structure):
    """gp_envelope (runtime/include/gp_mission.h)."""

    _fields_ = [*((name, ctypes.c_double) for name, _ in envelope_figures(TABLES_ENVELOPE)),
                ("action", ctypes.c_uint8)]

    @classmethod
    def of(cls, envelope: Envelope) -> _Envelope:
        return cls(*(value for _, value in envelope_figures(envelope)), envelope.action)


class Report(ctypes.Structure):
    """gp_tick_report: a tick's transitions, a refused event, a command outside the
    envelope."""

    _fields_ = [("transitions", _Transition * 3), ("n_transitions", ctypes.c_uint8),
                ("fault", ctypes.c_uint8), ("refused", _Transition),
                ("envelope", _Breach), ("envelope_state", ctypes.c_uint8)]


_VALUES = struct.Struct(f"<{N_SENSORS}f")


class CStep:
    """The compiled runtime's step in this process, as `sim.loop.Runtime`: the mission's
    tables (with the vehicle's and board's `limits`) and its plan (`plan_bytes`, a plan
    file's bytes, read by the runtime's own reader; None: no plan).

    After a run it reports what the Python executor does: the variables each state was
    first entered with, the events fired, the ticks after which the board slept."""

    def __init__(self, mission: ir.CheckedMission, plan_bytes: bytes | None,
                 limits: FlightLimits, naive_tracker: bool = False,
                 tables: int | None = None, context_bytes: int = 0) -> None:
        """`tables`: the address of the mission's compiled tables, if already built
        (a batch of missions in one shared object); else they are built here. Either
        way the runtime holds the commands to `limits.envelope`.
        `context_bytes`: room for a context that begins with the step's (a flight's)."""
        self.mission = mission
        self.library = library = step_library()
        self.context = ctypes.create_string_buffer(max(library.gps_step_size(),
                                                       context_bytes))
        self._tables = tables if tables is not None else mission_tables(mission, limits)
        error = ctypes.create_string_buffer(PLAN_ERROR_LEN)
        envelope = _Envelope.of(limits.envelope)  # copied into the context
        if library.gps_step_init(self.context, self._tables, ctypes.byref(envelope),
                                 plan_bytes,
                                 0 if plan_bytes is None else len(plan_bytes),
                                 int(naive_tracker), error) < 0:
            from gliderplan.planner.planfile import PlanRejected

            raise PlanRejected(f"the runtime refused the plan: {error.value.decode()}")
        self._held = plan_bytes  # the plan file in force
        self._values = ctypes.create_string_buffer(_VALUES.size)
        self._command = _Command()
        self._report = Report()
        self._tick = library.gps_step_tick
        self._fields = [name for name, _ in _Command._fields_]
        self.envelope_notes: list[str] = []  # what the envelope guard did, in its words
        self.superseded: list[tuple[int, int, int, int]] = []  # as the Python executor's

    def step(self, tick: int, mask: int, values: list[float]) -> Command:
        """Answer one SENSORS frame: `values` holds all sensors [registry units], of which
        those in `mask` arrive, through binary32 as on the link. MissionFault for an
        event the runtime refuses (a call past the stack, a return with none)."""
        _VALUES.pack_into(self._values, 0, *values)
        self._tick(self.context, tick, mask, self._values, ctypes.byref(self._command),
                   ctypes.byref(self._report))
        if self._report.fault:
            raise self._fault()
        if self._report.envelope.limit and self.note_envelope(self._report):
            raise MissionFault(f"tick {tick}: {self.envelope_notes[-1]}")
        r = self._report
        self.superseded = [(t.kind, t.from_state, t.to_state, t.depth)
                           for t in r.transitions[:max(r.n_transitions - 1, 0)]
                           if t.kind != TransitionKind.START]
        c = self._command
        return Command(c.tick, c.state, c.stack_depth, c.transition, c.from_state, c.to_state,
                       c.profile, c.flags, c.depth_target_m, c.pitch_rad, c.ballast_cc,
                       c.heading_rad, c.sensor_power, c.event_count, c.speed_mps, c.thrust_w)

    def note_envelope(self, report: Report) -> bool:
        """Keep the guard's words on a tick's breach; whether it hands control back (the
        fault action: the run ends there)."""
        note = ctypes.create_string_buffer(NOTE_LEN)
        self.library.gps_step_envelope_note(self.context, note)
        self.envelope_notes.append(note.value.decode())
        return bool(self.library.gps_step_releases(self.context, ctypes.byref(report)))

    def update_plan(self, key: bytes) -> Callable[[bytes], tuple[int, int, str]]:
        """The vehicle's side of the shore's link (sim/replanning.py): a plan update applied
        by the runtime's own `gp_update_apply` with the vehicle's `key` to the plan file in
        force, flown from the next tick; returns the verdict (contract.UpdateStatus, the
        plan in force after it, its words)."""
        from gliderplan.contract import MAX_PLAN_BYTES, UpdateStatus

        out = ctypes.create_string_buffer(MAX_PLAN_BYTES)
        message = ctypes.create_string_buffer(UPDATE_MESSAGE_LEN)
        size = ctypes.c_size_t()

        def deliver(update: bytes) -> tuple[int, int, str]:
            held = self._held or b""
            status = UpdateStatus(self.library.gps_step_update(
                self.context, update, len(update), held, len(held), key, out,
                ctypes.byref(size), message))
            if status == UpdateStatus.APPLIED:
                self._held = out.raw[:size.value]
            return status, self.library.gps_step_plan_seq(self.context), \
                message.value.decode()

        return deliver

    def _fault(self) -> MissionFault:
        return MissionFault(fault_message(self.mission, self._report,
                                          _VALUES.unpack(self._values.raw)[0]))

    # ---- what the runtime holds ----------------------------------------------------

    @property
    def events_fired(self) -> int:
        """Events fired so far (transitions and assignments), as its COMMANDs count them."""
        return self.library.gps_step_events(self.context)

    @property
    def suspends(self) -> int:
        """Ticks after which the board slept until the next frame."""
        return self.library.gps_step_suspends(self.context)

    @property
    def variables(self) -> dict[str, float]:
        """The mission's variables now."""
        values = (ctypes.c_double * MAX_VARIABLES)()
        self.library.gps_step_variables(self.context, values)
        return {v.name: values[i] for i, v in enumerate(self.mission.variables)}

    @property
    def entry_variables(self) -> dict[str, dict[str, float]]:
        """State -> the variables as it was first entered (the states entered so far)."""
        values = (ctypes.c_double * MAX_VARIABLES)()
        entered = {}
        for i, state in enumerate(self.mission.states):
            if self.library.gps_step_entered(self.context, i, values):
                entered[state.name] = {v.name: values[k]
                                       for k, v in enumerate(self.mission.variables)}
        return entered

    def own_readings(self) -> tuple[float, float, float]:
        """(halfcycle, wptdist, wptreached) as the last tick's events saw them (wptdist
        NaN unless the mission reads it: the runtime works it out only then)."""
        values = (ctypes.c_double * 3)()
        self.library.gps_step_own_readings(self.context, values)
        return values[0], values[1], values[2]


def fault_message(mission: ir.CheckedMission, report: Report, time_s: float) -> str:
    """The event the runtime refused at missiontime `time_s` [s], in the words of the
    reference semantics (language/semantics.py)."""
    refused, names = report.refused, [s.name for s in mission.states]
    here = names[refused.from_state]
    if FAULTS.get(report.fault) == "overflow":
        return (f"{time_s:g} s: call {names[refused.to_state]} from {here} overflows the "
                f"state stack ({mission.stack_depth})")
    if FAULTS.get(report.fault) == "underflow":
        return f"{time_s:g} s: return from {here} with an empty stack"
    return f"{time_s:g} s: an event of {here} targets no state"

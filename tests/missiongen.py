"""Missions drawn at random, for the differential tests of the runtime's step
(tests/test_step_generated.py) and `make mutants`.

A mission is a few states of two kinds: states entered by `goto` (the first, the start
state, among them), which never `return`, and states entered by `call`, which may, and
which call only states after them (so calls nest without a cycle, as deep as the
mission's declared stack). Events read every sensor of the array, the mission's
variables and the functions of the language, assign variables, and `goto`, `call`,
`return` or `exit`; the states fly every profile (their arguments constants or
variables) along every route, sleep between ticks or set a clock. Half the missions fly
a plan: sensor duty cycles and profile shares.

Readings are drawn from a seed, tick by tick, as a science computer would send them:
depths along a random walk, positions around the route's points (so that waypoints are
reached), a battery that may run down to its reserve, devices whose readings stop
arriving, values that are missing (NaN).
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import dataclass

import numpy as np
from hypothesis import strategies as st

from gliderplan.contract import N_SENSORS, RUNTIME_READINGS_MASK
from gliderplan.language.registry import SENSOR_BY_NAME, SENSORS

# The range each sensor's readings are drawn in (and conditions compare against).
RANGES = {
    "missiontime": (0.0, 800.0), "depth": (0.0, 60.0), "pitch": (-0.6, 0.6),
    "roll": (-0.2, 0.2), "heading": (0.0, 6.28), "altitude": (0.0, 20.0),
    "lat": (3909.5, 3910.5), "lon": (-7350.0, -7349.0), "battery": (14.0, 16.0),
    "temp": (6.0, 24.0), "conductivity": (3.0, 5.0), "salinity": (33.0, 36.0),
    "oxygen": (200.0, 300.0), "chlorophyll": (0.0, 3.0), "backscatter": (0.0, 0.01),
    "current": (0.0, 0.5), "modem": (0.0, 100.0), "halfcycle": (0.0, 8.0),
    "wptdist": (0.0, 400.0), "timeofday": (0.0, 86400.0), "energy_left": (0.0, 36000.0),
    "wptreached": (0.0, 4.0), "groundspeed": (0.0, 0.5), "shear": (0.0, 0.05),
}
assert set(RANGES) == {s.name for s in SENSORS}
NAMES = tuple(s.name for s in SENSORS)
# Route points: a few hundred metres apart, DDMM.MMMM
POINTS = ((3910.0, -7349.8), (3910.1, -7349.6), (3909.9, -7349.5), (3910.2, -7349.9),
          (3909.8, -7349.7))
BATTERY_J = 36000.0  # `battery 10 Wh`
TICKS = 150


@dataclass(frozen=True)
class Case:
    """One generated case: a mission's source, its plan (None: none), the seed of its
    readings, the tick [s] and the tracker."""

    source: str
    plan: list | None  # the schedule `plans` draws (plan_text writes its file)
    seed: int
    tick_s: float
    naive: bool

    def to_json(self) -> dict:
        return {"source": self.source, "plan": self.plan, "seed": self.seed,
                "tick_s": self.tick_s, "naive": self.naive}


def _number(draw, low: float, high: float) -> str:
    value = draw(st.floats(low, high, allow_nan=False, allow_infinity=False))
    return repr(round(value, draw(st.integers(0, 3))))


@st.composite
def expressions(draw, variables: tuple[str, ...], depth: int = 0) -> str:
    """A value: a reading, a variable, a number, arithmetic and the functions."""
    leaves = [st.sampled_from(NAMES)]
    if variables:
        leaves.append(st.sampled_from(variables))
    leaves.append(st.builds(lambda x: repr(x), st.integers(-5, 60)))
    if depth >= 2 or draw(st.integers(0, 2)) == 0:
        return draw(st.one_of(leaves))
    kind = draw(st.integers(0, 4))
    a = draw(expressions(variables, depth + 1))
    b = draw(expressions(variables, depth + 1))
    if kind == 0:
        return f"({a} {draw(st.sampled_from('+-*/'))} {b})"
    if kind == 1:
        return f"{draw(st.sampled_from(['min', 'max', 'mod']))}({a}, {b})"
    if kind == 2:
        return f"abs({a})"
    if kind == 3:
        return f"-{a}"
    return f"({a} + {b})"


@st.composite
def conditions(draw, variables: tuple[str, ...], depth: int = 0) -> str:
    """A condition that holds now and then: a reading against a threshold in its range,
    a variable, the time on a period, and their combinations."""
    kind = draw(st.integers(0, 7 if depth < 2 else 3))
    if kind <= 1:
        name = draw(st.sampled_from(NAMES))
        low, high = RANGES[name]
        op = draw(st.sampled_from(["<", "<=", ">", ">=", "==", "!="]))
        return f"{name} {op} {_number(draw, low, high)}"
    if kind == 2:
        period = draw(st.sampled_from([8, 12, 20, 40, 100]))
        return f"mod(missiontime, {period}) {draw(st.sampled_from(['<', '>=', '==']))} " \
               f"{draw(st.integers(0, period - 1))}"
    if kind == 3:
        if not variables:
            return f"missiontime >= {draw(st.integers(0, 600))}"
        return f"{draw(st.sampled_from(variables))} {draw(st.sampled_from(['<', '>', '==']))} " \
               f"{draw(st.integers(-2, 12))}"
    if kind == 4:
        return f"{draw(expressions(variables))} {draw(st.sampled_from(['<', '>=']))} " \
               f"{draw(expressions(variables))}"
    if kind == 5:
        return f"!({draw(conditions(variables, depth + 1))})"
    op = "&&" if kind == 6 else "||"
    return f"({draw(conditions(variables, depth + 1))} {op} " \
           f"{draw(conditions(variables, depth + 1))})"


@st.composite
def profiles(draw, variables: tuple[str, ...]) -> str:
    kind = draw(st.integers(0, 5))
    low = draw(st.integers(0, 10))
    high = low + draw(st.integers(3, 40))  # check refuses a band thinner than the envelope's 3 m
    pitch = draw(st.sampled_from([".3", ".454", ".6"]))
    band = (f"{low}, {high}" if "top" not in variables or draw(st.booleans())
            else "top, bottom")
    if kind <= 1:
        stop = ", " + draw(st.sampled_from(["0", "2", "4.5"])) if kind else ""
        return f"yo({band}, {pitch}, {draw(st.sampled_from(['.3', '.454']))}{stop})"
    if kind == 2:
        stop = ", " + draw(st.sampled_from(["3", "0"])) if draw(st.booleans()) else ""
        return (f"thermotrackyo({band}, {pitch}, .454, {draw(st.integers(1, 6))}, "
                f"{draw(st.integers(2, 8))}{stop})")
    if kind == 3:
        return "surface"
    return f"hover({draw(st.integers(0, 30))})"


def _points(draw, count: int) -> str:
    return ", ".join(f"({lat}, {lon})" for lat, lon in
                     draw(st.lists(st.sampled_from(POINTS), min_size=count, max_size=count)))


@st.composite
def routes(draw) -> str:
    kind = draw(st.integers(0, 4))
    if kind == 0:
        lat, lon = draw(st.sampled_from(POINTS))
        return f"nav({lat}, {lon})"
    if kind == 1:
        return "noheading"
    if kind == 2:
        return f"waypoints({_points(draw, draw(st.integers(1, 4)))})"
    if kind == 3:
        return f"goto_list({draw(st.integers(30, 120))}, {_points(draw, draw(st.integers(1, 3)))})"
    corners = draw(st.lists(st.sampled_from(POINTS), min_size=3, max_size=4, unique=True))
    return (f"sweep({draw(st.integers(40, 300))}, "
            + ", ".join(f"({a}, {b})" for a, b in corners) + ")")


@st.composite
def missions(draw) -> tuple[str, list[dict]]:
    """(the source, per state what a plan needs: sensors logged, alternatives, sleep)."""
    deep = draw(st.integers(0, 9)) == 0
    n_goto = draw(st.integers(1, 3))
    n_call = 31 if deep else draw(st.integers(0, 4))
    gotos = [f"g{i}" for i in range(n_goto)]
    calls = [f"c{i}" for i in range(n_call)]
    variables = tuple(draw(st.sampled_from([(), ("v0",), ("v0", "v1"), ("v0", "top", "bottom"),
                                            ("v0", "v1", "top", "bottom")])))
    lines = ["mission generated"]
    if draw(st.integers(0, 3)) == 0:
        lines.append("computer none")
    sleeps_allowed = "computer none" not in lines
    lines.append(f"battery 10 Wh reserve {draw(st.sampled_from([0, 10, 50]))}%")
    initial = {"top": "4", "bottom": "30"}
    for name in variables:
        lines.append(f"var {name} = {initial.get(name) or draw(st.integers(-3, 10))}")
    depth = n_call + 1 if deep else draw(st.integers(max(n_call, 1), 8))
    lines.append(f"stack {depth}")
    info = []
    names = gotos + calls
    for name in names:
        is_call = name in calls
        callable_ = calls[calls.index(name) + 1:] if is_call else calls
        if deep and is_call:
            callable_ = callable_[:1]
        if deep and is_call:  # a link of the long chain: a call on and a return
            lines += ["", *_link(draw, name, callable_)]
            info.append({"logged": ["missiontime", "depth"], "alternatives": 1,
                         "sleep": False})
            continue
        logged = ["missiontime", "depth", *draw(st.lists(st.sampled_from(NAMES), max_size=6,
                                                         unique=True))]
        logged = list(dict.fromkeys(logged))
        alternatives = draw(st.lists(profiles(variables), min_size=1, max_size=2))
        state = [f"state {name}", "begin", f"  flightroute {draw(routes())}",
                 "  flightprofile " + " | ".join(alternatives),
                 "  sensors " + ", ".join(logged)]
        sleep = sleeps_allowed and draw(st.integers(0, 3)) == 0
        if sleep:
            state.append("  computer sleep between ticks")
        events = []
        for _ in range(draw(st.integers(1, 4))):
            actions = ["exit", "none"] + [f"goto {g}" for g in gotos]
            actions += [f"call {c}" for c in callable_] * 2
            if is_call:
                actions += ["return"] * 2
            action = draw(st.sampled_from(actions))
            sets = ""
            if variables and (action == "none" or draw(st.booleans())):
                assigned = draw(st.lists(st.sampled_from(variables), min_size=1, max_size=2,
                                         unique=True))
                sets = " set " + ", ".join(f"{v} = {draw(expressions(variables))}"
                                          for v in assigned)
            elif action == "none":
                action = "exit"
            events.append(f"    case {draw(conditions(variables))}{sets}"
                          + ("" if action == "none" else f" {action}"))
        state += ["  events", *events, "end"]
        lines += ["", *state]
        info.append({"logged": logged, "alternatives": len(alternatives), "sleep": sleep})
    return "\n".join(lines) + "\n", info


def _link(draw, name: str, callable_: list[str]) -> list[str]:
    """A state of a long chain of calls: it calls the next now and then, and returns."""
    period = draw(st.sampled_from([2, 3, 5]))
    events = [f"    case mod(missiontime, {period * 4}) < {period * 2} call {callable_[0]}"
              if callable_ else "    case missiontime > 300 exit",
              f"    case depth > {draw(st.integers(10, 50))} return"]
    return [f"state {name}", "begin", "  flightroute noheading",
            "  flightprofile yo(3, 20, .454, .454)", "  sensors missiontime, depth",
            "  events", *events, "end"]


@st.composite
def cases(draw) -> Case:
    """A mission, maybe a plan for it, and its readings' seed, tick and tracker."""
    source, info = draw(missions())
    plan = None
    if draw(st.booleans()):
        plan = draw(plans(info))
    return Case(source, plan, draw(st.integers(0, 2**32 - 1)),
                draw(st.sampled_from([4.0, 2.0, 0.5, 3.7])), draw(st.booleans()))


@st.composite
def plans(draw, info: list[dict]) -> list[tuple]:
    """A plan's schedule per state (the file is written for the checked mission):
    (cycle [s], sleep, per device sensor (name, period [s], on [s]), per alternative
    (share, pitch [rad], ballast [cc]))."""
    schedule = []
    for state in info:
        sensors = [(name, period, min(period, draw(st.integers(0, 300))))
                   for name in state["logged"] if SENSOR_BY_NAME[name].device
                   for period in [draw(st.integers(10, 300))]]
        weights = [draw(st.integers(0, 4)) for _ in range(state["alternatives"])]
        if not any(weights):
            weights[0] = 1
        shares = [w / sum(weights) for w in weights]
        alternatives = [(share, draw(st.sampled_from([0.3, 0.454, 0.6])),
                         draw(st.sampled_from([100.0, 150.0, 233.0]))) for share in shares]
        sleep = state["sleep"] and draw(st.booleans())
        schedule.append((draw(st.integers(60, 600)), sleep, sensors, alternatives))
    return schedule


def plan_text(mission, schedule: list[tuple], clock_mhz: float, limits) -> bytes:
    """The plan file of a drawn schedule for a checked mission, held to the mission's
    `limits` as every plan is (contract.plan_check): its budget the battery less its
    reserve, its prediction its states' sum, each glide's pitch and volume within the
    vehicle's."""
    computer = "none 0" if mission.computer.is_none else f"{mission.computer.board} " \
                                                         f"{clock_mhz:g}"
    state_j = min(1000.0, limits.max_budget_j / (2 * len(mission.states)))
    low, high = limits.pitch_range_rad
    lines = ["GPPLAN 3", f"mission {mission.name}", f"hash {mission.hash}",
             f"computer {computer}", f"budget_j {limits.max_budget_j:.9g}",
             f"predicted_j {state_j * len(mission.states):.9g}",
             "components hotel", "assumptions 0", f"states {len(mission.states)}"]
    for s, (state, (cycle, sleep, sensors, alternatives)) in enumerate(
            zip(mission.states, schedule, strict=True)):
        clock = 0 if mission.computer.is_none else clock_mhz
        lines.append(f"state {state.name} {clock:g} {cycle} {len(sensors)} "
                     f"{len(alternatives)}")
        if sleep:
            lines.append("power 1 200000")
        lines += [f"predict {state_j:.9g} 1 10", f"energy {state_j:.9g}"]
        lines += [f"sensor {name} {period} {on}" for name, period, on in sensors]
        shares = [format(share, ".9g") for share, _, _ in alternatives]
        for k, (share, (_, pitch, ballast)) in enumerate(zip(shares, alternatives,
                                                             strict=True)):
            least = limits.min_ballast_cc[s][k] if limits.min_ballast_cc else 0.0
            pitch = min(max(pitch, low + 0.01), high - 0.01)
            ballast = min(max(ballast, math.floor(least) + 1.0), limits.max_ballast_cc)
            lines.append(f"profile {k} {share} {pitch:g} {ballast:g} 0.3")
        lines.append("end")
    body = "".join(line + "\n" for line in lines).encode()
    return body + f"crc32 {zlib.crc32(body):08x}\n".encode()


def readings(seed: int, tick_s: float, ticks: int = TICKS
             ) -> tuple[np.ndarray, np.ndarray]:
    """(masks (ticks,), values (ticks, N_SENSORS)): what a science computer sends each
    tick, drawn from `seed`."""
    rng = np.random.default_rng(seed)
    values = np.empty((ticks, N_SENSORS))
    for name, (low, high) in RANGES.items():
        values[:, SENSOR_BY_NAME[name].index] = rng.uniform(low, high, ticks)
    index = SENSOR_BY_NAME
    values[:, index["missiontime"].index] = np.arange(ticks) * tick_s
    depth = np.cumsum(rng.normal(0.0, 2.0, ticks)) + rng.uniform(0.0, 40.0)
    values[:, index["depth"].index] = np.abs(depth)
    temp = 24.0 - 0.4 * np.abs(depth) + rng.normal(0.0, 0.5, ticks)
    values[:, index["temp"].index] = temp
    # positions about the route's points: within tens of metres of one now and then
    centre = np.array(POINTS)[rng.integers(0, len(POINTS), ticks)]
    spread = rng.choice([0.002, 0.02, 0.2], ticks)[:, None]  # [DDMM minutes]
    position = centre + rng.normal(0.0, 1.0, (ticks, 2)) * spread
    values[:, index["lat"].index], values[:, index["lon"].index] = position.T
    values[:, index["altitude"].index] = np.where(rng.random(ticks) < 0.3, math.nan,
                                                  rng.uniform(0.0, 12.0, ticks))
    used = rng.uniform(0.0, 1.3) * BATTERY_J
    values[:, index["energy_left"].index] = BATTERY_J - used * np.arange(ticks) / ticks
    values[:, index["timeofday"].index] = np.fmod(rng.uniform(0, 86400.0)
                                                  + np.arange(ticks) * tick_s, 86400.0)
    missing = rng.random((ticks, N_SENSORS)) < 0.02
    missing[:, index["missiontime"].index] = False
    values[missing] = math.nan
    sent = (1 << N_SENSORS) - 1 & ~RUNTIME_READINGS_MASK
    masks = np.full(ticks, sent, np.int64)
    dropped = rng.random(ticks) < 0.2  # some devices' readings stop arriving
    masks[dropped] &= rng.integers(0, 1 << N_SENSORS, dropped.sum()) | 0b11
    return masks, values


# ---- stepping a case under both implementations ------------------------------------------

def checked(case: Case):
    """(the checked mission, its plan file's bytes or None); AssertionError with the
    checker's diagnostics if the generator drew a mission the checker refuses."""
    from gliderplan.language import check_source

    result = check_source(case.source, "generated.mission")
    assert result.mission is not None, result.render() + "\n" + case.source
    mission = result.mission
    if case.plan is None:
        return mission, None
    return mission, plan_text(mission, case.plan, mission.computer.clock_mhz or 0.0,
                              limits_of(mission))


def limits_of(mission):
    from gliderplan.planner.limits import flight_limits

    return flight_limits(mission)


def _bits(x: float, f32: bool = False) -> bytes:
    """The number's bits, every NaN alike: the language has one NaN, whose sign and
    payload nothing reads (C's fmod(38, -0.0) is x86's negative NaN, Python's positive)."""
    if x != x:
        return b"NaN"
    return struct.pack("<f" if f32 else "<d", x)


def compare(case: Case, mission, plan_bytes: bytes | None, tables: int | None = None) -> None:
    """Step `mission` (and its plan) on the case's readings under the Python reference
    executor and the compiled runtime's step (`tables`: the address of its compiled
    tables, else built here): AssertionError at the first tick on which they differ, in
    the COMMAND, the runtime's own readings or a refused event; then in the envelope
    guard's words, the variables, the variables each state was entered with, the events
    fired and the board's sleeps."""
    from gliderplan.contract import NO_STATE, TransitionKind
    from gliderplan.language.codegen_c import own_read_mask
    from gliderplan.language.semantics import MissionFault
    from gliderplan.planner.planfile import read_plan_bytes
    from gliderplan.sim.cstep import CStep
    from gliderplan.sim.executor import PythonRuntime

    limits = limits_of(mission)
    plan = None if plan_bytes is None else read_plan_bytes(plan_bytes, mission)
    reference = PythonRuntime(mission, plan, limits.default_ballast_cc, not case.naive,
                              limits.max_ballast_cc, limits.envelope, limits)
    step = CStep(mission, plan_bytes, limits, case.naive, tables)
    reads_distance = own_read_mask(mission) >> SENSOR_BY_NAME["wptdist"].index & 1
    own = [SENSOR_BY_NAME[n].index for n in ("halfcycle", "wptdist", "wptreached")]
    masks, values = readings(case.seed, case.tick_s)
    live = True
    for tick in range(len(masks)):
        mask, row = int(masks[tick]), values[tick].tolist()
        answers = []
        for runtime in (reference, step):
            try:
                answers.append(runtime.step(tick, mask, row))
            except MissionFault as fault:
                answers.append(f"fault: {fault}")
        expected, got = answers
        where = f"tick {tick}"
        if isinstance(expected, str) or isinstance(got, str):
            assert expected == got, f"{where}: reference {expected!r}, step {got!r}"
            return
        for name in expected._fields:
            a, b = getattr(expected, name), getattr(got, name)
            same = _bits(a, True) == _bits(b, True) if isinstance(a, float) else a == b
            assert same, f"{where}: COMMAND {name}: reference {a!r}, step {b!r}"
        if live and expected.transition != TransitionKind.RESERVE:
            halfcycle, distance, reached = step.own_readings()
            theirs = [reference.s[i] for i in own]
            assert _bits(halfcycle) == _bits(theirs[0]), f"{where}: halfcycle"
            assert _bits(reached) == _bits(theirs[2]), f"{where}: wptreached"
            if reads_distance:
                assert _bits(distance) == _bits(theirs[1]), f"{where}: wptdist"
        live = expected.state != NO_STATE
    assert reference.envelope_notes == step.envelope_notes, "the envelope guard's words"
    assert reference.event_count == step.events_fired
    assert reference.suspends == step.suspends, "suspends"
    variables = reference.machine.variables if reference.machine else {}
    assert {k: _bits(v) for k, v in variables.items()} == \
        {k: _bits(v) for k, v in step.variables.items()}, "variables"
    assert {s: {k: _bits(v) for k, v in d.items()} for s, d in
            reference.entry_variables.items()} == \
        {s: {k: _bits(v) for k, v in d.items()} for s, d in step.entry_variables.items()}, \
        "variables on entry"

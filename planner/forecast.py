"""What a mission will cost on a glider, as it will be flown: `gliderplan forecast`.

The mission's timeline is walked as `plan` walks it (`occupancy`): the time in each state
and its visits. Each state is then billed as the glider flies it without a plan, with the
vehicle's own figures (calibrated from its logs, or a preset):

- a yo: the commanded band (a `thermotrackyo` at the band it flies on average, as the
  planner takes it; over a known sea floor, `--floor` or the logs of `--ocean`, a dive with
  an altimeter stop turns at min(max_depth, floor - altitude), the floor's median), pitch
  and the pump's full stroke (what the glider pumps unplanned),
  through the water given (`--ocean`), at the vehicle's gliding load by device
  (`power_models.devices`: the base, the fin, each instrument the state logs at its duty;
  an instrument the hotel load holds that the state does not run is taken out), and its
  pump and pitch energy per yo;
- a surfacing: the GPS fix and the Iridium call at the vehicle's figures; the glider stays
  at least until its call ends, however short the mission's wait, the time taken from the
  states it glides in;
- hover: the gliding load;
- the computer: the mission's board at its clock and work per tick, or nothing for
  `computer none` (the glider's own computers, in the base load).

The 90 % interval draws the vehicle's figures from its uncertainty (fitted figures with
their bootstrap sd, published figures with the sd of their published span), forecasts each
draw, and adds the drift of the base load between deployments (a forecast is always for
another deployment than the calibration's: `Vehicle.base_drift_w`, or the stated default
`deployments.DEFAULT_DRIFT_W` where the file gives none, for the time the glider glides).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.contract import DEFAULT_HORIZON_S, RUNTIME_CYCLES_PER_TICK, TICK_S, Component
from gliderplan.language import ir
from gliderplan.language.registry import SENSOR_BY_NAME
from gliderplan.planner.occupancy import DEFAULT_HORIZON_NOTE, Occupancy, mission_occupancy
from gliderplan.planner.rates import altimeter_note, ballasted_in, floored_args, yo_band
from gliderplan.power_models import load_board, load_vehicle
from gliderplan.power_models.deployments import DEFAULT_DRIFT_W, DRIFT_SOURCE
from gliderplan.power_models.devices import gliding_power_w, held_instruments
from gliderplan.power_models.draws import DEFAULT_DRAWS, DEFAULT_SEED, draw_vehicles
from gliderplan.power_models.flight import DensityProfile
from gliderplan.power_models.forecast import INTERVAL_LEVEL
from gliderplan.power_models.vehicle import Vehicle, flying_yo

if TYPE_CHECKING:
    from gliderplan.planner.surfacings import Surfacing
    from gliderplan.sim.currents import CurrentField
    from gliderplan.sim.ocean import SeaFloor

@dataclass(frozen=True)
class StateBill:
    """One state's time [s], visits, yos and surfacings, and energy [J] by device."""

    time_s: float
    visits: int
    yos: float
    surfacings: float
    gliding_s: float  # [s] of it the glider glides (its base load runs, and drifts)
    energy_j: dict[str, float]


@dataclass(frozen=True)
class MissionForecast:
    mission: str
    vehicle: str
    computer: str
    duration_s: float
    states: dict[str, StateBill]
    interval_j: tuple[float, float]  # central INTERVAL_LEVEL of the energy [J]
    assumptions: tuple[str, ...]
    yos_interval: tuple[float, float] = (math.nan, math.nan)  # and of the yos flown
    defaults: tuple[str, ...] = ()  # what the forecast took by default: "horizon 30 d", ...
    # where and when it surfaces (planner.surfacings): given a start
    positions: tuple[Surfacing, ...] = ()
    start_epoch_s: float = 0.0  # [s since 1970] when it starts, for the surfacings' times
    currents: CurrentField | None = None  # the field the surfacings were flown in

    @property
    def energy_j(self) -> float:
        return float(sum(self.devices_j.values()))

    @property
    def devices_j(self) -> dict[str, float]:
        """Energy [J] by device and component over the mission."""
        total: dict[str, float] = {}
        for bill in self.states.values():
            for k, v in bill.energy_j.items():
                total[k] = total.get(k, 0.0) + v
        return total

    @property
    def yos(self) -> float:
        return float(sum(b.yos for b in self.states.values()))

    @property
    def surfacings(self) -> float:
        return float(sum(b.surfacings for b in self.states.values()))

    def to_json(self) -> dict:
        return {
            "mission": self.mission, "vehicle": self.vehicle, "computer": self.computer,
            "energy_j": self.energy_j, "energy_interval_j": list(self.interval_j),
            "interval_level": INTERVAL_LEVEL, "duration_s": self.duration_s,
            "yos": self.yos, "yos_interval": list(self.yos_interval),
            "surfacing_count": self.surfacings,
            "surfacings": [p.to_json() for p in self.positions], "devices": self.devices_j,
            "states": {name: {"time_s": b.time_s, "visits": b.visits, "yos": b.yos,
                              "surfacings": b.surfacings, "energy_j": b.energy_j}
                       for name, b in self.states.items()},
            "assumptions": list(self.assumptions), "defaults": list(self.defaults),
        }


def instruments(state: ir.State) -> dict[str, float]:
    """The instruments (power-model devices) a state runs -> duty [1]: a sensor's fixed
    duty, else always on (`duty auto` without a plan is flown always on, as `sim` flies
    it); a device serving several sensors runs at the largest of their duties."""
    run: dict[str, float] = {}
    for use in state.sensors:
        device = SENSOR_BY_NAME[use.name].device
        if device is not None:
            duty = float(use.duty) if isinstance(use.duty, int | float) else 1.0
            run[device] = max(run.get(device, 0.0), duty)
    return run


def _yo(vehicle: Vehicle, state: ir.State, occupancy: Occupancy, time_s: float,
        ocean: DensityProfile | None, floor_m: float | None = None) -> StateBill:
    profile = state.profiles[0]
    args = floored_args(profile.kind, _args(state, occupancy), floor_m)
    low, high = yo_band(profile, args)
    if not (math.isfinite(low) and math.isfinite(high) and 0.0 <= low < high):
        low, high = vehicle.nominal_min_depth_m, vehicle.nominal_max_depth_m
    pitch = 0.5 * (args[2] + args[3]) if all(map(math.isfinite, args[2:4])) \
        else vehicle.nominal_pitch_rad
    with flying_yo(state.place, vehicle, low, high):
        cycle_s, actuators_j, _ = vehicle.yo_cycle(low, high, pitch,
                                                   vehicle.unplanned_ballast_cc, ocean)
    cycles = time_s / float(cycle_s)
    pitch_j = 2.0 * vehicle.pitch_energy_j * cycles
    energy = {d: w * time_s for d, w in gliding_power_w(vehicle, instruments(state)).items()}
    energy[Component.PUMP] = float(actuators_j) * cycles - pitch_j
    energy[Component.PITCH] = pitch_j
    return StateBill(time_s, occupancy.visits[state.name], cycles, 0.0, time_s, energy)


def _args(state: ir.State, occupancy: Occupancy) -> tuple[float, ...]:
    """The arguments of the state's (first) profile, at its variables' values."""
    return tuple(ir.evaluate(a, {}, occupancy.variables[state.name])
                 for a in state.profiles[0].args)


def _surface(vehicle: Vehicle, state: ir.State, occupancy: Occupancy, time_s: float
             ) -> StateBill:
    """A surfacing state: each visit a GPS fix then the Iridium call, at least as long as
    they take; the rest of the stay at the surface power."""
    visits = occupancy.visits[state.name]
    stay = max(time_s / max(visits, 1), vehicle.surface_s + vehicle.iridium_s)
    call = min(max(stay - vehicle.surface_s, 0.0), vehicle.iridium_s)
    energy = {Component.SURFACE: visits * (vehicle.surface_w * (stay - call)
                                           + vehicle.surfacing_fixed_j),
              Component.IRIDIUM: visits * vehicle.iridium_w * call}
    return StateBill(visits * stay, visits, 0.0, float(visits), 0.0, energy)


def _hover(vehicle: Vehicle, state: ir.State, occupancy: Occupancy, time_s: float
           ) -> StateBill:
    energy = {d: w * time_s for d, w in gliding_power_w(vehicle, instruments(state)).items()}
    return StateBill(time_s, occupancy.visits[state.name], 0.0, 0.0, time_s, energy)


@dataclass(frozen=True)
class ComputerDraw:
    """What the mission's board draws: [W] in each state (0 for `computer none`) and [J]
    its boot. It does not depend on the vehicle: read once for all the drawn vehicles."""

    state_w: dict[str, float]
    boot_j: float


def computer_draw(mission: ir.CheckedMission) -> ComputerDraw:
    """The board's draw in each state of `mission` (its board file read once)."""
    c = mission.computer
    board = load_board(c.board, c.clock_mhz)
    state_w = {}
    for state in mission.states:
        use = state.computer
        at = board.at_clock(use.clock_mhz) if use.clock_mhz else board
        power = float(at.mean_power_w(use.cycles_per_tick or RUNTIME_CYCLES_PER_TICK, TICK_S,
                                      use.sleep and at.sleep is not None))
        state_w[state.name] = at.active_w if math.isnan(power) else power
    return ComputerDraw(state_w, board.boot_j)


def bill_states(mission: ir.CheckedMission, vehicle: Vehicle, occupancy: Occupancy,
                ocean: DensityProfile | None = None, floor_m: float | None = None,
                computer: ComputerDraw | None = None) -> dict[str, StateBill]:
    """Each state of `mission` flown by `vehicle` for the time `occupancy` gives it, over
    a sea floor `floor_m` [m] deep (None: unknown); `computer`: the board's draw
    (default: read from the mission's board)."""
    computer = computer or computer_draw(mission)
    bills: dict[str, StateBill] = {}
    for state in mission.states:
        time_s = occupancy.time_s.get(state.name, 0.0)
        if time_s <= 0.0:
            continue
        kind = state.profiles[0].kind
        if kind in ("yo", "thermotrackyo"):
            bills[state.name] = _yo(vehicle, state, occupancy, time_s, ocean, floor_m)
        elif kind == "surface":
            bills[state.name] = _surface(vehicle, state, occupancy, time_s)
        else:
            bills[state.name] = _hover(vehicle, state, occupancy, time_s)
    # a surfacing longer than the mission's wait takes its time from the glides
    extra = sum(b.time_s for b in bills.values()) - sum(occupancy.time_s.values())
    gliding = sum(b.gliding_s for b in bills.values())
    if extra > 0.0 and gliding > 0.0:
        keep = max(1.0 - extra / gliding, 0.0)
        bills = {name: _scaled(b, keep) if b.gliding_s > 0.0 else b
                 for name, b in bills.items()}
    first = True
    for state in mission.states:
        if state.name in bills:
            bill = bills[state.name]
            joules = computer.state_w[state.name] * bill.time_s + (
                computer.boot_j if first else 0.0)
            first = False
            bills[state.name] = replace(bill, energy_j={**bill.energy_j,
                                                        Component.COMPUTER: joules})
    return bills


def _scaled(bill: StateBill, share: float) -> StateBill:
    return StateBill(bill.time_s * share, bill.visits, bill.yos * share, bill.surfacings,
                     bill.gliding_s * share, {k: v * share for k, v in bill.energy_j.items()})


def load_forecast_mission(path: str, mafiles: str | None = None
                          ) -> tuple[ir.CheckedMission, tuple[str, ...]]:
    """(the checked mission, warnings) of a gliderplan mission file, or of a Slocum `.mi`
    translated as `import-slocum` translates it (its warnings: what it could not carry,
    each "import-slocum: FILE:LINE: warning: ...")."""
    from gliderplan.language import check_file, check_source

    if not path.lower().endswith(".mi"):
        result = check_file(path)
        return result.checked(), (result.render(),) if result.diagnostics else ()
    from gliderplan.language.slocum import translate
    from gliderplan.language.slocum_files import read_mission

    translation = translate(read_mission(path, mafiles, False))
    checked = check_source(translation.source, path)
    return checked.checked(), tuple(f"import-slocum: {w}" for w in translation.warnings)


def water(spec: str | None, floor: SeaFloor | None = None
          ) -> tuple[DensityProfile | None, str | None, SeaFloor | None, str | None]:
    """(density profile, what it is, sea floor, what it is or why there is none) of an
    ocean spec and a floor as `sim --ocean`, `--floor` take them (`sim.ocean.load_water`:
    science logs give the floor they saw); Nones without them."""
    if spec is None:
        return None, None, floor, None if floor is None else floor.describe()
    from gliderplan.sim.ocean import WATER_DEPTHS_M, density_profile_of, load_water

    given = load_water(spec, floor)
    profile = density_profile_of(given.ocean)
    return profile, (f"{spec}: in-situ density (TEOS-10) {profile.rho_kg_m3.min():.1f}-"
                     f"{profile.rho_kg_m3.max():.1f} kg/m3 over 0-{WATER_DEPTHS_M[-1]:.0f} m, "
                     "the glider ballasted for its mean over the depths the mission flies, "
                     "as its trim was in its calibration water"), given.floor, given.floor_note


def forecast_mission(mission: ir.CheckedMission, *, vehicle: str | None = None,
                     duration_s: float | None = None, ocean: DensityProfile | None = None,
                     ocean_source: str | None = None, draws: int = DEFAULT_DRAWS,
                     seed: int = DEFAULT_SEED, floor: SeaFloor | None = None,
                     floor_note: str | None = None, said: tuple[str, ...] = ()
                     ) -> MissionForecast:
    """Forecast `mission` (on `vehicle`, a preset or file, default its own) for
    `duration_s` [s] (default its horizon, else DEFAULT_HORIZON_S) through `ocean`
    (default uniform water of the vehicle's reference density) over the sea floor `floor`
    (its median; default unknown: a yo is planned to its max_depth; `floor_note` says
    what it is or why there is none); `said`: what else the forecast rests on (what a
    Slocum mission's import could not carry over)."""
    spec = vehicle or mission.vehicle
    glider = load_vehicle(spec)
    floor_m = None if floor is None else floor.median_m
    if ocean is not None:
        glider, _ = ballasted_in(mission, ocean, glider, floor_m)
    occupancy = mission_occupancy(mission, mission.run_limit_s(duration_s))
    computer = computer_draw(mission)
    bills = bill_states(mission, glider, occupancy, ocean, floor_m, computer)
    rng = np.random.default_rng(seed)
    drift_w = glider.base_drift_w or DEFAULT_DRIFT_W
    gliding_s = sum(b.gliding_s for b in bills.values())
    drawn = [bill_states(mission, v, occupancy, ocean, floor_m, computer)
             for v in draw_vehicles(glider, draws, rng)]
    energies = np.array([sum(sum(b.energy_j.values()) for b in d.values()) for d in drawn])
    energies = energies + rng.normal(0.0, drift_w, energies.size) * gliding_s
    yos = np.array([sum(b.yos for b in d.values()) for d in drawn])
    result = MissionForecast(mission.name, glider.name, _computer_name(mission),
                             float(sum(b.time_s for b in bills.values())), bills,
                             _central(energies), (), _central(yos))
    notes = _assumptions(mission, glider, spec, occupancy, result, drift_w, draws,
                         ocean_source)
    notes += _floor_notes(mission, occupancy, result, floor_m, floor_note)
    defaults = []  # what neither the mission nor the caller named
    if vehicle is None and "vehicle" in mission.defaults_used:
        defaults.append(f"vehicle {spec}")
    if "computer" in mission.defaults_used:
        defaults.append(f"computer {result.computer}")
    if DEFAULT_HORIZON_NOTE in occupancy.notes:
        defaults.append(f"horizon {DEFAULT_HORIZON_S / 86400:g} d")
    return replace(result, assumptions=tuple(notes) + said, defaults=tuple(defaults))


def _floor_notes(mission: ir.CheckedMission, occupancy: Occupancy, result: MissionForecast,
                 floor_m: float | None, floor_note: str | None) -> list[str]:
    """What the forecast assumed of the sea floor and of each yo's altimeter stop."""
    notes = [] if floor_note is None else [f"sea floor: {floor_note}"]
    for state in mission.states:
        profile = state.profiles[0]
        if state.name in result.states and profile.kind in ("yo", "thermotrackyo"):
            note = altimeter_note(state.name, profile.kind, _args(state, occupancy), floor_m)
            notes += [] if note is None else [note]
    return notes


def _central(values: np.ndarray) -> tuple[float, float]:
    """The central INTERVAL_LEVEL of `values`."""
    tail = 50.0 * (1.0 - INTERVAL_LEVEL)
    low, high = np.percentile(values, [tail, 100.0 - tail])
    return float(low), float(high)


def _computer_name(mission: ir.CheckedMission) -> str:
    c = mission.computer
    return c.board if c.clock_mhz is None else f"{c.board} @ {c.clock_mhz:g} MHz"


def _assumptions(mission: ir.CheckedMission, vehicle: Vehicle, spec: str,
                 occupancy: Occupancy, result: MissionForecast, drift_w: float, draws: int,
                 ocean_source: str | None) -> list[str]:
    given = "" if spec != mission.vehicle else " (the mission's)"
    notes = [f"vehicle {spec}{given}: {vehicle.description or vehicle.name}",
             f"computer {result.computer}" + (
                 ": the glider's own computers run the mission, in its base load; no extra "
                 "board is charged" if mission.computer.board == "none" else
                 ": an extra board, charged for its clock and work in every state")]
    run = set()
    for state in mission.states:
        if state.name in result.states:
            run |= set(instruments(state))
    for device in held_instruments(vehicle):
        if device not in run:
            notes.append(f"{device}: in the vehicle's hotel load as calibrated, not run by "
                         "this mission: taken out at its figure")
    for device in sorted(run):
        own = vehicle.device(device)
        origin = "the vehicle's own figure" if own is not None else "its preset's figure"
        notes.append(f"{device}: run by the mission, at {origin}")
    notes.append("yo: flown as commanded without a plan: the pump's full stroke "
                 f"({vehicle.unplanned_ballast_cc:g} cc either side of neutral), the "
                 "commanded band and pitch (a thermotrackyo at the band it flies on average)")
    notes.append(f"each surfacing: the GPS fix ({vehicle.surface_s:.0f} s) and the Iridium "
                 f"call ({vehicle.iridium_s:.0f} s) at the vehicle's figures, the glider "
                 "staying at least until the call ends")
    notes.append("water: " + (ocean_source or "uniform, the vehicle's reference density "
                              f"({vehicle.flight.rho_kg_m3:.1f} kg/m3)"))
    notes.append(f"the {INTERVAL_LEVEL:.0%} interval: {draws} draws of the vehicle's figures "
                 "from their uncertainty, and the base load's drift to another deployment, "
                 f"sd {drift_w:g} W over the gliding time ("
                 + ("its file's base_drift" if vehicle.base_drift_w else DRIFT_SOURCE) + ")")
    notes += list(occupancy.notes)
    return notes

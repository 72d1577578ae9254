"""A replan that changes what a propelled vehicle flies: given the water (planner/water.py)
the shore chooses a thruster's power and the yo's speed anew, the update carries THRUST_W
(appended to a profile line that left it out) and the speed, the vehicle's runtime applies
it and the energy it draws follows; a thrust or a speed beyond the vehicle's rating is
refused by the plan check wherever a plan enters."""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from test_sim_currents import START, write_field

from gliderplan.cli.main import main
from gliderplan.contract import TICK_S, UpdateField, UpdateStatus
from gliderplan.language import check_source
from gliderplan.planner.make import make_plan
from gliderplan.planner.planfile import PlanFileError, plan_board_limits, read_plan_bytes
from gliderplan.planner.replan import Replanner
from gliderplan.planner.update import (
    Change,
    PlanUpdate,
    apply_update,
    changed_plan,
    make_updates,
    plan_hash,
)
from gliderplan.planner.water import route_legs
from gliderplan.power_models.telemetry import SurfacingReport
from gliderplan.power_models.vehicle import load_vehicle
from gliderplan.sim.currents import UniformCurrent
from gliderplan.sim.loop import DEFAULT_START_EPOCH_S, RunConfig, start_position

KEY = bytes(range(32))
# a hybrid gliding north with its thruster `auto`, surfacing every hour
MISSION = """mission hybridReplan

vehicle slocum_g3_hybrid
computer none
battery 15 Ah at 15 V reserve 10%
horizon 6 h

var next_fix = 3600
var fix_until = 0

state transit
begin
  flightroute nav(3912.0, -7349.8058)
  flightprofile yo(3, 30, .454, .454) thrust auto
  sensors missiontime, depth, pitch
  events
    case missiontime >= 14400 exit
    case missiontime >= next_fix
      set fix_until = missiontime + 600, next_fix = missiontime + 3600 call surface_fix
end

state surface_fix
begin
  flightroute noheading
  flightprofile surface
  sensors missiontime, depth, pitch, lat, lon
  events
    case missiontime >= fix_until return
end
"""
HEAD = UniformCurrent(-0.3, 0.0)  # toward the south: against the vehicle's track


@pytest.fixture(scope="module")
def held(tmp_path_factory):
    """The mission, and its plan made in still water signed as plan 1, and the key file."""
    where = tmp_path_factory.mktemp("hybrid")
    key = where / "vehicle.key"
    key.write_text(KEY.hex() + "\n")
    key.chmod(0o600)
    mission = check_source(MISSION, "hybrid_replan.mission").mission
    make_plan(mission, output=where / "held.plan", sign=key, seq=1)
    return mission, where / "held.plan", key


def _legs(mission):
    return route_legs(mission, HEAD, start_position(mission, RunConfig()),
                      DEFAULT_START_EPOCH_S)


def _transit(plan_bytes: bytes, mission):
    return read_plan_bytes(plan_bytes, mission).states[0].profiles[0]


def test_a_replan_in_a_head_current_turns_the_thruster_on_in_one_update(held):
    mission, path, _ = held
    data = path.read_bytes()
    assert _transit(data, mission).thrust_w == 0.0  # still water: the yo alone pays
    report = SurfacingReport(3600.0, state_time_s={"transit": 3600.0})
    replanner = Replanner(mission, data, legs=_legs(mission))
    replanner.observe(report)
    target = replanner.replan(data, report).target
    chain = make_updates(data, target, KEY)
    (update,) = chain.updates
    assert len(update) <= 270
    new = _transit(chain.plan_file, mission)
    assert new.thrust_w == 4.5 and new.speed_mps > 2 * _transit(data, mission).speed_mps
    applied = apply_update(data, update, KEY)
    assert applied.status == UpdateStatus.APPLIED and applied.plan_file == chain.plan_file
    # without the water the plan's speeds and thrusts stay
    still = Replanner(mission, data)
    still.observe(report)
    assert _transit(make_updates(data, still.replan(data, report).target, KEY).plan_file,
                    mission).thrust_w == 0.0


def test_a_thrust_or_speed_beyond_the_rating_is_refused_naming_the_line(held):
    mission, path, _ = held
    data = path.read_bytes()
    line = next(n for n, text in enumerate(data.decode().split("\n"), 1)
                if text.startswith("profile 0 1 0.454 "))
    hybrid = load_vehicle("slocum_g3_hybrid").propulsion

    limits = plan_board_limits(mission, read_plan_bytes(data, mission))

    def check(made: bytes) -> None:  # as `replan` checks what it sends
        read_plan_bytes(made, mission, "", limits)

    for change, said in (
            (Change(line, UpdateField.PROFILE_THRUST, 12, 0),
             f"THRUST_W 12 outside the vehicle's thruster (1-{hybrid.max_command_w:g} W)"),
            (Change(line, UpdateField.PROFILE_THRUST, 5, -1), "THRUST_W 0.5 outside")):
        made = changed_plan(data, (change,), 2, KEY)
        with pytest.raises(PlanFileError, match=re.escape(said)):
            check(made)
        update = PlanUpdate(1, 2, plan_hash(data), plan_hash(made), (change,)).pack(KEY)
        refused = apply_update(data, update, KEY, check=check)
        assert refused.status == UpdateStatus.BAD_PLAN and said in refused.message
        assert refused.plan_file == data


def test_a_propelled_speed_beyond_the_propulsion_is_refused(tmp_path):
    example = Path(__file__).parent.parent / "examples" / "propelled_transect.mission"
    source = example.read_text().replace("vehicle slocum_g3_hybrid", "vehicle lauv")
    mission = check_source(source, "propelled_transect.mission").mission
    key = tmp_path / "vehicle.key"
    key.write_text(KEY.hex() + "\n")
    key.chmod(0o600)
    make_plan(mission, output=tmp_path / "held.plan", sign=key, seq=1)
    data = (tmp_path / "held.plan").read_bytes()
    line = next(n for n, text in enumerate(data.decode().split("\n"), 1)
                if text.startswith("profile 1 1 0 0 "))
    limits = plan_board_limits(mission, read_plan_bytes(data, mission))
    change = Change(line, UpdateField.PROFILE_SPEED, 2, 0)
    made = changed_plan(data, (change,), 2, KEY)
    update = PlanUpdate(1, 2, plan_hash(data), plan_hash(made), (change,)).pack(KEY)
    refused = apply_update(data, update, KEY,
                           check=lambda d: read_plan_bytes(d, mission, "", limits))
    assert refused.status == UpdateStatus.BAD_PLAN
    assert "SPEED_MPS 2 outside the vehicle's propulsion (0.555556-1.55556 m/s)" in refused.message


@pytest.mark.skipif(shutil.which("cc") is None, reason="the C runtime needs a C compiler")
def test_the_c_runtime_flies_the_replanned_thrust_and_the_energy_follows(held):
    from gliderplan.sim.flight import fly
    from gliderplan.sim.ocean import load_water
    from gliderplan.sim.replanning import ShoreLoop
    from gliderplan.sim.vehicle import Current

    mission, path, key = held
    data = path.read_bytes()
    shore = ShoreLoop(mission, data, KEY, tick_s=TICK_S, legs=_legs(mission))
    config = RunConfig(duration_s=3 * 3600.0, current=Current(HEAD.north_mps, HEAD.east_mps))
    vehicle = load_vehicle(mission.vehicle)
    record = fly(mission, load_water("bench").ocean, config, vehicle,
                 read_plan_bytes(data, mission), str(path), "c", key_path=str(key),
                 shore=shore)
    assert shore.log.applied >= 1 and shore.log.refused == 0
    first = next(e for e in shore.log.events if e.get("update_bytes"))
    thrust = _transit(shore.sent[shore.vehicle_seq], mission).thrust_w
    assert thrust == 4.5
    time_s = record.columns["time_s"]
    drawn = record.columns["propulsion_w"]
    # the thruster is off until the update, then draws what its new command costs
    assert not np.any(drawn[time_s < first["time_s"]] > 0.0)
    running = drawn[drawn > 0.0]
    assert len(running) > 0 and np.all(time_s[drawn > 0.0] > first["time_s"])
    assert np.allclose(running, vehicle.propulsion.assist_draw_w(thrust))
    assert math.isclose(float(running[0]), 4.3378 + 2.0227 * 4.5, rel_tol=1e-3)


@pytest.mark.skipif(shutil.which("cc") is None, reason="the C runtime needs a C compiler")
@pytest.mark.parametrize("built_by", ["compile", "sim"])
def test_the_runtime_refuses_an_update_beyond_the_rating(held, tmp_path, built_by):
    """The compiled runtime's own plan check, as `replan` would send it: the runtime
    `compile` builds and the one the simulator builds for its flight alike."""
    from gliderplan.sim.emulator import start_c_runtime
    from gliderplan.sim.flight import flown_limits

    mission, path, key = held
    data = path.read_bytes()
    line = next(n for n, text in enumerate(data.decode().split("\n"), 1)
                if text.startswith("profile 0 1 0.454 "))
    change = Change(line, UpdateField.PROFILE_THRUST, 12, 0)
    made = changed_plan(data, (change,), 2, KEY)
    update = PlanUpdate(1, 2, plan_hash(data), plan_hash(made), (change,)).pack(KEY)
    limits = plan_board_limits(mission, read_plan_bytes(data, mission))
    if built_by == "sim":
        limits = flown_limits(mission, load_vehicle(mission.vehicle), limits.clocks_mhz)
    runtime = start_c_runtime(mission, str(path), limits, key_path=str(key),
                              state_dir=str(tmp_path))
    try:
        status, seq, message = runtime.deliver_update(update)
    finally:
        runtime.close()
    assert status == UpdateStatus.BAD_PLAN and seq == 1
    assert "THRUST_W 12 outside the vehicle's thruster (1-9 W)" in message
    assert Path(path).read_bytes() == data


@pytest.mark.skipif(shutil.which("cc") is None, reason="the C runtime needs a C compiler")
@pytest.mark.parametrize("current", ["field", "uniform"])
def test_sim_replans_in_the_current_it_flies(held, tmp_path, current):
    """Issue 25: `sim --replan-every surfacing --currents` replanned in still water, so a
    plan made in still water kept its slow speed and its thruster off against a head
    current. The shore replans in the water flown: the plan the vehicle ends with flies
    the speed and thrust `plan --currents` chooses for it (the runtime keeps the plan in
    force in its state directory)."""
    mission, still, key = held
    source = tmp_path / "hybrid_replan.mission"
    source.write_text(MISSION)
    spec = str(write_field(tmp_path / "head.nc", east=HEAD.east_mps, north=HEAD.north_mps)) \
        if current == "field" else f"{HEAD.north_mps},{HEAD.east_mps}"
    water = [f"--currents={spec}", "--start", START]
    assert main(["plan", str(source), *water, "-o", str(tmp_path / "aware.plan")]) == 0
    aware = _transit((tmp_path / "aware.plan").read_bytes(), mission)
    assert _transit(still.read_bytes(), mission).thrust_w == 0.0 < aware.thrust_w
    vehicle = tmp_path / "vehicle"
    assert main(["sim", str(source), "--plan", str(still), "--key", str(key), *water,
                 "--replan-every", "surfacing", "--runtime", "c", "--state-dir", str(vehicle),
                 "-o", str(tmp_path / "run")]) == 0
    flown = _transit((vehicle / "plan").read_bytes(), mission)
    assert flown.thrust_w == aware.thrust_w
    assert math.isclose(flown.speed_mps, aware.speed_mps, rel_tol=1e-6)
    # once the vehicle flies it, a replan that rounds to it sends nothing and says so
    surfacings = pd.read_csv(tmp_path / "run" / "replans.csv")
    assert len(surfacings) > 1
    assert list(surfacings.status) == ["updated"] + ["unchanged"] * (len(surfacings) - 1)
    assert surfacings.update_bytes.notna().tolist() == [True] + [False] * (len(surfacings) - 1)

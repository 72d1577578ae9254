"""The contract between the parts: one definition of each shared fact.

The C header is what the contract generates, the parts import the contract rather than
retype it, and `check` refuses what a later stage would refuse for its size.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from gliderplan import contract
from gliderplan.contract import FlightLimits, units
from gliderplan.contract.c_header import c_header
from gliderplan.language import check_source
from gliderplan.language.codegen_c import generate_c
from gliderplan.language.registry import PROFILES, ROUTES
from gliderplan.planner.hardware import parse_battery
from gliderplan.power_models import load_vehicle
from gliderplan.power_models.battery import read_battery_file

ROOT = Path(__file__).resolve().parents[1]
HEADER = ROOT / "runtime" / "include" / "gp_contract.h"
PACKAGES = ("cli", "language", "planner", "power_models", "reports", "runtime", "sim")
CONTRACT_NAMES = frozenset(name for module in (contract, units) for name in vars(module)
                           if not name.startswith("_") and name[0].isupper())


def test_the_committed_header_is_the_one_the_contract_generates():
    assert HEADER.read_text() == c_header(), (
        "runtime/include/gp_contract.h is stale: run "
        "`python -m gliderplan.contract > runtime/include/gp_contract.h`")


def test_the_header_carries_every_value_of_the_contract():
    text = HEADER.read_text()
    defined = {m[1]: int(m[2], 0) for m in re.finditer(r"#define GP_(\w+) (0x[0-9A-F]+|\d+)u?\b",
                                                        text)}
    for name in ("MAX_STATES", "MAX_STACK_DEPTH", "MAX_EVENTS_PER_STATE", "MAX_NAME_LENGTH",
                 "N_SENSORS", "FLIGHT_SENSORS_MASK", "NO_STATE", "MAX_PAYLOAD"):
        assert defined[name] == getattr(contract, name), name
    for sensor in contract.SENSORS:
        assert f"GP_SENSOR_{sensor.name.upper()} = {sensor.index}," in text
    assert f"GP_TR_CALL = {contract.TransitionKind.CALL}," in text
    assert f"GP_EXIT_LINK_LOST = {contract.RuntimeExit.LINK_LOST}," in text


def _python_sources() -> list[Path]:
    return [p for package in PACKAGES for p in sorted((ROOT / package).rglob("*.py"))]


@pytest.mark.parametrize("path", _python_sources(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_module_redefines_a_fact_of_the_contract(path):
    tree = ast.parse(path.read_text())
    for node in tree.body:
        targets = [node.target] if isinstance(node, ast.AnnAssign) else \
            node.targets if isinstance(node, ast.Assign) else []
        names = {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}
        if isinstance(node, ast.ClassDef):
            names = {node.name}
        assert not names & CONTRACT_NAMES, (
            f"{path.name}:{node.lineno} defines {sorted(names & CONTRACT_NAMES)}; "
            "import it from gliderplan.contract")


def _numbers(nodes) -> bool:
    return any(isinstance(n, ast.Constant) and type(n.value) is int for n in nodes)


@pytest.mark.parametrize("path", _python_sources(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_module_reads_a_flag_or_a_sensor_by_its_number(path):
    """A COMMAND's flags are tested by their names (`flags & FLAG_HEADING`, not `flags & 8`)
    and a sensor is picked by its name's index, not by its place in the array (`case 9:`
    over a sensor index): the contract may grow, and the layout is its alone."""
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.BitAnd):
            flags = any(isinstance(n, ast.Name) and n.id.endswith("flags")
                        for n in (node.left, node.right))
            assert not (flags and _numbers((node.left, node.right))), (
                f"{path.name}:{node.lineno} tests a flag by its number")
        if isinstance(node, ast.Match) and isinstance(node.subject, ast.Name) \
                and node.subject.id.endswith("index"):
            values = [p.value for c in node.cases for p in ast.walk(c.pattern)
                      if isinstance(p, ast.MatchValue)]
            assert not _numbers(values), f"{path.name}:{node.lineno} picks a sensor by number"


def _c_sources() -> list[Path]:
    runtime = ROOT / "runtime"
    return [p for p in sorted([*runtime.glob("include/*.h"), *runtime.glob("src/*.c")])
            if p != HEADER]


@pytest.mark.parametrize("path", _c_sources(), ids=lambda p: p.name)
def test_no_c_file_redefines_a_fact_of_the_header(path):
    generated = set(re.findall(r"^#define (GP_\w+)|^\s+(GP_\w+) = ", HEADER.read_text(), re.M))
    names = {a or b for a, b in generated}
    text = path.read_text()
    defined = set(re.findall(r"^#define (GP_\w+)", text, re.M))
    defined |= set(re.findall(r"^\s+(GP_\w+) = ", text, re.M))
    assert not defined & names, f"{path.name} defines {sorted(defined & names)} again"
    # the sensor array is indexed by name (GP_SENSOR_*), never by a bare number
    assert not re.search(r"sensors\[\d+\]", text), f"{path.name} indexes sensors by number"


# ---- check refuses what the runtime or the plan file cannot hold --------------------


def _source(states: int = 1, variables: int = 0, events: int = 1, alternatives: int = 1,
            mission: str = "m", state: str = "s") -> str:
    """A mission of the given size: line 1 the name, then the variables, then the states."""
    lines = [f"mission {mission}", *(f"var v{i} = {i}" for i in range(variables))]
    for k in range(states):
        lines += [f"state {state}{k}", "begin",
                  "  flightprofile " + " | ".join(["surface"] * alternatives),
                  "  sensors missiontime", "  events",
                  *(f"    case missiontime > {i} exit" for i in range(events)), "end"]
    return "\n".join(lines) + "\n"


def _errors(source: str) -> list[tuple[int, int, str]]:
    result = check_source(source, "m.mission")
    return [(d.span.line, d.span.column, d.message) for d in result.diagnostics if d.is_error]


LIMITS = [  # (what, sizes at the limit, one more, where the error points, its message)
    ("states", {"states": contract.MAX_STATES}, {"states": contract.MAX_STATES + 1},
     (2 + 7 * contract.MAX_STATES, 7), f"the mission has {contract.MAX_STATES + 1} states, "
     f"more than the {contract.MAX_STATES} the runtime holds"),
    ("variables", {"variables": contract.MAX_VARIABLES},
     {"variables": contract.MAX_VARIABLES + 1}, (2 + contract.MAX_VARIABLES, 5),
     f"the mission has {contract.MAX_VARIABLES + 1} variables, more than the "
     f"{contract.MAX_VARIABLES} the runtime holds"),
    ("events", {"events": contract.MAX_EVENTS_PER_STATE},
     {"events": contract.MAX_EVENTS_PER_STATE + 1}, (7 + contract.MAX_EVENTS_PER_STATE, 5),
     f"state 's0' has {contract.MAX_EVENTS_PER_STATE + 1} events, more than the "
     f"{contract.MAX_EVENTS_PER_STATE} the runtime holds"),
    ("alternatives", {"alternatives": contract.MAX_PROFILE_ALTERNATIVES},
     {"alternatives": contract.MAX_PROFILE_ALTERNATIVES + 1},
     (4, 17 + 10 * contract.MAX_PROFILE_ALTERNATIVES),
     f"state 's0' has {contract.MAX_PROFILE_ALTERNATIVES + 1} flight-profile alternatives, "
     f"more than the {contract.MAX_PROFILE_ALTERNATIVES} the runtime holds"),
    ("mission name", {"mission": "m" * contract.MAX_NAME_LENGTH},
     {"mission": "m" * (contract.MAX_NAME_LENGTH + 1)}, (1, 9),
     f"mission name '{'m' * (contract.MAX_NAME_LENGTH + 1)}' has "
     f"{contract.MAX_NAME_LENGTH + 1} characters, more than the {contract.MAX_NAME_LENGTH} a "
     "plan file holds"),
    ("state name", {"state": "s" * (contract.MAX_NAME_LENGTH - 1)},
     {"state": "s" * contract.MAX_NAME_LENGTH}, (2, 7),
     f"state name '{'s' * contract.MAX_NAME_LENGTH}0' has {contract.MAX_NAME_LENGTH + 1} "
     f"characters, more than the {contract.MAX_NAME_LENGTH} a plan file holds"),
]


@pytest.mark.parametrize(("what", "fits", "too_big", "where", "message"), LIMITS,
                         ids=[case[0] for case in LIMITS])
def test_check_refuses_one_past_each_limit_at_its_line(what, fits, too_big, where, message):
    assert _errors(_source(**fits)) == []
    assert _errors(_source(**too_big)) == [(*where, message)]


@pytest.mark.parametrize(("what", "fits"), [(case[0], case[1]) for case in LIMITS[:4]],
                         ids=[case[0] for case in LIMITS[:4]])
def test_what_check_accepts_at_a_limit_the_code_generator_accepts(what, fits):
    mission = check_source(_source(**fits), "m.mission").mission
    limits = FlightLimits(200.0, 233.0, (300.0,),
                          envelope=load_vehicle("slocum_g2_shallow").envelope)
    assert "const gp_mission gp_mission_table" in generate_c(mission, limits)


def test_a_size_error_does_not_hide_the_flow_analysis():
    source = _source(states=contract.MAX_STATES + 1).replace(
        "    case missiontime > 0 exit\n", "    case missiontime > 0 return\n", 1)
    messages = [m for _, _, m in _errors(source)]
    assert len(messages) == 2 and "'return' in state 's0' can run with an empty stack" in \
        messages[0] and "states, more than the" in messages[1]


def test_the_vocabulary_fits_the_runtime_and_the_plan_file():
    assert all(len(p.params) <= contract.MAX_PROFILE_ARGS for p in PROFILES.values())
    assert all(r.max_points <= contract.MAX_ROUTE_POINTS for r in ROUTES.values())
    # a plan's state block lists the sensors with a device: at most every such sensor
    assert sum(1 for s in contract.SENSORS if s.device) <= contract.MAX_PLAN_SENSORS
    devices = {s.device for s in contract.SENSORS if s.device}
    # a plan's `components` line: the vehicle's, the computer and every device
    assert len(contract.VEHICLE_COMPONENTS) + 1 + len(devices) <= contract.MAX_PLAN_COMPONENTS
    assert [s.index for s in contract.SENSORS] == list(range(contract.N_SENSORS)) \
        and contract.N_SENSORS <= 32


def test_the_pilots_sensor_table_is_the_contracts_and_every_device_has_a_preset():
    from gliderplan.power_models.catalog import preset_names

    rows = re.findall(r"^\| (\d+) \| `(\w+)` \| ([^|]+) \| ([^|]+) \|",
                      (ROOT / "docs" / "pilot.md").read_text(), re.M)
    assert [(int(i), name, unit.strip()) for i, name, unit, _ in rows] == [
        (s.index, s.name, s.unit) for s in contract.SENSORS]
    assert [d.strip().strip("`") for *_, d in rows] == [
        s.device or ("runtime" if s.source == "runtime" else "-") for s in contract.SENSORS]
    # the devices Slocum gliders carry: a DVL and a microstructure logger among them
    by_name = {s.name: s for s in contract.SENSORS}
    assert (by_name["groundspeed"].device, by_name["groundspeed"].unit) == ("dvl", "m/s")
    assert (by_name["shear"].device, by_name["shear"].unit) == ("logger", "1/s")
    for device in {s.device for s in contract.SENSORS if s.device}:
        assert device in preset_names("sensor"), f"no power model of the {device}"


def test_a_unit_means_the_same_in_a_mission_a_data_file_and_an_option(tmp_path):
    source = "mission m\nbattery 10 Ah at 14.4 V\nstate s begin flightprofile surface end\n"
    from_mission = check_source(source, "m.mission").mission.battery.energy_j
    pack = tmp_path / "pack.toml"
    pack.write_text('kind = "battery"\nname = "pack"\n'
                    'voltage = { value = 14.4, unit = "V", source = "test" }\n'
                    'capacity = { value = 10, unit = "Ah", source = "test" }\n'
                    'usable_fraction = { value = 1, unit = "1", source = "test" }\n')
    from_file = read_battery_file(pack).energy_j
    from_option = parse_battery("10Ah@14.4V")[0]
    assert from_mission == from_file == from_option == pytest.approx(10 * 3600 * 14.4)
    clock = check_source("mission m\ncomputer ts7800 @ 0.5 GHz\nstate s begin flightprofile "
                         "surface end\n", "m.mission").mission.computer.clock_mhz
    assert clock == 500.0


def test_a_mission_without_a_horizon_is_planned_and_flown_over_the_same_time():
    """The plan budgets what the simulator flies: one default horizon for both."""
    from gliderplan.planner.occupancy import mission_occupancy
    from gliderplan.sim.loop import RunConfig

    source = "mission m\nstate s begin flightprofile yo(5, 20, .454, .454) end\n"
    occupancy = mission_occupancy(check_source(source, "m.mission").mission)
    assert occupancy.total_s == pytest.approx(contract.DEFAULT_HORIZON_S, abs=contract.TICK_S)
    assert RunConfig().duration_s == contract.DEFAULT_HORIZON_S


def test_plan_names_one_thing():
    """One `Plan` type, the plan file's (`planner/planfile.py`): the PLAN frame that carries a
    piece of it over the link is a `PlanPiece`."""
    named = [str(p.relative_to(ROOT)) for p in _python_sources()
             for node in ast.walk(ast.parse(p.read_text()))
             if isinstance(node, ast.ClassDef) and node.name == "Plan"]
    assert named == ["planner/planfile.py"]

"""The C code generator: golden output for Fig. 2, determinism, warning-free C, and
expressions that the compiled C evaluates bit for bit as `ir.evaluate` does.

Regenerate the golden file after an intended change of the generated C with
`GLIDERPLAN_REGENERATE_GOLDEN=1 pytest tests/test_codegen_c.py`.
"""

from __future__ import annotations

import math
import os
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from gliderplan.contract import FlightLimits
from gliderplan.language import check_source, ir
from gliderplan.language.codegen_c import (
    CodegenError,
    c_double,
    generate_c,
    own_read_mask,
    read_mask,
)
from gliderplan.language.registry import SENSOR_BY_NAME, SENSORS
from gliderplan.power_models import load_vehicle
from gliderplan.runtime.build import TARGETS

ROOT = Path(__file__).resolve().parents[1]
# the default vehicle's full stroke and the TS-7800's clocks, as `compile` passes them
ENVELOPE = load_vehicle("slocum_g2_shallow").envelope
LIMITS = FlightLimits(default_ballast_cc=233.0, max_ballast_cc=233.0,
                      clocks_mhz=(300.0, 500.0), envelope=ENVELOPE)
EXAMPLES = sorted((ROOT / "examples").glob("*.mission"))
GOLDEN = ROOT / "tests" / "golden" / "fig2.c"
INCLUDE = ROOT / "runtime" / "include"
CC = shutil.which("cc")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc) on PATH")
STRICT = ["-std=c11", "-pedantic", "-O2", "-Wall", "-Wextra", "-Werror", f"-I{INCLUDE}"]


def checked(path: Path) -> ir.CheckedMission:
    result = check_source(path.read_text(), str(path))
    assert result.mission is not None, result.render()
    return result.mission


def test_fig2_matches_the_golden_file():
    generated = generate_c(checked(ROOT / "examples" / "fig2.mission"), LIMITS)
    if os.environ.get("GLIDERPLAN_REGENERATE_GOLDEN"):
        GOLDEN.parent.mkdir(exist_ok=True)
        GOLDEN.write_text(generated)
    assert generated == GOLDEN.read_text()


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_generation_is_deterministic(path):
    # Two independent checks of the same text: nothing may depend on object identity.
    assert generate_c(checked(path), LIMITS) == generate_c(checked(path), LIMITS)


@needs_cc
@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_example_compiles_without_warnings(path, tmp_path):
    source = tmp_path / f"{path.stem}.c"
    source.write_text(generate_c(checked(path), LIMITS))
    done = subprocess.run([CC, *STRICT, "-c", str(source), "-o", str(tmp_path / "m.o")],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def test_fig2_reads_the_sensors_its_conditions_profiles_and_routes_need():
    mask = read_mask(checked(ROOT / "examples" / "fig2.mission"))
    read = {name for name, info in SENSOR_BY_NAME.items() if mask >> info.index & 1}
    # missiontime (conditions), depth (every profile), temp (thermotrackyo in s2), lat and
    # lon (nav routes in s1 and s3), energy_left (the energy guard, in every mission);
    # nothing else: pitch is commanded, not read.
    assert read == {"missiontime", "depth", "temp", "lat", "lon", "energy_left"}


def test_the_runtime_works_out_its_own_readings_for_the_missions_that_read_them():
    # Fig. 2 reads neither halfcycle nor wptdist: the runtime spares the distance to the
    # waypoint (a cosine and a hypot a tick); a goto list whose events read both gets both.
    assert own_read_mask(checked(ROOT / "examples" / "fig2.mission")) == 0
    goto_list = checked(ROOT / "tests" / "missions" / "sim_goto_list.mission")
    mask = own_read_mask(goto_list)
    own = {name for name, info in SENSOR_BY_NAME.items() if mask >> info.index & 1}
    assert own == {"halfcycle", "wptdist"}
    assert not read_mask(goto_list) & mask  # neither comes over the link


def test_fig2_tables_name_the_transitions_of_the_paper():
    text = generate_c(checked(ROOT / "examples" / "fig2.mission"), LIMITS)
    assert "{state0_event0_condition, NULL, GP_ACT_GOTO, 2}" in text
    assert "{state0_event1_condition, NULL, GP_ACT_CALL, 1}" in text
    assert "{state1_event0_condition, NULL, GP_ACT_RETURN, 0}" in text
    assert "{state2_event0_condition, NULL, GP_ACT_EXIT, 0}" in text


def _read_back(literal: str) -> float:
    """The value of a literal c_double printed: decimal or C99 hex, parenthesised if negative."""
    text = literal.split("/*")[0].strip().strip("()").strip()
    return float.fromhex(text) if "0x" in text else float(text)


@pytest.mark.parametrize("number", [0.1, 0.454, -7349.8058, 2000.0, 0.5, 1e-310, 5e-324,
                                    1.7976931348623157e308, -0.0, 2.0**53 + 2])
def test_constants_are_printed_so_that_they_read_back_exactly(number):
    value = _read_back(c_double(number))
    assert value == number and math.copysign(1, value) == math.copysign(1, number)


def test_constants_are_decimal_only_when_the_decimal_is_exact():
    # Decimal text is read in 80-bit precision on the i486: only exact ones stay decimal.
    assert c_double(2000.0) == "2000.0" and c_double(-0.5) == "(-0.5)"
    assert c_double(0.454) == "0x1.d0e5604189375p-2 /* 0.454 */"


def test_the_vehicle_and_board_limits_are_inputs_not_files_read():
    mission = ir.CheckedMission(name="m", states=(_state("s"),), vehicle="no/such/glider.toml")
    source = generate_c(mission, FlightLimits(123.5, 200.0, (133.0,), envelope=ENVELOPE))
    assert "    .default_ballast_cc = 123.5,\n    .max_ballast_cc = 200.0,\n" in source
    assert "board_clocks_mhz[1] = {133.0};" in source and "    .n_clocks = 1,\n" in source


def _mission(states: tuple[ir.State, ...], variables=(), stack_depth=8) -> ir.CheckedMission:
    return ir.CheckedMission(name="limits", states=states, variables=variables,
                             stack_depth=stack_depth)


def _state(name: str, events=(), profiles=None, route=None) -> ir.State:
    return ir.State(name=name, route=route or ir.Route("noheading"),
                    profiles=profiles or (ir.Profile("hover", (ir.Const(10.0),)),),
                    sensors=(), events=tuple(events))


@pytest.mark.parametrize(
    ("mission", "message"),
    [
        (_mission(tuple(_state(f"s{i}") for i in range(65))), "states: 65 exceeds"),
        (_mission((_state("s"),), stack_depth=40), "stack depth: 40 exceeds"),
        (_mission((_state("s", [ir.Event(ir.Const(1.0))] * 256),)),
         "state s: events: 256 exceeds"),
        (_mission((_state("s", profiles=(ir.Profile("surface", ()),) * 9),)),
         "state s: flight-profile alternatives: 9 exceeds"),
        (_mission((_state("s", profiles=(ir.Profile("barrelroll", ()),)),)),
         "flight profile 'barrelroll' has no runtime routine"),
        (_mission((_state("s", route=ir.Route("waypoints", (), ((1.0, 2.0),) * 65)),)),
         "state s: route points: 65 exceeds"),
    ],
    ids=["states", "stack", "events", "profiles", "unknown-profile", "points"],
)
def test_missions_beyond_the_runtime_limits_are_refused_with_a_reason(mission, message):
    with pytest.raises(CodegenError, match=message):
        generate_c(mission, LIMITS)


# ---- expressions: the compiled C against ir.evaluate ---------------------------------

SENSORS_USED = ("missiontime", "depth", "temp")
INPUT_VARIABLES = ("x0", "x1", "x2")
RESULT = "r"  # every assignment writes r; the driver reads it after each event

_DRIVER = r"""
#include <inttypes.h>
#include <stdio.h>
#include <string.h>
#include "gp_mission.h"

/* stdin: lines of GP_N_SENSORS sensor and n_vars variable values as hex bit patterns.
 * stdout: per line, per event: the condition (0/1) and the assigned value's bits. */
static double from_bits(uint64_t bits) { double d; memcpy(&d, &bits, sizeof d); return d; }
static uint64_t to_bits(double d) { uint64_t bits; memcpy(&bits, &d, sizeof bits); return bits; }

int main(void)
{
    const gp_mission *m = &gp_mission_table;
    double sensors[GP_N_SENSORS] = {0}, vars[GP_MAX_VARIABLES] = {0}, out[GP_MAX_VARIABLES];
    uint64_t bits;
    for (;;) {
        for (int i = 0; i < GP_N_SENSORS; i++) {
            if (scanf("%" SCNx64, &bits) != 1) return 0;
            sensors[i] = from_bits(bits);
        }
        for (int i = 0; i < m->n_vars; i++) {
            if (scanf("%" SCNx64, &bits) != 1) return 1;
            vars[i] = from_bits(bits);
        }
        for (int s = 0; s < m->n_states; s++) {
            for (int e = 0; e < m->states[s].n_events; e++) {
                const gp_event *event = &m->states[s].events[e];
                memcpy(out, vars, sizeof vars);
                event->assign(sensors, out);
                printf("%d %016" PRIx64 "\n", event->condition(sensors, vars) != 0,
                       to_bits(out[m->n_vars - 1]));
            }
        }
    }
}
"""

_SPECIAL = [0.0, -0.0, 1.0, -1.0, 2.0, 0.5, 3.0, math.inf, -math.inf, math.nan, 1e308,
            -1e308, 5e-324]
_numbers = st.one_of(st.sampled_from(_SPECIAL), st.floats(allow_nan=True, allow_infinity=True))
# A mission's constants are never NaN (its hash is canonical JSON); inputs may be.
_leaves = st.one_of(
    _numbers.filter(lambda x: not math.isnan(x)).map(ir.Const),
    st.sampled_from(SENSORS_USED).map(ir.SensorRef),
    st.sampled_from(INPUT_VARIABLES).map(ir.VarRef),
)


def _extend(children: st.SearchStrategy[ir.Expr]) -> st.SearchStrategy[ir.Expr]:
    binary = ("+", "-", "*", "/", "<", "<=", ">", ">=", "==", "!=", "&&", "||")
    return st.one_of(
        st.builds(ir.UnaryOp, st.sampled_from(("-", "!")), children),
        st.builds(ir.BinaryOp, st.sampled_from(binary), children, children),
        st.builds(lambda a: ir.FuncCall("abs", (a,)), children),
        st.builds(lambda f, a, b: ir.FuncCall(f, (a, b)),
                  st.sampled_from(("min", "max", "mod")), children, children),
    )


expressions = st.recursive(_leaves, _extend, max_leaves=12)
_inputs = st.lists(_numbers, min_size=len(SENSORS_USED) + len(INPUT_VARIABLES),
                   max_size=len(SENSORS_USED) + len(INPUT_VARIABLES))


def _expression_mission(exprs: list[ir.Expr]) -> ir.CheckedMission:
    """One event per expression: the expression is its condition and the value it assigns."""
    per_state = 200
    states = tuple(
        _state(f"s{n}", [ir.Event(e, (ir.Assign(RESULT, e),))
                         for e in exprs[start:start + per_state]])
        for n, start in enumerate(range(0, len(exprs), per_state))
    )
    variables = tuple(ir.Variable(name, 0.0) for name in (*INPUT_VARIABLES, RESULT))
    return _mission(states, variables)


def _bits(value: float) -> str:
    return f"{struct.unpack('<Q', struct.pack('<d', value))[0]:016x}"


def _same(expected: float, c_bits: str, x87: bool = False) -> bool:
    """Bit-identical; any NaN equals any NaN (its sign and payload carry no meaning). On the
    x87 (`x87`) a subnormal result (below 2.2e-308, far from any physical quantity) may
    be a unit in the last place off: rounded to 53 bits in the register's wide exponent
    range, then again to the subnormal's fewer bits when stored."""
    actual = struct.unpack("<d", struct.pack("<Q", int(c_bits, 16)))[0]
    if math.isnan(expected):
        return math.isnan(actual)
    if x87 and 0.0 < abs(expected) < sys.float_info.min:
        return math.copysign(1.0, actual) == math.copysign(1.0, expected) and \
            abs(actual - expected) <= math.ulp(expected)
    return _bits(expected) == c_bits


# Every build target, the boards' on their own CPU models under qemu-user. The i486
# computes on the x87, with 80-bit registers and decimal constants read in 80-bit precision.
@pytest.mark.parametrize("board", TARGETS)
# Each example compiles a C file; shrinking would compile hundreds, and the assertion
# already names the failing expression and inputs.
@settings(max_examples=4, deadline=None, phases=[Phase.explicit, Phase.reuse, Phase.generate],
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                 HealthCheck.function_scoped_fixture])
@given(exprs=st.lists(expressions, min_size=300, max_size=300),
       rows=st.lists(_inputs, min_size=12, max_size=12))
def test_compiled_expressions_agree_bit_for_bit_with_the_reference(board, exprs, rows,
                                                                   tmp_path_factory,
                                                                   board_runner):
    emulator = board_runner(board)
    compiler, flags = TARGETS[board].compiler, TARGETS[board].flags
    work = tmp_path_factory.mktemp("exprs")
    mission = _expression_mission(exprs)
    (work / "mission.c").write_text(generate_c(mission, LIMITS))
    (work / "driver.c").write_text(_DRIVER)
    binary = work / "exprs"
    done = subprocess.run([compiler, *STRICT, *flags, str(work / "mission.c"),
                           str(work / "driver.c"), "-o", str(binary), "-lm"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr

    lines = []
    for row in rows:
        sensors = [math.nan] * len(SENSORS)
        for name, value in zip(SENSORS_USED, row, strict=False):
            sensors[SENSOR_BY_NAME[name].index] = value
        variables = [*row[len(SENSORS_USED):], 0.0]
        lines.append(" ".join(_bits(v) for v in (*sensors, *variables)))
    run = subprocess.run([*emulator, str(binary)], input="\n".join(lines) + "\n",
                         capture_output=True, text=True, check=True)
    answers = iter(run.stdout.split("\n"))
    for row in rows:
        sensors = dict(zip(SENSORS_USED, row, strict=False))
        variables = dict(zip(INPUT_VARIABLES, row[len(SENSORS_USED):], strict=True))
        for expr in exprs:
            truth, value_bits = next(answers).split()
            expected = ir.evaluate(expr, sensors, variables)
            assert int(truth) == (expected != 0.0), (expr, sensors, variables)
            assert _same(expected, value_bits, x87=board == "ts5500"), \
                (expr, sensors, variables, value_bits)

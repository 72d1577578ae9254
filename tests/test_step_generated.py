"""Differential tests by generation: the runtime's step against the Python reference.

Missions drawn at random (tests/missiongen.py: states entered by goto and by call, calls
nested up to the declared stack, every sensor, variables and `set`, every profile and
route, sleep between ticks, a plan's duty cycles and profile shares) are stepped by the
Python reference executor and by the compiled runtime's step, in this process, on the
same readings: the COMMAND of every tick, the runtime's own readings, a refused event,
the variables, the variables each state was entered with, the events fired and the
board's sleeps must be identical. The missions are compiled a batch at a time, in one
shared object.

A case that fails is written to tests/step_regressions/unsaved-failure.json (hypothesis
shrinks it first: the last one written is the smallest); give it a name and commit it:
`test_regressions_still_agree` steps every case kept there. The missions' tables are
compiled without optimisation (half the time; the same doubles), the step library as
the simulator builds it.

GLIDERPLAN_GENERATED_BATCHES sets the number of batches (default 250: 2,000 missions);
GLIDERPLAN_MUTANT (tests/mutants.py) turns shrinking and the keeping of failures off.
"""

from __future__ import annotations

import ctypes
import json
import os
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st
from missiongen import Case, cases, checked, compare, limits_of, readings

REGRESSIONS = Path(__file__).with_name("step_regressions")
# 8 missions an example: more overflow hypothesis's buffer, and drawing them is retried
MISSIONS_PER_BATCH = 8
BATCHES = int(os.environ.get("GLIDERPLAN_GENERATED_BATCHES", "250"))  # 2,000 missions
MUTANT = bool(os.environ.get("GLIDERPLAN_MUTANT"))  # a fault is planted: find it, fast

needs_cc = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")


def compiled_tables(missions: list, directory: Path) -> list[int]:
    """The addresses of the missions' tables, compiled together into one shared object."""
    from gliderplan.language.codegen_c import generate_c
    from gliderplan.sim.cstep import build_shared, tables_in

    source = directory / "batch.c"
    source.write_text("\n".join(generate_c(m, limits_of(m), prefix=f"m{i}_")
                                for i, m in enumerate(missions)))
    library = ctypes.CDLL(str(build_shared("batch", [source], directory, optimize=False)))
    return [tables_in(library, f"m{i}_gp_mission_table") for i in range(len(missions))]


def kept(case: Case) -> None:
    """Write a failing case where it is kept (see the module's docstring)."""
    if MUTANT:
        return
    REGRESSIONS.mkdir(exist_ok=True)
    (REGRESSIONS / "unsaved-failure.json").write_text(json.dumps(case.to_json(), indent=1)
                                                      + "\n")


@needs_cc
@settings(max_examples=BATCHES, deadline=None, database=None,
          phases=[Phase.generate] if MUTANT else list(Phase),
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                 HealthCheck.large_base_example])
@given(st.lists(cases(), min_size=MISSIONS_PER_BATCH, max_size=MISSIONS_PER_BATCH))
def test_the_step_and_the_reference_agree_on_generated_missions(batch):
    flown = [(case, *checked(case)) for case in batch]
    with tempfile.TemporaryDirectory(prefix="gliderplan-generated-") as directory:
        tables = compiled_tables([mission for _, mission, _ in flown], Path(directory))
    for (case, mission, plan), address in zip(flown, tables, strict=True):
        try:
            compare(case, mission, plan, address)
        except AssertionError:
            kept(case)
            raise


@needs_cc
@pytest.mark.parametrize("path", sorted(REGRESSIONS.glob("*.json")), ids=lambda p: p.stem)
def test_regressions_still_agree(path):
    case = Case(**json.loads(path.read_text()))
    compare(case, *checked(case))


@needs_cc
def test_a_yo_band_end_set_to_nan_ends_the_mission_at_the_envelope():
    """A thermotrackyo whose bottom an event sets from a missing reading (`altitude + 30`
    without a floor: NaN): neither runtime commands a NaN depth nor puts a number in its
    place; the envelope ends the mission on that tick (the vehicle's `surface` action), in
    the same words."""
    from gliderplan.contract import NO_STATE, TransitionKind
    from gliderplan.sim.cstep import CStep
    from gliderplan.sim.executor import PythonRuntime

    case = Case(**json.loads((REGRESSIONS / "nan-bottom.json").read_text()))
    mission, _ = checked(case)
    limits = limits_of(mission)
    runtimes = (PythonRuntime(mission, None, limits.default_ballast_cc, not case.naive,
                              limits.max_ballast_cc, limits.envelope, limits),
                CStep(mission, None, limits, case.naive))
    masks, values = readings(case.seed, case.tick_s)
    for tick in range(len(masks)):
        commands = [r.step(tick, int(masks[tick]), values[tick].tolist()) for r in runtimes]
        assert all(c.depth_target_m == c.depth_target_m for c in commands), tick  # no NaN
        if commands[0].state == NO_STATE:
            break
    assert [(c.state, c.transition, c.depth_target_m) for c in commands] == \
        [(NO_STATE, TransitionKind.ENVELOPE, 0.0)] * 2
    notes = [r.envelope_notes for r in runtimes]
    assert notes[0] == notes[1] and len(notes[0]) == 1
    assert "state g0: depth nan m beyond the vehicle's 100 m; the mission ends" in notes[0][0]

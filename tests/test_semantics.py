"""The reference semantics on the paper's Fig. 2: the transitions the paper reports."""

from __future__ import annotations

from pathlib import Path

import pytest

from gliderplan.language import check_source, ir
from gliderplan.language.semantics import MissionFault, Transition, start, step

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def run(mission, tick_s=1.0, until_s=10_000.0, sensors=None):
    machine, first = start(mission)
    trace = [first]
    t = 0.0
    while not machine.exited and t <= until_s:
        readings = {"missiontime": t, "depth": 10.0, "pitch": 0.4, "temp": 15.0,
                    **(sensors or {})}
        machine, transition = step(mission, machine, readings, t)
        if transition:
            trace.append(transition)
        t += tick_s
    return trace


def test_fig2_follows_the_papers_timeline():
    mission = check_source((EXAMPLES / "fig2.mission").read_text()).mission
    assert run(mission) == [
        Transition(0.0, "start", "", "s1", 0),
        Transition(500.0, "call", "s1", "s2", 1),
        Transition(1500.0, "return", "s2", "s1", 0),
        Transition(2000.0, "goto", "s1", "s3", 0),
        Transition(2500.0, "exit", "s3", "", 0),
    ]


def test_assignments_run_in_order_and_feed_later_conditions():
    mission = check_source("""
mission vars
var top = 5
var bottom = 20
state a begin
  flightprofile yo(top, bottom, .454, .454)
  sensors depth, missiontime
  events
    case missiontime >= 3 && bottom == 20 set bottom = depth + 2, top = bottom - 10
    case bottom == 12 exit
end
""").mission
    machine, _ = start(mission)
    for t in range(5):
        machine, transition = step(mission, machine, {"depth": 10.0, "missiontime": t}, t)
        if t == 3:
            assert machine.variables == {"top": 2.0, "bottom": 12.0}
    assert machine.exited


def test_return_with_empty_stack_is_a_fault():
    # The checker rejects this mission; the semantics must still refuse it, not crash.
    mission = ir.CheckedMission("m", (ir.State(
        "a", ir.Route("noheading"), (), (),
        (ir.Event(ir.Const(1.0), action="return"),)),))
    machine, _ = start(mission)
    with pytest.raises(MissionFault, match="empty stack"):
        step(mission, machine, {}, 7.0)

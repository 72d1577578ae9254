"""Every checker and flow-analysis diagnostic, one mission fragment per case."""

from __future__ import annotations

import math

import pytest

from gliderplan.contract import MAX_ROUTE_POINTS
from gliderplan.language import check_source

_TEMPLATE = """mission m
{decl}
state s1
begin
  flightroute {route}
  flightprofile {profile}
  sensors {sensors}
  events
    {event}
    case missiontime > 100 exit
end
{states}"""

_DEFAULTS = {"decl": "", "route": "noheading", "profile": "yo(5, 20, .454, .454)",
             "sensors": "missiontime, depth", "event": "", "states": ""}


def _diagnostics(**parts: str) -> list[str]:
    source = _TEMPLATE.format(**{**_DEFAULTS, **parts})
    result = check_source(source, "m.mission")
    return [f"{d.severity}: {d.message} | {d.hint}" for d in result.diagnostics]


def _state(name: str, event: str, sensors: str = "missiontime, depth") -> str:
    return (f"state {name}\nbegin\n  flightprofile surface\n  sensors {sensors}\n"
            f"  events\n    {event}\nend\n")


CASES = [
    # names, with suggestions
    ({"event": "case depth > 5 goto s11"}, "error: unknown state 's11' | did you mean 's1'?"),
    ({"event": "case temperature > 5 exit"},
     "error: unknown sensor or variable 'temperature' | did you mean 'temp'?"),
    ({"sensors": "missiontime, depht"}, "error: unknown sensor 'depht' | did you mean 'depth'?"),
    ({"profile": "yoyo(5, 20, .454, .454)"}, "error: unknown flight profile 'yoyo' | did you"),
    ({"route": "navv(3910.5, -7349.8)"}, "error: unknown flight route 'navv' | did you mean"),
    ({"event": "case abss(depth) > 5 exit"}, "error: unknown function 'abss' | did you mean"),
    ({"event": "case depth > 5 set x = 1 exit"}, "error: unknown variable 'x'"),
    ({"event": "case depth > 5 set depth = 1 exit"},
     "error: unknown variable 'depth' | sensors are read-only"),
    # arguments
    ({"profile": "yo(5, 20, .454)"}, "error: 'yo' takes 4 or 5 argument(s), got 3 | "
     "yo(min_depth [m], max_depth [m], dive_pitch [rad], climb_pitch [rad], [altitude [m]])"),
    ({"profile": "yo(5, 20, .454, .454, 4, 1)"}, "error: 'yo' takes 4 or 5 argument(s), got 6"),
    ({"profile": "thermotrackyo(5, 20, .454, .454, 3, 6, 4, 1)"},
     "error: 'thermotrackyo' takes 6 or 7 argument(s), got 8"),
    ({"profile": "yo(5, 20, .454, .454, -4)"},
     "error: altitude of 'yo' is -4 m, outside [0, inf] | the height above the sea floor"),
    ({"profile": "thermotrackyo(5, 20, .454, .454, 3, 6, -1)"},
     "error: altitude of 'thermotrackyo' is -1 m, outside"),
    ({"profile": "yo(5, 20, .454, .454, 0/0)"},
     "error: altitude of 'yo' is nan, not a finite number"),
    ({"profile": "yo(5, 20, .454, .454, 1/0)"},
     "error: altitude of 'yo' is inf, not a finite number"),
    ({"profile": "yo(5, 20, .454, .454, depth)"}, "error: sensor 'depth' cannot be used here"),
    ({"profile": "yo(5, 20, .454, .454, floor)"}, "error: unknown sensor or variable 'floor'"),
    ({"route": "nav(3910.5)"}, "error: 'nav' takes lat [DDMM.MMMM], lon [DDMM.MMMM]"),
    ({"route": "sweep(100, (3910, -7349), (3911, -7349))"}, "error: 'sweep' takes spacing"),
    ({"profile": "yo(-5, 20, .454, .454)"}, "error: min_depth of 'yo' is -5 m, outside"),
    ({"profile": "yo(20, 5, .454, .454)"}, "error: min depth 20 m is not above max depth 5 m"),
    ({"profile": "yo(5, 20, 0, .454)"}, "error: dive_pitch of 'yo' is 0 rad, outside (0,"),
    ({"profile": "yo(5, 20, .454, 1.6)"}, "error: climb_pitch of 'yo' is 1.6 rad, outside"),
    ({"route": "nav(3975.5, -7349.8)"}, "error: 3975.5 is not DDMM.MMMM"),
    ({"route": "nav(9100, -7349.8)"}, "error: lat of 'nav' is 9100 DDMM.MMMM, outside"),
    ({"route": "heading(360)"}, "error: heading of 'heading' is 360 deg, outside [0, 360) | "
     "a compass heading in degrees, true, clockwise from north: 0 north, 90 east"),
    ({"route": "heading(-90)"}, "error: heading of 'heading' is -90 deg, outside [0, 360)"),
    ({"route": "heading(90, (3910, -7349))"}, "error: 'heading' takes heading"),
    ({"profile": "hover(depth)"}, "error: sensor 'depth' cannot be used here"),
    ({"event": "case max(depth) > 5 exit"}, "error: 'max' takes 2 argument(s), got 1"),
    ({"sensors": "missiontime, depth duty auto"},
     "error: 'depth' is a flight sensor, always on: it has no duty"),
    ({"sensors": "missiontime, temp duty 1.5"}, "error: duty must lie between 0 and 1"),
    ({"sensors": "missiontime, depth, depth"}, "error: sensor 'depth' is listed twice"),
    # structure
    ({"states": _state("s1", "case missiontime > 5 exit")}, "error: state 's1' is defined twice"),
    ({"states": "state s2\nbegin\n  sensors depth\nend\n"},
     "error: state 's2' has no flightprofile"),
    ({"event": "case depth > 5"}, "error: this event does nothing"),
    ({"decl": "vehicle slocum_g9"}, "error: unknown vehicle preset 'slocum_g9' | did you mean"),
    ({"decl": "computer ts7700 @ 300 MHz"}, "error: unknown board preset 'ts7700' | did you"),
    ({"decl": "horizon 1 h\nhorizon 2 h"}, "error: 'horizon' is declared twice"),
    ({"decl": "var depth = 1"}, "error: variable 'depth' has the name of a sensor"),
    ({"decl": "var v = 1\nvar v = 2"}, "error: variable 'v' is declared twice"),
    ({"decl": "var v = depth"}, "error: sensor 'depth' cannot be used here"),
    ({"decl": "stack 100"}, "error: stack depth must be a whole number from 1 to 32"),
    ({"decl": "stack 40"}, "error: stack depth must be a whole number from 1 to 32 | the "
                           "runtime's state stack holds at most 32 states"),
    ({"decl": "objective maximize energy"}, "error: cannot maximize 'energy'"),
    ({"decl": "objective maximize quality quality >= 0.5"},
     "warning: a quality floor has no effect when maximizing quality"),
    # units and contradictory annotations
    ({"decl": "battery 1.2"}, "error: missing unit: expected energy or charge"),
    ({"decl": "battery 1.2 kW"}, "error: 'kW' is not a unit of energy or charge"),
    ({"decl": "battery 1.2 kwh"}, "error: 'kwh' is not a unit of energy or charge | did you "
                                  "mean 'kWh'? (units are case-sensitive)"),
    ({"decl": "battery 60 Ah"}, "error: a charge needs a voltage to become energy"),
    ({"decl": "battery 1 kWh at 14 V"}, "error: a voltage only applies to a charge (Ah)"),
    ({"decl": "battery 1 kWh reserve 100 %"},
     "error: reserve must be at least 0 % and below 100 %"),
    ({"decl": "horizon 36"}, "error: missing unit: expected time"),
    ({"decl": "horizon 0 h"}, "error: horizon must lie between one tick (4 s) and 10 years"),
    ({"decl": "computer ts7800 @ 300"}, "error: missing unit: expected clock frequency"),
    ({"decl": "sensor temp duty >= 0.8 duty <= 0.2"},
     "error: duty bounds of 'temp' contradict each other: at least 0.8 but at most 0.2"),
    ({"decl": "sensor temp duty >= 1.5"}, "error: duty must lie between 0 and 1"),
    ({"decl": "sensor temp weight -1"}, "error: a weight must lie between 0 and 1e+06"),
    ({"decl": "sensor temp\nsensor temp"}, "error: sensor 'temp' is annotated twice"),
    ({"sensors": "missiontime, temp\n  expect 2 h .. 20 min"},
     "error: expected time must be a range 'low .. high'"),
    ({"sensors": "missiontime, temp\n  require oxygen duty >= 0.5"},
     "error: requirement on 'oxygen', which this state does not log"),
    ({"sensors": "missiontime, temp\n  require temp weight 2"},
     "error: a weight is mission-wide: put it on a 'sensor' line"),
    # flow
    ({"event": "case depth > 5 return"}, "error: 'return' in state 's1' can run with an empty "
                                          "stack | it is the start state"),
    ({"event": "case depth > 5 goto s2", "states": _state("s2", "case depth > 1 return")},
     "error: 'return' in state 's2' can run with an empty stack | it is entered by 'goto'"),
    ({"event": "case depth > 5 call s2", "states": _state("s2", "case depth > 1 call s1")},
     "error: call cycle s1 -> s2 -> s1 makes the state stack grow without bound"),
    ({"event": "case depth > 5 call s2", "states": _state("s2", "case depth > 1 call s2")},
     "error: call cycle s2 -> s2 makes the state stack grow without bound"),
    ({"decl": "stack 1", "event": "case depth > 5 call s2",
      "states": _state("s2", "case depth > 1 call s3") + _state("s3", "case depth > 1 return")},
     "error: calls nest 2 deep (s1 -> s2 -> s3), deeper than the runtime stack of 1"),
    ({"states": _state("s2", "case depth > 1 exit")}, "warning: state 's2' is never entered"),
    ({"event": "case depth < 0 goto s2", "states": _state("s2", "case depth > 1 exit")},
     "warning: state 's2' is never entered | no goto or call that can fire leads to it"),
    ({"event": "case depth > 5 goto s2", "states": _state("s2", "case depth > 1 goto s2")},
     "warning: state 's2' can never reach 'exit'"),
    ({"event": "case temp > 5 goto s1"},
     "warning: event reads 'temp', which state 's1' does not log"),
    ({"event": "case depth < 0 goto s1"}, "warning: this condition can never be true"),
    ({"event": "case depth == -1 goto s1"}, "warning: this condition can never be true"),
    ({"event": "case depth > 5 && depth < 5 goto s1"}, "warning: this condition can never be"),
    ({"event": "case depth > 10 && depth < 5 goto s1"},
     "warning: this condition can never be true"),
    ({"event": "case 1 > 2 || pitch > 2 goto s1"}, "warning: this condition can never be true"),
    ({"event": "case 1 goto s1"}, "warning: this event can never fire | the event on line 9"),
]


@pytest.mark.parametrize(("parts", "expected"), CASES, ids=lambda v: str(v)[:60])
def test_diagnostic(parts, expected):
    found = _diagnostics(**parts)
    matching = [d for d in found if d.startswith(expected)]
    assert len(matching) == 1, found


def test_mission_that_never_exits():
    source = "mission m\nstate s1\nbegin\n  flightprofile surface\nend\n"
    (diagnostic,) = check_source(source).diagnostics
    assert (diagnostic.severity, diagnostic.message) == ("warning", "mission 'm' never exits")


def test_the_template_itself_is_clean():
    assert _diagnostics() == []


def _sweep(corners: int) -> str:
    """A sweep over `corners` points on a circle about 39 10'N 73 49'W."""
    ring = ((3910 + 0.5 * math.sin(2 * math.pi * k / corners),
             -7349 + 0.5 * math.cos(2 * math.pi * k / corners)) for k in range(corners))
    return "sweep(100, " + ", ".join(f"({lat:.4f}, {lon:.4f})" for lat, lon in ring) + ")"


def test_a_sweep_takes_as_many_corners_as_the_runtime_s_route_table_holds():
    assert _diagnostics(route=_sweep(MAX_ROUTE_POINTS)) == []
    (refused,) = _diagnostics(route=_sweep(MAX_ROUTE_POINTS + 1))
    assert refused.startswith(f"error: 'sweep' takes spacing [m], 3 to {MAX_ROUTE_POINTS} "
                              "(lat, lon) points"), refused


def test_all_errors_of_a_pass_at_once():
    found = _diagnostics(decl="battery 1.2 kW\nhorizon 36", route="navv(1, 2)",
                         profile="yo(20, 5, .454, .454)", event="case dept > 1 goto s9")
    assert len([d for d in found if d.startswith("error")]) == 6, found


@pytest.mark.parametrize("condition", ["depth <= 0", "depth >= 5 && depth <= 5", "depth < v",
                                       "depth < 1.5", "missiontime > 100 || depth < 0"])
def test_conditions_that_can_hold_are_not_flagged(condition):
    assert _diagnostics(decl="var v = 1", event=f"case {condition} goto s1") == []


def test_a_very_long_call_chain_is_reported_briefly():
    def state(i: int) -> str:
        action = f"call s{i + 1}" if i < 2999 else "exit"
        back = "    case depth < 1 return\n" if i else ""
        return (f"state s{i}\nbegin\n  flightprofile surface\n  sensors depth\n  events\n"
                f"    case depth > 1 {action}\n{back}end\n")

    states = [state(i) for i in range(3000)]
    result = check_source("mission m\n" + "".join(states))
    chain, size = result.diagnostics  # more states than the runtime holds, too
    assert chain.message == ("calls nest 2999 deep (s0 -> s1 -> s2 -> s3 -> ... -> s2996 "
                             "-> s2997 -> s2998 -> s2999), deeper than the runtime stack of 8")
    assert size.message.startswith("the mission has 3000 states, more than the 64")


def test_rendering_splits_the_source_once_however_many_diagnostics():
    """Each message looks its line up in one list of lines: rendering grows with the
    number of messages, not with messages times the length of the file."""
    from gliderplan.language.diagnostics import render_all

    class CountingSource(str):
        splits = 0

        def splitlines(self, keepends: bool = False) -> list[str]:
            CountingSource.splits += 1
            return super().splitlines(keepends)

    spares = "".join(_state(f"spare{i}", "case missiontime > 5 exit") for i in range(300))
    source = _TEMPLATE.format(**{**_DEFAULTS, "states": spares})
    result = check_source(source, "m.mission")
    never_entered = [d for d in result.diagnostics if "is never entered" in d.message]
    assert len(never_entered) == 300

    text = render_all(result.diagnostics, "m.mission", CountingSource(source))

    assert CountingSource.splits == 1
    last = never_entered[-1].span.line
    assert f"m.mission:{last}:7: warning: state 'spare299' is never entered" in text
    assert f"{last:>5} | state spare299\n" in text


def test_checking_leaves_the_cycle_collector_as_it_found_it():
    """check_source pauses Python's cycle collector while it builds its trees; afterwards
    the collector runs as before, on what was there before as on what comes after."""
    import gc
    import weakref

    class Node:
        pass

    def cycle() -> weakref.ref:
        a, b = Node(), Node()
        a.other, b.other = b, a
        return weakref.ref(a)

    before = cycle()
    assert gc.isenabled()
    assert check_source(_TEMPLATE.format(**_DEFAULTS), "m.mission").ok
    assert gc.isenabled()
    after = cycle()
    gc.collect()
    assert before() is None and after() is None
    gc.disable()
    try:
        check_source(_TEMPLATE.format(**_DEFAULTS), "m.mission")
        assert not gc.isenabled()
    finally:
        gc.enable()


@pytest.mark.parametrize("profile", ["yo(5, 20, .454, .454, 4)", "yo(5, 20, .454, .454, 0)",
                                     "yo(5, 20, .454, .454, v)",
                                     "thermotrackyo(5, 20, .454, .454, 3, 6, 4)"])
def test_a_yo_s_altimeter_stop_is_an_optional_last_argument(profile):
    assert _diagnostics(decl="var v = 2", profile=profile) == []
    args = check_source(_TEMPLATE.format(**{**_DEFAULTS, "decl": "var v = 2",
                                            "profile": profile})).mission.states[0].profiles[0]
    assert len(args.args) == profile.count(",") + 1  # kept as written, not filled in

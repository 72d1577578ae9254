"""Flow analysis of a checked mission: what the state machine can and cannot do.

The stack only grows through `call` (goto clears it, return pops), so a state can
run with an empty stack exactly when it is the start state or a goto target, and
the deepest stack is the longest chain of call edges.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

from gliderplan.language import ast, ir
from gliderplan.language.diagnostics import Diagnostic, error, warning


def _ast_events(state: ast.State) -> list[ast.Event]:
    for item in state.items:
        if isinstance(item, ast.EventsItem):
            return list(item.events)
    return []


def _edges(mission: ir.CheckedMission, kind: str) -> dict[str, list[str]]:
    return {s.name: [e.target for e in s.events if e.action == kind and e.target]
            for s in mission.states}


def reachable_states(mission: ir.CheckedMission,
                     impossible: Mapping[int, bool] | None = None) -> set[str]:
    """States the start state can lead to through goto and call (return goes back).

    An event whose condition can never be true leads nowhere; `impossible` may hold
    `never_true` of each event's condition already, by the event's id().
    """
    def leads_nowhere(event: ir.Event) -> bool:
        if impossible is not None:
            return impossible[id(event)]
        return never_true(event.condition)

    seen = {mission.states[0].name}
    todo = [mission.states[0].name]
    while todo:
        state = mission.state(todo.pop())
        for event in state.events:
            if event.target and event.target not in seen and not leads_nowhere(event):
                seen.add(event.target)
                todo.append(event.target)
    return seen


def _call_cycle(calls: Mapping[str, list[str]], roots: set[str]) -> list[str] | None:
    """A cycle of call edges among states reachable from roots, as a path, or None.

    Depth-first with an explicit stack: call chains may be thousands of states long.
    """
    colour: dict[str, int] = {}  # 1 on the current path, 2 done
    for root in sorted(roots):
        if root in colour:
            continue
        colour[root] = 1
        path, pending = [root], [iter(calls[root])]
        while pending:
            target = next(pending[-1], None)
            if target is None:
                colour[path.pop()] = 2
                pending.pop()
            elif colour.get(target) == 1:
                return path[path.index(target):] + [target]
            elif target not in colour:
                colour[target] = 1
                path.append(target)
                pending.append(iter(calls[target]))
    return None


def _deepest_call_chain(calls: Mapping[str, list[str]], roots: set[str]) -> list[str]:
    """Longest path of call edges from a root (the call graph is acyclic here)."""
    longest: dict[str, list[str]] = {}
    for root in sorted(roots):
        stack = [root]
        while stack:  # post-order: a state's chain once all its callees' are known
            state = stack[-1]
            waiting = [t for t in calls[state] if t not in longest]
            if waiting:
                stack.extend(waiting)
                continue
            stack.pop()
            tails = [longest[t] for t in calls[state]]
            longest[state] = [state] + max(tails, key=len, default=[])
    return max((longest[r] for r in sorted(roots)), key=len, default=[])


class _Interval(NamedTuple):
    """Values a sensor may take for a condition to hold; open ends exclude the bound."""

    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False

    def meet(self, other: _Interval) -> _Interval:
        low, low_open = max((self.low, self.low_open), (other.low, other.low_open))
        high, high_open = min((self.high, not self.high_open), (other.high, not other.high_open))
        return _Interval(low, high, low_open, not high_open)

    @property
    def empty(self) -> bool:
        return self.low > self.high or (self.low == self.high
                                         and (self.low_open or self.high_open))


# Physical range of flight sensors, for conditions that can never hold.
_SENSOR_RANGE = {
    "missiontime": _Interval(0.0, math.inf),
    "depth": _Interval(0.0, math.inf),
    "altitude": _Interval(0.0, math.inf),
    "pitch": _Interval(-math.pi / 2, math.pi / 2),
    "roll": _Interval(-math.pi, math.pi),
}


def _intervals(expr: ir.Expr) -> dict[str, _Interval] | None:
    """Per-sensor bounds implied by a conjunction of `sensor CMP constant`.

    Returns None when the expression is not such a conjunction (nothing is decided).
    Finds contradictions such as `missiontime < 100 && missiontime > 200` or `depth < 0`.
    """
    match expr:
        case ir.BinaryOp("&&", left, right):
            a, b = _intervals(left), _intervals(right)
            if a is None or b is None:
                return a or b
            merged = dict(a)
            for name, interval in b.items():
                merged[name] = merged.get(name, _Interval()).meet(interval)
            return merged
        case ir.BinaryOp(op, ir.SensorRef(name), constant) if op in _FLIP and ir.is_constant(
                constant):
            return {name: _bound(op, ir.evaluate(constant, {}, {}))}
        case ir.BinaryOp(op, constant, ir.SensorRef(name)) if op in _FLIP and ir.is_constant(
                constant):
            return {name: _bound(_FLIP[op], ir.evaluate(constant, {}, {}))}
    return None


_FLIP = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "==": "=="}


def _bound(op: str, value: float) -> _Interval:
    if op in ("<", "<="):
        return _Interval(high=value, high_open=op == "<")
    if op in (">", ">="):
        return _Interval(low=value, low_open=op == ">")
    return _Interval(value, value)


def never_true(condition: ir.Expr) -> bool:
    """True when the condition is statically false (constant, or contradictory bounds)."""
    if ir.is_constant(condition):
        return ir.evaluate(condition, {}, {}) == 0.0
    if isinstance(condition, ir.BinaryOp) and condition.op == "||":
        return never_true(condition.left) and never_true(condition.right)
    bounds = _intervals(condition)
    if not bounds:
        return False
    return any(interval.meet(_SENSOR_RANGE.get(name, _Interval())).empty
               for name, interval in bounds.items())


def _always_true(condition: ir.Expr) -> bool:
    return ir.is_constant(condition) and ir.evaluate(condition, {}, {}) != 0.0


def _path_text(states: list[str], shown: int = 8) -> str:
    """`a -> b -> c`, shortened in the middle when long."""
    if len(states) > shown:
        states = states[: shown // 2] + ["..."] + states[-(shown // 2):]
    return " -> ".join(states)


def check_flow(mission: ir.CheckedMission, states: Mapping[str, ast.State]) -> list[Diagnostic]:
    """All flow diagnostics; `states` maps names to their syntax (for locations)."""
    found: list[Diagnostic] = []
    impossible = {id(e): never_true(e.condition) for s in mission.states for e in s.events}
    reachable = reachable_states(mission, impossible)
    calls = _edges(mission, "call")
    gotos = _edges(mission, "goto")
    start = mission.states[0].name
    empty_stack = {start} | {t for s in reachable for t in gotos[s]}

    for state in mission.states:
        syntax = states[state.name]
        if state.name not in reachable:
            found.append(warning(f"state '{state.name}' is never entered", syntax.name.span,
                                 "no goto or call that can fire leads to it from the start state "
                                 f"'{start}'"))
            continue
        logged = {s.name for s in state.sensors}
        fired_always_at: int | None = None
        for event, node in zip(state.events, _ast_events(syntax), strict=True):
            if fired_always_at is not None and event.action:
                found.append(warning("this event can never fire", node.span,
                                     f"the event on line {fired_always_at} is always true "
                                     "and fires first"))
            for sensor in sorted(ir.sensors_read(event.condition) - logged):
                found.append(warning(
                    f"event reads '{sensor}', which state '{state.name}' does not log",
                    node.condition.span, f"add '{sensor}' to the sensors of '{state.name}'"))
            if impossible[id(event)]:
                found.append(warning("this condition can never be true", node.condition.span))
            elif _always_true(event.condition) and event.action and fired_always_at is None:
                fired_always_at = node.span.line
            if event.action == "return" and state.name in empty_stack:
                how = ("it is the start state" if state.name == start
                       else "it is entered by 'goto', which empties the stack")
                found.append(error(
                    f"'return' in state '{state.name}' can run with an empty stack",
                    node.action.span, f"{how}; enter it with 'call', or leave it with 'goto'"))

    cycle = _call_cycle(calls, reachable)
    if cycle:
        first = states[cycle[0]]
        call_span = next(n.action.span for n, e in zip(_ast_events(first),
                                                        mission.state(cycle[0]).events,
                                                        strict=True)
                         if e.action == "call" and e.target == cycle[1])
        found.append(error(
            f"call cycle {_path_text(cycle)} makes the state stack grow without bound",
            call_span,
            f"the runtime's stack holds {mission.stack_depth} states; break the cycle with "
            "'return' or 'goto'"))
    else:
        chain = _deepest_call_chain(calls, empty_stack & reachable)
        depth = len(chain) - 1
        if depth > mission.stack_depth:
            found.append(error(
                f"calls nest {depth} deep ({_path_text(chain)}), deeper than the runtime "
                f"stack of {mission.stack_depth}", states[chain[0]].name.span,
                f"raise the bound with 'stack {depth}' or flatten the calls"))

    found.extend(_exit_warnings(mission, reachable, calls, gotos, states))
    return found


def _exit_warnings(mission: ir.CheckedMission, reachable: set[str],
                   calls: Mapping[str, list[str]], gotos: Mapping[str, list[str]],
                   states: Mapping[str, ast.State]) -> list[Diagnostic]:
    """States from which no sequence of transitions reaches `exit`."""
    exits = {s.name for s in mission.states if any(e.action == "exit" for e in s.events)}
    if not exits:
        return [warning(f"mission '{mission.name}' never exits", ast.NO_SPAN,
                        "add 'case ... exit' to a state; until then the mission runs until "
                        "the battery is flat")]
    # Walk transitions backwards from the exiting states (linear in states + edges).
    # `return` leads back to any state that calls the returning one.
    returns = {s.name for s in mission.states if any(e.action == "return" for e in s.events)}
    predecessors: dict[str, list[str]] = {s.name: [] for s in mission.states}
    for source in predecessors:
        for target in gotos[source] + calls[source]:
            predecessors[target].append(source)
            if target in returns:
                predecessors[source].append(target)
    can_exit = set(exits)
    todo = list(exits)
    while todo:
        for earlier in predecessors[todo.pop()]:
            if earlier not in can_exit:
                can_exit.add(earlier)
                todo.append(earlier)
    return [
        warning(f"state '{s.name}' can never reach 'exit'", states[s.name].name.span,
                "once here, the mission runs until the battery is flat")
        for s in mission.states
        if s.name in reachable and s.name not in can_exit
    ]

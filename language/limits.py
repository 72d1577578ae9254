"""The sizes the runtime's tables and the plan file hold, checked on the syntax tree.

Every limit is `gliderplan.contract`'s, the definition the code generator, the C
runtime and the plan reader use: a mission `check` accepts is never refused later for
its size. The check reads the tree as written, so it reports alongside every other
problem and never holds up the flow analysis.
"""

from __future__ import annotations

from collections.abc import Sequence

from gliderplan.contract import (
    MAX_EVENTS_PER_STATE,
    MAX_EXPRESSION_DEPTH,
    MAX_NAME_LENGTH,
    MAX_PROFILE_ALTERNATIVES,
    MAX_STATES,
    MAX_VARIABLES,
)
from gliderplan.language import ast
from gliderplan.language.diagnostics import Diagnostic, error


def check_sizes(mission: ast.Mission) -> list[Diagnostic]:
    """An error at the first item past each limit, and at each name too long."""
    found: list[Diagnostic] = []

    def at_most(items: Sequence[ast.Node], most: int, owner: str, what: str, hint: str) -> None:
        if len(items) > most:
            found.append(error(f"{owner} has {len(items)} {what}, more than the {most} the "
                               "runtime holds", items[most].span, hint))

    def name_fits(name: ast.Ident, what: str) -> None:
        if len(name.text) > MAX_NAME_LENGTH:
            found.append(error(f"{what} '{name.text}' has {len(name.text)} characters, more "
                               f"than the {MAX_NAME_LENGTH} a plan file holds", name.span,
                               "choose a shorter name"))

    def shallow(expr: ast.Expr | ast.Point) -> None:
        depth = _depth(expr)
        if depth > MAX_EXPRESSION_DEPTH:
            found.append(error(f"expression nested {depth} operators deep, more than the "
                               f"{MAX_EXPRESSION_DEPTH} a mission may hold", expr.span,
                               "split the expression with a variable ('set v = ...')"))

    name_fits(mission.name, "mission name")
    for declaration in mission.declarations:
        if isinstance(declaration, ast.VarDecl):
            shallow(declaration.initial)
    at_most([s.name for s in mission.states], MAX_STATES, "the mission", "states",
            "split the mission, or merge states that fly alike")
    at_most([d.name for d in mission.declarations if isinstance(d, ast.VarDecl)],
            MAX_VARIABLES, "the mission", "variables",
            "reuse a variable whose value is no longer needed")
    for state in mission.states:
        name_fits(state.name, "state name")
        owner = f"state '{state.name.text}'"
        for item in state.items:
            match item:
                case ast.RouteItem(route):
                    for arg in route.args:
                        shallow(arg)
                case ast.ProfileItem(alternatives):
                    at_most(alternatives, MAX_PROFILE_ALTERNATIVES, owner,
                            "flight-profile alternatives",
                            "fly the others in a state of their own")
                    for arg in (a for profile in alternatives for a in profile.args):
                        shallow(arg)
                case ast.EventsItem(events):
                    at_most(events, MAX_EVENTS_PER_STATE, owner, "events",
                            "split the state, or combine events that do the same")
                    for event in events:
                        shallow(event.condition)
                        for assignment in event.assignments:
                            shallow(assignment.value)
    return found


def _depth(expr: ast.Expr | ast.Point) -> int:
    """Operators and calls nested in `expr`, counted without recursion (it may be nested
    beyond Python's stack)."""
    deepest, pending = 0, [(expr, 0)]
    while pending:
        node, depth = pending.pop()
        match node:
            case ast.Unary(_, operand):
                pending.append((operand, depth + 1))
            case ast.Binary(_, left, right):
                pending += [(left, depth + 1), (right, depth + 1)]
            case ast.Call(_, args):
                pending += [(arg, depth + 1) for arg in args]
            case ast.Point(lat, lon):
                pending += [(lat, depth), (lon, depth)]
            case _:
                deepest = max(deepest, depth)
    return deepest

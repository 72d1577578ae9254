"""The plan report: JSON for the simulator and for tools, a table for people."""

from __future__ import annotations

import math

from gliderplan.planner.plan import J_PER_WH, InfeasibleBudget, Plan, StatePlan

REPORT_VERSION = 1


def _state_json(s: StatePlan) -> dict:
    return {
        "name": s.name,
        "time_s": s.time_s,
        "visits": s.visits,
        "clock_mhz": s.clock_mhz,
        "cycle_s": s.cycle_s,
        "energy_j": s.energy_j,
        "energy_by_component_j": dict(s.energy_by_component_j),
        "inflections": s.inflections,
        "profiles": [{"index": p.index, "kind": p.kind, "share": p.share,
                      "speed_mps": p.speed_mps, "pitch_rad": p.pitch_rad,
                      "ballast_cc": p.ballast_cc} for p in s.profiles],
        "sensors": [{"name": x.name, "device": x.device, "duty": x.duty,
                     "period_s": x.period_s, "on_s": x.on_s} for x in s.sensors],
        "quality": s.quality,
    }


def report_json(plan: Plan) -> dict:
    """The JSON report (planner/README.md documents every field)."""
    return {
        "report_version": REPORT_VERSION,
        "mission": plan.mission,
        "hash": plan.mission_hash,
        "status": plan.status,
        "objective": plan.objective,
        "quality": plan.quality,
        "energy_j": plan.energy_j,
        "budget_j": plan.budget_j,
        "minimum_energy_j": plan.minimum_energy_j,
        "shadow_price": plan.shadow_price,
        "shadow_price_unit": "quality per Wh",
        "computer": {"board": plan.computer, "clock_mhz": plan.clock_mhz},
        "defaults_used": list(plan.defaults_used),
        "time_source": plan.time_source,
        "solver": {"name": "CLARABEL", "status": plan.solver_status,
                   "time_s": plan.solve_s, "iterations": plan.solver_iterations},
        "components_j": plan.components_j,
        "states": [_state_json(s) for s in plan.states],
        "confidence": plan.confidence.to_json() if plan.confidence is not None else None,
    }


def infeasible_json(short: InfeasibleBudget) -> dict:
    """The report of a budget below what the mission needs."""
    return {"report_version": REPORT_VERSION, "status": "infeasible", "message": str(short),
            "budget_j": short.budget_j, "minimum_energy_j": short.minimum_j,
            "shortfall_j": short.minimum_j - short.budget_j,
            "largest_consumers_j": dict(short.consumers)}


def _wh(joules: float) -> str:
    """Three significant figures, without an exponent a pilot would have to decode."""
    wh = joules / J_PER_WH
    return f"{wh:,.0f}" if abs(wh) >= 1000 else f"{wh:.3g}"


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    fmt = "  ".join(f"{{:{'<' if i == 0 else '>'}{w}}}" for i, w in enumerate(widths))
    return [fmt.format(*header), *(fmt.format(*r) for r in rows)]


def _does(s: StatePlan) -> str:
    flying = ", ".join(
        f"{p.kind}#{p.index} {100 * p.share:.0f}% @ {p.speed_mps:.2f} m/s"
        for p in s.profiles if p.share > 5e-4)
    sensors = ", ".join(f"{x.name} {100 * x.duty:.0f}%" for x in s.sensors)
    return flying + (f"; {sensors}" if sensors else "")


def report_text(plan: Plan) -> str:
    """A readable summary: what each state does, energy by component, quality, price."""
    lines = [f"mission {plan.mission}: {plan.objective.replace('_', ' ')} on "
             f"{plan.computer} @ {plan.clock_mhz:g} MHz",
             f"quality {plan.quality:.4f}   energy {_wh(plan.energy_j)} Wh of a "
             f"{_wh(plan.budget_j)} Wh budget ({100 * plan.energy_j / plan.budget_j:.1f} %)"
             f"   minimum {_wh(plan.minimum_energy_j)} Wh",
             f"shadow price {plan.shadow_price:.4g} quality per extra Wh"
             + ("  (the budget is not the limit)" if plan.shadow_price < 1e-9 else ""),
             "", "what each state does:"]
    if plan.confidence is not None:
        c = plan.confidence
        lines.insert(3, f"confidence {c.achieved:.3g} (asked {c.requested:g}): the budget "
                        f"holds in all {c.scenarios} simulated scenarios; {c.method}, risk "
                        f"{c.risk:g}, {c.dimension} decisions, {c.support} scenarios active; "
                        "the shadow price is at this confidence")
    lines += _table(["state", "time h", "clock", "plan"],
                    [[s.name, f"{s.time_s / 3600:.2f}", f"{s.clock_mhz:g}", _does(s)]
                     for s in plan.states])
    components = list(plan.components_j)
    lines += ["", "energy by component [Wh]:"]
    rows = [[s.name, *(_wh(s.energy_by_component_j.get(c, 0.0)) for c in components),
             _wh(s.energy_j), "-" if s.quality is None or math.isnan(s.quality)
             else f"{s.quality:.3f}"] for s in plan.states]
    rows.append(["total", *(_wh(plan.components_j[c]) for c in components),
                 _wh(plan.energy_j), f"{plan.quality:.3f}"])
    lines += _table(["state", *components, "total", "quality"], rows)
    if plan.defaults_used:
        lines += ["", "defaults and assumptions used:"]
        lines += [f"  - {d}" for d in plan.defaults_used]
    lines.append(f"\nsolver: {plan.solver_status}, {plan.solver_iterations} iterations, "
                 f"{1000 * plan.solve_s:.1f} ms")
    return "\n".join(lines) + "\n"

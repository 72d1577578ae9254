"""The plan report: JSON for tools, a table for people (the plan itself is in its file)."""

from __future__ import annotations

import math

from gliderplan.contract import SBD_MT_MESSAGE_BYTES
from gliderplan.language import ir
from gliderplan.planner.plan import J_PER_WH, InfeasibleBudget, PlanResult
from gliderplan.planner.planfile import StatePlan, computer_text

REPORT_VERSION = 1


def _state_json(result: PlanResult, s: int) -> dict:
    state, kinds = result.plan.states[s], result.mission.states[s].profiles
    propelled = [p for p in state.profiles if kinds[p.index].propelled and p.share > 0]
    # the chosen speed through the water [m/s] where the vehicle flies propelled: the
    # shares' mean over its propelled profiles
    speed = {"speed_m_s": sum(p.share * p.speed_mps for p in propelled)
             / sum(p.share for p in propelled)} if propelled else {}
    return {
        "name": state.name,
        "time_s": state.time_s,
        "visits": state.visits,
        "clock_mhz": state.clock_mhz,
        "sleep": state.sleep,
        "cycles_per_tick": state.cycles_per_tick,
        "cycle_s": state.cycle_s,
        "energy_j": state.energy_j,
        "energy_by_component_j": dict(state.energy_by_component_j),
        "inflections": state.inflections,
        "profiles": [{"index": p.index, "kind": kinds[p.index].kind, "share": p.share,
                      "speed_mps": p.speed_mps, "pitch_rad": p.pitch_rad,
                      "ballast_cc": p.ballast_cc} for p in state.profiles],
        "sensors": [{"name": x.name, "device": x.device, "duty": x.duty,
                     "period_s": x.period_s, "on_s": x.on_s} for x in state.sensors],
        "quality": result.state_quality[s],
        **speed,
    }


def sbd_messages(size_bytes: int) -> int:
    """Iridium SBD mobile-terminated messages a plan of `size_bytes` takes to send."""
    return -(-size_bytes // SBD_MT_MESSAGE_BYTES)


def report_json(result: PlanResult) -> dict:
    """The JSON report (planner/README.md documents every field)."""
    plan = result.plan
    return {
        "report_version": REPORT_VERSION,
        "mission": plan.mission,
        "hash": plan.mission_hash,
        "status": result.status,
        "objective": result.objective,
        "quality": result.quality,
        "energy_j": plan.predicted_j,
        "budget_j": plan.budget_j,
        "battery": {"energy_j": result.battery_j, "reserve_fraction": result.reserve_fraction},
        "budgeted_energy_j": result.budgeted_energy_j,
        "minimum_energy_j": result.minimum_energy_j,
        "shadow_price": result.shadow_price,
        "shadow_price_unit": "quality per Wh",
        "computer": {"board": plan.computer, "clock_mhz": plan.clock_mhz},
        "assumptions": [{"subject": a.subject, "text": a.text} for a in plan.assumptions],
        "time_source": result.time_source,
        "solver": {"name": "CLARABEL", "status": result.solver_status,
                   "time_s": result.solve_s, "iterations": result.solver_iterations},
        "components_j": plan.components_j,
        "states": [_state_json(result, s) for s in range(len(plan.states))],
        "confidence": result.confidence.to_json() if result.confidence is not None else None,
        "upload": {"bytes": result.upload_bytes, "signed": result.plan.seq > 0,
                   "seq": result.plan.seq, "sbd_messages": sbd_messages(result.upload_bytes)},
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


def _does(state: StatePlan, kinds: tuple[ir.Profile, ...]) -> str:
    flying = ", ".join(
        f"{kinds[p.index].kind}#{p.index} {100 * p.share:.0f}% @ {p.speed_mps:.2f} m/s"
        for p in state.profiles if p.share > 5e-4)
    sensors = ", ".join(f"{x.name} {100 * x.duty:.0f}%" for x in state.sensors)
    return flying + (f"; {sensors}" if sensors else "")


def report_text(result: PlanResult) -> str:
    """A readable summary: what each state does, energy by component, quality, price."""
    plan = result.plan
    lines = [f"mission {plan.mission}: {result.objective.replace('_', ' ')} on "
             f"{computer_text(plan.computer, plan.clock_mhz)}",
             f"quality {result.quality:.4f}   energy {_wh(plan.predicted_j)} Wh of a "
             f"{_wh(plan.budget_j)} Wh budget ({100 * plan.predicted_j / plan.budget_j:.1f} %)"
             f"   least budget {_wh(result.minimum_energy_j)} Wh",
             f"shadow price {result.shadow_price:.4g} quality per extra Wh"
             + ("  (the budget is not the limit)" if result.shadow_price < 1e-9 else ""),
             "", "what each state does:"]
    defaults = [a.text.split(" (default)")[0] for a in plan.assumptions
                if " (default)" in a.text]
    if defaults:  # beside the prediction, which rests on them
        lines.insert(3, f"defaults: {', '.join(defaults)} (not named by the mission)")
    if result.confidence is not None:
        c = result.confidence
        lines.insert(3, f"confidence {c.achieved:.3g} (asked {c.requested:g}): the budget "
                        f"holds in all {c.scenarios} simulated scenarios; {c.method}, risk "
                        f"{c.risk:g}, {c.dimension} decisions, {c.support} scenarios active; "
                        "the shadow price is at this confidence")
    lines += _table(["state", "time h", "clock MHz", "plan"],
                    [[s.name, f"{s.time_s / 3600:.2f}",
                      (f"{s.clock_mhz:g}" if s.clock_mhz else "-")  # 0: computer none
                      + (", asleep between ticks" if s.sleep else ""),
                      _does(s, m.profiles)]
                     for s, m in zip(plan.states, result.mission.states, strict=True)])
    components = list(plan.components_j)
    lines += ["", "energy by component [Wh]:"]
    rows = [[s.name, *(_wh(s.energy_by_component_j.get(c, 0.0)) for c in components),
             _wh(s.energy_j), "-" if q is None or math.isnan(q) else f"{q:.3f}"]
            for s, q in zip(plan.states, result.state_quality, strict=True)]
    rows.append(["total", *(_wh(plan.components_j[c]) for c in components),
                 _wh(plan.predicted_j), f"{result.quality:.3f}"])
    lines += _table(["state", *components, "total", "quality"], rows)
    if plan.assumptions:
        lines += ["", "defaults and assumptions used:"]
        lines += [f"  - {a}" for a in plan.assumptions]
    lines.append(f"\nsolver: {result.solver_status}, {result.solver_iterations} iterations, "
                 f"{1000 * result.solve_s:.1f} ms")
    if result.upload_bytes:
        messages = sbd_messages(result.upload_bytes)
        lines.append(f"upload: {result.upload_bytes} bytes, "
                     + (f"signed (seq {plan.seq})" if plan.seq else "unsigned")
                     + f"; {messages} Iridium SBD message{'s' if messages > 1 else ''} "
                     f"({SBD_MT_MESSAGE_BYTES} bytes each)")
    return "\n".join(lines) + "\n"

"""The board comparison as people and tools read it: a table, JSON, CSV files and a plot
of each board's energy against the workload per tick with the crossovers marked."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, TICK_S
from gliderplan.contract.files import OutputFolder, output_folder
from gliderplan.contract.units import J_PER_WH
from gliderplan.planner.compare import BoardResult, Comparison, Crossover
from gliderplan.power_models.computation import load_computations
from gliderplan.reports.figures import pyplot, render

FILES = ("boards.csv", "workload.csv", "crossovers.csv", "sbc.png")

# What every comparison rests on besides the boards' own figures and its workload.
MODEL_NOTES = (
    "cycles of the reference computations: i486 instructions counted by "
    "bench/bench_workloads.py x 4 cycles per instruction (an assumption), the same on "
    "every board",
    "energy against workload: the states' times of each board's own plan, each state at "
    "the board's cheapest clock for that workload",
    "endurance: the usable battery spent at the vehicle and sensor power of the mission's "
    "own plan (the same sampling plan for every board) plus each board's mean power",
)
UNMEASURED = ("the kernel's system calls, the serial line's interrupts and the journal's "
              "fdatasync around it")


def workload_basis(comparison: Comparison) -> str:
    """The workload the boards were compared at, and where it comes from."""
    cycles = comparison.cycles_per_tick
    if cycles == RUNTIME_CYCLES_PER_TICK:
        return (f"workload per tick: {cycles:,.0f} cycles, the runtime's whole {TICK_S:g} s "
                "tick on every board, an assumption (contract.RUNTIME_CYCLES_PER_TICK): the "
                "runtime's own code is measured where a board file gives runtime_instructions, "
                f"{UNMEASURED} are not; --cycles-per-tick sets another")
    return (f"workload per tick: {cycles:,.0f} cycles, given with --cycles-per-tick "
            f"(without it the runtime's whole tick is taken as {RUNTIME_CYCLES_PER_TICK:,.0f} "
            "cycles, an assumption)")


def boards(comparison: Comparison) -> list[BoardResult]:
    """The compared boards, without `none` (no board: nothing to rank or measure)."""
    return [r for r in comparison.boards if not r.board.is_none]


def cheapest_board(comparison: Comparison) -> BoardResult:
    """The board that costs the mission least energy (`none` aside)."""
    return min(boards(comparison) or comparison.boards, key=lambda r: r.energy.total_j)


def no_board_text(comparison: Comparison) -> str | None:
    """What the cheapest board adds to a mission on the glider's own computers, where
    `none` is compared beside the boards (a `computer none` mission); else None."""
    none = next((r for r in comparison.boards if r.board.is_none), None)
    if none is None or not boards(comparison):
        return None
    cheapest, alone = cheapest_board(comparison), none.planned.plan.predicted_j
    more = cheapest.planned.plan.predicted_j - alone
    return (f"without a board ({none.name}: the glider's own computers, whose power is in "
            f"the vehicle's base load) the mission takes {_wh(alone):.3g} Wh; the cheapest "
            f"board, {cheapest.name}, adds {_wh(more):.3g} Wh ({100 * more / alone:.1f} %), "
            f"{_wh(cheapest.energy.total_j):.3g} Wh of it its own")


def runtime_code_lines(comparison: Comparison) -> list[str]:
    """How the workload relates to the runtime's measured code, board by board: its
    cycles, their share of the workload, and what the rest costs the board on the mission."""
    lines, unmeasured = [], []
    for r in boards(comparison):
        code = r.runtime_code
        if code is None:
            unmeasured.append(r.name)
            continue
        rest = comparison.cycles_per_tick - code.cycles
        text = (f"{r.name}: the runtime's own code is {code.cycles:,.0f} cycles a tick, "
                f"{100 * code.share:.3g} % of the workload: {code.instructions:,.0f} "
                f"instructions ({code.sources['runtime_instructions']}) x "
                f"{code.cycles_per_instruction:g} cycles per instruction "
                f"({code.sources['cycles_per_instruction']})")
        if rest >= 0:
            share = 100 * code.rest_j / r.energy.total_j
            text += (f"; the other {rest:,.0f} cycles, for {UNMEASURED} (not measured), cost "
                     f"it {_wh(code.rest_j):.2g} Wh on this mission, {share:.2g} % of its "
                     "energy")
        lines.append(text)
    if unmeasured:
        lines.append(f"{', '.join(unmeasured)}: the runtime's own code is not measured on "
                     "this board's build (its board file gives no runtime_instructions)")
    return lines


def model_notes(comparison: Comparison) -> list[str]:
    """The workload the comparison was made at, where it comes from and how it relates to
    the runtime's measured code; then MODEL_NOTES."""
    return [workload_basis(comparison), *runtime_code_lines(comparison), *MODEL_NOTES]


def _wh(joules: float) -> float:
    return joules / J_PER_WH


def _clock(result: BoardResult) -> float | None:
    """The board's clock [MHz], or None when the planner picks it per state or there is
    no board (none)."""
    if len(result.hardware.modes) > 1 or result.board.is_none:
        return None
    return result.board.clock_mhz


def _clock_text(result: BoardResult) -> str:
    if result.board.is_none:
        return "-"
    return "auto" if _clock(result) is None else f"{_clock(result):g}"


def board_json(result: BoardResult, comparison_cycles: float) -> dict[str, Any]:
    """One board: its data file's figures as given, and what it costs on the mission."""
    board, energy, planned = result.board, result.energy, result.planned
    sleep = board.sleep
    return {
        "description": board.description,
        "clock_mhz": _clock(result),
        "clocks_mhz": [] if board.is_none else [m.clock_mhz for m in result.hardware.modes],
        "active_power_w": board.active_w,
        "idle_power_w": board.idle_w,
        "sleep_power_w": sleep.power_w if sleep else None,
        "wake_latency_s": sleep.wake_latency_s if sleep else None,
        "wake_energy_j": sleep.wake_j if sleep else None,
        "wakes_on": list(sleep.wakes_on) if sleep else [],
        "boot_time_s": board.boot_s,
        "boot_energy_j": board.boot_j,
        "status": planned.status,
        "board_energy_j": energy.total_j,
        "active_j": energy.active_j,
        "idle_j": energy.idle_j,
        "sleep_j": energy.sleep_j,
        "wake_j": energy.wake_j,
        "boot_j": energy.boot_j,
        "share_of_mission": result.share,
        "mission_energy_j": planned.plan.predicted_j,
        "minimum_energy_j": planned.minimum_energy_j,
        "quality": planned.quality,
        "endurance_days": result.endurance_days,
        "assumptions": dict(result.assumptions),
        "runtime_code": _code_json(result, comparison_cycles),
    }


def _code_json(result: BoardResult, cycles_per_tick: float) -> dict[str, Any] | None:
    """The runtime's measured code on the board beside the workload; None: not measured."""
    code = result.runtime_code
    if code is None:
        return None
    return {"instructions_per_tick": code.instructions,
            "instructions_source": code.sources["runtime_instructions"],
            "cycles_per_instruction": code.cycles_per_instruction,
            "cycles_per_instruction_source": code.sources["cycles_per_instruction"],
            "cycles_per_tick": code.cycles, "share_of_workload": code.share,
            "rest_cycles_per_tick": cycles_per_tick - code.cycles,
            "rest_energy_j": code.rest_j}


def crossover_json(crossover: Crossover) -> dict[str, Any]:
    return {"cycles_per_tick": crossover.cycles_per_tick,
            "ranking_before": list(crossover.before), "ranking_after": list(crossover.after),
            "reason": crossover.reason,
            "extra_computations_per_tick": crossover.equivalents}


def comparison_json(comparison: Comparison) -> dict[str, Any]:
    """The whole comparison; boards keyed by their names ("ts5500", "ts7800@300", ...)."""
    return {
        "mission": comparison.mission,
        "cycles_per_tick": comparison.cycles_per_tick,
        "tick_s": TICK_S,
        "battery_j": comparison.battery_j,
        "budget_j": comparison.budget_j,
        "reference_plan": comparison.reference,
        "workload": {"cycles_per_tick": comparison.cycles_per_tick,
                     "assumed": comparison.cycles_per_tick == RUNTIME_CYCLES_PER_TICK,
                     "source": workload_basis(comparison)},
        "boards": {r.name: board_json(r, comparison.cycles_per_tick)
                   for r in comparison.boards},
        "crossovers": [crossover_json(c) for c in comparison.crossovers],
        "computations": {c.name: {"cycles": c.cycles, "description": c.description,
                                  "source": c.source} for c in load_computations()},
        "assumptions": model_notes(comparison),
    }


def boards_frame(comparison: Comparison) -> pd.DataFrame:
    """One row per board (boards.csv): figures, energy split, mission energy, endurance."""
    rows = []
    for r in comparison.boards:
        data = board_json(r, comparison.cycles_per_tick)
        code = data.pop("runtime_code") or {}
        rows.append({"board": r.name, **{k: v for k, v in data.items()
                                         if k not in ("description", "clocks_mhz", "wakes_on",
                                                      "assumptions")},
                     "workload_cycles_per_tick": comparison.cycles_per_tick,
                     "runtime_code_cycles_per_tick": code.get("cycles_per_tick", math.nan),
                     "board_energy_wh": _wh(r.energy.total_j),
                     "mission_energy_wh": _wh(r.planned.plan.predicted_j)})
    return pd.DataFrame(rows)


def workload_frame(comparison: Comparison) -> pd.DataFrame:
    """Each board's energy on the mission [Wh] against the workload (workload.csv); empty
    where the board cannot keep up."""
    columns = {"cycles_per_tick": comparison.workload}
    columns.update({f"{name}_wh": _wh(values) for name, values in comparison.curves_j.items()})
    return pd.DataFrame(columns)


def crossovers_frame(comparison: Comparison) -> pd.DataFrame:
    """One row per crossover (crossovers.csv)."""
    rows = [{"cycles_per_tick": c.cycles_per_tick, "ranking_before": " < ".join(c.before),
             "ranking_after": " < ".join(c.after), "reason": c.reason,
             **{f"{k}_per_tick": v for k, v in c.equivalents.items()}}
            for c in comparison.crossovers]
    columns = ["cycles_per_tick", "ranking_before", "ranking_after", "reason",
               *(f"{c.name}_per_tick" for c in load_computations())]
    return pd.DataFrame(rows, columns=columns)


def cycles_text(cycles: float) -> str:
    """A workload as people say it: "532 M cycles/tick"."""
    for factor, prefix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if cycles >= factor:
            return f"{cycles / factor:.3g} {prefix}cycles/tick"
    return f"{cycles:.3g} cycles/tick"


def equivalents_text(crossover: Crossover) -> str:
    """ "beyond the runtime's own work: 74 thermocline fits or 525 spectra per tick"."""
    parts = [f"{n:,.3g} x {name}" for name, n in crossover.equivalents.items()]
    return "beyond the runtime's own work, " + " or ".join(parts) + " per tick"


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    fmt = "  ".join(f"{{:{'<' if i == 0 else '>'}{w}}}" for i, w in enumerate(widths))
    return [fmt.format(*header), *(fmt.format(*r) for r in rows)]


def _num(value: float | None, digits: str = ".3g") -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) \
        else format(value, digits)


def _assumed(result: BoardResult, key: str) -> str:
    """"*" when the board's figure `key` ("idle_power", "boot_time") is an assumption."""
    return "*" if any(k == key or k.endswith(f".{key}") for k in result.assumptions) else ""


def comparison_text(comparison: Comparison) -> str:
    """The table a person reads, the crossovers and every assumption behind them."""
    c = comparison
    given = "" if c.cycles_per_tick == RUNTIME_CYCLES_PER_TICK else ", given"
    none = " and none (no extra board)" if len(boards(c)) < len(c.boards) else ""
    lines = [f"mission {c.mission}: {len(boards(c))} boards{none} at "
             f"{c.cycles_per_tick:,.0f} cycles per {TICK_S:g} s tick (workload{given}: "
             f"below), battery {_wh(c.battery_j):,.4g} Wh ({_wh(c.budget_j):,.4g} Wh usable)", ""]
    header = ["board", "clock MHz", "active W", "idle W", "boot s", "board Wh", "active Wh",
              "idle Wh", "sleep+wake Wh", "boot Wh", "share", "mission Wh", "quality",
              "endurance d"]
    rows = []
    for r in c.boards:
        e, b = r.energy, r.board
        rows.append([r.name, _clock_text(r),
                     _num(b.active_w, "g") + _assumed(r, "active_power"),
                     _num(b.idle_w, "g") + _assumed(r, "idle_power"),
                     _num(b.boot_s, "g") + _assumed(r, "boot_time"), _num(_wh(e.total_j)),
                     _num(_wh(e.active_j)), _num(_wh(e.idle_j)),
                     _num(_wh(e.sleep_j + e.wake_j)), _num(_wh(e.boot_j)),
                     f"{100 * r.share:.1f} %",
                     _num(_wh(r.planned.plan.predicted_j))
                     + (" (over)" if r.planned.status != "optimal" else ""),
                     _num(r.planned.quality, ".4f"), _num(r.endurance_days, ".1f")])
    lines += _table(header, rows)
    lines.append("* an assumption, not a measurement (below)")
    cheapest = cheapest_board(c)
    lines += ["", f"cheapest board on this mission: {cheapest.name} "
              f"({_wh(cheapest.energy.total_j):.3g} Wh)"]
    if (alone := no_board_text(c)) is not None:
        lines.append(alone)
    over = [r.name for r in c.boards if r.planned.status != "optimal"]
    if over:
        lines.append(f"over the battery on: {', '.join(over)} (the least-energy plan shown)")
    lines += ["", workload_basis(c)]
    lines += [f"  {line}" for line in runtime_code_lines(c)]
    lines += ["", "crossovers (workload at which the ranking changes, cheapest first):"]
    if not c.crossovers:
        lines.append("  none up to the fastest board's capacity")
    for x in c.crossovers:
        lines.append(f"  {cycles_text(x.cycles_per_tick)}: {' < '.join(x.before) or '-'} "
                     f"becomes {' < '.join(x.after) or '-'}; {x.reason}")
        lines.append(f"    ({equivalents_text(x)})")
    lines += ["", "assumptions (figures without a measurement behind them):"]
    lines += [f"  {line}" for line in assumption_lines(c, workload=False)]
    return "\n".join(lines) + "\n"


def assumptions_by_figure(comparison: Comparison) -> dict[str, list[str]]:
    """Each assumed figure ("ts7800 idle_power 2.57 W: assumption: ...") and the compared
    boards that use it."""
    found: dict[str, list[str]] = {}
    for r in comparison.boards:
        for key, text in r.assumptions.items():
            figure = re.sub(r"^mode\[\d+\]\.", "", key)  # the clock is in the value
            found.setdefault(f"{r.board.name} {figure} {text}", []).append(r.name)
    return found


def assumption_lines(comparison: Comparison, workload: bool = True) -> list[str]:
    """One line per assumed figure (with the boards that use it), then the model's own,
    the workload's first unless `workload` is False (said apart)."""
    lines = []
    for figure, boards in assumptions_by_figure(comparison).items():
        value, source = figure.split(": ", 1)
        lines.append(f"{value} (for {', '.join(boards)}): {source}")
    return lines + (model_notes(comparison) if workload else list(MODEL_NOTES))


def energy_plot(comparison: Comparison, fmt: str = "png") -> bytes:
    """Each board's energy on the mission [Wh] against the workload per tick (log axis),
    the mission's workload and the crossovers marked."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 4.6), dpi=110)
    w = comparison.workload
    for name, values in comparison.curves_j.items():
        ax.plot(w, _wh(values), label=name, lw=1.8)
    ax.set_xscale("log")
    ax.axvline(comparison.cycles_per_tick, color="grey", ls=":", lw=1)
    top = np.nanmax([np.nanmax(_wh(v)) for v in comparison.curves_j.values()])
    ax.annotate("mission's workload", (comparison.cycles_per_tick, top), fontsize=8,
                rotation=90, va="top", ha="right", color="grey")
    for r in comparison.boards:  # the part of a tick that is measured, where it is
        code = r.runtime_code
        if code is not None and w[0] <= code.cycles <= w[-1]:
            ax.axvline(code.cycles, color="grey", ls="-.", lw=0.8)
            ax.annotate(f"{r.name}: runtime's code, measured", (code.cycles, top), fontsize=7,
                        rotation=90, va="top", ha="right", color="grey")
    for x in comparison.crossovers:
        ax.axvline(x.cycles_per_tick, color="black", ls="--", lw=0.8)
        ax.annotate(f"crossover {cycles_text(x.cycles_per_tick)}", (x.cycles_per_tick, top),
                    fontsize=7, rotation=90, va="top", ha="right")
    ax.set_xlabel(f"workload [cycles per {TICK_S:g} s tick]")
    ax.set_ylabel("board energy on the mission [Wh]")
    ax.set_title(f"{comparison.mission}: board energy against workload (ends where a "
                 "board cannot keep up)", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")  # the upper left holds the workload labels
    return render(fig, fmt)


def write_files(comparison: Comparison, out: Path | OutputFolder) -> tuple[Path, ...]:
    """Write FILES into the directory `out`, a folder written whole
    (contract.files.output_folder), or into the folder `out` being written."""
    if not isinstance(out, OutputFolder):
        with output_folder(out, command="compare-sbc", recognised=FILES) as folder:
            return write_files(comparison, folder)
    contents = {"boards.csv": boards_frame(comparison).to_csv(index=False),
                "workload.csv": workload_frame(comparison).to_csv(index=False),
                "crossovers.csv": crossovers_frame(comparison).to_csv(index=False),
                "sbc.png": energy_plot(comparison, "png")}
    return tuple(out.write(name, contents[name]) for name in FILES)


def as_json(comparison: Comparison) -> str:
    return json.dumps(comparison_json(comparison), indent=2, allow_nan=False) + "\n"

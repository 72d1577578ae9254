"""Plots of a simulated run: the depth profile coloured by water temperature with the
states as bands (the paper's Fig. 5), and energy over time against the plan. Each is
drawn from a series (`depth_series`, `energy_series`) that is small whatever the run's
length, so that another process can draw it (sim/plotter.py)."""

from __future__ import annotations

import io
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.contract import NO_STATE

if TYPE_CHECKING:  # the plotting process (sim/plotter.py) draws without the simulator
    from gliderplan.planner.planfile import Plan
    from gliderplan.sim.energy import RunEnergy
    from gliderplan.sim.loop import RunRecord

BUDGET_LINE_SPAN = 3.0  # draw the budget line only if it lies within 3x the energy spent
PLOTTED_TICKS = 6000  # a longer run is drawn from about this many of its ticks (decimated)


def pyplot():
    """matplotlib.pyplot on the Agg backend (imported on the first call)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _time_axis(time_s: np.ndarray) -> tuple[np.ndarray, str]:
    span = float(time_s[-1]) if len(time_s) else 0.0
    for unit, factor in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if span >= 3 * factor:
            return time_s / factor, unit
    return time_s, "s"


def _state_runs(state: np.ndarray) -> list[tuple[int, int, int]]:
    """(state, first tick, stop tick) of each stretch in one state."""
    if len(state) == 0:
        return []
    edges = np.flatnonzero(np.diff(state)) + 1
    starts = np.concatenate([[0], edges])
    stops = np.concatenate([edges, [len(state)]])
    return [(int(state[a]), int(a), int(b)) for a, b in zip(starts, stops, strict=True)]


def decimated(values: np.ndarray, most: int = PLOTTED_TICKS) -> np.ndarray:
    """Indices of at most about `most` ticks that draw `values` as all of them would at a
    figure's resolution: in each of most/3 equal stretches of ticks, its first tick and
    those of its smallest and largest value (a yo's turns stay where they were, and so
    does the band it flew), in order. All ticks when there are no more than `most`."""
    n = len(values)
    if n <= most:
        return np.arange(n)
    width = -(-3 * n // most)  # ticks per stretch, rounded up
    stretches = -(-n // width)
    padded = np.concatenate([values, np.full(stretches * width - n, values[-1])])
    rows = padded.reshape(stretches, width)
    first = np.arange(stretches) * width
    picked = np.concatenate([first, first + rows.argmin(axis=1), first + rows.argmax(axis=1),
                             [n - 1]])
    return np.unique(np.minimum(picked, n - 1))


@dataclass(frozen=True)
class DepthSeries:
    """What depth.png draws of a run (`depth_series`): small whatever the run's length."""

    time: np.ndarray  # the ticks drawn, in `unit`
    unit: str  # of the time axis: s, min, h or d
    depth_m: np.ndarray
    temperature_c: np.ndarray  # the water's at those ticks
    stretches: list[tuple[int, float, float]]  # (state, start, end [unit]) of every stretch
    state_names: tuple[str, ...]
    ticks: int  # in the run


def depth_series(record: RunRecord) -> DepthSeries:
    """The depth profile decimated (`decimated`), the states' stretches from every tick."""
    c = record.columns
    t, unit = _time_axis(c["time_s"])
    stretches = [(index, float(t[a]), float(t[b] if b < len(t) else t[-1]))
                 for index, a, b in _state_runs(c["state"].astype(int)) if index != NO_STATE]
    shown = decimated(c["depth_m"])
    return DepthSeries(t[shown], unit, c["depth_m"][shown], c["temperature_c"][shown],
                       stretches, record.state_names, len(t))


def depth_png(series: DepthSeries) -> bytes:
    """Depth against time coloured by the water's temperature, on bands of the states
    flown (the paper's Fig. 5)."""
    plt = pyplot()
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.patches import Patch

    fig, ax = plt.subplots(figsize=(10, 4.5), dpi=110)
    colours = plt.get_cmap("tab10")
    # every stretch a band across the axes' height: one collection for all of them
    ax.add_collection(PolyCollection(
        [[(a, 0.0), (b, 0.0), (b, 1.0), (a, 1.0)] for _, a, b in series.stretches],
        facecolors=[colours(index % 10) for index, _, _ in series.stretches], alpha=0.15,
        lw=0, transform=ax.get_xaxis_transform()), autolim=False)
    flown = sorted({index for index, _, _ in series.stretches})
    handles = [Patch(color=colours(i % 10), alpha=0.3, label=series.state_names[i])
               for i in flown]
    if handles:  # none when the mission exits on its first tick
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.13),
                  fontsize=8, ncol=min(len(handles), 6), frameon=False)
    # the dive as a line from tick to tick, each piece coloured by the water where it
    # starts: decimated, the line runs up and down the band the glider flew
    points = np.column_stack([series.time, series.depth_m])
    path = LineCollection(np.stack([points[:-1], points[1:]], axis=1), cmap="coolwarm",
                          array=series.temperature_c[:-1], linewidths=1.0)
    ax.add_collection(path)
    ax.autoscale_view()
    fig.colorbar(path, ax=ax, label="water temperature [degC]")
    ax.invert_yaxis()
    ax.set_xlabel(f"mission time [{series.unit}]")
    ax.set_ylabel("depth [m]")
    drawn = len(series.time)
    ax.set_title("depth profile coloured by water temperature; bands: mission states"
                 + (f" ({drawn:,} of {series.ticks:,} ticks drawn)" if drawn < series.ticks
                    else ""))
    return _png(fig, plt)


@dataclass(frozen=True)
class EnergySeries:
    """What energy.png draws of a run (`energy_series`): small whatever the run's length."""

    time: np.ndarray  # the ticks drawn, in `unit`
    unit: str
    spent_kj: dict[str, np.ndarray]  # component -> energy spent by then, most first
    planned_kj: np.ndarray | None  # the plan's prediction by then (None: no plan)
    budget_j: float | None


def energy_series(record: RunRecord, energy: RunEnergy, plan: Plan | None) -> EnergySeries:
    """Cumulative energy by component, and each state's predicted energy spent at its
    predicted rate along the simulated states, up to its predicted time; decimated (the
    curves are cumulative: smooth), every tick counted."""
    c = record.columns
    t, unit = _time_axis(c["time_s"])
    parts = sorted(energy.per_tick_j.items(), key=lambda kv: -kv[1].sum())
    spent = {k: np.cumsum(v) for k, v in parts}
    shown = decimated(sum(spent.values(), np.zeros(len(t))))
    planned = None
    if plan is not None:
        # each state spends its predicted energy at its predicted rate, for no longer
        # than the time the plan gave it
        state = c["state"].astype(int)
        planned = np.zeros(len(state))
        for i, p in enumerate(plan.states):
            if p.time_s:
                time_in_state = np.cumsum(state == i) * record.tick_s
                planned += p.energy_j / p.time_s * np.minimum(time_in_state, p.time_s)
        planned = planned[shown] / 1e3
    return EnergySeries(t[shown], unit, {k: v[shown] / 1e3 for k, v in spent.items()},
                        planned, plan.budget_j if plan is not None else None)


def energy_png(series: EnergySeries) -> bytes:
    """Cumulative energy by component against the plan's prediction and budget."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(10, 4.5), dpi=110)
    ax.stackplot(series.time, *series.spent_kj.values(), labels=list(series.spent_kj),
                 alpha=0.8)
    if series.planned_kj is not None:
        ax.plot(series.time, series.planned_kj, "k--", lw=1.5,
                label="plan (each state's prediction)")
    title = "energy over time"
    top_kj = ax.get_ylim()[1]
    budget_j = series.budget_j
    if budget_j is not None and budget_j / 1e3 <= BUDGET_LINE_SPAN * top_kj:
        ax.axhline(budget_j / 1e3, color="red", lw=1, label="plan budget")
    elif budget_j is not None:  # a line far above the data would flatten the curves
        title += f" (plan budget {budget_j / 1e3:,.0f} kJ, off the scale)"
    ax.set_xlabel(f"mission time [{series.unit}]")
    ax.set_ylabel("energy [kJ]")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(title)
    return _png(fig, plt)


def _png(fig, plt) -> bytes:
    sink = io.BytesIO()
    fig.tight_layout()
    fig.savefig(sink, format="png")
    plt.close(fig)
    return sink.getvalue()


# ---- Monte Carlo -----------------------------------------------------------------------

def energy_histogram_png(energy_j: np.ndarray, budget_j: np.ndarray, nominal_budget_j: float,
                         held_share: float | None, requested: int | None = None) -> bytes:
    """Energy spent in each scenario against the budget: the plan's budget as a line, the
    range of the scenarios' own budgets (their batteries differ) as a band. `held_share`
    None: an interrupted run (`requested` scenarios asked for), which gives no share."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=110)
    ax.hist(energy_j / 1e3, bins=min(50, max(10, len(energy_j) // 10)), color="tab:blue",
            alpha=0.8, label="scenarios")
    if len(budget_j):
        low, high = np.quantile(budget_j, [0.05, 0.95]) / 1e3
        ax.axvspan(low, high, color="red", alpha=0.12, lw=0,
                   label="scenarios' budgets (5-95 %)")
    ax.axvline(nominal_budget_j / 1e3, color="red", lw=1.5, label="plan budget")
    ax.set_xlabel("energy spent [kJ]")
    ax.set_ylabel("scenarios")
    ax.set_title(f"energy per scenario: the budget held in {100 * held_share:.1f} %"
                 if held_share is not None else
                 f"PARTIAL: interrupted after {len(energy_j)} of {requested or '?'} scenarios "
                 "(no share held)")
    ax.legend(fontsize=8)
    return _png(fig, plt)


def exhaustion_png(exhausted_s: np.ndarray, duration_s: np.ndarray) -> bytes:
    """Share of scenarios still within the usable charge drawn for them against mission
    time (a scenario that passed it at t drops out at t; one that never did stays to its
    end; the runs themselves go on)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=110)
    n = len(exhausted_s)
    end = float(np.nanmax(duration_s)) if n else 1.0
    t, unit = _time_axis(np.array([0.0, end]))
    scale = end / t[-1] if t[-1] else 1.0
    out = np.sort(exhausted_s[np.isfinite(exhausted_s)])
    times = np.concatenate([[0.0], out, [end]])
    holding = 1.0 - np.concatenate([[0], np.arange(1, len(out) + 1), [len(out)]]) / max(n, 1)
    ax.step(times / scale, 100 * holding, where="post", color="tab:green")
    ax.set_ylim(0, 102)
    ax.set_xlabel(f"mission time [{unit}]")
    ax.set_ylabel("scenarios within their drawn usable charge [%]")
    ax.set_title(f"{len(out)} of {n} scenarios exceeded the usable charge drawn for them")
    return _png(fig, plt)

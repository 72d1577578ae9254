"""The report's figures, drawn from the same tables its CSV files hold, as SVG text.

Each function takes a pandas frame (the CSV behind the figure) and returns the SVG
document matplotlib writes. Dense series (a month of 4 s ticks) are rasterised inside
the SVG (`rasterized=True`) so that the page stays small.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from gliderplan.reports.figures import pyplot, render

WIDE = (8.4, 4.2)
BUDGET_SPAN = 3.0  # a budget line is drawn when it lies within 3x the largest value


def _svg(fig) -> str:
    return render(fig, "svg").decode("utf-8")


def pareto(frame: pd.DataFrame, budget_wh: float, plan_wh: float, quality: float) -> str:
    """Quality against budget, the shadow price on a second axis, the plan marked at the
    budget it takes (`plan_wh`, counted as the curve's budgets are)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=WIDE)
    ax.plot(frame["budget_wh"], frame["quality"], "o-", ms=3, color="tab:blue",
            label="best quality at the budget")
    ax.plot([plan_wh], [quality], "*", ms=14, color="tab:orange",
            label=f"the plan: {plan_wh:.4g} Wh of budget, quality {quality:.3f}")
    if frame["budget_wh"].min() <= budget_wh <= frame["budget_wh"].max() * 1.5:
        ax.axvline(budget_wh, color="grey", ls=":", lw=1, label=f"budget {budget_wh:.4g} Wh")
    ax.set_xlabel("energy budget [Wh]")
    ax.set_ylabel("quality [1]", color="tab:blue")
    ax.grid(alpha=0.3)
    price = ax.twinx()
    price.plot(frame["budget_wh"], frame["shadow_price"], "--", color="tab:red")
    price.set_ylabel("shadow price [quality per Wh]", color="tab:red")
    ax.legend(fontsize=8, loc="lower right")
    return _svg(fig)


def energy_by_state(frame: pd.DataFrame) -> str:
    """Stacked bars: each state's energy [Wh] by component (columns other than state)."""
    plt = pyplot()
    components = [c for c in frame.columns if c not in ("state", "total_wh")]
    fig, ax = plt.subplots(figsize=(WIDE[0], 0.5 * len(frame) + 1.6))
    left = np.zeros(len(frame))
    colours = plt.get_cmap("tab20")
    for i, component in enumerate(components):
        values = frame[component].to_numpy(float)
        ax.barh(frame["state"], values, left=left, color=colours(i % 20),
                label=component.removesuffix("_wh"))
        left += values
    ax.invert_yaxis()
    ax.set_xlabel("energy [Wh]")
    ax.grid(alpha=0.3, axis="x")
    ax.legend(fontsize=8, ncol=min(len(components), 5), loc="upper center",
              bbox_to_anchor=(0.5, -0.18), frameon=False)
    return _svg(fig)


def plan_vs_simulation(frame: pd.DataFrame) -> str:
    """Predicted against simulated energy [Wh] per state, the difference written above."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=WIDE)
    x = np.arange(len(frame))
    ax.bar(x - 0.2, frame["predicted_wh"], 0.4, label="plan", color="tab:blue")
    ax.bar(x + 0.2, frame["simulated_wh"], 0.4, label="simulation", color="tab:orange")
    for i, (p, s) in enumerate(zip(frame["predicted_wh"], frame["simulated_wh"], strict=True)):
        if p and math.isfinite(p) and math.isfinite(s):
            ax.annotate(f"{100 * (s - p) / p:+.1f} %", (i, max(p, s)), ha="center",
                        va="bottom", fontsize=8)
    ax.set_xticks(x, frame["state"], rotation=20, ha="right")
    ax.set_ylabel("energy [Wh]")
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8)
    return _svg(fig)


def profile(frame: pd.DataFrame) -> str:
    """Depth against time coloured by water temperature, the states as bands."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=WIDE)
    hours = frame["time_h"].to_numpy(float)
    states = frame["state"].astype(str).to_numpy()
    colours = plt.get_cmap("tab10")
    names = list(dict.fromkeys(s for s in states if s))
    edges = np.flatnonzero(states[1:] != states[:-1]) + 1
    starts, stops = np.r_[0, edges], np.r_[edges, len(states)]
    for a, b in zip(starts, stops, strict=True):
        if states[a]:
            ax.axvspan(hours[a], hours[min(b, len(hours) - 1)], lw=0, alpha=0.12,
                       color=colours(names.index(states[a]) % 10))
    points = ax.scatter(hours, frame["depth_m"], c=frame["temperature_c"], s=3,
                        cmap="coolwarm", rasterized=True)
    fig.colorbar(points, ax=ax, label="water temperature [degC]")
    ax.invert_yaxis()
    ax.set_xlabel("mission time [h]")
    ax.set_ylabel("depth [m]")
    from matplotlib.patches import Patch

    ax.legend(handles=[Patch(color=colours(i % 10), alpha=0.3, label=n)
                       for i, n in enumerate(names)], fontsize=8, frameon=False,
              loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=min(len(names), 6))
    return _svg(fig)


def tornado(frame: pd.DataFrame, energy_wh: float, quality: float) -> str:
    """Two panels: the plan's energy and its quality with each figure down and up."""
    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(9.6, 0.38 * len(frame) + 1.6),
                                      sharey=True)
    y = np.arange(len(frame))
    for ax, low, high, base, label in (
            (left, "energy_down_wh", "energy_up_wh", energy_wh, "mission energy [Wh]"),
            (right, "quality_down", "quality_up", quality, "quality [1]")):
        down = frame[low].to_numpy(float) - base
        up = frame[high].to_numpy(float) - base
        ax.barh(y, np.nan_to_num(down), left=base, color="tab:blue", label="figure down")
        ax.barh(y, np.nan_to_num(up), left=base, color="tab:red", alpha=0.7,
                label="figure up")
        ax.axvline(base, color="black", lw=0.8)
        ax.set_xlabel(label)
        ax.grid(alpha=0.3, axis="x")
    left.set_yticks(y, frame["figure"], fontsize=8)
    left.invert_yaxis()
    left.legend(fontsize=8, loc="lower left")
    return _svg(fig)


def histogram(values: np.ndarray, budget_wh: float | None, label: str) -> str:
    """A distribution (e.g. Monte Carlo energy [Wh]) against the budget."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=WIDE)
    finite = values[np.isfinite(values)]
    ax.hist(finite, bins=min(40, max(5, len(finite) // 5)), color="tab:blue", alpha=0.8)
    if budget_wh is not None and len(finite):
        # a budget far beyond the spread would squeeze it into one bar: then say it only
        if budget_wh <= BUDGET_SPAN * float(finite.max()):
            ax.axvline(budget_wh, color="tab:red", ls="--", label=f"budget {budget_wh:,.4g} Wh")
        else:
            ax.plot([], [], " ", label=f"budget {budget_wh:,.4g} Wh (off the scale)")
        ax.legend(fontsize=8)
    ax.set_xlabel(label)
    ax.set_ylabel("scenarios")
    ax.grid(alpha=0.3)
    return _svg(fig)

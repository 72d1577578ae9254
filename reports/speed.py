"""Energy per km against speed where a mission flies on a propeller: for each state the
plan flies propelled, the curve its speed is chosen on (the vehicle's [propulsion] model
with the state's hotel and board load, over ground along its route in the plan's current,
and in still water beside it where there is one), the chosen speed marked, a fixed 1 m/s
cruise drawn for reference. The HTML report shows it (speed.csv beside it), and
`plan -o PLAN` writes it as PLAN.speed.png."""

from __future__ import annotations

from typing import Any

import pandas as pd

from gliderplan.language import ir
from gliderplan.language.registry import PROFILES
from gliderplan.planner.hardware import Hardware
from gliderplan.planner.planfile import Plan
from gliderplan.planner.rates import state_load_w
from gliderplan.planner.speed import STILL_WATER, choice_at, energy_per_km_curve
from gliderplan.reports.figures import pyplot, render

REFERENCE_SPEED_MPS = 1.0  # [m/s] a fixed cruise to compare the chosen speed with
COLUMNS = ("state", "water", "speed_mps", "energy_per_km_kj", "chosen")
STILL, CURRENT = "still water", "in the current"


def speed_frame(mission: ir.CheckedMission, hardware: Hardware, plan: Plan) -> pd.DataFrame:
    """Rows of (state, water, speed [m/s], energy per km over ground [kJ], whether the
    plan chose it): each propelled state's curve in the water it was planned for ("in the
    current" on its route's legs, else "still water"), the still-water curve beside a
    current's, then its chosen speeds; empty where nothing is propelled."""
    propulsion = hardware.vehicle.propulsion
    rows = []
    for state, planned in zip(mission.states, plan.states, strict=True):
        chosen = [p for p in planned.profiles
                  if p.share > 0.0 and PROFILES[state.profiles[p.index].kind].propelled]
        if propulsion is None or not chosen:
            continue
        load, legs = state_load_w(hardware, state), hardware.water(state)
        water = STILL if legs == STILL_WATER else CURRENT
        for name, along in ((water, legs), *(((STILL, STILL_WATER),) if water == CURRENT
                                               else ())):
            speeds, per_km = energy_per_km_curve(propulsion, load, along)
            rows += [(state.name, name, float(u), float(e), False)
                     for u, e in zip(speeds, per_km, strict=True)]
        rows += [(state.name, water, p.speed_mps,
                  choice_at(propulsion, load, p.speed_mps, legs).energy_per_m_j, True)
                 for p in chosen]
    return pd.DataFrame(rows, columns=list(COLUMNS))


def _figure(frame: pd.DataFrame) -> Any:  # a matplotlib figure
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8.4, 4.2))
    colours = plt.get_cmap("tab10")
    for i, (state, rows) in enumerate(frame.groupby("state", sort=False)):
        for water, curve in rows[~rows["chosen"]].groupby("water", sort=False):
            ax.plot(curve["speed_mps"], curve["energy_per_km_kj"], color=colours(i % 10),
                    ls="-" if water == rows["water"].iloc[0] else "--",
                    label=f"{state}: energy per km, {water}")
        for _, point in rows[rows["chosen"]].iterrows():
            ax.plot([point["speed_mps"]], [point["energy_per_km_kj"]], "*", ms=13,
                    color=colours(i % 10),
                    label=f"{state}: chosen {point['speed_mps']:.3g} m/s, "
                          f"{point['energy_per_km_kj']:.4g} kJ/km {point['water']}")
    low, high = frame["speed_mps"].min(), frame["speed_mps"].max()
    if low <= REFERENCE_SPEED_MPS <= high:
        ax.axvline(REFERENCE_SPEED_MPS, color="grey", ls=":", lw=1,
                   label=f"a fixed {REFERENCE_SPEED_MPS:g} m/s cruise")
    ax.set_xlabel("speed through the water [m/s]")
    ax.set_ylabel("energy per km over ground [kJ]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def speed_svg(frame: pd.DataFrame) -> str:
    """The figure as SVG text (the HTML report)."""
    return render(_figure(frame), "svg").decode("utf-8")


def speed_png(frame: pd.DataFrame) -> bytes:
    """The figure as a PNG file's bytes (beside a plan file)."""
    return render(_figure(frame), "png")


# the vehicles a propelled mission is compared on in the report: a glider, a hybrid, an AUV
COMPARED_VEHICLES = ("slocum_g2_shallow", "slocum_g3_hybrid", "lauv")


def vehicles_frame(results: list) -> pd.DataFrame:
    """Energy per km [kJ] against a head current [m/s] of each vehicle of `results`
    (planner.vehicles.VehicleResult), one column per vehicle; empty where it makes no way."""
    from gliderplan.planner.vehicles import HEAD_CURRENTS_MPS

    return pd.DataFrame({"head_current_mps": HEAD_CURRENTS_MPS,
                         **{r.vehicle: [j / 1e3 for j in r.per_km_against_current_j]
                            for r in results}})


def vehicles_svg(frame: pd.DataFrame, flips: list[dict]) -> str:
    """Each vehicle's energy per km against the head current, the crossovers marked."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8.4, 4.2))
    for name in frame.columns[1:]:
        ax.plot(frame["head_current_mps"], frame[name], label=name)
    for flip in flips:
        ax.axvline(flip["head_current_mps"], color="grey", ls=":", lw=1)
        ax.annotate(f"{flip['to']} from {flip['head_current_mps']:.3g} m/s",
                    (flip["head_current_mps"], ax.get_ylim()[1]), rotation=90, fontsize=7,
                    va="top", ha="right")
    ax.set_xlabel("head current [m/s]")
    ax.set_ylabel("energy per km over ground [kJ]")
    ax.set_yscale("log")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return render(fig, "svg").decode("utf-8")

"""Power per device, fitted from a log: battery power regressed on the logged state of each
device while the glider glides.

Over the glide's sample intervals (outside pump runs, battery moves and the surface),
power P = V I from the current sensor is modelled as

    P = P_base + sum_d w_d s_d

with s_d the share of the interval device d was on (an instrument's sampling duty from
its switch, the fin moving or not; `slocum_log`), fitted by least squares weighted by the
intervals' lengths. A device can be told apart only when it switches on and off
independently of the others, for long enough: one whose state the other columns (and the
base) explain to SEPARABLE_R2 or better, or that spends less than MIN_STATE_S of glide on
or off (a few intervals are noise, not a measurement), cannot be fitted. An instrument the
log cannot separate keeps its published figure (its sensor preset's), with an sd from
the published span, and stays in the hotel load: a forecast of a mission that does not
run it takes that figure out. Devices that switch together are fitted as one and split by
their published figures. An actuator the log cannot separate (no published figure) is
merged into the base. A fitted figure outside its device's published span is flagged.

The current sensor samples every few seconds and is spiky; single intervals are not
trusted alone but the fit is over thousands of them, and the bootstrap over whole dives
(`vehicle_fit`) gives each fitted figure's sd.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gliderplan.power_models import segments as seg
from gliderplan.power_models.catalog import preset_names
from gliderplan.power_models.sensor import load_sensor
from gliderplan.power_models.slocum_log import FlightLog

SEPARABLE_R2 = 0.99  # a device state the others explain this well is not told apart
MIN_STATE_S = 600.0  # [s] of glide a device must spend on, and off, to be told apart
SAME_SWITCHING = 0.01  # devices whose states differ less (time-weighted) switch together
# one sd of a published figure: a quarter of its published span (the span taken as about
# two sd either side), or this share of the figure where the preset gives no span
SPAN_SDS = 4.0
UNSPANNED_RELATIVE_SD = 0.5
MIN_RELATIVE_SD = 0.2
# one sd of a device's share of a group's fitted power split by published figures, as a
# share of its figure, scaled by (1 - its share): the published figures' ratio is known no
# better than the figures themselves
SPLIT_RELATIVE_SD = 0.5
ACTUATORS = ("fin",)


@dataclass(frozen=True)
class DeviceFigure:
    """One device's figures from a log."""

    device: str
    kind: str  # "sensor" | "actuator"
    on_power_w: float  # [W] while on (an actuator: while it moves)
    duty: float  # [1] share of the glide it was on
    fitted: bool  # False: its published figure (the log cannot separate it)
    held: bool  # in the hotel load (on throughout the glide, or an actuator of the flight)
    basis: str  # what it rests on
    # [W] a published figure's sd (from its published span); for a fitted figure split
    # from a group's, the split's sd (the bootstrap adds the fit's)
    sd_w: float | None = None
    flag: str = ""  # a fitted figure outside the device's published span, said why


@dataclass(frozen=True)
class DeviceFit:
    """The glide's power split into a base and the devices'."""

    base_w: float  # [W] gliding with every instrument off and the fin still
    figures: tuple[DeviceFigure, ...]
    merged: tuple[str, ...]  # devices merged into the base (no figure of their own)
    glide_s: float  # [s] of glide the fit rests on
    rms_w: float  # [W] RMS of the fit's residual power, time-weighted

    @property
    def hotel_w(self) -> float:
        """[W] the hotel load: the base, the instruments it holds and the actuators'
        share of every glide."""
        return self.base_w + sum(f.on_power_w * (f.duty if f.kind == "actuator" else 1.0)
                                 for f in self.figures if f.held)


def _weighted_r2(column: np.ndarray, others: np.ndarray, weight: np.ndarray) -> float:
    """R^2 of `column` regressed on `others` (with an intercept), weighted."""
    spread = np.average((column - np.average(column, weights=weight)) ** 2, weights=weight)
    if spread <= 1e-12:
        return 1.0
    design = np.column_stack([np.ones(column.size), others]) * np.sqrt(weight)[:, None]
    coef, *_ = np.linalg.lstsq(design, column * np.sqrt(weight), rcond=None)
    residual = column * np.sqrt(weight) - design @ coef
    return float(1.0 - np.sum(residual ** 2) / (spread * weight.sum()))


def _published(device: str) -> tuple[float, float, str]:
    """(figure [W], sd [W], what it is) of an instrument's sensor preset."""
    preset = load_sensor(device)
    span = preset.power_range_w
    if span is None:
        sd = UNSPANNED_RELATIVE_SD * preset.on_power_w
        said = f"its published figure {preset.on_power_w:.3g} W (sd {sd:.2g} W: " \
               f"{UNSPANNED_RELATIVE_SD:.0%}, no published span)"
    else:
        sd = max((span[1] - span[0]) / SPAN_SDS, MIN_RELATIVE_SD * preset.on_power_w)
        said = f"its published figure {preset.on_power_w:.3g} W (sd {sd:.2g} W from the " \
               f"published span {span[0]:.3g}-{span[1]:.3g} W)"
    return preset.on_power_w, sd, said


def _flag(device: str, watts: float) -> str:
    """Why a fitted figure [W] lies outside its device's published span, or ""."""
    if device not in preset_names("sensor"):
        return ""
    span = load_sensor(device).power_range_w
    if span is None or span[0] <= watts <= span[1]:
        return ""
    return f"{watts:.3g} W lies outside the published {span[0]:.3g}-{span[1]:.3g} W"


def _groups(columns: np.ndarray, weight: np.ndarray) -> list[list[int]]:
    """Indices of the columns that switch together (time-weighted mean difference below
    SAME_SWITCHING), each group in column order."""
    groups: list[list[int]] = []
    for j in range(columns.shape[1]):
        for group in groups:
            if np.average(np.abs(columns[:, j] - columns[:, group[0]]),
                          weights=weight) < SAME_SWITCHING:
                group.append(j)
                break
        else:
            groups.append([j])
    return groups


def fit_devices(log: FlightLog, parts: seg.Segmentation, energy_j: np.ndarray) -> DeviceFit:
    """Split the glide's power of `log` (its `segment`ation and interval energies [J])
    into a base load and each logged device's."""
    dt = np.diff(log.t_s)
    rows = (parts.phase == seg.GLIDE) & (dt > 0.0)
    if not rows.any():
        raise ValueError("the log holds no glide to fit devices on")
    weight = dt[rows]
    power = energy_j[rows] / weight
    names = log.device_names
    on = log.devices_on()[:-1][rows]
    on_s = on.T @ weight if names else np.zeros(0)
    share = on_s / weight.sum()
    figures: list[DeviceFigure] = []
    merged: list[str] = []
    glide = f"{weight.sum():.0f} s of glide"

    def published(device: str, why: str, held: bool) -> None:
        watts, sd, said = _published(device)
        figures.append(DeviceFigure(device, "sensor", watts, 1.0 if held else 0.0, False, held,
                                    f"{why}: {said}", sd))

    switching = []
    for j, name in enumerate(names):
        if on_s[j] < MIN_STATE_S:
            if name not in ACTUATORS:
                published(name, f"on for {on_s[j]:.0f} s of {glide}: too little to fit it",
                          False)
        elif weight.sum() - on_s[j] < MIN_STATE_S:
            if name in ACTUATORS:
                merged.append(name)
            else:
                off = weight.sum() - on_s[j]
                when = f"on for all but {off:.0f} s of {glide}" if off >= 1.0 \
                    else f"on throughout {glide}"
                published(name, f"{when}: the log cannot tell it from the base load", True)
        else:
            switching.append(j)
    groups = _groups(on[:, switching], weight) if switching else []
    groups = [[switching[k] for k in g] for g in groups]
    # a group whose state the base and the other groups explain cannot be fitted
    separable = []
    for g in groups:
        others = [h[0] for h in groups if h is not g]
        if _weighted_r2(on[:, g[0]], on[:, others], weight) < SEPARABLE_R2:
            separable.append(g)
            continue
        for j in g:
            if names[j] in ACTUATORS:
                merged.append(names[j])
            else:
                published(names[j], "switches with the others and the base load alike: the "
                          "log cannot separate it", True)
    # what the published figures of instruments it cannot separate draw, taken out first
    fixed = np.zeros(power.size)
    for f in figures:
        if f.held:
            fixed += f.on_power_w * on[:, names.index(f.device)]
    design = np.column_stack([np.ones(power.size)] + [on[:, g[0]] for g in separable])
    root = np.sqrt(weight)
    coef, *_ = np.linalg.lstsq(design * root[:, None], (power - fixed) * root, rcond=None)
    residual = power - fixed - design @ coef
    for g, total in zip(separable, coef[1:], strict=True):
        members = [names[j] for j in g]
        duty = float(share[g[0]])
        actuator = [m for m in members if m in ACTUATORS]
        if actuator and len(members) > 1:
            raise ValueError(f"{', '.join(members)} switch together: an actuator cannot "
                             "be split from an instrument")
        if actuator:
            figures.append(DeviceFigure(members[0], "actuator", float(total), duty, True, True,
                                        f"{glide}, moving {duty:.0%} of it: power while it "
                                        "moves", flag=""))
            continue
        published_w = {m: load_sensor(m).on_power_w for m in members}
        whole = sum(published_w.values())
        for m in members:
            part = published_w[m] / whole if whole > 0 else 1.0 / len(members)
            watts = float(total) * part
            split, sd = "fitted", None
            if len(members) > 1:
                others = ", ".join(o for o in members if o != m)
                split = (f"switching with {others}: their fitted {float(total):.3g} W split by "
                         f"their published figures (the split's sd "
                         f"{SPLIT_RELATIVE_SD:.0%} of its figure x (1 - its share))")
                sd = SPLIT_RELATIVE_SD * watts * (1.0 - part)
            figures.append(DeviceFigure(m, "sensor", watts, duty, True, False,
                                        f"{glide}, on {duty:.0%} of it: {split}", sd,
                                        flag=_flag(m, watts)))
    rms = float(np.sqrt(np.average(residual ** 2, weights=weight)))
    order = {name: k for k, name in enumerate(names)}
    figures.sort(key=lambda f: order[f.device])
    return DeviceFit(float(coef[0]), tuple(figures), tuple(merged), float(weight.sum()), rms)

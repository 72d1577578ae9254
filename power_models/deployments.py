"""Several deployments of one glider in one calibration.

The logs given to `calibrate` are grouped into deployments: consecutive segments whose
files were opened within DEPLOYMENT_GAP_S of each other (the `fileopen_time` of a log's
header) belong to one. Each deployment is fitted alone (`vehicle_fit`); then:

- a device figure fitted in more than one deployment is their inverse-variance mean
  (the devices are the same; the fit of each is a measurement of them), with its sd;
- the base load and the actuators drift between years (the same glider's base load moved
  by ~0.5 W between two deployments, DESIGN.md section 11): the hotel load is the latest
  deployment's, and the spread of the deployments' hotel loads is the drift a forecast
  for another deployment adds (`base_drift`): their sd with three or more, with two the
  larger of their difference / sqrt(2) and the stated default (two points say little);
- every other figure (flight, pump, surfacing: the glider trimmed for its latest water) is
  the latest deployment's.

Each figure's basis says which deployment(s) it rests on.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from datetime import datetime
from pathlib import Path

import numpy as np

from gliderplan.contract.files import read_input
from gliderplan.power_models.fit_figure import Figure
from gliderplan.power_models.vehicle import Uncertainty, with_figures
from gliderplan.power_models.vehicle_fit import VehicleFit

DEPLOYMENT_GAP_S = 5 * 86400.0  # segments opened further apart belong to another deployment
DEFAULT_DRIFT_W = 0.5  # [W] (DESIGN.md section 11: the same Slocum's base load, two years)
DRIFT_SOURCE = ("the same Slocum's base load moved by ~0.5 W between two years' "
                "deployments (DESIGN.md section 11)")
_OPENED = re.compile(rb"^fileopen_time:\s*(\S+)\s*$", re.M)
_HEADER_BYTES = 4096


@dataclass(frozen=True)
class Deployment:
    """One deployment's files and when its first was opened."""

    files: tuple[str, ...]
    opened: datetime | None  # None: no header says (a compressed log)

    @property
    def name(self) -> str:
        stem = Path(self.files[0]).stem
        return stem if self.opened is None else f"{stem} ({self.opened:%Y-%m-%d})"


def _opened(path: str) -> datetime | None:
    """The `fileopen_time` of a log's header, or None."""
    found = _OPENED.search(read_input(path, "Slocum log", head=_HEADER_BYTES))
    if found is None:
        return None
    try:
        return datetime.strptime(found[1].decode(), "%a_%b_%d_%H:%M:%S_%Y")
    except (UnicodeDecodeError, ValueError):
        return None


def split_deployments(files: list[str]) -> list[Deployment]:
    """The files grouped into deployments, oldest first; one deployment when any file's
    header gives no opening time."""
    opened = [(_opened(f), f) for f in files]
    if any(t is None for t, _ in opened):
        return [Deployment(tuple(files), None)]
    opened.sort()
    groups: list[list[tuple[datetime, str]]] = [[opened[0]]]
    for when, name in opened[1:]:
        if (when - groups[-1][-1][0]).total_seconds() > DEPLOYMENT_GAP_S:
            groups.append([])
        groups[-1].append((when, name))
    return [Deployment(tuple(n for _, n in g), g[0][0]) for g in groups]


def drift_w(hotel_w: list[float]) -> tuple[float, str]:
    """([W] the sd of a glider's base load between deployments, what it rests on) from the
    hotel loads of its deployments, oldest first."""
    if len(hotel_w) >= 3:
        return float(np.std(hotel_w, ddof=1)), (
            f"the sd of the hotel loads of its {len(hotel_w)} deployments "
            f"({', '.join(f'{w:.3g}' for w in hotel_w)} W)")
    measured = abs(hotel_w[1] - hotel_w[0]) / math.sqrt(2.0)
    if measured >= DEFAULT_DRIFT_W:
        return measured, (f"the hotel loads of its two deployments ({hotel_w[0]:.3g}, "
                          f"{hotel_w[1]:.3g} W): their difference / sqrt(2)")
    return DEFAULT_DRIFT_W, (f"its two deployments' hotel loads ({hotel_w[0]:.3g}, "
                             f"{hotel_w[1]:.3g} W) differ less; two say little: "
                             f"{DRIFT_SOURCE}")


def combine(fits: list[VehicleFit], deployments: list[Deployment]) -> tuple[VehicleFit, str]:
    """(the latest deployment's fit with the device figures pooled over every deployment
    that fitted them, its drift's source): see the module's notes."""
    latest = fits[-1]
    pooled: dict[str, Figure] = {}
    for key in {f.key for f in latest.figures if f.key.startswith("devices.")
                and f.key.endswith(".on_power")}:  # a duty is the mission's, not the device's
        measured = [(fit.figure(key), d) for fit, d in zip(fits, deployments, strict=True)
                    if any(f.key == key and f.fitted and f.sd for f in fit.figures)]
        if len(measured) < 2:
            continue
        weights = np.array([1.0 / f.sd ** 2 for f, _ in measured])
        value = float(np.dot(weights, [f.value for f, _ in measured]) / weights.sum())
        names = ", ".join(d.name for _, d in measured)
        pooled[key] = replace(latest.figure(key), value=value,
                              sd=float(1.0 / math.sqrt(weights.sum())),
                              basis=f"fitted on {len(measured)} deployments ({names}): "
                                    "their inverse-variance mean")
    hotel = [fit.vehicle.hotel_w for fit in fits]
    drift, source = drift_w(hotel)
    figures = tuple(pooled.get(f.key, replace(f, basis=f"{f.basis} (deployment "
                                                       f"{deployments[-1].name})"))
                    for f in latest.figures)
    vehicle = with_figures(latest.vehicle, {k: f.value for k, f in pooled.items()})
    u = vehicle.uncertainty
    if u is not None:
        sd = np.array([pooled[k].sd if k in pooled else s for k, s in zip(u.keys, u.sd,
                                                                          strict=True)])
        vehicle = replace(vehicle, uncertainty=Uncertainty(
            u.keys, sd, u.correlation, f"{u.source}; pooled over deployments: "
            f"{', '.join(sorted(pooled)) or 'none'}", u.at_least))
    return replace(latest, vehicle=replace(vehicle, base_drift_w=drift), figures=figures), \
        source

"""The physical ranges a figure of a vehicle, board or battery file must lie in.

A figure can be finite, positive and carry a source and still describe no glider: a pump
of 1e-300 cc/s was planned at 1e-101 m/s and simulated sitting at the surface. Each range
below is wide (about a decade beyond the figures published or measured for real gliders,
boards and packs) so that only a typo or a wrong unit falls outside; `datafile.Table`
refuses a figure outside its range, naming the file and the key, whoever loads it
(`gliderplan check` of a mission that names the file, `plan`, `sim`, `power`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass


@dataclass(frozen=True)
class Plausible:
    """in the model's unit of the figure, and why."""

    low: float
    high: float
    source: str


_SLOCUM = "the Slocum G2 shallow log 2.41 W; Slocum G3 fit (mousebrains/GliderSimulator) 1.0-1.31 W"
_PUMP = "glidersim: deep pump 4, 200 m 20.5, shallow 32 cc/s; the shallow log 42 cc/s"

# (kind, key) -> range in the model's unit of the figure (W, cc/s, cc, J/cc, J, kg/m3, m/s2, m2,
# 1, cc, MHz, s, V); a key inside an array of tables drops its index ("mode.clock").
RANGES: dict[tuple[str, str], Plausible] = {
    ("vehicle", "hotel_power"): Plausible(0.05, 50.0, _SLOCUM),
    ("vehicle", "pump_rate"): Plausible(0.5, 500.0, _PUMP),
    ("vehicle", "max_ballast"): Plausible(10.0, 5000.0, "glidersim: shallow +-233 cc, "
                                          "200 m extended +-560 cc"),
    ("vehicle", "pump_out_energy_per_volume"): Plausible(
        0.01, 100.0, "Slocum G3 fit 2.49 J/cc, the shallow log 0.39 J/cc"),
    ("vehicle", "pump_in_energy_per_volume"): Plausible(
        0.0, 100.0, "the shallow log 0.25 J/cc"),
    ("vehicle", "pitch_energy"): Plausible(0.0, 5000.0, "Slocum G3 fit 540 J per "
                                           "inflection, the shallow log 3.9 J"),
    ("vehicle", "surface_power"): Plausible(0.05, 100.0, "the shallow log 3.9-4.8 W"),
    ("vehicle", "iridium_power"): Plausible(0.05, 100.0, "the shallow log 5.2-5.7 W"),
    ("vehicle", "flight.water_density"): Plausible(
        950.0, 1100.0, "fresh water 1000, sea water 1020-1030 kg/m3"),
    ("vehicle", "flight.gravity"): Plausible(9.7, 9.9, "9.78 at the equator to "
                                             "9.83 at the poles"),
    ("vehicle", "flight.wing_area"): Plausible(0.01, 10.0, "Merckelbach et al. 2019: "
                                               "0.1 m2"),
    ("vehicle", "flight.drag_cd0"): Plausible(0.01, 2.0, "Merckelbach et al. 2019: "
                                              "0.15-0.17"),
    ("vehicle", "flight.hull_volume"): Plausible(
        1e4, 2e6, "Merckelbach et al. 2019: 71.6 l; 10 l to 2 m3 covers any glider"),
    ("board", "mode.clock"): Plausible(1.0, 10000.0, "Woithe & Kremer, Table I: "
                                       "133-500 MHz"),
    ("board", "mode.active_power"): Plausible(0.01, 100.0, "Woithe & Kremer, Table I: "
                                              "2.7-4.14 W"),
    ("board", "boot_time"): Plausible(0.0, 600.0, "TS-7800 0.7-2 s; ten minutes is "
                                      "beyond any Linux board"),
    ("battery", "energy"): Plausible(1e3, 1e8, "Slocum alkaline pack 7.8 MJ, G3 "
                                     "3381 Wh (12 MJ)"),
    ("battery", "voltage"): Plausible(1.0, 100.0, "the Slocum bus 14-15 V"),
}


def plausible(kind: str, key: str) -> Plausible | None:
    """The range of figure `key` (dotted, as `Table.key` gives it) of a `kind` file."""
    return RANGES.get((kind, re.sub(r"\[\d+\]", "", key)))

"""Fleets for the fleet tests and the bench: generated ones (a box cut into lines, gliders
of different kinds, charges and starts), and small assignment problems."""

from __future__ import annotations

import numpy as np

from gliderplan.planner import fleet_assign as assign

VEHICLES = (("slocum_g3", "1.2 kWh"), ("slocum_g2_shallow", "350 Ah at 15 V"))


def ddmm(degrees: float) -> float:
    sign = -1.0 if degrees < 0 else 1.0
    whole = int(abs(degrees))
    return sign * (whole * 100 + (abs(degrees) - whole) * 60.0)


def generated_fleet(seed: int, gliders: int = 5, lines: int = 12, line_km: float = 16.0,
                    spacing_km: float = 4.0, days: float = 7.0,
                    confidence: str = "90 %") -> str:
    """The text of a fleet of `gliders` over a box of `lines` lines `line_km` long and
    `spacing_km` apart off New Jersey: each glider of a random kind, charge and start time,
    put in the water near the box's edge."""
    rng = np.random.default_rng(seed)
    lat0, lon0 = 39.3, -74.1
    km_lat, km_lon = 1 / 111.2, 1 / (111.2 * np.cos(np.radians(lat0)))
    width = lines * spacing_km
    corners = [(lat0, lon0), (lat0 + line_km * km_lat, lon0),
               (lat0 + line_km * km_lat, lon0 + width * km_lon), (lat0, lon0 + width * km_lon)]
    area = ", ".join(f"({ddmm(a):.4f}, {ddmm(b):.4f})" for a, b in corners)
    text = [f"fleet generated{seed}", "", "start 2024-06-01T00:00Z", f"finish by {days:g} d",
            f"confidence {confidence}", f"field {3 * spacing_km:g} km 2 d noise 10 %", "",
            "survey", "begin",
            f"  area {area} heading 0 deg", "end", "",
            f"sample temp, conductivity depth 5 .. 30 m spacing {spacing_km:g} km", ""]
    for n in range(gliders):
        vehicle, battery = VEHICLES[int(rng.integers(len(VEHICLES)))]
        charge = float(rng.choice([0.25, 0.4, 0.7, 1.0]))
        along = float(rng.uniform(0.0, width))
        lat = lat0 - float(rng.uniform(1.0, 4.0)) * km_lat
        lon = lon0 + along * km_lon
        late = float(rng.choice([0.0, 0.0, 0.0, 12.0, 24.0]))
        start = f"start ({ddmm(lat):.4f}, {ddmm(lon):.4f})" + (
            f" at 2024-06-0{1 + int(late // 24)}T{int(late % 24):02d}:00Z" if late else "")
        text += [f"glider g{n}", "begin", f"  vehicle {vehicle}", "  computer none",
                 f"  battery {battery} reserve 10 %", f"  charge {100 * charge:g} %",
                 f"  {start}", "end", ""]
    return "\n".join(text)


def block_problem(seed: int, gliders: int = 3, parts: int = 7,
                  scenarios: int = 20) -> assign.BlockInputs:
    """A small random assignment: lines, gliders of different speeds, ends and starts,
    scenario factors, and a revisit error rising with the pass time."""
    rng = np.random.default_rng(seed)
    length = rng.uniform(5e3, 15e3, parts)
    transit = rng.uniform(0.0, 30e3, (gliders, parts, 2))
    line_factor = rng.uniform(1.0, 1.6, (gliders, parts, scenarios))
    transit_factor = rng.uniform(1.0, 1.6, (gliders, parts, 2, scenarios))

    def error_of_pass(pass_s):
        return 1.0 - np.exp(-np.asarray(pass_s, float) / (3 * 86400.0))

    return assign.BlockInputs(
        length_m=length, link_m=np.append(np.full(parts - 1, 3e3), 0.0),
        weight=length / length.sum(), speed_mps=rng.uniform(0.18, 0.33, gliders),
        flight_share=0.96, launch_s=600.0, start_s=rng.choice([0.0, 0.0, 43200.0], gliders),
        end_s=rng.uniform(3.0, 7.0, gliders) * 86400.0, period_s=7 * 86400.0,
        transit_m=transit, line_factor=line_factor, transit_factor=transit_factor,
        quantile=0.05, revisit_s=None, error_of_pass=error_of_pass, time_scale_s=2 * 86400.0)

"""A map of a glider at sea: the current field (arrows), the mission's waypoints, the
planned and the flown tracks, and the surfacings with their 90 % ellipses. Drawn by
`sim --map`, `forecast --map`, `route --map` (PNG) and in the report (SVG)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gliderplan.sim.currents import CurrentField, GriddedCurrent

ARROWS = 15  # current arrows a side


@dataclass(frozen=True)
class SeaMap:
    """What a map shows; every position (lat, lon) [deg]."""

    title: str
    # label: (lat, lon) arrays
    tracks: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    waypoints: tuple[tuple[float, float], ...] = ()
    surfacings: tuple[dict, ...] = ()  # lat, lon [, ellipse_m (a, b), ellipse_azimuth_deg]
    currents: CurrentField | None = None
    epoch_s: float = 0.0  # when the field is drawn [s since 1970]


def draw(m: SeaMap):
    """The map as a matplotlib figure."""
    from matplotlib.patches import Ellipse

    from gliderplan.reports.figures import pyplot

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 6.0))
    lats = [p[0] for p in m.waypoints] + [s["lat"] for s in m.surfacings]
    lons = [p[1] for p in m.waypoints] + [s["lon"] for s in m.surfacings]
    for lat, lon in m.tracks.values():
        lats += [float(np.min(lat)), float(np.max(lat))]
        lons += [float(np.min(lon)), float(np.max(lon))]
    coslat = math.cos(math.radians(float(np.mean(lats)))) if lats else 1.0
    if m.currents is not None and lats:
        _arrows(ax, m.currents, m.epoch_s, (min(lats), max(lats)), (min(lons), max(lons)))
    for label, (lat, lon) in m.tracks.items():
        ax.plot(lon, lat, lw=1.2, label=label)
    if m.waypoints:
        ax.plot([p[1] for p in m.waypoints], [p[0] for p in m.waypoints], "k^", ms=7,
                label="waypoints")
    for i, s in enumerate(m.surfacings):
        ax.plot(s["lon"], s["lat"], "o", color="tab:red", ms=4,
                label="surfacings" if i == 0 else None)
        if "ellipse_m" in s and s["ellipse_m"][0] > 0.0:
            a, b = s["ellipse_m"]
            deg = 180.0 / (math.pi * 6371000.0)  # degrees of latitude per metre
            # drawn in (lon, lat): east-west stretched by 1 / cos(lat); the azimuth is
            # from north, clockwise
            ax.add_patch(Ellipse((s["lon"], s["lat"]), 2 * b * deg / coslat, 2 * a * deg,
                                 angle=-s.get("ellipse_azimuth_deg", 0.0), fill=False,
                                 color="tab:red", lw=0.8,
                                 label="90 % ellipses" if i == 0 else None))
    if lats:  # a square of the larger span: a track along a parallel stays readable
        half = 0.6 * max(max(lats) - min(lats), (max(lons) - min(lons)) * coslat, 1e-3)
        mid_lat, mid_lon = (max(lats) + min(lats)) / 2, (max(lons) + min(lons)) / 2
        ax.set_ylim(mid_lat - half, mid_lat + half)
        ax.set_xlim(mid_lon - half / coslat, mid_lon + half / coslat)
    ax.set_aspect(1.0 / coslat)
    ax.ticklabel_format(useOffset=False)
    ax.tick_params(axis="x", labelrotation=30)
    ax.set_xlabel("longitude [deg]")
    ax.set_ylabel("latitude [deg]")
    ax.set_title(m.title)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize=8)
    return fig


def _arrows(ax, currents: CurrentField, epoch_s: float, lat_range: tuple[float, float],
            lon_range: tuple[float, float]) -> None:
    """The field's current as arrows over the map's area (a gridded field: its own box)."""
    coslat = math.cos(math.radians(sum(lat_range) / 2))
    half = 0.6 * max(lat_range[1] - lat_range[0], (lon_range[1] - lon_range[0]) * coslat, 1e-3)
    mid_lat, mid_lon = sum(lat_range) / 2, sum(lon_range) / 2
    lat = np.linspace(mid_lat - half, mid_lat + half, ARROWS)
    lon = np.linspace(mid_lon - half / coslat, mid_lon + half / coslat, ARROWS)
    if isinstance(currents, GriddedCurrent):
        lat = np.clip(lat, currents.lat_deg[0], currents.lat_deg[-1])
        lon = np.clip(lon, currents.lon_deg[0], currents.lon_deg[-1])
    grid_lat, grid_lon = np.meshgrid(lat, lon, indexing="ij")
    north, east = currents.along(grid_lat, grid_lon, epoch_s)
    speed = np.hypot(north, east)
    q = ax.quiver(grid_lon, grid_lat, east, north, speed, cmap="Blues", alpha=0.7)
    ax.figure.colorbar(q, ax=ax, label="current [m/s]", shrink=0.8)


def image(m: SeaMap, fmt: str = "png") -> bytes:
    """The map as PNG or SVG bytes."""
    from gliderplan.reports.figures import render

    return render(draw(m), fmt)


def write_map(path: str, m: SeaMap) -> None:
    """`--map FILE.png|FILE.svg`: the map written there (atomically)."""
    from gliderplan.contract.errors import UsageError
    from gliderplan.contract.files import write_atomically

    fmt = path.lower().rsplit(".", 1)[-1]
    if fmt not in ("png", "svg"):
        raise UsageError(f"--map {path}: expected a .png or .svg file")
    write_atomically(path, image(m, fmt))

"""Where a fleet's survey lies: positions in local metres, areas cut into transects, and
paths around keep-out areas.

Positions are projected onto a local plane about the survey's centre with the
equirectangular approximation the pilot's routes use (docs/pilot.md, Routes), good to a
fraction of a per cent over the hundred kilometres of a shelf survey. Polygons are
shapely's (GEOS), so that self-crossing areas, overlaps and clipping are decided by one
well-tested library rather than by hand.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gliderplan.contract import EARTH_RADIUS_M
from gliderplan.planner.legs import ddmm_to_degrees

XY = tuple[float, float]  # (east, north) [m] on the local plane
KEEPOUT_MARGIN_M = 200.0  # a path around a keep-out area passes this far from it [m]
MIN_PIECE_M = 100.0  # a transect piece shorter than this is a sliver of clipping [m]


@dataclass(frozen=True)
class Projection:
    """The local plane: (east, north) [m] about (lat0, lon0) [deg]."""

    lat0: float
    lon0: float

    @property
    def _scale(self) -> float:
        return EARTH_RADIUS_M * math.pi / 180.0

    def to_xy(self, lat_deg, lon_deg):
        """(east, north) [m] of positions [deg] (scalars or arrays)."""
        north = (np.asarray(lat_deg, float) - self.lat0) * self._scale
        east = (np.asarray(lon_deg, float) - self.lon0) * self._scale \
            * math.cos(math.radians(self.lat0))
        return east, north

    def to_latlon(self, east_m, north_m):
        """(lat, lon) [deg] of plane positions [m] (scalars or arrays)."""
        lat = self.lat0 + np.asarray(north_m, float) / self._scale
        lon = self.lon0 + np.asarray(east_m, float) / (
            self._scale * math.cos(math.radians(self.lat0)))
        return lat, lon

    def point(self, ddmm: tuple[float, float]) -> XY:
        """The plane position of a (lat, lon) point in DDMM.MMMM."""
        x, y = self.to_xy(ddmm_to_degrees(ddmm[0]), ddmm_to_degrees(ddmm[1]))
        return float(x), float(y)


def projection_about(points_ddmm: list[tuple[float, float]]) -> Projection:
    """The plane about the middle of `points_ddmm` (DDMM.MMMM)."""
    lats = [ddmm_to_degrees(p[0]) for p in points_ddmm]
    lons = [ddmm_to_degrees(p[1]) for p in points_ddmm]
    return Projection(0.5 * (min(lats) + max(lats)), 0.5 * (min(lons) + max(lons)))


def polygon(points: list[XY]):
    """A shapely polygon of plane points (its ring closed for it)."""
    from shapely.geometry import Polygon

    return Polygon(points)


def polygon_problem(points: list[XY]) -> str | None:
    """Why `points` is no usable area (None when it is one)."""
    from shapely.validation import explain_validity

    shape = polygon(points)
    if shape.area <= 1.0 and shape.convex_hull.area <= 1.0:
        return "it encloses no area (its corners lie on a line)"
    if not shape.is_valid:
        why = explain_validity(shape)
        return "its edges cross each other" if why.startswith("Self-intersection") \
            else why.lower()
    return None


def longest_edge_heading(shape) -> float:
    """Heading [rad, clockwise from north] of the longest edge of a polygon: lines along
    it need the fewest turns."""
    ring = list(shape.exterior.coords)
    edges = [(b[0] - a[0], b[1] - a[1]) for a, b in zip(ring, ring[1:], strict=False)]
    east, north = max(edges, key=lambda e: math.hypot(*e))
    return math.atan2(east, north) % math.pi


def transects(shape, spacing_m: float, heading_rad: float, keepouts
              ) -> list[tuple[XY, XY, int]]:
    """Lines `spacing_m` apart along `heading_rad` across `shape`, the first half a
    spacing in from its edge, clipped to it and cut where they cross `keepouts` (one
    shapely geometry or None): (one end, the other, which line) of each piece, in order
    of offset, then along each line."""
    from shapely.geometry import LineString

    along = np.array([math.sin(heading_rad), math.cos(heading_rad)])
    across = np.array([along[1], -along[0]])
    corners = np.asarray(shape.exterior.coords)
    offsets = corners @ across
    reach = corners @ along
    low, high = float(offsets.min()), float(offsets.max())
    start, stop = float(reach.min()) - 1.0, float(reach.max()) + 1.0
    pieces: list[tuple[XY, XY, int]] = []
    offset = low + 0.5 * spacing_m
    line_number = 0
    while offset <= high:
        a = offset * across + start * along
        b = offset * across + stop * along
        cut = shape.intersection(LineString([tuple(a), tuple(b)]))
        if keepouts is not None:
            cut = cut.difference(keepouts)
        for line in _lines(cut):
            (x0, y0), (x1, y1) = line.coords[0], line.coords[-1]
            if line.length >= MIN_PIECE_M:
                first = np.dot([x0, y0], along) <= np.dot([x1, y1], along)
                pieces.append(((x0, y0), (x1, y1), line_number) if first
                              else ((x1, y1), (x0, y0), line_number))
        offset += spacing_m
        line_number += 1
    return pieces


def pieces_outside(a: XY, b: XY, keepouts) -> list[tuple[XY, XY]]:
    """The parts of the segment a-b outside `keepouts` (None: the whole segment)."""
    from shapely.geometry import LineString

    if keepouts is None:
        return [(a, b)]
    rest = LineString([a, b]).difference(keepouts)
    return [(line.coords[0], line.coords[-1]) for line in _lines(rest)
            if line.length >= MIN_PIECE_M]


def _lines(geometry) -> list:
    """The line strings in a shapely result (a line, several, or a collection)."""
    if geometry.is_empty:
        return []
    if geometry.geom_type == "LineString":
        return [geometry]
    if hasattr(geometry, "geoms"):
        return [g for part in geometry.geoms for g in _lines(part)]
    return []


class Router:
    """Shortest paths on the plane that keep `KEEPOUT_MARGIN_M` clear of keep-out areas:
    straight where nothing is in the way, else through the corners of the keep-outs
    grown by the margin (a visibility graph; exact for polygons and a few corners)."""

    def __init__(self, keepouts: list) -> None:
        from shapely.ops import unary_union

        self.grown = [k.buffer(KEEPOUT_MARGIN_M, join_style="mitre") for k in keepouts]
        self.blocked = unary_union(keepouts) if keepouts else None
        # corners a path may bend at: those of the grown areas, just outside them
        self.corners = [c for g in self.grown for c in list(g.exterior.coords)[:-1]]

    def clear(self, a: XY, b: XY) -> bool:
        """True when the straight leg a-b passes no keep-out area's inside."""
        from shapely.geometry import LineString, Point

        if self.blocked is None:
            return True
        if a == b:
            return not self.blocked.contains(Point(a))
        leg = LineString([a, b])
        return not leg.intersects(self.blocked) or leg.touches(self.blocked)

    def path(self, a: XY, b: XY) -> list[XY]:
        """The points from a to b (both included) around the keep-outs; [a, b] when the
        straight leg is clear, or when no path around exists (the caller checks)."""
        if self.clear(a, b) or not self.corners:
            return [a, b]
        from scipy.sparse import csr_matrix
        from scipy.sparse.csgraph import dijkstra

        nodes = [a, b, *self.corners]
        n = len(nodes)
        rows, cols, weights = [], [], []
        for i in range(n):
            for j in range(i + 1, n):
                if self.clear(nodes[i], nodes[j]):
                    rows.append(i)
                    cols.append(j)
                    weights.append(math.dist(nodes[i], nodes[j]) + 1e-9)
        graph = csr_matrix((weights, (rows, cols)), shape=(n, n))
        dist, previous = dijkstra(graph, directed=False, indices=0, return_predecessors=True)
        if not math.isfinite(dist[1]):
            return [a, b]
        route, at = [], 1
        while at != -9999 and at != 0:
            route.append(nodes[at])
            at = previous[at]
        return [a, *reversed(route)]

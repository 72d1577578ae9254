"""The surfacing forecast: where and when the glider will surface, with a 90 % ellipse
that holds the real surfacing nine times in ten, and its check on a real flight."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

from gliderplan.cli.main import main
from gliderplan.planner.surfacings import Voyage, forecast_surfacings
from gliderplan.sim.currents import UniformCurrent
from gliderplan.sim.geo import move_degrees

COMET = Path(__file__).resolve().parents[2] / "shared" / "data" / "slocum-logs-comet-2016"


def test_a_glider_surfaces_where_its_speed_and_the_current_carry_it():
    voyage = Voyage(54.0, 15.0, 0.0, (), 0.3, 3000.0, 600.0, UniformCurrent(0.1, 0.0),
                    heading_rad=math.pi / 2)
    first, second = forecast_surfacings(voyage, 2)
    assert first.time_s == pytest.approx(3000.0, rel=0.02)
    lat, lon = move_degrees(54.0, 15.0, 0.1 * 3000.0, 0.3 * 3000.0)
    assert first.distance_m(lat, lon) < 0.03 * 900.0
    assert second.time_s == pytest.approx(6600.0, rel=0.02)
    assert second.ellipse_m[0] > first.ellipse_m[0] > first.ellipse_m[1] > 0.0


def test_the_90_percent_ellipse_holds_a_surfacing_drawn_from_the_same_uncertainty():
    rng = np.random.default_rng(7)
    sigma, inside = 0.05, []
    for trial in range(60):
        known = UniformCurrent(0.1, -0.05)
        voyage = Voyage(54.0, 15.0, 0.0, ((54.05, 15.0),), 0.3, 1800.0, 300.0, known)
        surfacing = forecast_surfacings(voyage, 1, seed=trial)[0]
        true = UniformCurrent(0.1 + sigma * rng.standard_normal(),
                              -0.05 + sigma * rng.standard_normal())
        real = forecast_surfacings(Voyage(54.0, 15.0, 0.0, ((54.05, 15.0),), 0.3, 1800.0,
                                          300.0, true, current_sigma_mps=1e-9,
                                          dive_sigma_s=1e-9), 1, draws=2)[0]
        inside.append(surfacing.inside(real.lat_deg, real.lon_deg))
    assert 0.8 <= np.mean(inside) <= 1.0


def test_a_waypoint_is_reached_and_the_next_one_flown_to():
    wp = ((54.01, 15.0), (54.01, 15.03))
    voyage = Voyage(54.0, 15.0, 0.0, wp, 0.3, 1800.0, 300.0, capture_m=100.0)
    surfacings = forecast_surfacings(voyage, 4)
    # 1.1 km north at 0.3 m/s: 540 m a dive, the first waypoint in the second, then east
    assert surfacings[0].lat_deg == pytest.approx(54.00485, abs=3e-4)
    assert surfacings[0].lon_deg == pytest.approx(15.0, abs=1e-4)
    assert surfacings[-1].lon_deg > 15.01 and surfacings[-1].lat_deg == pytest.approx(54.01,
                                                                                       abs=2e-3)


@pytest.mark.skipif(not COMET.is_dir() and os.environ.get("CI") != "true",
                    reason="the shared comet logs are not present")
def test_the_hindcast_on_a_real_flight_reports_errors_by_horizon(capsys):
    assert main(["hindcast", str(COMET), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    rows = {r["ahead"]: r for r in data["summary"]}
    assert rows[1]["count"] >= 15 and rows[1]["median_horizon_s"] < rows[2]["median_horizon_s"]
    assert rows[1]["median_error_m"] < 500.0  # the glider moves ~150 m a dive
    assert rows[1]["median_error_m"] < rows[2]["median_error_m"]
    assert all(0.0 <= r["inside_ellipse"] <= 1.0 for r in rows.values())


def test_hindcast_without_flight_logs_is_a_message(tmp_path, capsys):
    assert main(["hindcast", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "no Slocum flight logs (*.dbd)" in err and "Traceback" not in err

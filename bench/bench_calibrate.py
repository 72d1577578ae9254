"""Benchmark: calibrating the shared Slocum logs, and forecasting a 30-day mission.

    .venv/bin/python bench/bench_calibrate.py [--runs 3] [LOGDIR]   # ../shared/data/slocum-logs

1. Whole process, as the user runs it (bench/whole_process.py: medians after a warm-up,
   wall and CPU time): `gliderplan calibrate LOGDIR -o FILE` (the fit and its 40-refit
   bootstrap over dives) and `gliderplan calibrate LOGDIR --validate --json` (that, plus
   the forward check's own fit and bootstrap, the forecast's 400 draws and the replay).
   Target: under 30 s. Baseline in the same run: one steady-state flight calibration of
   the log as gliderflight ships it (the angle of attack solved with fsolve for 100
   pitches at every step of the minimiser) against the same calibration with
   `flight_fit`'s angle-of-attack table, in this process; `calibrate -o` runs 41 of them.
   The second glider's logs (comet 2016, ten segments, with its DVL, logger, FLNTU and
   CTD: the device fit) the same way, `calibrate COMETDIR -o FILE`: target under 60 s.
2. Whole process, as the user runs it: `gliderplan forecast nsb3.mi --vehicle COMET.toml
   --duration 30d --json`, the imported Slocum mission on the glider calibrated above
   (its timeline, each state billed by device, 400 drawn vehicles for the interval).
   Target: under 2 s. Baseline in the same run: the simulator flying the same imported
   mission for one day (`gliderplan sim --duration 1d`, whole process), times 30.
3. Whole process (`python -c`, imports included): the forward forecast of a 30-day yo
   mission (3-38 m at 0.454 rad, 230 cc, 40 dives between surfacings: every ~6 h) with
   its 90 % energy interval (400 vehicles drawn from the preset's uncertainty). Target:
   under 1 s. Baseline in the same run: the simulator (Python executor) flying the first
   day of `tests/missions/sim_month.mission` (the same yo band and pitch, surfacing
   every 6 h), in this process, times 30.
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from whole_process import ENV, gliderplan, load_average, median_of  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
LOGS = ROOT.parent / "shared" / "data" / "slocum-logs"
COMET = ROOT.parent / "shared" / "data" / "slocum-logs-comet-2016"
NSB3 = ROOT.parent / "shared" / "data" / "slocum-missions" / "nsb3" / "nsb3.mi"
MONTH = ROOT / "tests" / "missions" / "sim_month.mission"
CALIBRATE_GOAL_S, FORECAST_GOAL_S = 30.0, 1.0
GOALS_S = {"calibrate comet -o FILE": 60.0, "forecast nsb3.mi 30d (comet)": 2.0,
           "30-day forecast": FORECAST_GOAL_S}
RUNS_IN_PROCESS = 3

FORECAST = """
from gliderplan.power_models import load_vehicle
from gliderplan.power_models.draws import draw_vehicles
from gliderplan.power_models.forecast import YoCommand, energy_interval_j, forecast
vehicle = load_vehicle("slocum_g2_shallow")
command = YoCommand(3.0, 38.0, 0.454, 0.454, 230.0, 40)
month = 30 * 86400.0
result = forecast(vehicle, command, horizon_s=month)
low, high = energy_interval_j(draw_vehicles(vehicle), command, horizon_s=month)
print(f"{result.energy_j / 3.6e6:.3f} kWh (90 % {low / 3.6e6:.3f}-{high / 3.6e6:.3f}), "
      f"{result.yos:.0f} yos, {result.surfacings:.0f} surfacings, "
      f"yo period {result.yo_period_s:.0f} s")
"""


def flight_fit_s(logs: Path) -> tuple[float, float]:
    """(stock gliderflight, flight_fit's) seconds for one steady-state calibration of the
    log, from the same start (each the median of RUNS_IN_PROCESS)."""
    import gliderflight
    import numpy as np

    from gliderplan.power_models import flight_fit, load_vehicle
    from gliderplan.power_models.slocum_log import read_flight_log

    log = read_flight_log([str(logs)])
    steady = flight_fit.steady_glides(log)
    rho = float(np.mean(log.density_kg_m3[steady]))
    base = replace(load_vehicle("slocum_g2_shallow").flight, rho_kg_m3=rho)
    volume_m3 = base.hull_volume_cc * 1e-6
    seconds: list[list[float]] = [[], []]
    for _, (k, model) in itertools.product(range(RUNS_IN_PROCESS), enumerate(
            (gliderflight.SteadyStateCalibrate(rho0=rho), flight_fit._calibrator(base)))):
        model.define(S=base.wing_area_m2, aw=base.lift_wing_per_rad, ah=base.lift_hull_per_rad,
                     Cd1=base.drag_cd1_per_rad2, Vg=volume_m3, mg=rho * volume_m3,
                     Cd0=base.drag_cd0, epsilon=flight_fit.EPSILON_START)
        model.set_input_data(time=log.t_s, pressure=rho * base.g_m_s2 * log.depth_m / 1e5,
                             pitch=log.pitch_rad, buoyancy_change=log.ballast_cc,
                             density=np.where(steady, log.density_kg_m3, rho),
                             dhdt=flight_fit.depth_rate_mps(log))
        model.OR(~steady)
        start = time.perf_counter()
        model.calibrate("Cd0", "mg", "epsilon")
        seconds[k].append(time.perf_counter() - start)
    return statistics.median(seconds[0]), statistics.median(seconds[1])


def imported(work: Path) -> Path:
    """nsb3.mi imported into `work`, for the simulator."""
    out = work / "nsb3.mission"
    subprocess.run(gliderplan("import-slocum", str(NSB3), "-o", str(out)), check=True,
                   env=ENV, capture_output=True)
    return out


def simulated_day_s() -> float:
    """Seconds the Python executor takes to fly the first day of sim_month.mission (the
    median of RUNS_IN_PROCESS)."""
    from gliderplan.language import check_file
    from gliderplan.sim.flight import fly
    from gliderplan.sim.setup import FlightOptions, flight_setup

    mission = check_file(str(MONTH)).checked()
    setup = flight_setup(mission, FlightOptions(noise="none", duration_s=86400.0))
    seconds = []
    for _ in range(RUNS_IN_PROCESS):
        start = time.perf_counter()
        fly(mission, setup.water.ocean, setup.config, setup.vehicle)
        seconds.append(time.perf_counter() - start)
    return statistics.median(seconds)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("logs", nargs="?", default=str(LOGS))
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    logs = Path(args.logs)
    if not logs.is_dir():
        sys.exit(f"{logs}: no such directory (the Slocum logs to calibrate)")
    with tempfile.TemporaryDirectory() as work:
        comet = Path(work) / "comet.toml"
        subprocess.run(gliderplan("calibrate", str(COMET), "-o", str(comet)), check=True,
                       env=ENV, capture_output=True)
        times = median_of({
            "calibrate -o FILE": gliderplan("calibrate", str(logs), "-o",
                                            str(Path(work) / "sebastian.toml")),
            "calibrate --validate --json": gliderplan("calibrate", str(logs), "--validate",
                                                      "--json"),
            "calibrate comet -o FILE": gliderplan("calibrate", str(COMET), "-o",
                                                  str(Path(work) / "again.toml")),
            "forecast nsb3.mi 30d (comet)": gliderplan(
                "forecast", str(NSB3), "--vehicle", str(comet), "--duration", "30d", "--json"),
            "sim nsb3 1 day (x30 below)": gliderplan(
                "sim", str(imported(Path(work))), "--duration", "1d", "-o",
                str(Path(work) / "run")),
            "30-day forecast": [sys.executable, "-c", FORECAST],
        }, args.runs)
    said = subprocess.run([sys.executable, "-c", FORECAST], capture_output=True, text=True,
                          check=True, env=ENV).stdout.strip()
    stock_s, ours_s = flight_fit_s(logs)
    day_s = simulated_day_s()
    print(f"medians of {args.runs} runs after a warm-up, {load_average()} after them")
    for name, t in times.items():
        goal = GOALS_S.get(name, CALIBRATE_GOAL_S)
        verdict = "" if name.startswith("sim ") else \
            f"(target < {goal:g} s wall: {'met' if t.wall_s < goal else 'MISSED'})"
        print(f"  {name:28s} wall {t.wall_s:6.2f} s   cpu {t.cpu_s:6.2f} s   {verdict}")
    month_s = 30 * times["sim nsb3 1 day (x30 below)"].wall_s
    print(f"  simulating nsb3 for 30 days, as 30 x one day: {month_s:.1f} s wall, "
          f"{month_s / times['forecast nsb3.mi 30d (comet)'].wall_s:.0f}x the forecast")
    print(f"  the forecast: {said}")
    print(f"one flight calibration of the log: gliderflight as shipped {stock_s:.2f} s, "
          f"with flight_fit's angle-of-attack table {ours_s:.3f} s ({stock_s / ours_s:.0f}x)")
    forecast_s = times["30-day forecast"].wall_s
    print(f"simulating the same yo: {day_s:.2f} s a day, {30 * day_s:.1f} s for 30 days "
          f"({30 * day_s / forecast_s:.0f}x the forecast's whole process)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

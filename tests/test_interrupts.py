"""Interrupts end the work, honestly (issue 29, point 1).

SIGINT and SIGTERM stop every command promptly with exit 130 or 143, whatever the number
of workers (one, a process pool, Dask); nothing interrupted is counted as a result; what
was completed is written and marked partial (summary.json's `complete`, the folder's
marker), and an interrupted Monte Carlo or confidence plan never reports a hold rate or a
plan as if complete. The first test sends the signals at seeded random moments; the
others put a stop where the issue found one swallowed or lost.
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pandas as pd
import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode, interrupts
from gliderplan.contract.files import RUN_MARKER
from gliderplan.sim import montecarlo, outputs
from gliderplan.sim.science import ScienceComputer

REPO = Path(__file__).resolve().parents[1]
FIG2 = REPO / "examples" / "fig2.mission"
SURVEY = REPO / "examples" / "thermocline_survey.mission"
MONTH = REPO / "examples" / "survey_month.mission"
FLEET = REPO / "tests" / "fleets" / "small.fleet"
CALM = str(REPO / "tests" / "fleets" / "calm.toml")
STOPPED = {signal.SIGINT: ExitCode.INTERRUPTED, signal.SIGTERM: ExitCode.TERMINATED}
PROMPT_S = 60.0  # a stopped command exits within this of the signal, whatever the load
HUNG_S = 300.0  # a command still running this long after its start is killed: it hung

# (name, command, what it writes: a folder or a plan file). The Monte Carlo runs are far
# longer than the moments drawn (1,000 scenarios of a 35 h survey): one that ran on past
# its stop would be seen.
COMMANDS = {
    "montecarlo, 1 worker": (["montecarlo", str(SURVEY), "--scenarios", "1000",
                              "--workers", "1"], "folder"),
    "montecarlo, 2 workers": (["montecarlo", str(SURVEY), "--scenarios", "1000",
                               "--workers", "2"], "folder"),
    "montecarlo, Dask": (["montecarlo", str(SURVEY), "--scenarios", "1000", "--workers", "2",
                          "--scheduler", "local"], "folder"),
    "plan --confidence, 1 worker": (["plan", str(FIG2), "--confidence", "0.95",
                                     "--workers", "1"], "plan"),
    "plan --confidence, 2 workers": (["plan", str(FIG2), "--confidence", "0.95",
                                      "--workers", "2"], "plan"),
    "sim, a month": (["sim", str(MONTH)], "folder"),
}
MOMENTS = 3  # signals per command, at seeded random moments


def moments(name: str) -> list[tuple[int, float, signal.Signals, bool]]:
    """(progress lines to wait for, then seconds, the signal, to the whole process group):
    seeded by the command, so that a failure is the same moment again."""
    rng = random.Random(f"issue 29: {name}")
    drawn = []
    for i in range(MOMENTS):  # the first while it starts, the others while it works
        lines = 0 if i == 0 else rng.choice([1, 2, 4, 8])
        delay = rng.uniform(0.0, 2.0 if lines == 0 else 0.5)
        drawn.append((lines, delay, (signal.SIGINT, signal.SIGTERM)[i % 2], rng.random() < 0.5))
    return drawn


def _stop(process: subprocess.Popen, lines: int, delay: float, signum: int,
          group: bool) -> tuple[bool, float, str]:
    """Send `signum` after `lines` progress lines and `delay` s: (whether it was sent
    while the command ran, when, what the command said)."""
    said = []
    while len(said) < lines:
        line = process.stderr.readline()
        if not line:
            break
        said.append(line)
    time.sleep(delay)
    sent = process.poll() is None
    if sent:
        (os.killpg if group else os.kill)(process.pid, signum)
    return sent, time.monotonic(), "".join(said)


def _group_gone(pgid: int, within_s: float) -> bool:
    """Whether every process of the command's group (workers, a Dask cluster) ended."""
    end = time.monotonic() + within_s
    while time.monotonic() < end:
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.1)
    return False


def _check_folder(out: Path, sent: bool, code: int) -> str:
    """The invariants of a folder a stopped command may have written; what it held."""
    leftovers = [p.name for p in out.parent.glob(f".{out.name}.*")]
    assert leftovers == [], leftovers  # its hidden folder and lock are gone
    if not out.exists():
        assert code != 0, "a run that ended well wrote nothing"
        return "nothing"
    marker = json.loads((out / RUN_MARKER).read_text())
    assert sorted(marker["files"]) == sorted(p.name for p in out.iterdir()
                                             if p.name != RUN_MARKER)
    summary = json.loads((out / "summary.json").read_text())
    assert marker["complete"] is summary["complete"]
    if "finish_probability" in summary:  # a fleet's Monte Carlo: a row per glider
        table = pd.read_parquet(out / "scenarios.parquet")
        gliders = table.groupby("scenario")["glider"].nunique()
        assert len(gliders) == summary["scenarios"]
        assert (gliders == table["glider"].nunique()).all()  # each scenario flown by all
        assert not (table["ended"] == "interrupted").any()
        if summary["complete"]:
            assert summary["scenarios"] == summary["requested"]
            assert summary["finish_probability"] is not None
        else:  # no finish probability as if complete
            assert summary["interrupted"] and summary["scenarios"] < summary["requested"]
            assert summary["finish_probability"] is None
            assert summary["finish_interval"] is None
    elif "requested" in summary:  # Monte Carlo
        table = pd.read_parquet(out / "scenarios.parquet")
        assert len(table) == summary["scenarios"] and table["scenario"].is_unique
        assert not (table["ended"] == "interrupted").any()  # no scenario cut short counted
        if summary["complete"]:
            assert summary["scenarios"] == summary["requested"]
            assert summary["probability_budget_holds"] is not None
        else:  # no hold rate as if complete
            assert summary["interrupted"] and summary["scenarios"] < summary["requested"]
            assert summary["probability_budget_holds"] is None
            assert summary["probability_interval_95"] is None
    else:  # sim
        table = pd.read_parquet(out / "timeseries.parquet")
        assert table["time_s"].iloc[-1] == summary["simulated_s"]
        assert summary["complete"] is (summary["ended"] != "interrupted")
    if code == 0:
        assert summary["complete"]
    if not summary["complete"]:
        assert sent and code != 0
    return "complete" if summary["complete"] else "partial"


@pytest.fixture(scope="module")
def fleet_plan(tmp_path_factory) -> Path:
    """A plan of the small fleet (`fleet plan -o`), for the fleet's runs to fly."""
    out = tmp_path_factory.mktemp("fleet") / "plan"
    assert main(["fleet", "plan", str(FLEET), "--scenario-file", CALM, "-o", str(out)]) == 0
    return out


@pytest.mark.parametrize("name", COMMANDS)
def test_a_signal_at_any_moment_stops_the_command_and_nothing_passes_for_complete(
        name, tmp_path):
    if "Dask" in name:
        pytest.importorskip("distributed")
    signals_at_random_moments(name, *COMMANDS[name], tmp_path)


@pytest.mark.parametrize("workers", ["1", "2"])
def test_a_signal_at_any_moment_stops_a_fleet_monte_carlo_with_no_finish_probability(
        workers, fleet_plan, tmp_path):
    """Longer than any moment drawn (1,000 scenarios of three gliders): a run that went on
    past its stop, or gave a finish probability from the scenarios it had, would be seen."""
    signals_at_random_moments(
        f"fleet montecarlo, {workers} workers",
        ["fleet", "montecarlo", str(FLEET), "--plan", str(fleet_plan), "--scenarios", "1000",
         "--workers", workers], "folder", tmp_path)


def signals_at_random_moments(name: str, argv: list[str], writes: str, tmp_path: Path) -> None:
    """Run the command MOMENTS times, each stopped by a signal at a moment drawn for it;
    every one must stop promptly with 130 or 143, its workers gone, and leave a whole
    run, a partial one marked so, or nothing."""
    seen, stopped = [], 0
    for attempt, (lines, delay, signum, group) in enumerate(moments(name)):
        out = tmp_path / f"out{attempt}" / ("p.plan" if writes == "plan" else "run")
        process = subprocess.Popen(
            [sys.executable, "-m", "gliderplan.cli", *argv, "-o", str(out)],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
            start_new_session=True, env={**os.environ, "GLIDERPLAN_PROGRESS_S": "0"})
        hung = threading.Timer(HUNG_S, os.killpg, (process.pid, signal.SIGKILL))
        hung.start()  # a command that hangs fails the test (exit -9), not the test run
        try:
            sent, at, said = _stop(process, lines, delay, signum, group)
            said += process.stderr.read()
            code = process.wait()
        finally:
            hung.cancel()
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGKILL)
        took = time.monotonic() - at
        print(f"{name}: {lines} lines + {delay:.2f} s: exit {code} {took:.1f} s after")
        moment = f"{name}: {signal.Signals(signum).name} after {lines} lines + {delay:.2f} s"
        if code == -signum or "Fatal Python error" in said:
            # stopped by the signal itself as Python started, before gliderplan ran (a
            # shell says 128 + N), or cut Python's own start-up
            assert not out.exists(), moment
            seen.append("nothing")
            continue
        assert "Traceback" not in said and "internal error" not in said, (moment, said)
        if sent:
            stopped += 1
            assert code == STOPPED[signum], (moment, code, said)
            assert took < PROMPT_S, (moment, took)
        else:
            assert code == 0, (moment, code, said)
        assert _group_gone(process.pid, 30.0), f"{moment}: a worker outlived the command"
        if writes == "plan":  # an interrupted plan is no plan: nothing written
            written = out.exists(), Path(f"{out}.json").exists()
            assert written in ((True, True), (False, False)), moment  # never one alone
            if code == 0:
                assert written == (True, True), moment
            if written[0]:  # finished (a stop as it was written waits for it): the plan
                assert out.read_bytes() == reference_plan(argv, tmp_path), moment
            seen.append("plan" if written[0] else "nothing")
        else:
            seen.append(_check_folder(out.parent / out.name, sent, code))
    assert stopped, seen  # at least one moment fell while the command ran


def reference_plan(argv: list[str], tmp_path: Path) -> bytes:
    """The plan the command makes when nothing stops it (the same for any workers)."""
    out = tmp_path / "reference.plan"
    if not out.exists():
        subprocess.run([sys.executable, "-m", "gliderplan.cli", *argv, "-o", str(out)],
                       check=True, capture_output=True)
    return out.read_bytes()


def interrupt_scenario(monkeypatch, scenario: int, at_tick: int = 50) -> None:
    """Ctrl-C in the middle of the flight of the `scenario`-th flight flown (0 first)."""
    original, flights = ScienceComputer.readings, []
    # the stop is injected where the Python loop reads the sensors: fly it there
    monkeypatch.setattr("gliderplan.sim.flight.default_runtime", lambda: "python")

    def readings(self, tick):
        if tick == 0:
            flights.append(self)
        if tick >= at_tick and len(flights) == scenario + 1:
            raise KeyboardInterrupt
        return original(self, tick)
    monkeypatch.setattr(ScienceComputer, "readings", readings)


def test_a_scenario_cut_short_is_not_counted_and_the_run_stops(tmp_path, monkeypatch, capsys):
    """The issue: with one worker, the scenario loop caught the interrupt, counted the
    scenario cut short as held and flew on ("200 of 200 held", interrupted false)."""
    interrupt_scenario(monkeypatch, 2)
    out = tmp_path / "mc"
    assert main(["montecarlo", str(FIG2), "--scenarios", "6", "--workers", "1",
                 "-o", str(out)]) == ExitCode.INTERRUPTED
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] is False and summary["interrupted"] is True
    assert (summary["scenarios"], summary["requested"]) == (2, 6)
    assert summary["probability_budget_holds"] is None
    assert summary["probability_interval_95"] is None
    assert json.loads((out / RUN_MARKER).read_text())["complete"] is False
    table = pd.read_parquet(out / "scenarios.parquet")
    assert list(table["scenario"]) == [0, 1] and set(table["ended"]) == {"exit"}
    said = capsys.readouterr()
    assert "INTERRUPTED after 2 of 6 scenarios: no probability" in said.out
    assert "%" not in said.out  # no share held, of any kind
    assert "2 of 6 scenarios finished" in said.err and "marked partial" in said.err


def test_an_interrupted_confidence_plan_writes_no_plan(tmp_path, monkeypatch, capsys):
    """The issue: `plan --confidence 0.95 --workers 1` interrupted exited 0 with another
    plan (the scenario cut short counted). A plan written before stays as it was."""
    plan = tmp_path / "p.plan"
    plan.write_text("an earlier plan\n")
    interrupt_scenario(monkeypatch, 3)
    assert main(["plan", str(FIG2), "--confidence", "0.95", "--workers", "1",
                 "-o", str(plan)]) == ExitCode.INTERRUPTED
    assert plan.read_text() == "an earlier plan\n" and not Path(f"{plan}.json").exists()
    said = capsys.readouterr()
    assert "gliderplan plan: interrupted" in said.err and "quality" not in said.out


def test_a_stop_that_a_library_swallowed_still_stops_the_command(tmp_path, monkeypatch,
                                                                 capsys):
    """A signal that something on the way caught and dropped (a solver, a scheduler) still
    stops the command: no plan is written and the exit is 143, not 0."""
    from gliderplan.planner import plan as planner

    real = planner.plan_mission

    def swallowing(*args, **kwargs):
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(1.0)  # the handler raises here
        except KeyboardInterrupt:
            pass
        return real(*args, **kwargs)
    monkeypatch.setattr(planner, "plan_mission", swallowing)
    plan = tmp_path / "p.plan"
    assert main(["plan", str(FIG2), "-o", str(plan)]) == ExitCode.TERMINATED
    assert not plan.exists() and not Path(f"{plan}.json").exists()
    assert "terminated" in capsys.readouterr().err


def test_ctrl_c_just_after_the_flight_writes_the_whole_flight(tmp_path, monkeypatch, capsys):
    """The issue: Ctrl-C just after the flight of a month printed "interrupted" and wrote
    nothing. Now the run is written, whole (its flight ended), and the command stops."""
    real = outputs.summary

    def interrupted_while_writing(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        return real(*args, **kwargs)
    monkeypatch.setattr(outputs, "summary", interrupted_while_writing)
    out = tmp_path / "run"
    assert main(["sim", str(FIG2), "-o", str(out)]) == ExitCode.INTERRUPTED
    summary = json.loads((out / "summary.json").read_text())
    assert summary["ended"] == "exit" and summary["complete"] is True
    assert summary["simulated_s"] == 2500.0
    assert len(pd.read_parquet(out / "timeseries.parquet")) == 626
    assert "interrupted once the flight was over: the outputs in" in capsys.readouterr().err


def test_a_second_ctrl_c_while_writing_abandons_it_and_keeps_the_previous_run(
        tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    assert main(["sim", str(FIG2), "--seed", "1", "-o", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    real = outputs.summary

    def twice(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(1.0)
        return real(*args, **kwargs)
    monkeypatch.setattr(outputs, "summary", twice)
    assert main(["sim", str(FIG2), "--seed", "2", "-o", str(out)]) == ExitCode.INTERRUPTED
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["run"]
    assert "gliderplan sim: interrupted" in capsys.readouterr().err


def test_sigterm_once_every_scenario_flew_writes_the_whole_run(tmp_path, monkeypatch, capsys):
    real = montecarlo.summary

    def terminated_while_writing(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGTERM)
        return real(*args, **kwargs)
    monkeypatch.setattr(montecarlo, "summary", terminated_while_writing)
    out = tmp_path / "mc"
    assert main(["montecarlo", str(FIG2), "--scenarios", "3", "--workers", "1",
                 "-o", str(out)]) == ExitCode.TERMINATED
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] and summary["scenarios"] == 3
    assert summary["probability_budget_holds"] == 1.0
    assert "interrupted once every scenario had flown" in capsys.readouterr().err


def test_an_interrupted_run_says_so_in_its_netcdf_and_report_refuses_it(tmp_path,
                                                                        monkeypatch, capsys):
    import xarray as xr

    original = ScienceComputer.readings

    def readings(self, tick):
        if tick == 300:
            raise KeyboardInterrupt
        return original(self, tick)
    monkeypatch.setattr(ScienceComputer, "readings", readings)
    run = tmp_path / "run"
    assert main(["sim", str(FIG2), "--runtime", "python", "--netcdf", "-o",
                 str(run)]) == ExitCode.INTERRUPTED
    with xr.open_dataset(run / "trajectory.nc") as data:
        assert "PARTIAL RUN: interrupted after 1196 s" in data.attrs["summary"]
        assert "PARTIAL RUN" in data.attrs["comment"]
    monkeypatch.undo()
    capsys.readouterr()
    assert main(["report", str(FIG2), "--run", str(run), "-o",
                 str(tmp_path / "report")]) == ExitCode.USAGE
    assert "a partial run, interrupted after 1196 s" in capsys.readouterr().err
    assert not (tmp_path / "report").exists()


def test_report_refuses_a_partial_monte_carlo(tmp_path, monkeypatch, capsys):
    interrupt_scenario(monkeypatch, 1)
    mc = tmp_path / "mc"
    assert main(["montecarlo", str(FIG2), "--scenarios", "3", "--workers", "1",
                 "-o", str(mc)]) == ExitCode.INTERRUPTED
    monkeypatch.undo()
    capsys.readouterr()
    assert main(["report", str(FIG2), "--montecarlo", str(mc), "-o",
                 str(tmp_path / "report")]) == ExitCode.USAGE
    assert "a partial Monte Carlo, interrupted after 1 of 3 scenarios" in \
        capsys.readouterr().err


def test_a_deferred_stop_waits_for_the_writing_and_a_second_one_does_not():
    with interrupts.handling():
        with interrupts.deferred() as writing:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)  # not raised: the block goes on
            assert writing.requested and interrupts.stopped()
            with pytest.raises(KeyboardInterrupt):
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(1.0)
        with pytest.raises(KeyboardInterrupt):
            interrupts.raise_if_stopped()  # remembered for the command
    assert not interrupts.stopped()  # and forgotten after it
    with interrupts.handling(), pytest.raises(KeyboardInterrupt):
        with interrupts.deferred(reraise=True):  # written whole, then stopped
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
    with interrupts.handling(), pytest.raises(interrupts.Terminated):
        with interrupts.deferred(armed=False) as later:
            os.kill(os.getpid(), signal.SIGTERM)  # not armed yet: raises
            time.sleep(1.0)
    assert not later.requested


def test_runs_in_threads_leave_their_deferred_blocks_in_any_order():
    """Two flights in threads (the runtime's line-noise test flies four side by side):
    the first to finish must not take the other's deferral, equal as it looks, out of the
    list; the other then arms its own and leaves as usual."""
    first, second = interrupts.deferred(armed=False), interrupts.deferred(armed=False)
    first_deferral = first.__enter__()
    second.__enter__()
    second.__exit__(None, None, None)
    first_deferral.arm()
    first.__exit__(None, None, None)  # raised ValueError when deferrals compared equal


def test_a_fleet_monte_carlo_stopped_keeps_whole_scenarios_and_gives_no_probability(
        fleet_plan, tmp_path, monkeypatch, capsys):
    """One worker flies alpha, bravo, charlie of scenario 0, then of 1...: stopped in
    bravo's flight of scenario 1, only scenario 0 was flown by the whole fleet."""
    interrupt_scenario(monkeypatch, 4)
    out = tmp_path / "mc"
    assert main(["fleet", "montecarlo", str(FLEET), "--plan", str(fleet_plan), "--scenarios",
                 "3", "--workers", "1", "-o", str(out)]) == ExitCode.INTERRUPTED
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] is False and summary["interrupted"] is True
    assert (summary["scenarios"], summary["requested"]) == (1, 3)
    assert summary["finish_probability"] is None and summary["finish_interval"] is None
    assert json.loads((out / RUN_MARKER).read_text())["complete"] is False
    table = pd.read_parquet(out / "scenarios.parquet")
    assert sorted(table["glider"]) == ["alpha", "bravo", "charlie"]
    assert set(table["scenario"]) == {0}
    said = capsys.readouterr()
    assert "interrupted after 1 of 3 scenarios: no finish probability" in said.out
    assert "1 of 3 scenarios finished" in said.err
    assert "Interrupted after 1 of 3 scenarios" in (out / "fleet.html").read_text()


def test_a_fleet_sim_stopped_writes_the_gliders_flown_and_no_verdict(fleet_plan, tmp_path,
                                                                     monkeypatch, capsys):
    """Stopped in bravo's flight, one worker: alpha's run is written, bravo's part flown
    is not (a flight cut short is no flight), and the survey gets no verdict."""
    interrupt_scenario(monkeypatch, 1)
    out = tmp_path / "sim"
    assert main(["fleet", "sim", str(FLEET), "--plan", str(fleet_plan), "--workers", "1",
                 "-o", str(out)]) == ExitCode.INTERRUPTED
    summary = json.loads((out / "fleet_sim.json").read_text())
    assert summary["complete"] is False and summary["interrupted"] is True
    assert (summary["flown"], summary["requested"]) == (1, 3)
    assert summary["finished"] is None and summary["mapping_error"] is None
    assert [g["name"] for g in summary["gliders"]] == ["alpha"]
    assert sorted(p.name for p in out.iterdir()) == [RUN_MARKER, "alpha", "fleet_sim.json"]
    assert json.loads((out / "alpha" / "summary.json").read_text())["complete"] is True
    assert json.loads((out / RUN_MARKER).read_text())["complete"] is False
    said = capsys.readouterr()
    assert "no verdict on the survey" in said.out and "1 of 3 gliders flown" in said.err


def test_an_interrupted_monte_carlo_with_replanning_gives_no_hold_rate(tmp_path, monkeypatch,
                                                                        capsys):
    """With --replan each scenario is flown twice (the plan alone, then replanned): stopped
    in scenario 2's, two scenarios are kept and neither hold rate is given."""
    plan = tmp_path / "p.plan"
    assert main(["plan", str(FIG2), "-o", str(plan)]) == 0
    capsys.readouterr()
    interrupt_scenario(monkeypatch, 4)
    out = tmp_path / "mc"
    assert main(["montecarlo", str(FIG2), "--plan", str(plan), "--replan", "--scenarios", "5",
                 "--workers", "1", "--json", "-o", str(out)]) == ExitCode.INTERRUPTED
    printed = json.loads(capsys.readouterr().out)
    for summary in (json.loads((out / "summary.json").read_text()), printed):
        assert summary["complete"] is False
        assert (summary["scenarios"], summary["requested"]) == (2, 5)
        for key in ("probability_budget_holds", "probability_interval_95", "hold_rate",
                    "hold_rate_interval_95", "hold_rate_static",
                    "hold_rate_static_interval_95"):
            assert summary[key] is None, key

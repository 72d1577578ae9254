"""Faults in the closed loop (`gliderplan sim --runtime c --faults SPEC`): a damaged,
duplicated, reordered, truncated or late frame is recovered by retransmission and the
flight is the fault-free one; a cut line hands the glider to layered control and back;
the runtime killed (SIGKILL) at random moments resumes from its checkpoint and flies
the same flight; its event log loses and repeats nothing; a killed `gliderplan sim`
leaves each of its files whole (the old one or the new one) or absent."""

from __future__ import annotations

import functools
import json
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from waiting import wait_until

from gliderplan.cli.main import main
from gliderplan.contract.errors import UsageError
from gliderplan.sim.faults import FaultSpec, parse_faults

ROOT = Path(__file__).resolve().parents[1]
FIG2 = ROOT / "examples" / "fig2.mission"
LINE_FAULTS = "drop=0.002,flip=1e-4,dup=0.01,reorder=0.01,truncate=0.005,burst=5@0.005"


def fly(tmp_path: Path, name: str, *options: str) -> Path:
    run = tmp_path / name
    assert main(["sim", str(FIG2), "--runtime", "c", "--seed", "1", "-o", str(run),
                 *options]) == 0
    return run


@pytest.fixture(scope="module")
def fault_free(tmp_path_factory) -> Path:
    return fly(tmp_path_factory.mktemp("faults"), "fault-free")


def trace_rows(run: Path) -> list[str]:
    return (run / "trace.csv").read_text().splitlines()[1:]


def log_as_trace(run: Path) -> list[str]:
    """The runtime's events.log in trace.csv's form (`-` is an empty state there)."""
    rows = []
    for line in (run / "events.log").read_text().splitlines():
        time_s, kind, from_state, to_state, depth = line.split()
        rows.append(",".join((time_s, kind, from_state.strip("-"), to_state.strip("-"), depth)))
    return rows


def faults(run: Path) -> dict:
    return json.loads((run / "summary.json").read_text())["faults"]


@pytest.mark.parametrize(("text", "expected"), [
    ("drop=0.01,flip=1e-4", FaultSpec("drop=0.01,flip=1e-4", drop=0.01, flip=1e-4)),
    ("burst=5@0.001,delay=0.3s@0.01", FaultSpec("burst=5@0.001,delay=0.3s@0.01", burst=0.001,
                                                burst_bytes=5, delay=0.01, delay_s=0.3)),
    ("disconnect=10min@1h,disconnect=60s@0s",
     FaultSpec("disconnect=10min@1h,disconnect=60s@0s",
               disconnects=((0.0, 60.0), (3600.0, 600.0)))),
    ("kill=100@2500s", FaultSpec("kill=100@2500s", kills=100, kills_within_s=2500.0)),
])
def test_a_fault_spec_reads_as_written(text, expected):
    assert parse_faults(text) == expected


@pytest.mark.parametrize(("text", "said"), [
    ("drop=2", "--faults 'drop=2': '2' is not a probability in [0, 1]"),
    ("flip=nan", "--faults 'flip=nan': 'nan' is not a probability"),
    ("burst=5", "--faults 'burst=5': expected N@P"),
    ("burst=0@0.1", "--faults 'burst=0@0.1': N must be a whole number of bytes, 1..64"),
    ("delay=0.3@0.1", "--faults 'delay=0.3@0.1': '0.3' is not a time with a unit"),
    ("disconnect=0s@10s", "--faults 'disconnect=0s@10s': '0s' must be a positive time"),
    ("kill=-1", "--faults 'kill=-1': kill=N[@T] takes a whole number N"),
    ("lightning=1", "--faults 'lightning=1': unknown fault"),
])
def test_a_bad_fault_spec_is_one_clear_error(text, said):
    with pytest.raises(UsageError, match=None) as error:
        parse_faults(text)
    assert said in str(error.value)


def test_sim_refuses_faults_without_the_c_runtime_and_a_bad_spec(tmp_path, capsys):
    assert main(["sim", str(FIG2), "--faults", "drop=0.1", "-o", str(tmp_path / "a")]) == 2
    assert main(["sim", str(FIG2), "--runtime", "c", "--faults", "drop=x",
                 "-o", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "add --runtime c" in err[0] and "drop=x" in err[1]
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_recoverable_line_faults_leave_the_flight_and_the_log_as_without_them(
        tmp_path, fault_free):
    run = fly(tmp_path, "faulted", "--faults", LINE_FAULTS)
    # the same flight, tick for tick: every COMMAND arrived as it would have
    assert (run / "timeseries.parquet").read_bytes() == (
        fault_free / "timeseries.parquet").read_bytes()
    assert trace_rows(run) == trace_rows(fault_free)
    assert log_as_trace(run) == trace_rows(run)  # nothing lost, nothing twice
    report = faults(run)
    assert set(report["injected"]) == {"drop", "flip", "dup", "reorder", "truncate", "burst"}
    assert all(n > 0 for n in report["injected"].values())
    detected = report["detected"]
    assert detected["damaged_at_science_computer"] > 0 and detected["damaged_at_runtime"] > 0
    assert report["recovered"] > 0
    assert report["lost_exchanges"] == report["releases"] == 0
    assert report["layered_control_s"] == 0


def test_a_cut_line_hands_the_glider_to_layered_control_and_back(tmp_path, fault_free):
    """Cut from 452 s to 552 s (ticks every 4 s): the runtime's watchdog releases control,
    layered control flies 100 s, and the runtime takes the glider back when the line
    returns; the call due at 500 s is made on the first tick it hears, at 552 s."""
    run = fly(tmp_path, "cut", "--faults", "disconnect=100s@452s")
    expected = trace_rows(fault_free)
    assert expected[1] == "500,call,s1,s2,1"
    expected[1] = "552,call,s1,s2,1"
    assert trace_rows(run) == expected
    assert log_as_trace(run) == expected
    report = faults(run)
    assert (report["disconnects"], report["releases"]) == (1, 1)
    assert report["layered_control_s"] == 100.0


def test_a_runtime_killed_at_random_moments_flies_the_same_flight(tmp_path, fault_free):
    """Forty SIGKILLs over the mission, some while the runtime works on a tick's SENSORS:
    each restart resumes from the checkpoint, and the flight, the trace and the event
    log are the fault-free run's."""
    run = fly(tmp_path, "killed", "--faults", "kill=40@2500s")
    assert faults(run)["kills"] == 40
    assert (run / "timeseries.parquet").read_bytes() == (
        fault_free / "timeseries.parquet").read_bytes()
    assert trace_rows(run) == trace_rows(fault_free)
    assert log_as_trace(run) == trace_rows(run)


def snapshot(directory: Path) -> set[tuple[str, int, int]]:
    """Name, mtime and size of each file; a temporary file renamed away between the
    listing and its stat (the writer at work) is simply not in it."""
    files = set()
    for path in directory.iterdir() if directory.exists() else ():
        try:
            status = path.stat()
        except FileNotFoundError:
            continue
        files.add((path.name, status.st_mtime_ns, status.st_size))
    return files


def writing(parent: Path, name: str) -> bool:
    """Whether a run into parent/name writes its files (into its hidden folder there)."""
    for staging in parent.glob(f".{name}.new-*"):
        try:
            if any(staging.iterdir()):
                return True
        except FileNotFoundError:  # moved into place or removed as we looked
            return True
    return False


def _ended_or_wrote(process: subprocess.Popen, out: Path, before: set) -> bool:
    """Whether `process` has ended, changed the files in `out` from `before`, or started
    writing them (into its hidden folder beside `out`)."""
    return process.poll() is not None or snapshot(out) != before \
        or writing(out.parent, out.name)


def test_a_killed_sim_leaves_each_file_whole_or_absent(tmp_path):
    """`gliderplan sim` killed (SIGKILL) while it writes its files (a few milliseconds
    after the first one is touched): the folder holds the previous run or the new one
    whole, file for file (or, the first time, nothing), never a part of a file nor files
    of two runs; what a killed run left beside it is cleared by the next."""
    command = [sys.executable, "-m", "gliderplan.cli", "sim", str(FIG2), "-o"]
    old, new, out = tmp_path / "old", tmp_path / "new", tmp_path / "out"
    subprocess.run([*command, str(old)], check=True, capture_output=True)
    subprocess.run([*command, str(new), "--seed", "1"], check=True, capture_output=True)
    names = sorted(p.name for p in old.iterdir())
    runs = {run: {name: (run / name).read_bytes() for name in names} for run in (old, new)}
    rng = random.Random(7)
    killed_while_writing = 0
    for attempt in range(12):
        seed = ["--seed", "1"] if attempt % 2 else []
        before = snapshot(out)
        process = subprocess.Popen([*command, str(out), *seed], stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL)
        wait_until(functools.partial(_ended_or_wrote, process, out, before), 120,
                   "sim starts writing its files")
        time.sleep(rng.uniform(0.0, 0.03))  # then a random moment of its writing
        process.send_signal(signal.SIGKILL)
        killed_while_writing += process.wait() == -signal.SIGKILL
        if out.exists():
            whole = [run for run, files in runs.items()
                     if all((out / name).read_bytes() == data for name, data in files.items())]
            assert whole and sorted(p.name for p in out.iterdir()) == names, attempt
    subprocess.run([*command, str(out)], check=True, capture_output=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new", "old", "out"]
    assert killed_while_writing >= 6


HEAVY_NOISE = ("drop=0.05,flip=5e-4,dup=0.05,reorder=0.05,truncate=0.05,burst=20@0.01,"
               "delay=0.3s@0.05")
SHORT = ROOT / "tests" / "missions" / "fig2_short.mission"


def test_heavy_line_noise_flies_the_fault_free_flight_or_fails_the_link_cleanly(tmp_path):
    """Twenty seeds of heavy noise (most frames damaged) on Fig. 2 in 20 s: each run flies
    its seed's fault-free flight tick for tick, or ends on a link failure with what it
    flew written; never dies on the closed line; trace.csv is the runtime's event log.
    Runs fly side by side: they wait on the line, not on the processor."""
    from concurrent.futures import ThreadPoolExecutor

    from gliderplan.language import check_file
    from gliderplan.sim import FlightOptions, flight_setup, run_mission

    mission = check_file(str(SHORT)).mission

    def fly_seed(seed: int, faults: str | None) -> str:
        run = tmp_path / f"{seed}-{'faulted' if faults else 'fault-free'}"
        setup = flight_setup(mission, FlightOptions(runtime="c", seed=seed, faults=faults))
        return run_mission(setup, run, plots=False).record.ended

    fly_seed(0, None)  # builds the runtime once, before the runs share the build cache
    seeds = range(1, 21)
    with ThreadPoolExecutor(4) as pool:
        free = list(pool.map(fly_seed, seeds, [None] * len(seeds)))
        faulted = list(pool.map(fly_seed, seeds, [HEAVY_NOISE] * len(seeds)))
    assert free == ["exit"] * len(seeds)
    for seed, ended in zip(seeds, faulted, strict=True):
        run, clean = tmp_path / f"{seed}-faulted", tmp_path / f"{seed}-fault-free"
        assert log_as_trace(run) == trace_rows(run), seed  # nothing lost, nothing twice
        if ended == "exit":
            assert (run / "timeseries.parquet").read_bytes() == (
                clean / "timeseries.parquet").read_bytes(), seed
            assert trace_rows(run) == trace_rows(clean), seed
        else:
            assert "link failure" in ended, (seed, ended)
            assert trace_rows(run) == trace_rows(clean)[:len(trace_rows(run))], seed
        assert faults(run)["injected"]["drop"] > 0


@pytest.mark.parametrize(("asked", "delivered"), [(3, 3), (10, 5)])
def test_kills_fall_within_the_run_or_the_sim_says_how_many_it_could(tmp_path, capsys, asked,
                                                                     delivered):
    """The 20 s mission's five ticks after its first hold at most five kills; drawn over
    its timeline, not the hour of its horizon, every one that fits is delivered."""
    run = tmp_path / "killed"
    assert main(["sim", str(SHORT), "--runtime", "c", "--seed", "1", "--faults",
                 f"kill={asked}", "-o", str(run)]) == 0
    assert (faults(run)["kills"], faults(run)["kills_asked"]) == (delivered, asked)
    said = capsys.readouterr().err
    assert (f"kill={asked}: {delivered} delivered" in said) == (delivered < asked)
    assert log_as_trace(run) == trace_rows(run)


def test_writing_to_a_line_whose_runtime_has_gone_is_a_link_error_not_a_crash():
    import os

    from gliderplan.runtime.protocol import FdPort, LinkClosedError

    runtime_end, our_end = os.openpty()
    os.close(runtime_end)  # the runtime ended: its side of the pty is gone
    try:
        with pytest.raises(LinkClosedError, match="the line is closed"):
            FdPort(our_end).write(b"\x02\x02\x00")
    finally:
        os.close(our_end)

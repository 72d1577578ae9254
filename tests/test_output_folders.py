"""An output folder holds one run (issue 29, point 2).

Every command that writes a folder (sim, montecarlo, plan --sweep, export -o, report,
compare-sbc, compile, fleet plan, fleet sim, fleet montecarlo) writes it through
`contract.files.output_folder`: into a hidden folder beside the target, moved into place
whole; a folder that holds anything but a gliderplan run is refused without --force; a
second run into a folder being written is refused (a lock); a failed or full-disk run
leaves the previous run as it was. Files that go together (a plan and its report, a plan
update with the plan it makes) are written together or not at all.
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import random
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.contract.files import RUN_MARKER

REPO = Path(__file__).resolve().parents[1]
FIG2 = REPO / "examples" / "fig2.mission"
SURVEY = REPO / "examples" / "thermocline_survey.mission"
FLEET = REPO / "tests" / "fleets" / "small.fleet"
CALM = str(REPO / "tests" / "fleets" / "calm.toml")
BUSY = "another gliderplan run is writing this folder"


def contents(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def hidden_beside(folder: Path) -> list[str]:
    """What a run leaves beside its folder: nothing (no hidden folder, no lock)."""
    return sorted(p.name for p in folder.parent.glob(f".{folder.name}.*"))


def sim(out: Path, mission: Path = FIG2, *options: str) -> int:
    return main(["sim", str(mission), *options, "-o", str(out)])


@pytest.fixture(scope="module")
def fleet_plan(tmp_path_factory) -> Path:
    """A plan of the small fleet (`fleet plan -o`), for the fleet's runs to fly."""
    out = tmp_path_factory.mktemp("fleet") / "plan"
    assert main(["fleet", "plan", str(FLEET), "--scenario-file", CALM, "-o", str(out)]) == 0
    return out


def test_a_second_run_replaces_the_first_whole(tmp_path):
    """The issue: `sim --netcdf -o r` then `sim -o r` of another mission left the first
    run's trajectory.nc in the second run."""
    out = tmp_path / "r"
    assert sim(out, FIG2, "--netcdf") == 0
    assert (out / "trajectory.nc").is_file()
    assert sim(out, SURVEY, "--duration", "6h") == 0
    assert sorted(contents(out)) == [RUN_MARKER, "depth.png", "energy.png", "summary.json",
                                     "timeseries.parquet", "trace.csv"]
    assert json.loads((out / "summary.json").read_text())["mission"] == "thermoclineSurvey"
    marker = json.loads((out / RUN_MARKER).read_text())
    assert marker == {"command": "sim", "complete": True,
                      "files": sorted(set(contents(out)) - {RUN_MARKER})}
    assert hidden_beside(out) == []


def test_a_folder_that_is_not_a_run_is_refused_without_force(tmp_path, capsys):
    out = tmp_path / "r"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    assert sim(out) == ExitCode.USAGE
    assert (f"-o {out}: not empty and not a gliderplan run's folder (it holds notes.txt): "
            "name a new or empty folder, or add --force") in capsys.readouterr().err
    assert contents(out) == {"notes.txt": b"mine\n"}
    assert sim(out, FIG2, "--force") == 0  # asked for: what it held is deleted
    assert "notes.txt" not in contents(out) and "summary.json" in contents(out)
    (out / "notes.txt").write_text("added to a run\n")  # a run's folder, and more
    assert sim(out) == ExitCode.USAGE
    assert (out / "notes.txt").exists()


def test_a_run_written_before_folders_had_a_marker_is_replaced(tmp_path):
    out = tmp_path / "r"
    assert sim(out) == 0
    (out / RUN_MARKER).unlink()  # as an earlier gliderplan wrote it
    (out / "trajectory.nc").write_bytes(b"CDF")
    assert sim(out, SURVEY, "--duration", "1h") == 0
    assert "trajectory.nc" not in contents(out)


@pytest.mark.parametrize("command", ["sim", "montecarlo", "plan --sweep", "export", "report",
                                     "compare-sbc", "compile", "fleet plan", "fleet sim",
                                     "fleet montecarlo"])
def test_every_command_that_writes_a_folder_refuses_another_s(command, tmp_path, capsys,
                                                              request):
    run = tmp_path / "run"
    if command == "export":
        assert sim(run) == 0
    plan = str(request.getfixturevalue("fleet_plan")) if command.startswith("fleet ") \
        and command != "fleet plan" else ""
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    argv = {"sim": ["sim", str(FIG2)],
            "montecarlo": ["montecarlo", str(FIG2), "--scenarios", "2", "--workers", "1"],
            "plan --sweep": ["plan", str(FIG2), "--sweep", "3"],
            "export": ["export", str(run), "--geojson"],
            "report": ["report", str(FIG2)],
            "compare-sbc": ["compare-sbc", str(FIG2)],
            "compile": ["compile", str(FIG2)],
            "fleet plan": ["fleet", "plan", str(FLEET)],
            "fleet sim": ["fleet", "sim", str(FLEET), "--plan", plan, "--workers", "1"],
            "fleet montecarlo": ["fleet", "montecarlo", str(FLEET), "--plan", plan,
                                 "--scenarios", "2", "--workers", "1"]}[command]
    capsys.readouterr()
    assert main([*argv, "-o", str(out)]) == ExitCode.USAGE
    assert "not a gliderplan run's folder (it holds notes.txt)" in capsys.readouterr().err
    assert contents(out) == {"notes.txt": b"mine\n"} and hidden_beside(out) == []


def test_a_folder_being_written_is_refused_to_a_second_run(tmp_path, capsys):
    out = tmp_path / "r"
    lock = tmp_path / ".r.lock"
    with open(lock, "w") as held:  # as the run writing it holds it
        fcntl.flock(held, fcntl.LOCK_EX)
        held.write("4242\n")
        held.flush()
        assert sim(out) == ExitCode.USAGE
        assert f"-o {out}: {BUSY} (process 4242): wait for it to end" in \
            capsys.readouterr().err
    assert not out.exists()
    assert sim(out) == 0 and hidden_beside(out) == []  # free again: the lock is taken


def test_two_runs_at_once_never_mix_their_files(tmp_path):
    """The issue: two concurrent `sim -o r` left one run's summary and parquet beside the
    other's trace (2 of 24) and the other's trajectory.nc (16 of 24), both exit 0. Now one
    of two runs started together is refused (or they follow each other), and the folder
    holds one of them, every file its own."""
    reference = {}
    runs = {"fig2": [str(FIG2), "--netcdf"], "survey": [str(SURVEY), "--duration", "3h"]}
    for name, argv in runs.items():
        assert main(["sim", *argv, "-o", str(tmp_path / name)]) == 0
        reference[name] = contents(tmp_path / name)
    out = tmp_path / "r"
    rng = random.Random(29)
    outcomes = []
    for attempt in range(6):
        processes = {}
        for name in rng.sample(sorted(runs), 2):
            processes[name] = subprocess.Popen(
                [sys.executable, "-m", "gliderplan.cli", "sim", *runs[name], "-o", str(out)],
                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            time.sleep(rng.uniform(0.0, 0.3))
        for process in processes.values():
            err = process.communicate(timeout=300)[1]
            assert process.returncode in (0, ExitCode.USAGE), err
            if process.returncode:
                assert BUSY in err, err
            outcomes.append(process.returncode)
        held = contents(out)
        mine = [name for name, files in reference.items() if set(files) == set(held)]
        assert len(mine) == 1, (attempt, sorted(held))
        for file, data in held.items():
            if not file.endswith(".nc"):  # a NetCDF file carries the time it was written
                assert data == reference[mine[0]][file], (attempt, file)
        assert hidden_beside(out) == []
    assert 0 in outcomes


@pytest.mark.parametrize("full_at", [0, 2, 4])
def test_a_full_disk_leaves_the_previous_run_intact(full_at, tmp_path, monkeypatch, capsys):
    """The issue: a full disk left a new trace beside an old summary (4 of 8 fill levels).
    The disk fills at the `full_at`-th file written."""
    out = tmp_path / "r"
    assert sim(out, SURVEY, "--duration", "1h") == 0
    before = contents(out)
    real, opened = os.fdopen, []

    class FullDisk:
        def __init__(self, handle):
            self.handle = handle

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.handle.close()

        def write(self, data):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

        def flush(self):
            pass

        def fileno(self):
            return self.handle.fileno()

    def fdopen(fd, *args, **kwargs):
        opened.append(fd)
        handle = real(fd, *args, **kwargs)
        return FullDisk(handle) if len(opened) > full_at else handle

    monkeypatch.setattr("gliderplan.contract.files.os.fdopen", fdopen)
    capsys.readouterr()
    assert sim(out, FIG2, "--netcdf") == ExitCode.USAGE
    assert "cannot write: No space left on device" in capsys.readouterr().err
    monkeypatch.undo()
    assert contents(out) == before and hidden_beside(out) == []


def test_a_run_that_cannot_be_moved_into_place_leaves_the_previous_one(tmp_path, monkeypatch,
                                                                        capsys):
    from gliderplan.contract import files

    out = tmp_path / "r"
    assert sim(out) == 0
    before = contents(out)

    def refused(*args):
        raise OSError(errno.EIO, os.strerror(errno.EIO))
    monkeypatch.setattr(files, "_move_into_place", refused)
    assert sim(out, SURVEY, "--duration", "1h") == ExitCode.USAGE
    assert "cannot write: Input/output error" in capsys.readouterr().err
    assert contents(out) == before and hidden_beside(out) == []


def test_two_renames_move_a_run_into_place_where_one_exchange_cannot(tmp_path, monkeypatch):
    from gliderplan.contract import files

    out = tmp_path / "r"
    assert sim(out, FIG2, "--netcdf") == 0
    monkeypatch.setattr(files, "_exchange", lambda first, second: False)
    assert sim(out, SURVEY, "--duration", "1h") == 0
    assert "trajectory.nc" not in contents(out) and hidden_beside(out) == []
    assert json.loads((out / "summary.json").read_text())["mission"] == "thermoclineSurvey"


def test_a_mount_point_stays_and_holds_one_run(tmp_path, monkeypatch, capsys):
    """A folder that is a mount point (a container's volume) cannot be replaced: the run
    is staged inside it and swapped in entry by entry, and a failure puts it back."""
    import posixpath

    from gliderplan.contract import files

    out = tmp_path / "volume"
    out.mkdir()
    real_ismount = posixpath.ismount
    monkeypatch.setattr(posixpath, "ismount", lambda path: Path(path) == out or
                        real_ismount(path))
    assert sim(out, FIG2, "--netcdf") == 0
    inode = out.stat().st_ino
    assert sim(out, SURVEY, "--duration", "1h") == 0
    assert out.stat().st_ino == inode and "trajectory.nc" not in contents(out)
    assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == [RUN_MARKER]
    before = contents(out)
    real_rename, renamed = os.rename, []

    def full_half_way(source, destination):
        renamed.append(source)
        if len(renamed) == 9:  # the previous run moved aside, the new one half in
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_rename(source, destination)
    monkeypatch.setattr(files.os, "rename", full_half_way)
    assert sim(out, FIG2) == ExitCode.USAGE
    monkeypatch.setattr(files.os, "rename", real_rename)
    assert contents(out) == before and len(renamed) >= 9
    assert "cannot write: No space left on device" in capsys.readouterr().err
    assert main(["export", str(out), "--kml"]) == 0  # into its own run: added to it
    assert {"track.kml", "summary.json"} <= set(contents(out))
    assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == [RUN_MARKER]
    (out / "notes.txt").write_text("mine\n")
    assert sim(out) == ExitCode.USAGE  # a mount point holding other files: refused too


def test_a_killed_run_s_leftovers_are_cleared_by_the_next(tmp_path):
    out = tmp_path / "r"
    (tmp_path / ".r.new-abcd1234").mkdir()  # as a run killed while it wrote left them
    (tmp_path / ".r.new-abcd1234" / "trace.csv").write_text("half")
    (tmp_path / ".r.lock").write_text("1\n")
    (tmp_path / ".r.new-abcd1234x").mkdir()  # another name's: left alone
    assert sim(out) == 0
    assert hidden_beside(out) == [".r.new-abcd1234x"]


def test_a_plan_and_its_report_are_written_together(tmp_path, monkeypatch, capsys):
    plan = tmp_path / "p.plan"
    assert main(["plan", str(FIG2), "-o", str(plan)]) == 0
    before = plan.read_bytes(), Path(f"{plan}.json").read_bytes()
    from gliderplan.contract import files

    real = files.write_atomically

    def full_at_the_report(path, data, **kwargs):
        if str(path).endswith(".json"):
            raise files.OutputFileError(f"{path}: cannot write: No space left on device")
        return real(path, data, **kwargs)
    monkeypatch.setattr(files, "write_atomically", full_at_the_report)
    assert main(["plan", str(FIG2), "--battery", "500Wh", "-o", str(plan)]) == ExitCode.USAGE
    assert (plan.read_bytes(), Path(f"{plan}.json").read_bytes()) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.plan", "p.plan.json"]


def test_export_adds_to_its_run_and_a_new_run_clears_it(tmp_path):
    run = tmp_path / "run"
    assert sim(run) == 0
    assert main(["export", str(run), "--geojson"]) == 0
    marker = json.loads((run / RUN_MARKER).read_text())
    assert "track.geojson" in marker["files"] and "summary.json" in marker["files"]
    assert main(["export", str(run), "--kml", "-o", str(tmp_path / "kml")]) == 0
    assert sorted(contents(tmp_path / "kml")) == [RUN_MARKER, "track.kml"]
    assert sim(run) == 0  # one run: the export of the previous one goes with it
    assert "track.geojson" not in contents(run)


def test_what_a_run_reads_or_the_working_folder_is_never_its_folder(tmp_path, capsys,
                                                                     monkeypatch):
    out = tmp_path / "r"
    assert main(["plan", str(FIG2), "-o", str(tmp_path / "p.plan")]) == 0
    assert sim(out) == 0
    shutil.copy(tmp_path / "p.plan", out / "p.plan")
    capsys.readouterr()
    assert main(["sim", str(FIG2), "--plan", str(out / "p.plan"), "--force",
                 "-o", str(out)]) == ExitCode.USAGE
    assert f"{out / 'p.plan'}: lies inside -o {out}, which this run replaces whole" in \
        capsys.readouterr().err
    assert (out / "p.plan").is_file()
    monkeypatch.chdir(out)
    assert main(["sim", str(FIG2), "--force", "-o", "."]) == ExitCode.USAGE
    assert "is the working folder, one above it, the home folder or the root" in \
        capsys.readouterr().err
    assert main(["sim", str(FIG2), "--force", "-o", str(tmp_path)]) == ExitCode.USAGE


def test_a_link_to_a_folder_stays_a_link(tmp_path):
    target = tmp_path / "runs" / "today"
    assert sim(target) == 0
    link = tmp_path / "latest"
    link.symlink_to(target)
    assert sim(link, SURVEY, "--duration", "1h") == 0
    assert link.is_symlink() and json.loads((target / "summary.json").read_text())[
        "mission"] == "thermoclineSurvey"


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) for the runtime")
def test_a_build_without_a_plan_leaves_no_earlier_plan_beside_its_binary(tmp_path):
    plan = tmp_path / "fig2.plan"
    annotated = REPO / "examples" / "fig2_annotated.mission"
    assert main(["plan", str(annotated), "-o", str(plan)]) == 0
    build = tmp_path / "build"
    assert main(["compile", str(annotated), "--plan", str(plan), "-o", str(build)]) == 0
    assert (build / "fig2.plan").is_file()
    source = build / "sampleMission.c"
    stamp = source.stat().st_mtime_ns
    assert main(["compile", str(annotated), "-o", str(build)]) == 0
    assert sorted(contents(build)) == [RUN_MARKER, "sampleMission", "sampleMission.c"]
    assert source.stat().st_mtime_ns == stamp  # the same C: make sees nothing to do


def test_a_fleet_plan_is_a_folder_of_one_plan(fleet_plan, tmp_path, capsys):
    marker = json.loads((fleet_plan / RUN_MARKER).read_text())
    assert marker["command"] == "fleet plan" and marker["complete"] is True
    assert sorted(marker["files"]) == sorted(set(contents(fleet_plan)) - {RUN_MARKER})
    assert {"fleet.json", "alpha.plan", "bravo.mission", "charlie.plan.json",
            "fleet.html"} <= set(marker["files"])
    assert hidden_beside(fleet_plan) == []
    # a fleet run never replaces the plan it flies
    inside = fleet_plan.parent
    capsys.readouterr()
    assert main(["fleet", "montecarlo", str(FLEET), "--plan", str(fleet_plan), "--scenarios",
                 "1", "--workers", "1", "--force", "-o", str(inside)]) == ExitCode.USAGE
    assert f"{fleet_plan}: lies inside -o {inside}, which this run replaces whole" in \
        capsys.readouterr().err
    assert (fleet_plan / "fleet.json").is_file()


def test_a_fleet_monte_carlo_replaces_the_previous_one_whole(fleet_plan, tmp_path, capsys):
    out = tmp_path / "mc"
    for scenarios in ("2", "1"):
        assert main(["fleet", "montecarlo", str(FLEET), "--plan", str(fleet_plan),
                     "--scenarios", scenarios, "--workers", "1", "-o", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["scenarios"], summary["requested"], summary["complete"]) == (1, 1, True)
    import pandas as pd

    assert set(pd.read_parquet(out / "scenarios.parquet")["scenario"]) == {0}
    marker = json.loads((out / RUN_MARKER).read_text())
    assert marker["command"] == "fleet montecarlo" and marker["complete"] is True
    assert sorted(marker["files"]) == sorted(set(contents(out)) - {RUN_MARKER}) == [
        "fleet.geojson", "fleet.html", "fleet.kml", "fleet.png", "mapping_error.png",
        "scenarios.parquet", "summary.json"]
    assert hidden_beside(out) == []
    lock = tmp_path / ".mc.lock"  # a run writing it holds its lock: a second is refused
    with open(lock, "w") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        capsys.readouterr()
        assert main(["fleet", "montecarlo", str(FLEET), "--plan", str(fleet_plan),
                     "--scenarios", "1", "--workers", "1", "-o", str(out)]) == ExitCode.USAGE
        assert BUSY in capsys.readouterr().err
    assert json.loads((out / "summary.json").read_text()) == summary



@pytest.fixture
def planning(monkeypatch) -> list[str]:
    """The fleets planned while a command runs (each call of the fleet planner)."""
    import gliderplan.planner.fleet as fleet_planner

    calls: list[str] = []
    real = fleet_planner.plan_fleet

    def recorded(fleet, **kwargs):
        calls.append(fleet.name)
        return real(fleet, **kwargs)

    monkeypatch.setattr(fleet_planner, "plan_fleet", recorded)
    return calls


@pytest.mark.parametrize("command", [["sim"], ["montecarlo", "--scenarios", "1"]])
@pytest.mark.parametrize("folder", ["another's files", "a file", "being written"])
def test_a_fleet_run_refuses_its_folder_before_it_plans(command, folder, planning, tmp_path,
                                                        capsys):
    """Issues 24 and 29: without --plan, `fleet sim` and `fleet montecarlo` planned the
    fleet first, and only then found that -o could not take the run."""
    out = tmp_path / "out"
    expected = {"another's files": "not a gliderplan run's folder (it holds notes.txt)",
                "a file": f"-o {out}: not a directory", "being written": BUSY}[folder]
    if folder == "a file":
        out.write_text("mine\n")
    else:
        out.mkdir()
        (out / "notes.txt").write_text("mine\n")
    with open(tmp_path / ".out.lock", "w") as lock:
        if folder == "being written":
            fcntl.flock(lock, fcntl.LOCK_EX)
        capsys.readouterr()
        code = main(["fleet", *command, str(FLEET), "--scenario-file", CALM, "--workers", "1",
                     "-o", str(out)])
    assert code == ExitCode.USAGE
    err = capsys.readouterr().err
    assert expected in err and "Traceback" not in err
    assert planning == []


def test_a_fleet_run_plans_into_the_folder_it_claimed(planning, tmp_path):
    out = tmp_path / "mc"
    assert main(["fleet", "montecarlo", str(FLEET), "--scenario-file", CALM, "--scenarios",
                 "1", "--workers", "1", "-o", str(out)]) == 0
    assert planning == ["smallBox"]
    marker = json.loads((out / RUN_MARKER).read_text())
    assert marker["command"] == "fleet montecarlo" and "plan" in marker["files"]
    assert json.loads((out / "summary.json").read_text())["plan"] == str(out / "plan")
    assert {"fleet.json", "alpha.plan", "alpha.mission"} <= set(contents(out / "plan"))

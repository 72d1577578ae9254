"""Timing a command as the user runs it: a fresh process each time, medians of several runs.

Shared by the benchmarks that measure what a user waits for. Wall time is what the user
pays; CPU time (user + system, of the process and its children) is printed beside it
because the development machine's two cores are shared, and waiting for a core shows up
in wall time only.
"""

from __future__ import annotations

import os
import resource
import shutil
import statistics
import subprocess
import sys
import time
from collections.abc import Mapping
from pathlib import Path
from typing import NamedTuple

# Bytecode caching on, as on a user's machine (a warm-up run writes the .pyc files even
# if PYTHONDONTWRITEBYTECODE is set in this shell).
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


class Timing(NamedTuple):
    wall_s: float
    cpu_s: float


def gliderplan(*args: str) -> list[str]:
    """The `gliderplan` command of this interpreter's environment."""
    script = Path(sys.executable).with_name("gliderplan")
    command = [str(script)] if script.exists() else [sys.executable, "-m", "gliderplan.cli"]
    return command + list(args)


def run_once(command: list[str], exit_code: int = 0) -> Timing:
    """Wall and CPU time of one run; the command must exit with `exit_code` (its output
    is dropped)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                          env=ENV)
    wall = time.perf_counter() - start
    if done.returncode != exit_code:
        sys.exit(f"{' '.join(command)} exited {done.returncode}, not {exit_code}:\n"
                 f"{done.stderr.decode(errors='replace')}")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return Timing(wall, cpu)


def median_of(commands: dict[str, list[str]], runs: int, exit_code: int = 0,
              fresh: Mapping[str, Path] | None = None) -> dict[str, Timing]:
    """Median wall and CPU time of each command over `runs` runs, taken in turn (so that
    a change in the machine's load falls on all of them alike), after one warm-up run;
    each must exit with `exit_code`. `fresh[name]`: a directory removed before each run
    of that command (one that will not write over an earlier run's)."""
    def run(name: str) -> Timing:
        if fresh and name in fresh:
            shutil.rmtree(fresh[name], ignore_errors=True)
        return run_once(commands[name], exit_code)

    for name in commands:
        run(name)
    times: dict[str, list[Timing]] = {name: [] for name in commands}
    for _ in range(runs):
        for name in commands:
            times[name].append(run(name))
    return {name: Timing(statistics.median(t.wall_s for t in found),
                         statistics.median(t.cpu_s for t in found))
            for name, found in times.items()}


# The real Slocum missions the benches fly, from the shared Slocum logs beside the
# repository (read in place, imported with `gliderplan import-slocum`).
SLOCUM = Path(__file__).resolve().parents[2] / "shared" / "data" / "slocum-missions"
IMPORTED = {"nsb3": SLOCUM / "nsb3" / "nsb3.mi", "helgo": SLOCUM / "helgo" / "helgo.mi"}


def import_slocum(name: str, directory: Path) -> Path | None:
    """The shared Slocum mission `name` (of IMPORTED) imported into `directory` as
    NAME.mission (its missing .ma files allowed); None if the logs are not here."""
    source = IMPORTED[name]
    if not source.is_file():
        print(f"  {name}: {source.name} not found among the shared Slocum missions: skipped")
        return None
    out = directory / f"{name}.mission"
    subprocess.run(gliderplan("import-slocum", str(source), "--allow-missing-mafiles", "-o",
                              str(out)), check=True, env=ENV, capture_output=True)
    return out


def load_average() -> str:
    return "load average " + " ".join(f"{x:.1f}" for x in os.getloadavg())

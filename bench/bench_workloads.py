"""Cycles of computations a mission might add to each tick (power_models/data/computations.toml).

    .venv/bin/python bench/bench_workloads.py        # needs valgrind and an i486 compiler

Builds bench/workloads.c for the TS-5500's instruction set (the i486 target of
`gliderplan compile`, or i686-linux-gnu-gcc -march=i486 when musl for the i486 is
missing) and counts each computation's instructions with callgrind (`--toggle-collect`:
only the computation, not start-up). Cycles = instructions x 4 cycles per instruction,
the runtime bench's assumption for a 486 core doing x87 arithmetic; beside each, how
many times the runtime's own work per tick (`contract.RUNTIME_CYCLES_PER_TICK`) it is.
These are the figures the data file quotes; rerun after changing workloads.c.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from gliderplan.contract import RUNTIME_CYCLES_PER_TICK
from gliderplan.runtime.build import TARGETS

HERE = Path(__file__).resolve().parent
CPI = 4.0  # cycles per instruction assumed for the SC520's 486 core with x87 arithmetic
COMPUTATIONS = ("thermocline_fit", "spectrum_1024")


def compiler() -> list[str]:
    musl = TARGETS["ts5500"]
    if shutil.which(musl.compiler):
        return [musl.compiler, *musl.flags]
    if shutil.which("i686-linux-gnu-gcc"):
        return ["i686-linux-gnu-gcc", "-march=i486", "-mpc64", "-static"]
    sys.exit("bench_workloads: needs i486-linux-musl-gcc or i686-linux-gnu-gcc")


def instructions(binary: Path, name: str) -> int:
    out = binary.parent / f"callgrind.{name}"
    run = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                          f"--toggle-collect=run_{name}", str(binary), name],
                         capture_output=True, text=True, check=True)
    return int(re.search(r"Collected : (\d+)", run.stderr)[1])


def main() -> int:
    if not shutil.which("valgrind"):
        sys.exit("bench_workloads: needs valgrind")
    with tempfile.TemporaryDirectory() as work:
        binary = Path(work) / "workloads"
        command = compiler()
        subprocess.run([*command, "-O2", "-o", str(binary), str(HERE / "workloads.c"), "-lm"],
                       check=True)
        print(f"compiler: {' '.join(command)} -O2; {CPI:g} cycles per instruction (assumed)")
        print(f"{'computation':18s} {'instructions':>13s} {'cycles':>12s} "
              f"{'x runtime tick':>15s}")
        for name in COMPUTATIONS:
            count = instructions(binary, name)
            cycles = count * CPI
            print(f"{name:18s} {count:13,d} {cycles:12,.0f} "
                  f"{cycles / RUNTIME_CYCLES_PER_TICK:15.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The simulator's C loops (sim/native.c) under AddressSanitizer and UndefinedBehaviorSanitizer,
loaded into Python as the simulator loads them, over the edges of their arguments: no
tick, one tick, a leg clamped at the surface on its first tick, a waypoint reached on the
first tick, a fix on the last. Their numbers are checked against the reference in
test_sim_fast.py; here, that they stay inside the arrays they are given."""

from __future__ import annotations

import ast
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
NATIVE = REPO / "sim" / "native.c"


def build_flags() -> list[str]:
    """The flags setup.py builds native.c with (those that keep Python's bits among them)."""
    for node in ast.walk(ast.parse((REPO / "setup.py").read_text())):
        if isinstance(node, ast.keyword) and node.arg == "extra_compile_args":
            return ast.literal_eval(node.value)
    raise AssertionError("setup.py gives native.c no extra_compile_args")


FLAGS = [*build_flags(), "-O1", "-g", "-fsanitize=address,undefined",
         "-fno-sanitize-recover=all", "-fno-omit-frame-pointer", "-shared", "-fPIC"]

EXERCISE = r"""
import sys
import numpy as np
from gliderplan.sim import native

native._C = native._load(sys.argv[1])
rng = np.random.default_rng(3)
for n in (0, 1, 7):
    x = rng.uniform(-10, 10, n)
    for f in (native.sin, native.cos, native.tanh):
        assert f(x).shape == (n,)
    assert native.atan2(x, x[::-1].copy()).shape == (n,)
    assert len(native.first_order_lag(x, float("nan"), 0.3)) == n
dive, climb = np.array([(-1.0, -200.0, 0.01, 4.0)]), np.array([(1.0, 200.0, -0.01, 4.0)])
settling = np.array([(-1.0, -100.0, 0.01, 0.0), (-1.0, -200.0, 0.01, 2.0), *dive])
glides = [(settling, 2), (climb, 0), (dive, 0)]
for count in (1, 2, 50, 400):
    noise = rng.normal(0.0, 0.1, count + 1)
    for depth, dive_first in ((0.0, False), (0.0, True), (12.0, True), (39.0, False)):
        for given in (glides[:1], glides):
            legs, depths, stop = native.squeezed_yo(given, 1e4, 2e-9, noise, (5.5, 39.5),
                                                    (5.0, 40.0), dive_first, count, depth)
            flown = int(legs[-1].sum()) if len(legs) else 0
            assert len(depths) == flown + 1 and flown <= count and (len(legs) or stop)
start = (39.17, -73.8, 39.171, -73.801)
for count in (0, 1, 300):
    distance = rng.uniform(0.0, 2.0, count)
    for target, advance in (((39.17, -73.8), True), ((39.2, -73.5), True), ((39.2, -73.5), False)):
        for fix in (-1, 0, count - 1):
            flown, heading, positions = native.route(target, 50.0, advance, distance, fix, 4.0,
                                                     (0.1, -0.2), start)
            assert 0 <= flown <= count and positions.shape == (4, count + 1)
print("ok")
"""


@pytest.mark.skipif(shutil.which("gcc") is None,
                    reason="gcc builds the C loops (apt-get install gcc)")
def test_the_c_loops_stay_inside_their_arrays_under_sanitizers(tmp_path):
    library = tmp_path / "native-sanitized.so"
    build = subprocess.run(["gcc", *FLAGS, str(NATIVE), "-o", str(library), "-lm"],
                           capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    asan = subprocess.run(["gcc", "-print-file-name=libasan.so"], capture_output=True,
                          text=True).stdout.strip()
    env = {**os.environ, "LD_PRELOAD": asan, "ASAN_OPTIONS": "detect_leaks=0"}
    run = subprocess.run([sys.executable, "-c", EXERCISE, str(library)], capture_output=True,
                         text=True, env=env, timeout=300)
    assert run.returncode == 0 and run.stdout.strip() == "ok", run.stderr[-3000:]
    assert "runtime error" not in run.stderr and "AddressSanitizer" not in run.stderr

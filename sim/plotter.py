"""A long run's plots drawn in a second process while this one writes the run's other
files: importing matplotlib and drawing two figures cost about as much as the month's
flight, and a machine has more than one core.

`PlotProcess` starts the process at once (it imports matplotlib while the run is flown),
sends it the two series to draw (sim/plots.py; small whatever the run's length) and
takes back the PNG files' bytes. The process runs in a session of its own, so that
Ctrl-C at a terminal reaches only the run's process, which handles it: an interrupted
run still gets its plots.
"""

from __future__ import annotations

import pickle
import subprocess
import sys

from gliderplan.sim.plots import DepthSeries, EnergySeries


class PlotProcessError(RuntimeError):
    """The plotting process failed (a bug in gliderplan); the message holds its error."""


class PlotProcess:
    """`python -m gliderplan.sim.plotter`, started on creation; `close` ends it however
    the run ends."""

    def __init__(self) -> None:
        self._process = subprocess.Popen(
            [sys.executable, "-m", "gliderplan.sim.plotter"], stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)

    def draw(self, depth: DepthSeries, energy: EnergySeries) -> None:
        """Send the series; the process draws them while the caller goes on."""
        try:
            pickle.dump((depth, energy), self._process.stdin, pickle.HIGHEST_PROTOCOL)
            self._process.stdin.close()
        except BrokenPipeError:
            pass  # it died: `pngs` says why

    def pngs(self) -> tuple[bytes, bytes]:
        """depth.png's and energy.png's bytes, once drawn."""
        out = self._process.stdout.read()  # its error output is a traceback at most
        err = self._process.stderr.read()
        if self._process.wait():
            raise PlotProcessError("the plotting process failed: "
                                   + err.decode(errors="replace").strip()[-2000:])
        return pickle.loads(out)

    def close(self) -> None:
        """End the process if it still runs (the run ended without its plots)."""
        if self._process.poll() is None:
            self._process.kill()
            self._process.wait()
        for pipe in (self._process.stdin, self._process.stdout, self._process.stderr):
            pipe.close()


def main() -> None:
    from gliderplan.sim import plots

    plots.pyplot()  # import matplotlib while the run is flown
    depth, energy = pickle.load(sys.stdin.buffer)
    pickle.dump((plots.depth_png(depth), plots.energy_png(energy)), sys.stdout.buffer,
                pickle.HIGHEST_PROTOCOL)


if __name__ == "__main__":
    main()

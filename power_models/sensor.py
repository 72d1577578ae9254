"""Science sensors (devices): on-power, warm-up, sample rate and a quality curve.

The quality of the data a sensor gathers grows with its duty cycle d in [0, 1] with
diminishing returns: u(d) = log(1 + a d) / log(1 + a), with u(0) = 0, u(1) = 1 and a
per-sensor `quality_alpha` a > 0 (larger a: more of the value comes from the first
samples). The form is concave and written with `log`, so the planner states it in
cvxpy as `cp.log(1 + a * d) / np.log1p(a)`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gliderplan.power_models.catalog import resolve
from gliderplan.power_models.datafile import read_model_file


@dataclass(frozen=True)
class Sensor:
    """A sensor. Powers [W], times [s], energies [J], rates [Hz]."""

    name: str
    description: str
    on_power_w: float
    warmup_s: float
    warmup_j: float
    sample_hz: float
    quality_alpha: float  # [1] curvature of the quality utility
    # [W] the span of published on-powers for this class of device (low, high); a fitted
    # figure outside it is worth a second look. None: the file gives none
    power_range_w: tuple[float, float] | None = None
    path: Path | None = field(default=None, compare=False)  # its data file: the sources

    def utility(self, duty: np.ndarray | float) -> np.ndarray:
        """Quality [1] of data taken at duty cycle `duty` [1], concave, u(0)=0, u(1)=1."""
        d = np.asarray(duty, float)
        return np.log1p(self.quality_alpha * d) / np.log1p(self.quality_alpha)

    def mean_power_w(
        self, duty: np.ndarray | float, period_s: np.ndarray | float = np.inf
    ) -> np.ndarray:
        """Mean power [W] at duty `duty` [1] when switched on once every `period_s` [s].

        Each switch-on costs `warmup_j` on top of the on-time; a sensor always on (duty 1)
        or always off (duty 0) is never switched.
        """
        d = np.asarray(duty, float)
        cycling = (d > 0.0) & (d < 1.0)
        warmup_w = np.where(cycling, self.warmup_j / np.asarray(period_s, float), 0.0)
        return self.on_power_w * d + warmup_w


def load_sensor(spec: str) -> Sensor:
    """Load a sensor: a preset name (`ctd`, `optode`, `optics`, `adcp`, `dvl`, `logger`,
    `modem`) or a path to a .toml file."""
    return read_sensor_file(resolve("sensor", spec))


def read_sensor_file(path: Path) -> Sensor:
    """Parse and validate a sensor data file."""
    top = read_model_file(path, "sensor")
    on_power = top.quantity("on_power", "power")
    warmup_s = top.quantity("warmup_time", "time")
    sensor = Sensor(
        name=top.text("name"),
        description=top.text("description", ""),
        on_power_w=on_power,
        warmup_s=warmup_s,
        warmup_j=top.quantity("warmup_energy", "energy", warmup_s * on_power),
        sample_hz=top.quantity("sample_rate", "frequency", positive=True),
        quality_alpha=top.quantity("quality_alpha", "dimensionless", positive=True),
        power_range_w=top.span("power_range", "power"),
        path=path,
    )
    top.finish()
    return sensor

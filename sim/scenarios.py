"""Scenarios for Monte Carlo: seeded draws of the ocean, the model's figures and the battery.

A scenario file (TOML, `kind = "scenarios"`) names a distribution for each quantity
that varies between flights; `sim/data/scenarios_default.toml` ships with its sources.
Each entry is `{ dist = "fixed", value }`, `{ dist = "uniform", low, high }` or
`{ dist = "normal", mean, sd [, low] [, high] }` (a normal clipped to its bounds), in
the unit its key names (`_m`, `_c`, `_s`, `_mps`, `_deg`, `_1`).

- `[ocean]`: a thermocline (its depth, thickness, the surface temperature and the
  drop across it, one internal wave of random amplitude, period and phase) and a
  depth-averaged current of random speed and direction;
- `[sensors]`: the CTD's noise and lag, the depth sensor's noise, spikes (a reading
  off by `spike_c` with probability `spike_probability`);
- `[vehicle]`: the relative spread of a figure the vehicle file gives no `sd` for
  (a calibrated file's own standard deviations and correlations come first);
- `[battery]`: the share of the battery's rated energy that it really holds;
- `[drift]` (optional): where the truth departs from the model the plan rests on, the same
  draws changed: `current_speed_factor` (stronger or weaker currents),
  `usable_fraction_factor` (a weaker or stronger battery), and a vehicle figure's key with
  the factor it is off by, e.g. `"devices.dvl.on_power" = 1.3` (a device 30 % hungrier;
  one the hotel load holds leaves the rest of the glider's load as it was). `ScenarioSpec.
  model()` is the file without it: what a plan or a replan believes.

A file may start from a shipped one (`base = "default"`, or another's name: the file
`scenarios_NAME.toml` of sim/data) and set only what differs, section by section; a shipped
file is named by its NAME alone wherever a scenario file is asked for.

Draws depend only on the scenario's seed, never on the worker that flies it: the run's
seeds are children of one `numpy.random.SeedSequence`, one per scenario index.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from statistics import NormalDist

import numpy as np

from gliderplan.contract.errors import GliderplanError
from gliderplan.contract.files import DataFileError, parse_data, read_input_text
from gliderplan.power_models.draws import correlation_root
from gliderplan.power_models.vehicle import (
    FIGURES,
    Device,
    Vehicle,
    device_key,
    figure_spec,
    figure_value,
    with_figures,
)
from gliderplan.sim.ocean import InternalWave, Thermocline
from gliderplan.sim.science import SensorNoise
from gliderplan.sim.vehicle import MAX_CURRENT_MPS, Current

# Every quantity a scenario draws, in the order it draws them (the order fixes which
# random number goes where, so that a seed means the same scenario in every run).
OCEAN_KEYS = ("thermocline_depth_m", "thermocline_thickness_m", "surface_temperature_c",
              "temperature_drop_c", "wave_amplitude_m", "wave_period_s", "wave_phase_deg",
              "current_speed_mps", "current_direction_deg")
SENSOR_KEYS = ("temperature_sigma_c", "temperature_lag_s", "depth_sigma_m",
               "spike_probability_1", "spike_c")
BATTERY_KEYS = ("usable_fraction_1",)
# Where each quantity may lie, in its key's unit (a key not named: anywhere). A fixed
# value, a uniform distribution's bounds and a normal's mean and bounds are refused
# outside it; a normal's tails may still leave it (where the simulator needs a positive
# value, a draw is clipped).
RANGES = {
    "thermocline_depth_m": (0.0, 11_000.0), "thermocline_thickness_m": (0.0, 11_000.0),
    "surface_temperature_c": (-5.0, 50.0), "wave_amplitude_m": (0.0, 11_000.0),
    "wave_period_s": (0.0, math.inf), "current_speed_mps": (0.0, MAX_CURRENT_MPS),
    "temperature_sigma_c": (0.0, math.inf), "temperature_lag_s": (0.0, math.inf),
    "depth_sigma_m": (0.0, math.inf), "spike_probability_1": (0.0, 1.0),
    "usable_fraction_1": (0.0, 1.5),
}
_SALINITY_PSU = (31.0, 32.5)
_STANDARD_NORMAL = NormalDist()  # surface and deep: salinity does not steer any routine


class ScenarioFileError(GliderplanError, ValueError):
    """A bad scenario file; the message starts with `FILE: KEY:`."""


@dataclass(frozen=True)
class Distribution:
    """One quantity's distribution, in its key's unit."""

    kind: str  # "fixed" | "uniform" | "normal"
    a: float  # value | low | mean
    b: float = 0.0  # - | high | sd
    low: float = -math.inf  # bounds a normal is clipped to
    high: float = math.inf

    def text(self) -> str:
        """The distribution as written, for a reader: 'normal (mean 0.97, sd 0.03, within
        0.8-1.02)', 'uniform 0.9-1', 'fixed 0.95'."""
        if self.kind == "fixed":
            return f"fixed {self.a:g}"
        if self.kind == "uniform":
            return f"uniform {self.a:g}-{self.b:g}"
        bounds = f", within {self.low:g}-{self.high:g}" if math.isfinite(self.low) or \
            math.isfinite(self.high) else ""
        return f"normal (mean {self.a:g}, sd {self.b:g}{bounds})"

    def draw(self, rng: np.random.Generator) -> float:
        """One value; every kind takes exactly one number from `rng`, so that changing
        one distribution never shifts the draws of the others."""
        u = float(rng.random())
        if self.kind == "fixed":
            return self.a
        if self.kind == "uniform":
            return self.a + (self.b - self.a) * u
        z = float(_normal_quantile(u))
        return min(max(self.a + self.b * z, self.low), self.high)


def _normal_quantile(u: float) -> float:
    """Standard normal quantile of u in [0, 1) (u = 0 maps to -8.2, the quantile of
    1e-16)."""
    return _STANDARD_NORMAL.inv_cdf(min(max(u, 1e-16), 1.0 - 1e-16))


@dataclass(frozen=True)
class ScenarioSpec:
    """What varies between scenarios and how (a parsed scenario file)."""

    source: str  # the file it came from
    ocean: dict[str, Distribution]
    sensors: dict[str, Distribution]
    vehicle_relative_sd: dict[str, float]  # vehicle figure key -> sd / value, by default
    battery: dict[str, Distribution]
    drift: dict[str, float] = field(default_factory=dict)  # the truth off the model (factors)

    def model(self) -> ScenarioSpec:
        """What a plan believes: the file without its drift."""
        return replace(self, drift={})


@dataclass(frozen=True)
class Scenario:
    """One drawn world: what the simulator flies in and what the battery holds."""

    index: int
    seed: int  # the simulator's own random numbers (sensor noise): from the same child
    ocean: Thermocline
    current: Current
    noise: SensorNoise
    vehicle: Vehicle
    usable_fraction: float  # of the battery's rated energy [1]
    drawn: dict[str, float]  # every drawn number by key, for the results table


DEFAULT_NAME = "default"  # the shipped file read without one


def shipped_names() -> tuple[str, ...]:
    """The scenario files that ship with gliderplan, by name (`scenarios_NAME.toml`)."""
    files = resources.files("gliderplan.sim").joinpath("data").iterdir()
    return tuple(sorted(f.name[len("scenarios_"):-len(".toml")] for f in files
                        if f.name.startswith("scenarios_") and f.name.endswith(".toml")))


def _load(path: str | Path | None, depth: int = 0) -> tuple[str, dict]:
    """(where, TOML tables) of a scenario file, a shipped one by name, with its base's
    sections under its own."""
    name = None if path is None else str(path)
    if name is None or (name in shipped_names() and not Path(name).exists()):
        where = f"scenarios_{name or DEFAULT_NAME}.toml"
        text = resources.files("gliderplan.sim").joinpath("data", where).read_text()
    else:
        where = name
        text = read_input_text(name, "scenario file")
    try:
        data = parse_data(text, where)
    except DataFileError as err:
        raise ScenarioFileError(str(err)) from None
    base = data.pop("base", None)
    if base is None:
        return where, data
    if not isinstance(base, str) or base not in shipped_names() or depth > 4:
        raise ScenarioFileError(f"{where}: base: expected the name of a shipped scenario file "
                                f"({', '.join(shipped_names())}), got {base!r}")
    merged = _load(base, depth + 1)[1]
    for key, value in data.items():
        if isinstance(value, dict) and isinstance(merged.get(key), dict):
            merged[key] = {**merged[key], **value}
        else:
            merged[key] = value
    return where, merged


def read_spec(path: str | Path | None = None) -> ScenarioSpec:
    """A scenario file (or a shipped one's name); None: the default that ships with
    gliderplan."""
    where, data = _load(path)
    if data.get("kind") != "scenarios":
        raise ScenarioFileError(f"{where}: kind: expected \"scenarios\", got "
                                f"{data.get('kind')!r}")
    unknown = set(data) - {"kind", "description", "ocean", "sensors", "vehicle", "battery",
                           "drift"}
    if unknown:
        raise ScenarioFileError(f"{where}: {sorted(unknown)[0]}: unknown section")
    spreads = _vehicle_spreads(where, data.get("vehicle", {}))
    return ScenarioSpec(where, _section(where, data, "ocean", OCEAN_KEYS),
                        _section(where, data, "sensors", SENSOR_KEYS), spreads,
                        _section(where, data, "battery", BATTERY_KEYS),
                        _drift(where, data.get("drift", {})))


DRIFT_FACTORS = ("current_speed_factor", "usable_fraction_factor")


def _drift(where: str, table: object) -> dict[str, float]:
    """The [drift] section: factors by key, each finite and > 0."""
    if not isinstance(table, dict):
        raise ScenarioFileError(f"{where}: drift: expected a table")
    drift = {}
    for key, value in table.items():
        if key == "source":
            continue
        if key not in DRIFT_FACTORS:
            try:
                figure_spec(key)
            except KeyError:
                raise ScenarioFileError(
                    f"{where}: drift.{key}: neither {' nor '.join(DRIFT_FACTORS)} nor a "
                    f"vehicle figure (one of {', '.join(FIGURES)}, or "
                    "devices.NAME.on_power)") from None
        if isinstance(value, bool) or not isinstance(value, int | float) \
                or not (math.isfinite(value) and value > 0.0):
            raise ScenarioFileError(f"{where}: drift.{key}: expected a factor > 0, got "
                                    f"{value!r}")
        drift[key] = float(value)
    return drift


def _section(where: str, data: dict, name: str, keys: tuple[str, ...]) -> dict[str, Distribution]:
    table = data.get(name)
    if not isinstance(table, dict):
        raise ScenarioFileError(f"{where}: {name}: missing section [{name}]")
    unknown = sorted(set(table) - set(keys) - {"source"})
    if unknown:
        raise ScenarioFileError(f"{where}: {name}.{unknown[0]}: unknown key (expected one of "
                                f"{', '.join(keys)})")
    result = {}
    for key in keys:
        if key not in table:
            raise ScenarioFileError(f"{where}: {name}.{key}: missing")
        result[key] = _within(f"{where}: {name}.{key}", _distribution(
            f"{where}: {name}.{key}", table[key]), *RANGES.get(key, (-math.inf, math.inf)))
    return result


def _within(where: str, dist: Distribution, low: float, high: float) -> Distribution:
    """`dist`, if the values it is written with lie in [low, high]."""
    written = {"fixed": {"value": dist.a}, "uniform": {"low": dist.a, "high": dist.b},
               "normal": {"mean": dist.a, "low": dist.low, "high": dist.high}}[dist.kind]
    for name, value in written.items():
        if math.isfinite(value) and not low <= value <= high:
            raise ScenarioFileError(f"{where}: {name} {value:g} is outside [{low:g}, "
                                    f"{high:g}]")
    return dist


def _distribution(where: str, entry: object) -> Distribution:
    if isinstance(entry, int | float) and not isinstance(entry, bool):
        entry = {"dist": "fixed", "value": entry}
    if not isinstance(entry, dict):
        raise ScenarioFileError(f"{where}: expected a number or {{ dist = ..., ... }}")
    fields = {"fixed": ("value",), "uniform": ("low", "high"), "normal": ("mean", "sd")}
    kind = entry.get("dist")
    if kind not in fields:
        raise ScenarioFileError(f"{where}: dist: expected fixed, uniform or normal, got "
                                f"{kind!r}")
    allowed = {"dist", "source", *fields[kind], *(("low", "high") if kind == "normal" else ())}
    extra = sorted(set(entry) - allowed)
    if extra:
        raise ScenarioFileError(f"{where}: {extra[0]}: not a field of a {kind} distribution")
    numbers = {}
    for key in set(entry) - {"dist", "source"}:
        value = entry[key]
        if isinstance(value, bool) or not isinstance(value, int | float) \
                or not math.isfinite(value):
            raise ScenarioFileError(f"{where}: {key}: expected a finite number, got {value!r}")
        numbers[key] = float(value)
    missing = [k for k in fields[kind] if k not in numbers]
    if missing:
        raise ScenarioFileError(f"{where}: {missing[0]}: missing")
    if kind == "fixed":
        return Distribution("fixed", numbers["value"])
    if kind == "uniform":
        if numbers["high"] < numbers["low"]:
            raise ScenarioFileError(f"{where}: high must be >= low")
        return Distribution("uniform", numbers["low"], numbers["high"])
    if numbers["sd"] < 0.0:
        raise ScenarioFileError(f"{where}: sd must be >= 0")
    low, high = numbers.get("low", -math.inf), numbers.get("high", math.inf)
    if high < low:
        raise ScenarioFileError(f"{where}: high must be >= low")
    return Distribution("normal", numbers["mean"], numbers["sd"], low, high)


def _vehicle_spreads(where: str, table: object) -> dict[str, float]:
    if not isinstance(table, dict):
        raise ScenarioFileError(f"{where}: vehicle: expected a table")
    spreads = {}
    for key, entry in table.items():
        if key == "source":
            continue
        if key not in FIGURES:
            raise ScenarioFileError(f"{where}: vehicle.{key}: not a vehicle figure (one of "
                                    f"{', '.join(FIGURES)})")
        value = entry.get("relative_sd") if isinstance(entry, dict) else None
        if isinstance(value, bool) or not isinstance(value, int | float) \
                or not 0.0 <= value < 1.0:
            raise ScenarioFileError(f"{where}: vehicle.{key}: expected {{ relative_sd = x, "
                                    "source = ... }} with 0 <= x < 1")
        spreads[key] = float(value)
    return spreads


# ---- drawing ------------------------------------------------------------------------------

def scenario_seeds(seed: int, count: int) -> list[np.random.SeedSequence]:
    """One independent seed per scenario index, from the run's seed."""
    return np.random.SeedSequence(seed).spawn(count)


def draw_scenario(spec: ScenarioSpec, vehicle: Vehicle, index: int,
                  seed: np.random.SeedSequence) -> Scenario:
    """Scenario `index` from its own seed."""
    rng = np.random.default_rng(seed)
    drawn = {k: d.draw(rng) for k, d in spec.ocean.items()}
    drawn |= {k: d.draw(rng) for k, d in spec.sensors.items()}
    drawn |= {k: d.draw(rng) for k, d in spec.battery.items()}
    figures = draw_figures(vehicle, spec.vehicle_relative_sd, rng)
    drawn |= {f"vehicle.{k}": v for k, v in figures.items()}
    sim_seed = int(seed.generate_state(1, np.uint32)[0])
    surface = drawn["surface_temperature_c"]
    wave = InternalWave(drawn["wave_amplitude_m"], max(drawn["wave_period_s"], 1.0),
                        math.radians(drawn["wave_phase_deg"]))
    ocean = Thermocline(surface, surface - drawn["temperature_drop_c"],
                        drawn["thermocline_depth_m"], max(drawn["thermocline_thickness_m"], 0.1),
                        (wave,), *_SALINITY_PSU)
    heading = math.radians(drawn["current_direction_deg"])
    speed = drawn["current_speed_mps"]
    current = Current(speed * math.cos(heading), speed * math.sin(heading))
    noise = SensorNoise(temperature_sigma_c=max(drawn["temperature_sigma_c"], 0.0),
                        temperature_lag_s=max(drawn["temperature_lag_s"], 0.0),
                        depth_sigma_m=max(drawn["depth_sigma_m"], 0.0),
                        spike_probability=min(max(drawn["spike_probability_1"], 0.0), 1.0),
                        spike_c=drawn["spike_c"])
    truth, usable = with_figures(vehicle, figures), max(drawn["usable_fraction_1"], 0.0)
    if spec.drift:
        truth, current, usable = _drifted(spec.drift, truth, current, usable)
        drawn |= {f"drift.{k}": v for k, v in spec.drift.items()}
    return Scenario(index, sim_seed, ocean, current, noise, truth, usable, drawn)


def _drifted(drift: dict[str, float], vehicle: Vehicle, current: Current, usable: float
             ) -> tuple[Vehicle, Current, float]:
    """The drawn world with the truth's drift: the current's speed and the battery's usable
    share scaled, each vehicle figure named multiplied; a device the hotel load holds
    raises (or lowers) the hotel load by what it changes, so the rest of the glider's load
    stays, and a device the vehicle file has no figure for gets its preset's, changed."""
    from gliderplan.power_models.devices import sensor_on

    speed = drift.get("current_speed_factor", 1.0)
    scale = min(speed, MAX_CURRENT_MPS / max(math.hypot(current.north_mps, current.east_mps),
                                             1e-12))
    current = Current(current.north_mps * scale, current.east_mps * scale)
    usable *= drift.get("usable_fraction_factor", 1.0)
    figures = {}
    for key, factor in drift.items():
        if key in DRIFT_FACTORS:
            continue
        name = key[len("devices."):].rsplit(".", 1)[0] if key.startswith("devices.") else None
        if name is not None and vehicle.device(name) is None:
            on = sensor_on(vehicle, name).on_power_w
            vehicle = replace(vehicle, devices=(*vehicle.devices, Device(name, "sensor", on)))
        value = figure_value(vehicle, key)
        figures[key] = value * factor
        if name is not None and key == device_key(name) and name in vehicle.hotel_includes:
            figures["hotel_power"] = figures.get("hotel_power", vehicle.hotel_w) \
                + value * (factor - 1.0)
    return with_figures(vehicle, figures), current, usable


def draw_figures(vehicle: Vehicle, relative_sd: dict[str, float],
                 rng: np.random.Generator) -> dict[str, float]:
    """Vehicle figures drawn around their values: jointly normal with the vehicle file's
    standard deviations and correlations where it has them, else independent with the
    scenario file's relative spread. Figures stay positive (a draw at or below zero is
    clipped to 1 % of the value) and a lower bound (`at_least`) is never drawn below;
    always one standard normal per figure drawn."""
    keys: list[str] = []
    sd: list[float] = []
    correlation = np.eye(0)
    if vehicle.uncertainty is not None:
        keys = list(vehicle.uncertainty.keys)
        sd = list(vehicle.uncertainty.sd)
        correlation = vehicle.uncertainty.correlation
    for key, spread in relative_sd.items():
        if key not in keys:
            keys.append(key)
            sd.append(spread * abs(figure_value(vehicle, key)))
    if not keys:
        return {}
    full = np.eye(len(keys))
    full[:correlation.shape[0], :correlation.shape[0]] = correlation
    factor = correlation_root(full)
    z = np.array([_normal_quantile(float(u)) for u in rng.random(len(keys))])
    offsets = np.asarray(sd) * (factor @ z)
    values = {}
    bounds = () if vehicle.uncertainty is None else vehicle.uncertainty.at_least
    for key, offset in zip(keys, offsets, strict=True):
        nominal = figure_value(vehicle, key)
        floor = 0.01 * abs(nominal) if nominal > 0.0 else -math.inf
        if key in bounds:  # a lower bound (a call the log saw cut short): no less
            floor = nominal
        values[key] = max(nominal + float(offset), floor)
    return values

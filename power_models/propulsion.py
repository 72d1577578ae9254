"""Propulsion: the power a propeller or a glider's thruster draws to hold a speed through
the water, read from the `[propulsion]` table of a vehicle file.

Three models, each from published or fitted figures with their sources:

- `power_law`: P(U) = running + k U^n, k from `reference_power` at `reference_speed`
  (a fit such as P = hotel + k U^3; `running` is what the motor draws at any speed);
- `table`: the propulsion power against speed (or against propeller RPM, with the speed
  proportional to the RPM), linear between the rows and refused outside them (a LAUV's
  motor power at 500 / 850 / 1250 / 1400 RPM);
- `thruster`: a glider's thruster in power-command mode (Slocum G3: 1-9 W commanded; the
  battery draws offset + slope x the commanded watts). The commanded power drives the
  hull through the water against its zero-lift drag, efficiency x P_cmd = 1/2 rho S Cd0
  U^3, so the draw is a power law in U with n = 3.

Notes
-----
Energy per metre through still water at speed U with a load L [W] besides the motor is
E(U) = (L + P(U)) / U. For P = running + k U^n it is least at

    U* = ((L + running) / ((n - 1) k))^(1/n),   n = 3: U* = (hotel / (2 k))^(1/3)

with hotel = L + running: a hungrier hotel load makes the best speed faster.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gliderplan.power_models.datafile import Table

Array = np.ndarray

GLIDER, HYBRID, AUV = "glider", "hybrid", "auv"
VEHICLE_KINDS = (GLIDER, HYBRID, AUV)
POWER_LAW, TABLE, THRUSTER = "power_law", "table", "thruster"
MODELS = (POWER_LAW, TABLE, THRUSTER)


class SpeedOutOfRange(ValueError):
    """A speed the vehicle's propulsion model does not cover; the message names its range."""


@dataclass(frozen=True)
class Propulsion:
    """A vehicle's propulsion. Speeds through the water [m s-1], powers [W] drawn from the
    battery on top of the hotel load."""

    model: str  # power_law | table | thruster
    min_speed_mps: float
    max_speed_mps: float
    running_w: float = 0.0  # drawn while the motor runs, at any speed
    coefficient: float = 0.0  # k [W (m s-1)^-n] of a power law or a thruster
    exponent: float = 3.0  # n
    speeds_mps: tuple[float, ...] = ()  # a table's rows, increasing
    powers_w: tuple[float, ...] = ()  # its propulsion power at each (besides `running_w`)
    # a thruster in power-command mode: battery draw = running + slope x commanded power
    command_slope: float = 0.0  # [1]
    command_per_cube: float = 0.0  # commanded power [W] for 1 m/s: rho S Cd0 / (2 efficiency)
    efficiency: float = 0.0  # share of the commanded power that drives the hull [1]
    min_command_w: float = 0.0
    max_command_w: float = 0.0

    @property
    def is_thruster(self) -> bool:
        """Whether it is commanded in watts (a glider's thruster, which also assists yos)."""
        return self.model == THRUSTER

    @property
    def range_text(self) -> str:
        return f"{self.min_speed_mps:.3g}-{self.max_speed_mps:.3g} m/s"

    def check_speed(self, speed_mps: float) -> None:
        """Raise SpeedOutOfRange for a speed [m s-1] outside the model's range."""
        if not self.min_speed_mps * (1 - 1e-9) <= speed_mps <= self.max_speed_mps * (1 + 1e-9):
            raise SpeedOutOfRange(f"{speed_mps:g} m/s is beyond the propulsion's "
                                  f"{self.range_text}")

    def power_w(self, speed_mps: Array | float) -> Array:
        """Propulsion power [W] at a speed through the water [m s-1] within the range (NaN
        outside it)."""
        u = np.asarray(speed_mps, float)
        if self.model == TABLE:
            motor = np.interp(u, self.speeds_mps, self.powers_w)
        else:
            motor = self.coefficient * np.abs(u) ** self.exponent
        inside = (u >= self.min_speed_mps * (1 - 1e-9)) & (u <= self.max_speed_mps * (1 + 1e-9))
        return np.where(inside, self.running_w + motor, np.nan)

    def energy_per_m_j(self, speed_mps: Array | float, load_w: float) -> Array:
        """[J m-1] through still water at a speed [m s-1] with `load_w` [W] besides the motor."""
        u = np.asarray(speed_mps, float)
        return (load_w + self.power_w(u)) / u

    def optimal_speed_mps(self, load_w: float) -> float | None:
        """The closed form U* = ((L + running) / ((n - 1) k))^(1/n) [m s-1] of a power law
        (n > 1) in still water, before it is held to the range; None for a table."""
        if self.model == TABLE or self.exponent <= 1.0 or self.coefficient <= 0.0:
            return None
        return ((load_w + self.running_w) / ((self.exponent - 1.0) * self.coefficient)) \
            ** (1.0 / self.exponent)

    # ---- a thruster in power-command mode -----------------------------------------------
    def command_w(self, speed_mps: float) -> float:
        """The commanded thruster power [W] that holds a speed [m s-1] in level flight."""
        return self.command_per_cube * speed_mps ** 3

    def assist_draw_w(self, command_w: float) -> float:
        """Battery draw [W] of the thruster at a commanded power [W] (0: off)."""
        return self.running_w + self.command_slope * command_w if command_w > 0.0 else 0.0

    def thrust_power_w(self, command_w: float) -> float:
        """Power [W] that reaches the water as thrust at a commanded power [W]."""
        return self.efficiency * command_w

    def check_command(self, command_w: float) -> None:
        """Raise SpeedOutOfRange for a commanded power outside the thruster's range."""
        if not self.min_command_w * (1 - 1e-9) <= command_w <= self.max_command_w * (1 + 1e-9):
            raise SpeedOutOfRange(f"{command_w:g} W is beyond the thruster's power-command "
                                  f"range ({self.min_command_w:g}-{self.max_command_w:g} W)")

    def figures(self) -> dict:
        """The model as plain numbers (what `power show vehicle NAME --json` prints)."""
        data = {"model": self.model, "min_speed_mps": self.min_speed_mps,
                "max_speed_mps": self.max_speed_mps, "running_power_w": self.running_w}
        if self.model == TABLE:
            data["table"] = [{"speed_mps": u, "power_w": self.running_w + p}
                             for u, p in zip(self.speeds_mps, self.powers_w, strict=True)]
        else:
            data.update(coefficient_w_per_speed_n=self.coefficient, exponent=self.exponent)
        if self.is_thruster:
            data.update(command_slope=self.command_slope, efficiency=self.efficiency,
                        min_command_w=self.min_command_w, max_command_w=self.max_command_w,
                        command_w_at_1_mps=self.command_per_cube)
        return data


def read_propulsion(table: Table, wing_area_m2: float, rho_kg_m3: float,
                    drag_cd0: float) -> Propulsion:
    """The `[propulsion]` table of a vehicle file; a thruster's speeds come from the hull's
    zero-lift drag (`wing_area_m2` [m2], `rho_kg_m3` [kg m-3], `drag_cd0` [1])."""
    model = table.text("model")
    if model not in MODELS:
        raise table.error("model", f"expected one of {', '.join(MODELS)}, got {model!r}")
    if model == POWER_LAW:
        propulsion = _power_law(table)
    elif model == TABLE:
        propulsion = _table(table)
    else:
        propulsion = _thruster(table, drag_power_coefficient(rho_kg_m3, wing_area_m2, drag_cd0))
    table.finish()
    return propulsion


def _speed_range(table: Table) -> tuple[float, float]:
    low = table.quantity("min_speed", "speed", positive=True)
    high = table.quantity("max_speed", "speed", positive=True)
    if high < low:
        raise table.error("max_speed", f"must be at least min_speed ({low:g} m/s)")
    return low, high


def _power_law(table: Table) -> Propulsion:
    reference_w = table.quantity("reference_power", "power", positive=True)
    reference_mps = table.quantity("reference_speed", "speed", positive=True)
    exponent = table.quantity("exponent", "dimensionless", positive=True)
    low, high = _speed_range(table)
    return Propulsion(POWER_LAW, low, high, table.quantity("running_power", "power", 0.0),
                      reference_w / reference_mps ** exponent, exponent)


def _table(table: Table) -> Propulsion:
    powers = table.quantities("power", "power")
    if table.has("speed"):
        speeds = table.quantities("speed", "speed", positive=True)
    else:  # RPM rows: the speed is proportional to the RPM (a constant advance ratio)
        rpm = table.quantities("rpm", "rotation", positive=True)
        per_rpm = table.quantity("reference_speed", "speed", positive=True) \
            / table.quantity("reference_rpm", "rotation", positive=True)
        speeds = [r * per_rpm for r in rpm]
    key = "speed" if table.data.get("speed") is not None else "rpm"
    if len(speeds) != len(powers) or len(speeds) < 2:
        raise table.error("power", f"expected one power per {key} row, at least two rows "
                          f"({len(speeds)} {key} rows, {len(powers)} powers)")
    if any(b <= a for a, b in zip(speeds, speeds[1:], strict=False)):
        raise table.error(key, "the rows must increase")
    return Propulsion(TABLE, speeds[0], speeds[-1], table.quantity("running_power", "power", 0.0),
                      speeds_mps=tuple(speeds), powers_w=tuple(powers))


def _thruster(table: Table, drag_per_cube: float) -> Propulsion:
    """`drag_per_cube` [W (m s-1)^-3]: the hull's drag power 1/2 rho S Cd0 at 1 m/s."""
    offset = table.quantity("offset_power", "power")
    slope = table.quantity("power_slope", "dimensionless", positive=True)
    efficiency = table.quantity("efficiency", "fraction", positive=True, maximum=1.0)
    low_w = table.quantity("min_command", "power", positive=True)
    high_w = table.quantity("max_command", "power", positive=True)
    if high_w < low_w:
        raise table.error("max_command", f"must be at least min_command ({low_w:g} W)")
    per_cube = drag_per_cube / efficiency

    def speed(command_w: float) -> float:
        return (command_w / per_cube) ** (1.0 / 3.0)

    return Propulsion(THRUSTER, speed(low_w), speed(high_w), offset, slope * per_cube, 3.0,
                      command_slope=slope, command_per_cube=per_cube, efficiency=efficiency,
                      min_command_w=low_w, max_command_w=high_w)


def thrust_assisted_speed(glide_speed_mps: Array | float, thrust_w: Array | float,
                          rho_kg_m3: float, area_m2: float, drag: Array | float) -> Array:
    """Speed along the glide path [m s-1] of a glider that glides at `glide_speed_mps`
    with a thruster putting `thrust_w` [W] into the water, drag coefficient `drag` [1] on
    area `area_m2`: drag power balances buoyancy's plus the thrust's,
    1/2 rho S Cd U^3 = 1/2 rho S Cd Ug^2 U + P, so U^3 - Ug^2 U - a = 0, a = 2 P / (rho S
    Cd). The path's angle is kept (the thrust taken along it). Newton from Ug + a^(1/3),
    where the cubic is positive and convex, falls monotonically onto its one positive root."""
    ug = np.asarray(glide_speed_mps, float)
    a = 2.0 * np.asarray(thrust_w, float) / (rho_kg_m3 * area_m2 * np.asarray(drag, float))
    u = ug + np.cbrt(a)
    for _ in range(_NEWTON_STEPS):
        u = u - (u**3 - ug**2 * u - a) / np.maximum(3.0 * u**2 - ug**2, 1e-300)
    return np.where(a > 0.0, u, ug)


_NEWTON_STEPS = 40  # from at most twice the root: far below double precision's step


def ground_speed_mps(speed_mps: Array | float, along_mps: float, across_mps: float) -> Array:
    """Speed over ground [m s-1] of a vehicle flying `speed_mps` through the water on a
    track with a current of `along_mps` along it (positive: with it) and `across_mps`
    across it: it crabs into the cross current, sqrt(U^2 - c_x^2) + c_a; NaN where it
    cannot make headway."""
    u = np.asarray(speed_mps, float)
    crab = u * u - across_mps * across_mps
    ground = np.sqrt(np.maximum(crab, 0.0)) + along_mps
    return np.where((crab >= 0.0) & (ground > 0.0), ground, np.nan)


def drag_power_coefficient(rho_kg_m3: float, area_m2: float, drag_cd0: float) -> float:
    """1/2 rho S Cd0 [W (m s-1)^-3]: the hull's drag power at 1 m/s."""
    return 0.5 * rho_kg_m3 * area_m2 * drag_cd0


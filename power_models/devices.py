"""What each device of a glider draws, defined once for the planner, the simulator and the
forecast.

A vehicle's hotel load is the whole glider gliding, as its file gives it; `hotel_includes`
names the devices that load already holds (a load fitted from a log holds the instruments
that ran throughout it). A device's power is the vehicle's own figure when its file has
one (`[devices.NAME]`, calibrated from its logs), else its sensor preset's. The base load
is the hotel load less the instruments it holds: a mission pays the base while it glides
and each instrument for the time it runs it, so that an instrument the calibration log
ran and the mission does not is not billed, and one the mission duty-cycles costs what
its duty says. Actuators in the hotel load (the fin, moving for a share of every glide)
stay in the base: they run whenever the glider glides.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from functools import lru_cache

from gliderplan.contract import Component
from gliderplan.power_models.catalog import preset_names
from gliderplan.power_models.errors import ModelFileError
from gliderplan.power_models.sensor import Sensor, load_sensor
from gliderplan.power_models.vehicle import Vehicle

_preset = lru_cache(maxsize=None)(load_sensor)  # the shipped files do not change


def sensor_on(vehicle: Vehicle, name: str) -> Sensor:
    """The sensor preset `name` drawing what this vehicle's own figure says while on [W]
    (its file's `[devices.NAME]`), else the preset's figure."""
    preset = _preset(name)
    own = vehicle.device(name)
    return preset if own is None else replace(preset, on_power_w=own.on_power_w)


def held_instruments(vehicle: Vehicle) -> tuple[str, ...]:
    """The instruments (sensor presets) the vehicle's hotel load holds."""
    sensors = set(preset_names("sensor"))
    return tuple(d for d in vehicle.hotel_includes if d in sensors)


def held_power_w(vehicle: Vehicle) -> dict[str, float]:
    """Each instrument the hotel load holds -> its power while on [W]."""
    return {d: sensor_on(vehicle, d).on_power_w for d in held_instruments(vehicle)}


def base_power_w(vehicle: Vehicle) -> float:
    """The hotel load less the instruments it holds [W]: what the glider draws gliding with
    every instrument off (its computers, attitude sensors, the fin's share); never below 0
    (a file that says otherwise is refused on loading, `check_hotel`)."""
    return max(vehicle.hotel_w - sum(held_power_w(vehicle).values()), 0.0)


def check_hotel(vehicle: Vehicle) -> None:
    """Refuse (ModelFileError, naming the file) a hotel load smaller than the instruments
    it says it holds."""
    held = held_power_w(vehicle)
    if vehicle.hotel_w < sum(held.values()):
        listed = ", ".join(f"{d} {w:.3g} W" for d, w in held.items())
        raise ModelFileError(str(vehicle.path or vehicle.name), "hotel_power",
                             f"{vehicle.hotel_w:.3g} W is less than the instruments "
                             f"hotel_includes says it holds ({listed})")


def gliding_power_w(vehicle: Vehicle, instruments: Mapping[str, float] | None = None
                    ) -> dict[str, float]:
    """What the glider draws while it glides [W], by device: the hotel load's base less its
    actuators (`Component.HOTEL`), each actuator at its share of the glide (the fin), and
    each instrument of `instruments` (device -> duty [1]) at its duty. `instruments` None:
    the instruments the hotel load holds, always on (the glider as it was calibrated)."""
    actuators = {d.name: d.on_power_w * d.duty for d in vehicle.devices
                 if d.kind == "actuator" and d.name in vehicle.hotel_includes}
    run = dict.fromkeys(held_instruments(vehicle), 1.0) if instruments is None else instruments
    return {Component.HOTEL: base_power_w(vehicle) - sum(actuators.values()), **actuators,
            **{d: sensor_on(vehicle, d).on_power_w * duty for d, duty in run.items()
               if duty > 0.0}}

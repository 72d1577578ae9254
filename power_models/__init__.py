"""gliderplan.power_models: boards, sensors, vehicle (with the steady-glide flight model)
and battery, each loaded from a data file that gives a source and a unit for every number.

`load_board`, `load_sensor`, `load_vehicle` and `load_battery` are imported lazily so that
`gliderplan.power_models.catalog` (used by the language checker) stays free of numpy;
so is `calibrate`, the pipeline of `gliderplan calibrate` (log_calibration.py).
"""

from __future__ import annotations

import importlib
from typing import Any

_LAZY = {
    "load_board": "gliderplan.power_models.board",
    "Board": "gliderplan.power_models.board",
    "load_sensor": "gliderplan.power_models.sensor",
    "Sensor": "gliderplan.power_models.sensor",
    "load_vehicle": "gliderplan.power_models.vehicle",
    "Vehicle": "gliderplan.power_models.vehicle",
    "load_battery": "gliderplan.power_models.battery",
    "Battery": "gliderplan.power_models.battery",
    "ModelFileError": "gliderplan.power_models.errors",
    "calibrate": "gliderplan.power_models.log_calibration",
    "Calibration": "gliderplan.power_models.log_calibration",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

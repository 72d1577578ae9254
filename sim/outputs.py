"""The files of a simulated run: trace.csv, timeseries.parquet, summary.json (the plots
are in plots.py). Each is produced as bytes so that the caller writes it atomically."""

from __future__ import annotations

import io
import json

import numpy as np

from gliderplan.contract import NO_STATE
from gliderplan.language.registry import SENSORS
from gliderplan.language.semantics import Transition
from gliderplan.planner.planfile import Plan
from gliderplan.sim.energy import FlightCheck, RunEnergy
from gliderplan.sim.loop import RunRecord

TRACE_HEADER = "time_s,kind,from_state,to_state,stack_depth"
TIMESERIES_DICTIONARY = ("state", "stack_depth", "profile")  # few distinct values each


def trace_csv(trace: list[Transition]) -> str:
    """One row per transition; times in seconds as %g (ticks are whole seconds or halves)."""
    rows = [TRACE_HEADER] + [f"{t.time_s:g},{t.kind},{t.from_state},{t.to_state},"
                             f"{t.stack_depth}" for t in trace]
    return "\n".join(rows) + "\n"


def timeseries_table(record: RunRecord, energy: RunEnergy, battery_j: float,
                     salinity_psu: np.ndarray | None = None):
    """One row per tick: time, depth, pitch, water temperature and the CTD's reading (NaN
    while it is off), the water's practical salinity [PSU] (`salinity_psu`, as the
    simulated CTD reads it when it is on), state, stack depth, each sensor's power, power
    per component [W], battery remaining [J]."""
    import pyarrow as pa

    c = record.columns
    state = c["state"].astype(np.intp)
    names = list(record.state_names)
    columns = {
        "time_s": c["time_s"],
        "depth_m": c["depth_m"],
        "pitch_rad": c["pitch_rad"],
        "temperature_c": c["temperature_c"],
        "temp_reading_c": c["temp_reading_c"],
        **({} if salinity_psu is None else {"salinity_psu": np.broadcast_to(
            np.asarray(salinity_psu, np.float64), c["time_s"].shape).copy()}),
        "state": _strings(names + [""], np.where(state == NO_STATE, len(names), state)),
        "stack_depth": c["stack_depth"].astype(np.int16),
        "profile": c["profile"].astype(np.int16),
        "lat_deg": c["lat_deg"],
        "lon_deg": c["lon_deg"],
    }
    power = c["sensor_power"].astype(np.int64)
    for sensor in SENSORS:
        if sensor.device is not None:
            columns[f"{sensor.name}_on"] = (power >> sensor.index & 1).astype(bool)
    total = np.zeros(len(state))
    for component, joules in energy.per_tick_j.items():
        columns[f"power_{component}_w"] = joules / record.tick_s
        total = total + joules
    columns["power_total_w"] = total / record.tick_s
    columns["battery_remaining_j"] = battery_j - np.cumsum(total)
    return pa.Table.from_arrays([v if isinstance(v, pa.Array) else _arrow(v)
                                 for v in columns.values()], names=list(columns))


# Arrow arrays are built on the numpy arrays' memory: pyarrow's own conversion would
# import pandas to look for pandas types (a quarter of a second of every run).

def _arrow(values: np.ndarray):
    """A numpy array of numbers or booleans as an Arrow array."""
    import pyarrow as pa

    if values.dtype == np.bool_:
        return pa.Array.from_buffers(pa.bool_(), len(values), [
            None, pa.py_buffer(np.packbits(values, bitorder="little"))])
    values = np.ascontiguousarray(values)
    return pa.Array.from_buffers(pa.from_numpy_dtype(values.dtype), len(values),
                                 [None, pa.py_buffer(values)])


def _strings(names: list[str], index: np.ndarray):
    """An Arrow string array of names[index[i]] for every i."""
    import pyarrow as pa

    encoded = [name.encode() for name in names]
    width = max(map(len, encoded), default=0)
    padded = np.frombuffer(b"".join(e.ljust(width, b"\0") for e in encoded),
                           np.uint8).reshape(len(names), width)
    lengths = np.array([len(e) for e in encoded], np.int32)[index]
    offsets = np.zeros(len(index) + 1, np.int32)
    np.cumsum(lengths, out=offsets[1:])
    # each row's name padded to the longest, less the padding
    text = padded[index][np.arange(width) < lengths[:, None]]
    return pa.Array.from_buffers(pa.string(), len(index),
                                 [None, pa.py_buffer(offsets), pa.py_buffer(text)])


def parquet_bytes(table, dictionary: tuple[str, ...] = ()) -> bytes:
    """The table as Parquet; `dictionary`: the columns worth dictionary-encoding (few
    distinct values; trying it on every column costs more time than it saves space)."""
    import pyarrow.parquet as pq

    sink = io.BytesIO()
    pq.write_table(table, sink, use_dictionary=list(dictionary) or True)
    return sink.getvalue()


def simulated_s(record: RunRecord) -> float:
    """[s] mission time of the last tick flown (0 before the first)."""
    return float(record.columns["time_s"][-1]) if len(record.columns["time_s"]) else 0.0


def surfacing_fixes(record: RunRecord) -> list[dict]:
    """Each surfacing's GPS fix: time [s] and true position [deg], on the first tick of
    its Iridium call (the fix comes just before it)."""
    from gliderplan.power_models.segments import IRIDIUM

    c = record.columns
    calling = np.asarray(c["phase"]) == IRIDIUM
    starts = np.flatnonzero(calling & ~np.r_[False, calling[:-1]])
    return [{"time_s": float(c["time_s"][i]), "lat": float(c["lat_deg"][i]),
             "lon": float(c["lon_deg"][i])} for i in starts]


def summary(record: RunRecord, energy: RunEnergy, check: FlightCheck, plan: Plan | None,
            meta: dict) -> str:
    """Energy by component and by state, predicted against simulated, the verdict, and
    what the plan's prediction assumed."""
    predictions = {s.name: s for s in plan.states} if plan is not None else {}
    states = {}
    for name in record.state_names:
        simulated = energy.by_state_j.get(name)
        predicted = predictions.get(name)
        if simulated is None and predicted is None:
            continue
        entry: dict = {
            "time_s": energy.time_by_state_s.get(name, 0.0),
            "inflections": energy.inflections_by_state.get(name, 0),
            "simulated_j": sum((simulated or {}).values()),
            "simulated_by_component_j": simulated or {},
        }
        if predicted is not None:
            entry.update(predicted_j=predicted.energy_j,
                         predicted_by_component_j=predicted.energy_by_component_j,
                         predicted_time_s=predicted.time_s,
                         predicted_inflections=predicted.inflections)
        states[name] = entry
    data = {
        **meta,
        "ended": record.ended,
        # False: interrupted in flight, the files hold the part flown (to simulated_s)
        "complete": record.ended != "interrupted",
        "simulated_s": simulated_s(record),
        "transitions": len(record.trace),
        "envelope": record.envelope,
        "surfacings": record.surfacings,
        "surfacing_fixes": surfacing_fixes(record),
        "computer_suspends": record.suspends,
        "energy_j": energy.total_j,
        "energy_by_component_j": energy.by_component_j(),
        "states": states,
        "plan_check": check.to_json(),
        "plan_assumptions": [{"subject": a.subject, "text": a.text}
                             for a in (plan.assumptions if plan is not None else ())],
    }
    if record.faults is not None:
        data["faults"] = record.faults
    return json.dumps(data, indent=2, sort_keys=False, allow_nan=False) + "\n"

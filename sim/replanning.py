"""The shore in the simulated loop: at each surfacing the glider reports (telemetry up, one
short Iridium message), the shore replans the rest of the mission (planner/replan.py) and
sends the plan update down; the vehicle applies it and says so in its next report.

`ShoreLoop` is the shore; `PythonVehicle` is the Python executor's side of the link (the
update applied as the runtime applies it, planner.update.apply_update); the C runtime
applies its own over the serial link (sim/emulator.py). `surfacing_hook` wires the two
into a flight's surfacing hook (the Python loop's, `sim.loop.simulate`, or the C loop's,
`sim.cflight.CFlight.fly`). The loop counts the bytes each way.

The glider's report is made from what the simulator flew: the coulomb counter's reading
(the battery gauge), the battery's voltage (the truth's depth of discharge through the
posterior's discharge curve, with its noise, seeded), the position, the state, each
device's on-time and the time in each state since the start, the plan in force and the
last update's verdict.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from gliderplan.contract import (
    SBD_MO_SHORT_BYTES,
    SBD_MT_SHORT_BYTES,
    SENSOR_DEVICES,
    UpdateStatus,
)
from gliderplan.language import ir
from gliderplan.planner.plan import PlanningError
from gliderplan.planner.planfile import read_plan_bytes
from gliderplan.planner.replan import Replanner, stated_confidence
from gliderplan.planner.speed import Leg
from gliderplan.planner.update import UpdateError, apply_update, make_updates
from gliderplan.power_models.battery import drawn_budget_j
from gliderplan.power_models.posterior import DischargeCurve
from gliderplan.power_models.telemetry import (
    J_PER_AH,
    NOMINAL_BUS_V,
    SurfacingReport,
    TelemetryError,
    UpdateAck,
    pack_report,
    without_state_times,
)
from gliderplan.sim.energy import DEVICE_BITS
from gliderplan.sim.geo import degrees_to_ddmm
from gliderplan.sim.loop import Surfaced, SurfacingHook

MAX_UPDATES = 2  # a replan's changes may take this many updates at one surfacing
LAUNCH_UPDATES = 64  # before launch the plan goes on by cable: no message limit to keep


@dataclass
class LinkLog:
    """What crossed the satellite link, surfacing by surfacing."""

    surfacings: int = 0
    up_bytes: int = 0  # surfacing reports
    down_bytes: int = 0  # plan updates
    up_messages: int = 0
    down_messages: int = 0
    update_bytes_max: int = 0
    applied: int = 0  # updates the vehicle applied
    refused: int = 0  # updates it refused (their verdicts in `refusals`)
    unchanged: int = 0  # replans that changed nothing: no update sent
    least_energy: int = 0  # replans that found the budget short at the confidence
    not_sent: int = 0  # replans whose changes no update could carry
    not_replanned: int = 0  # surfacings whose replan failed (refused or the solver): no update
    refusals: list[str] = field(default_factory=list)
    events: list[dict] = field(default_factory=list)  # one per surfacing

    def summary(self, duration_s: float) -> dict:
        """The link's cost: bytes and messages each way, per day and per mission, against
        the short-burst limits."""
        days = max(duration_s / 86400.0, 1e-9)
        return {
            "surfacings": self.surfacings, "updates_applied": self.applied,
            "updates_refused": self.refused, "replans_unchanged": self.unchanged,
            "replans_least_energy": self.least_energy, "replans_not_sent": self.not_sent,
            "replans_failed": self.not_replanned,
            "up_bytes": self.up_bytes, "down_bytes": self.down_bytes,
            "up_bytes_per_day": self.up_bytes / days, "down_bytes_per_day": self.down_bytes / days,
            "up_messages": self.up_messages, "down_messages": self.down_messages,
            "update_bytes_max": self.update_bytes_max,
            "sbd_limits_bytes": {"up": SBD_MO_SHORT_BYTES, "down": SBD_MT_SHORT_BYTES},
            "refusals": self.refusals[:10],
        }


class ShoreLoop:
    """The shore of one simulated flight: `held` is the signed plan file the vehicle flies
    at the start, `key` the vehicle's. `usable_truth`: the share of its rating the
    simulated battery really holds (what its voltage tells); `confidence`, `spec`: as for
    `Replanner` (its prior); the rest of the mission is planned at the least energy when
    the budget left cannot hold it at the confidence. `legs`: the water the shore knows
    the vehicle flies (planner/water.py), its speeds and thrusts chosen anew in it."""

    def __init__(self, mission: ir.CheckedMission, held: bytes, key: bytes, *,
                 tick_s: float, usable_truth: float = 1.0, seed: int = 0,
                 confidence: float | None = None, spec=None,  # noqa: ANN001
                 if_infeasible: str = "least-energy", check=None,  # noqa: ANN001
                 legs: dict[str, tuple[Leg, ...]] | None = None) -> None:
        self.mission, self.key, self.tick_s = mission, key, tick_s
        self.replanner = Replanner(mission, held, confidence=confidence, spec=spec,
                                   if_infeasible=if_infeasible, legs=legs)
        self.held = held  # the plan the shore knows the vehicle holds
        self.sent: dict[int, bytes] = {}  # seq -> the plan file an update sent makes
        self.names = tuple(s.name for s in mission.states)
        self.usable_truth = usable_truth
        self.curve = DischargeCurve.nominal(NOMINAL_BUS_V)
        self.rng = np.random.default_rng(seed)
        self.check = check or (lambda data: read_plan_bytes(data, mission))
        self.counted = 0  # rows of the columns counted into the tallies below
        self.on_s = dict.fromkeys(SENSOR_DEVICES, 0.0)
        self.state_s = np.zeros(len(mission.states) + 1)
        self.vehicle_seq = self.replanner.plan.seq
        self.ack: UpdateAck | None = None
        self.log = LinkLog()
        self.workdir = None  # a temporary directory the vehicle's files are kept in, if any

    # -- the glider's side of the report

    def report(self, tick: int, columns: Mapping[str, np.ndarray], used_j: float,
               lat_deg: float, lon_deg: float) -> SurfacingReport:
        """What the glider sends up at a surfacing: its counter's last reading `used_j` [J],
        taken before tick `tick`, and what it flew up to then (`columns`: a row a tick)."""
        rows = slice(self.counted, min(tick, len(columns["state"])))
        power = columns["sensor_power"][rows].astype(np.int64)
        for device in SENSOR_DEVICES:
            self.on_s[device] += float(np.count_nonzero(power & DEVICE_BITS[device])) \
                * self.tick_s
        state = np.minimum(columns["state"][rows].astype(np.intp), len(self.names))
        self.state_s += np.bincount(state, minlength=len(self.names) + 1) * self.tick_s
        self.counted = rows.stop
        depth = used_j / drawn_budget_j(self.replanner.plan.budget_j, self.usable_truth)
        volts = self.curve.voltage(depth) + self.rng.normal(0.0, self.curve.noise_v)
        current = int(columns["state"][rows.stop - 1]) if rows.stop else -1
        return SurfacingReport(
            tick * self.tick_s, used_j / J_PER_AH, float(volts), degrees_to_ddmm(lat_deg),
            degrees_to_ddmm(lon_deg),
            self.names[current] if 0 <= current < len(self.names) else None, (),
            {d: s for d, s in self.on_s.items() if s > 0.0},
            {n: float(self.state_s[i]) for i, n in enumerate(self.names)},
            self.vehicle_seq, self.ack, f"surfacing {self.log.surfacings + 1}")

    def _sent_up(self, report: SurfacingReport) -> None:
        try:
            size = len(pack_report(report, self.names))
        except TelemetryError:
            size = len(pack_report(without_state_times(report), self.names))
        self.log.up_bytes += size
        self.log.up_messages += 1

    # -- the shore's side

    def at_surfacing(self, tick: int, columns: Mapping[str, np.ndarray], used_j: float,
                     lat_deg: float, lon_deg: float) -> tuple[bytes, ...]:
        """The glider's report goes up; the updates to send down come back (none when the
        replan changes nothing, or no update can carry it)."""
        report = self.report(tick, columns, used_j, lat_deg, lon_deg)
        self.log.surfacings += 1
        self._sent_up(report)
        if report.plan_seq in self.sent:  # the report says which plan the vehicle flies
            self.held = self.sent[report.plan_seq]
        event = {"time_s": report.time_s, "used_j": used_j, "plan_seq": report.plan_seq,
                 "voltage_v": report.battery_v}
        self.log.events.append(event)
        replanner = self.replanner
        replanner.observe(report)
        try:
            result = replanner.replan(self.held, report)
        except PlanningError as err:  # infeasible (with if_infeasible="refuse"), or the
            event["status"] = "not replanned"  # solver failed: the plan flies on
            self.log.not_replanned += 1
            self.log.refusals.append(str(err))
            return ()
        event.update(status=result.status, quality=result.quality,
                     budget_left_j=result.budget_left_j, energy_left_j=result.energy_left_j)
        self.log.least_energy += result.status == "least-energy"
        try:
            chain = make_updates(self.held, result.target, self.key,
                                 first_seq=self.vehicle_seq + 1, max_updates=MAX_UPDATES,
                                 check=self.check)
        except UpdateError as err:
            self.log.not_sent += 1
            event["status"] = "not sent"
            self.log.refusals.append(str(err))
            return ()
        if not chain.updates:  # what changed rounds to what the vehicle holds
            self.log.unchanged += 1
            event["status"] = "unchanged"
            return ()
        for plan_file in chain.plan_files:
            self.sent[read_plan_bytes(plan_file).seq] = plan_file
        sizes = [len(u) for u in chain.updates]
        self.log.down_bytes += sum(sizes)
        self.log.down_messages += len(sizes)
        self.log.update_bytes_max = max(self.log.update_bytes_max, *sizes)
        event["update_bytes"] = sizes
        return chain.updates

    def acknowledged(self, status: UpdateStatus, seq: int, message: str) -> None:
        """The vehicle's verdict on an update: it goes up in the next report."""
        self.ack = UpdateAck(status, seq, message)
        if status in (UpdateStatus.APPLIED, UpdateStatus.DUPLICATE):
            self.log.applied += status == UpdateStatus.APPLIED
            self.vehicle_seq = seq
        else:
            self.log.refused += 1
            self.log.refusals.append(f"{status.name.lower()}: {message}")


def plan_at_confidence(mission: ir.CheckedMission, held: bytes, key: bytes, *,
                       confidence: float | None, spec) -> tuple[bytes, float, str]:  # noqa: ANN001
    """The plan to launch with so that flying it alone and replanning it at each surfacing
    are both planned at one confidence: `held` itself if it was planned at `confidence`
    (`plan --confidence`; None: the plan's own, else the default), else `held` replanned
    before launch by the shore's model at that confidence against the prior (`spec`), as
    the signed plan file its updates make. (plan file, confidence, how it was made); a
    PlanningError when the budget cannot hold the mission at that confidence."""
    replanner = Replanner(mission, held, confidence=confidence, spec=spec, once=True)
    p = replanner.confidence
    if stated_confidence(replanner.plan) == p:
        return held, p, f"the plan as given, planned at confidence {p:g}"
    try:
        result = replanner.at_launch(held)
    except PlanningError as err:
        raise PlanningError(f"before launch: {err}") from None
    chain = make_updates(held, result.target, key, max_updates=LAUNCH_UPDATES,
                         check=lambda data: read_plan_bytes(data, mission))
    return chain.plan_file, p, (f"the plan replanned before launch at confidence {p:g} "
                                "(the shore's model, the prior figures)")


class PythonVehicle:
    """The Python executor's side of the link: it holds the plan file in force and the
    key, applies an update as the runtime does and flies the new plan from the next
    tick."""

    def __init__(self, executor, held: bytes, key: bytes,  # noqa: ANN001
                 mission: ir.CheckedMission, check=None) -> None:  # noqa: ANN001
        self.executor, self.held, self.key, self.mission = executor, held, key, mission
        self.check = check or (lambda data: read_plan_bytes(data, mission))

    def deliver(self, update: bytes) -> tuple[UpdateStatus, int, str]:
        applied = apply_update(self.held, update, self.key, check=self.check)
        if applied.status == UpdateStatus.APPLIED:
            self.held = applied.plan_file
            self.executor.adopt_plan(read_plan_bytes(applied.plan_file, self.mission))
        return applied.status, applied.seq, applied.message


def surfacing_hook(shore: ShoreLoop, deliver: Callable[[bytes], tuple[UpdateStatus, int, str]],
                   battery_j: float) -> SurfacingHook:
    """The flight's surfacing hook (`sim.loop.simulate`'s, `sim.cflight.CFlight.fly`'s): the
    counter's last reading (of a battery of `battery_j` [J]: the report is of when it was
    read out) and the glider's position into the shore's report, each update it sends
    delivered to the vehicle and its verdict noted for the next report."""

    def surfaced(at: Surfaced) -> None:
        used = battery_j - at.left_j
        if not math.isfinite(used):
            return
        for update in shore.at_surfacing(at.read_tick, at.columns, used, at.lat_deg,
                                         at.lon_deg):
            shore.acknowledged(*deliver(update))

    return surfaced

"""gliderplan.planner: the power-aware planner. From a checked mission, the power models
and a battery budget it chooses sensor duty cycles, flight-profile shares, transit speed
and the computer's clock (one convex cvxpy model, Clarabel), and writes the plan file and
its report. Entry points: `make_plan` and `sweep_mission` (the `gliderplan plan` command),
`plan.plan_mission` (the plan without files); see README.md."""

from gliderplan.planner.make import Sweep, make_plan, sweep_mission

__all__ = ["Sweep", "make_plan", "sweep_mission"]

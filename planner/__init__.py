"""gliderplan.planner: the power-aware planner. From a checked mission, the power models
and a battery budget it chooses sensor duty cycles, flight-profile shares, transit speed
and the computer's clock (one convex cvxpy model, Clarabel), and writes the plan file and
its report. Entry point: `gliderplan.planner.plan.plan_mission`; see README.md."""

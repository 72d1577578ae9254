"""gliderplan.sim: the glider simulator.

A run is a closed loop, lock-step on the simulator's clock (loop.py): each tick the
science computer (science.py) fills the sensor array from the simulated glider
(vehicle.py) in a simulated ocean (ocean.py) and sends it to a runtime, which answers
with a COMMAND that the glider flies for one tick. The runtime is the compiled C
runtime's own step in this process (cstep.py, step.c; by default, with the glider, its
science computer and its battery in C too: cflight.py, flight.c), the Python reference
executor (executor.py, pilot.py, compiled.py: language/semantics.py plus the library
routines of docs/pilot.md) or the compiled C runtime over a pseudo-terminal
(emulator.py). energy.py integrates every component's energy over the run and checks
it against the plan, whose file carries the prediction (`planner.planfile.Plan`: the
simulator never plans); outputs.py and plots.py write a run's
files; flight.py flies one run. `run_mission` (run.py) is the whole pipeline of
`gliderplan sim` as one Python call:

    from gliderplan.language import check_file
    from gliderplan.sim import run_mission
    result = run_mission(check_file("fig2.mission").checked(), "run", plan_path="fig2.plan")
    result.check.verdict          # "pass", "over prediction", "violation" or "no plan"

montecarlo.py flies a mission in many scenarios drawn by scenarios.py (ocean, model
figures, battery), on the executors of backends.py (this process, a process pool, Dask).
"""

from gliderplan.sim.run import RunResult, run_mission

__all__ = ["RunResult", "run_mission"]

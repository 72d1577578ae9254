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
files; flight.py flies one run. setup.py builds a flight's set-up once (vehicle, water,
plan and budget, runtime, faults) from the user's options; `run_mission` (run.py) flies
one and is the whole pipeline of `gliderplan sim` as one Python call:

    from gliderplan.language import check_file
    from gliderplan.sim import FlightOptions, flight_setup, run_mission
    mission = check_file("fig2.mission").checked()
    result = run_mission(flight_setup(mission, FlightOptions(plan_path="fig2.plan")), "run")
    result.check.verdict          # "pass", "over prediction", "violation" or "no plan"

montecarlo.py flies a mission in many scenarios drawn by scenarios.py (ocean, model
figures, battery), on the executors of backends.py (this process, a process pool, Dask).
"""

from gliderplan.sim.run import RunResult, run_mission
from gliderplan.sim.setup import FlightOptions, FlightSetup, flight_setup

__all__ = ["FlightOptions", "FlightSetup", "RunResult", "flight_setup", "run_mission"]

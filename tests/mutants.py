"""`make mutants`: plant each listed fault, one at a time, in each implementation of the
tick (the Python reference executor, the runtime's C step), run the differential and
unit tests against it, and say whether they caught it.

    .venv/bin/python tests/mutants.py [--batches 10] [NAME ...]

One line per mutant: `caught` (a test failed) or `survived` (all passed); the exit status
is 1 if any survived. Each fault is a replacement of one exact piece of source text,
applied in place and always put back (the file is rewritten as it was, even on Ctrl-C);
a replacement that no longer matches its file is an error (exit 2), not a survivor.
The tests: the generated differential test (tests/test_step_generated.py, --batches of
8 missions, no shrinking), and the implementation's unit tests (the reference's
semantics and executor tests; the runtime's own C unit tests).
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import NamedTuple

REPO = Path(__file__).resolve().parents[1]


class Mutant(NamedTuple):
    name: str
    implementation: str  # "python" or "c"
    path: str  # relative to the repository
    original: str
    mutated: str


MUTANTS = (
    Mutant("goto keeps the stack", "python", "language/semantics.py",
           "after = Machine(event.target, (), variables)",
           "after = Machine(event.target, stack, variables)"),
    Mutant("goto keeps the stack", "c", "runtime/src/gp_machine.c",
           "    case GP_ACT_GOTO:\n        m->depth = 0;\n",
           "    case GP_ACT_GOTO:\n"),
    Mutant("return resumes the wrong frame", "python", "language/semantics.py",
           "after = Machine(stack[-1], stack[:-1], variables)",
           "after = Machine(stack[0], stack[:-1], variables)"),
    Mutant("return resumes the wrong frame", "c", "runtime/src/gp_machine.c",
           "m->state = m->stack[--m->depth];",
           "m->state = m->stack[0];\n        --m->depth;"),
    Mutant("events evaluated in reverse order", "python", "sim/compiled.py",
           "for i, event in enumerate(state.events):",
           "for i, event in reversed(list(enumerate(state.events))):"),
    Mutant("events evaluated in reverse order", "c", "runtime/src/gp_machine.c",
           "for (int i = 0; i < state->n_events; i++) {\n"
           "        if (state->events[i].condition(sensors, m->vars)) {",
           "for (int i = state->n_events - 1; i >= 0; i--) {\n"
           "        if (state->events[i].condition(sensors, m->vars)) {"),
    # the state entered sees the variables before the event's `set`
    Mutant("set applied after the transition", "python", "sim/executor.py",
           "            self.machine = after\n            self.event_count += 1\n"
           "            if fired is not None:\n                transition = fired\n"
           "                self._follow(fired.kind, after.state)\n",
           "            self.event_count += 1\n"
           "            if fired is not None:\n                transition = fired\n"
           "                self._follow(fired.kind, after.state)\n"
           "            self.machine = after\n"),
    Mutant("set applied after the transition", "c", "runtime/src/gp_machine.c",
           "    if (event->assign) {\n        event->assign(sensors, m->vars);\n    }\n"
           "    m->event_count++;\n",
           "    m->event_count++;\n"),
    Mutant("set applied after the transition", "c", "runtime/src/gp_machine.c",
           "    out->to = m->state;\n    out->depth = m->depth;\n",
           "    if (event->assign) {\n        event->assign(sensors, m->vars);\n    }\n"
           "    out->to = m->state;\n    out->depth = m->depth;\n"),
    Mutant("the route's waypoint count not restored on return", "python", "sim/executor.py",
           "self.route.k, self.route.reached = k, reached",
           "self.route.k = k"),
    Mutant("the route's waypoint count not restored on return", "c",
           "runtime/src/gp_runtime.c",
           "                rt->route.reached = rt->reached_resume[rt->machine.depth];\n",
           ""),
)

UNIT_TESTS = {"python": ["tests/test_semantics.py", "tests/test_sim_executor.py"],
              "c": ["tests/test_sim_cstep.py"]}


def planted(mutants: list[Mutant]) -> list[tuple[Path, str]]:
    """Apply `mutants` (the parts of one fault) in place; the files' original texts."""
    kept: dict[Path, str] = {}
    for mutant in mutants:
        path = REPO / mutant.path
        current = path.read_text()
        kept.setdefault(path, current)
        if current.count(mutant.original) != 1:
            restore(list(kept.items()))
            sys.exit(f"mutants: {mutant.name} ({mutant.implementation}): its text occurs "
                     f"{current.count(mutant.original)} times in {mutant.path}, not once")
        path.write_text(current.replace(mutant.original, mutant.mutated))
    return list(kept.items())


def restore(originals: list[tuple[Path, str]]) -> None:
    for path, text in originals:
        path.write_text(text)


def caught(implementation: str, batches: int) -> bool:
    """Whether the tests fail with the fault planted."""
    env = {**os.environ, "GLIDERPLAN_MUTANT": "1", "GLIDERPLAN_GENERATED_BATCHES": str(batches)}
    tests = ["tests/test_step_generated.py", *UNIT_TESTS[implementation]]
    done = subprocess.run([sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
                           *tests], cwd=REPO, env=env, capture_output=True, text=True)
    if implementation == "c" and done.returncode == 0:
        with tempfile.TemporaryDirectory() as build:  # the runtime's own unit tests
            done = subprocess.run(["make", "-s", "-C", str(REPO / "runtime"), "test",
                                   f"BUILD={build}"], capture_output=True, text=True)
    return done.returncode != 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--batches", type=int, default=25,
                        help="batches of 8 generated missions per mutant (default 25)")
    parser.add_argument("names", nargs="*", help="only the mutants so named")
    args = parser.parse_args(argv)
    # a termination (a timeout's SIGTERM) unwinds like Ctrl-C: the planted file is put back
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    faults: dict[tuple[str, str], list[Mutant]] = {}
    for mutant in MUTANTS:
        if not args.names or mutant.name in args.names:
            faults.setdefault((mutant.name, mutant.implementation), []).append(mutant)
    survived = 0
    for (name, implementation), parts in faults.items():
        originals = planted(parts)
        try:
            verdict = caught(implementation, args.batches)
        finally:
            restore(originals)
        survived += not verdict
        label = "the Python reference" if implementation == "python" else "the C step"
        print(f"{'caught' if verdict else 'survived'}: {name} ({label})", flush=True)
    return 1 if survived else 0


if __name__ == "__main__":
    sys.exit(main())

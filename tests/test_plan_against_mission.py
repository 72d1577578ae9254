"""A plan that contradicts its mission is refused wherever it enters, signed or not: `sim`
(the Python reader, `contract.plan_check`) and `compile` (the runtime's own reader at
start, `gp_plan_check`) refuse the same plans with the same words, naming the line, the
field and the reason. Each case is one a user could make: a hand edit re-checksummed (and
re-signed), or a plan made for other hardware."""

from __future__ import annotations

import re
import zlib
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.planner.signing import read_key, sign_plan

MISSION = Path(__file__).resolve().parents[1] / "examples" / "fig2_annotated.mission"


@pytest.fixture(scope="module")
def made(tmp_path_factory) -> Path:
    """The planner's plan of the annotated Fig. 2 (budget 1.2 kWh less 15 %)."""
    folder = tmp_path_factory.mktemp("plan")
    assert main(["plan", str(MISSION), "-o", str(folder / "fig2.plan")]) == 0
    return folder / "fig2.plan"


def edited(plan: bytes, old: str, new: str) -> bytes:
    """`plan` with its first `old` replaced by `new` and its checksum made right again."""
    body = plan[: plan.rindex(b"crc32 ")]
    assert old.encode() in body, old
    body = body.replace(old.encode(), new.encode(), 1)
    return body + f"crc32 {zlib.crc32(body):08x}\n".encode()


def line_of(plan: bytes, start: str) -> int:
    """The number of the first line of `plan` that starts with `start`."""
    return next(i for i, line in enumerate(plan.decode().splitlines(), 1)
                if line.startswith(start))


def s1_profile(plan: bytes) -> str:
    """State s1's profile line: `profile 0 SHARE PITCH BALLAST SPEED`."""
    return next(line for line in plan.decode().splitlines()[line_of(plan, "state s1"):]
                if line.startswith("profile "))


def with_profile(plan: bytes, pitch: str | None = None, ballast: str | None = None,
                 speed: str | None = None) -> bytes:
    """`plan` with s1's profile flown at another pitch, ballast or speed."""
    old = s1_profile(plan)
    fields = old.split(" ")
    for i, value in ((3, pitch), (4, ballast), (5, speed)):
        fields[i] = value or fields[i]
    return edited(plan, old, " ".join(fields))


def predicted(plan: bytes) -> str:
    return re.search(rb"\npredicted_j (\S+)\n", plan)[1].decode()


# (id, how the plan is made from the planner's, the line it is refused at, the message)
CASES = [
    ("predicted 0", lambda p: edited(p, f"predicted_j {predicted(p)}", "predicted_j 0"),
     "predicted_j", r"predicted_j 0 J is not the sum of its states' energy \(16650.5 J\)"),
    ("predicted above the budget",
     lambda p: edited(p, "budget_j 3672000", "budget_j 10000"), "predicted_j",
     r"predicted_j 16650.5 J exceeds budget_j 10000 J"),
    ("budget 1e10 J on 1.2 kWh",
     lambda p: edited(p, "budget_j 3672000", "budget_j 1e10"), "budget_j",
     r"budget_j 1e\+10 J exceeds the mission's battery less its reserve \(3.672e\+06 J\)"),
    ("2 m/s at the mission's pitch and ballast", lambda p: with_profile(p, speed="2"),
     "state s1", r"state s1: profile 0: SPEED_MPS 2 exceeds the vehicle's fastest glide "
     r"\(0.342904 m/s\)"),
    ("temp off against require duty >= 0.5",
     lambda p: edited(p, "sensor temp 300 300\nsensor oxygen", "sensor temp 300 0\nsensor oxygen"),
     "state s2", r"state s2: sensor temp: duty 0 outside the mission's \[0.5, 1\]"),
    ("oxygen at full duty against duty <= 0.8",
     lambda p: edited(p, "sensor oxygen 300 240", "sensor oxygen 300 300"), "state s2",
     r"state s2: sensor oxygen: duty 1 outside the mission's \[0, 0.8\]"),
    ("pitch 1.5707 rad", lambda p: with_profile(p, pitch="1.5707"), "state s1",
     r"state s1: profile 0: PITCH_RAD 1.5707 outside the vehicle's \(0.0386372, 1.56312\) rad"),
    ("ballast 1e-6 cc", lambda p: with_profile(p, ballast="0.000001"), "state s1",
     r"state s1: profile 0: BALLAST_CC 1e-06 does not fly it: the vehicle needs more than "
     r"119.016 cc"),
    ("level flight on a glider", lambda p: with_profile(p, pitch="0", ballast="0"), "state s1",
     r"state s1: profile 0: PITCH_RAD and BALLAST_CC 0 fly it level on a propeller, and the "
     r"vehicle has none"),
    ("a thrust on a glider", lambda p: edited(p, s1_profile(p), s1_profile(p) + " 4.5"),
     "state s1", r"state s1: profile 0: THRUST_W 4.5 on a vehicle without a thruster"),
]
MADE_FOR_OTHER_HARDWARE = [
    ("TS-5500 plan on a TS-7800 mission", ["--computer", "ts5500"], "computer",
     r"computer ts5500: the mission flies on board ts7800 \(plan again with --computer "
     r"ts7800\)"),
    ("10 kWh plan on a 1.2 kWh mission", ["--battery", "10kWh"], "budget_j",
     r"budget_j 3.06e\+07 J exceeds the mission's battery less its reserve \(3.672e\+06 J\)"),
]


def refused(tmp_path: Path, command: str, plan: bytes, *extra: str) -> tuple[int, Path, Path]:
    """Run `sim` or `compile` of the mission on `plan`: (exit code, plan file, output folder)."""
    path = tmp_path / "edited.plan"
    path.write_bytes(plan)
    out = tmp_path / "out"
    code = main([command, str(MISSION), "--plan", str(path), *extra, "-o", str(out)])
    return code, path, out


def assert_refused(capsys, code: int, path: Path, out: Path, command: str, line: int,
                   message: str) -> None:
    err = capsys.readouterr().err.strip().splitlines()
    assert code == ExitCode.BAD_INPUT and len(err) == 1, err
    # the Python reader says file:line:, the runtime "file line N:"; the rest word for word
    where = rf"{re.escape(str(path))}:{line}: " if command == "sim" \
        else rf"{re.escape(str(path))} line {line}: "
    assert re.search(f"plan rejected: .*{where}{message}$", err[0]), err[0]
    assert not (out / "summary.json").exists() and not (out / "sampleMission").exists()


@pytest.mark.parametrize("command", ["sim", "compile"])
@pytest.mark.parametrize(("edit", "field", "message"), [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_an_edited_plan_is_refused_naming_the_field(made, tmp_path, capsys, command, edit,
                                                    field, message):
    plan = edit(made.read_bytes())
    code, path, out = refused(tmp_path, command, plan)
    assert_refused(capsys, code, path, out, command, line_of(plan, field), message)


@pytest.mark.parametrize("command", ["sim", "compile"])
@pytest.mark.parametrize(("options", "field", "message"),
                         [c[1:] for c in MADE_FOR_OTHER_HARDWARE],
                         ids=[c[0] for c in MADE_FOR_OTHER_HARDWARE])
def test_a_plan_made_for_other_hardware_is_refused(tmp_path, capsys, command, options, field,
                                                  message):
    made = tmp_path / "other.plan"
    assert main(["plan", str(MISSION), *options, "-o", str(made)]) == 0
    capsys.readouterr()
    plan = made.read_bytes()
    code, path, out = refused(tmp_path, command, plan)
    assert_refused(capsys, code, path, out, command, line_of(plan, field), message)


@pytest.mark.parametrize("command", ["sim", "compile"])
def test_a_signature_does_not_make_an_insane_plan_fly(made, tmp_path, capsys, command):
    """Signed with the vehicle's own key, a hand edit is still held to the mission: the
    signature says who made the plan, not that it is sane."""
    key = tmp_path / "vehicle.key"
    assert main(["keygen", "-o", str(key)]) == 0
    plan = sign_plan(edited(made.read_bytes(), "budget_j 3672000", "budget_j 1e10"),
                     read_key(key), 7)
    capsys.readouterr()
    code, path, out = refused(tmp_path, command, plan, "--key", str(key))
    assert_refused(capsys, code, path, out, command, line_of(plan, "budget_j"),
                   r"budget_j 1e\+10 J exceeds the mission's battery less its reserve "
                   r"\(3.672e\+06 J\)")


def test_the_planners_own_plan_flies_and_builds(made, tmp_path):
    assert main(["sim", str(MISSION), "--plan", str(made), "-o", str(tmp_path / "run")]) == 0
    assert main(["compile", str(MISSION), "--plan", str(made), "-o", str(tmp_path / "b")]) == 0

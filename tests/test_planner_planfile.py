"""The plan file: exact bytes per docs/plan-format.md, CRC-32, strict reading, round trip."""

from __future__ import annotations

import re
import zlib
from pathlib import Path

import pytest

from gliderplan.contract import ExitCode
from gliderplan.language import check_source
from gliderplan.language.source import read_mission
from gliderplan.planner.plan import plan_mission
from gliderplan.planner.planfile import (
    PlanFileError,
    number,
    plan_file_of,
    read_plan_bytes,
    read_plan_file,
    write_plan_bytes,
)

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ["examples/fig2.mission", "examples/fig2_annotated.mission",
            "examples/thermocline_survey.mission", "tests/missions/planner_separable.mission",
            "tests/missions/planner_transit.mission"]


def mission(path: str):
    return check_source(read_mission(str(ROOT / path)), path, None).mission


@pytest.fixture(scope="module")
def annotated():
    m = mission("examples/fig2_annotated.mission")
    return m, plan_mission(m)


@pytest.mark.parametrize("path", EXAMPLES)
def test_bytes_follow_the_format(path):
    m = mission(path)
    data = write_plan_bytes(plan_mission(m))
    assert data.endswith(b"\n") and b"\r" not in data and b"\t" not in data
    assert all(0x20 <= b <= 0x7E or b == 0x0A for b in data)
    lines = data.decode("ascii").split("\n")[:-1]
    assert all(0 < len(line) + 1 <= 255 and "  " not in line and line == line.strip()
               for line in lines)
    assert lines[:2] == ["GPPLAN 1", f"mission {m.name}"]
    assert lines[2] == f"hash {m.hash}"
    assert lines[6] == f"states {len(m.states)}"
    assert [line.split()[1] for line in lines if line.startswith("state ")] == \
        [s.name for s in m.states]
    body = data[: data.rindex(b"crc32 ")]
    assert lines[-1] == f"crc32 {zlib.crc32(body):08x}"
    number_re = re.compile(r"-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?\Z")
    for line in lines:
        if line.startswith(("sensor ", "profile ", "budget_j ", "predicted_j ")):
            assert all(number_re.match(f) for f in line.split()[2 if line[0] == "s" else 1:])


@pytest.mark.parametrize("path", EXAMPLES)
def test_round_trip_gives_the_same_plan(path):
    plan = plan_mission(mission(path))
    assert read_plan_bytes(write_plan_bytes(plan)) == plan_file_of(plan)


def test_sensor_lines_realise_the_duties(annotated):
    _, plan = annotated
    contents = read_plan_bytes(write_plan_bytes(plan))
    for state, block in zip(plan.states, contents.states, strict=True):
        assert [s.name for s in block.sensors] == [s.name for s in state.sensors]
        for planned, line in zip(state.sensors, block.sensors, strict=True):
            assert line.on_s / line.period_s == pytest.approx(planned.duty, abs=1e-8)


def test_numbers_have_nine_significant_digits():
    assert number(1 / 3) == "0.333333333"
    assert number(180000.0) == "180000"
    assert number(1.5e-7) == "1.5e-7"
    assert number(-0.0) == "0"
    with pytest.raises(ValueError):
        number(float("nan"))


def _mutate(data: bytes, old: bytes, new: bytes, fix_crc: bool = True) -> bytes:
    assert old in data
    data = data.replace(old, new, 1)
    if fix_crc:
        body = data[: data.rindex(b"crc32 ")]
        data = body + f"crc32 {zlib.crc32(body):08x}\n".encode()
    return data


@pytest.mark.parametrize("old,new,line,message", [
    (b"GPPLAN 1", b"GPPLAN 2", 1, "version"),
    (b"mission sampleMission", b"mission 9bad", 2, "NAME"),
    (b"budget_j ", b"budget_j  ", 5, "one space"),
    (b"states 3", b"states 65", 7, "out of range"),
    (b"\nend\n", b"\nend \n", 11, "one space"),
    (b"sensor temp 300 300", b"sensor temp 300 301", 9, "ON_S"),
    (b"profile 0 1 ", b"profile 0 0.5 ", 10, "sum to"),
    (b"profile 0 1 ", b"profile 1 1 ", 10, "out of order"),
    (b"computer ts7800 300", b"computer ts7800 inf", 4, "NUMBER"),
    (b"budget_j ", b"budget_j -", 5, "budget_j must be >= 0"),
    (b"predicted_j ", b"predicted_j -", 6, "predicted_j must be >= 0"),
    (b"\nend\n", b"\nfin\n", 11, "expected 'end'"),
    (b"sensor temp 300 300", b"sensor temp 300", 9, "3 fields"),
])
def test_reader_rejects_and_names_the_line(annotated, old, new, line, message):
    _, plan = annotated
    data = _mutate(write_plan_bytes(plan), old, new)
    with pytest.raises(PlanFileError, match=message) as info:
        read_plan_bytes(data)
    assert info.value.line == line


def test_reader_rejects_checksum_truncation_and_bad_bytes(annotated):
    _, plan = annotated
    data = write_plan_bytes(plan)
    with pytest.raises(PlanFileError, match="checksum"):
        read_plan_bytes(_mutate(data, b"sensor temp 300 300", b"sensor temp 300 299", False))
    with pytest.raises(PlanFileError, match="no LF"):
        read_plan_bytes(data[:-1])
    with pytest.raises(PlanFileError, match="file ends"):
        read_plan_bytes(data[: data.rindex(b"crc32 ")])
    with pytest.raises(PlanFileError, match="0x0d"):
        read_plan_bytes(data.replace(b"\n", b"\r\n", 1))
    with pytest.raises(PlanFileError, match="extra line"):
        read_plan_bytes(data + b"end\n")
    with pytest.raises(PlanFileError, match="more than 65536"):
        read_plan_bytes(data + b"x" * 70000)


def test_read_plan_file_checks_the_mission(tmp_path, annotated):
    m, plan = annotated
    path = tmp_path / "a.plan"
    path.write_bytes(write_plan_bytes(plan))
    assert read_plan_file(path, m).mission == m.name
    other = mission("examples/fig2.mission")  # same name and states, another hash
    with pytest.raises(PlanFileError, match="hash") as info:
        read_plan_file(path, other)
    assert str(info.value).startswith(f"{path}:3:")
    with pytest.raises(PlanFileError, match="missing.plan: no such file") as info:
        read_plan_file(tmp_path / "missing.plan")
    assert info.value.exit_code == ExitCode.USAGE


@pytest.mark.parametrize("path", EXAMPLES)
def test_the_simulators_reader_accepts_our_files(tmp_path, path):
    from gliderplan.sim.planfile import read_plan

    m = mission(path)
    plan = plan_mission(m)
    out = tmp_path / "x.plan"
    out.write_bytes(write_plan_bytes(plan))
    theirs = read_plan(out, m)
    assert [s.name for s in theirs.states] == [s.name for s in plan.states]

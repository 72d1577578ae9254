"""The plan file: exact bytes per docs/plan-format.md, CRC-32, strict reading, round trip."""

from __future__ import annotations

import re
import zlib
from dataclasses import replace
from pathlib import Path

import pytest

from gliderplan.contract import VEHICLE_COMPONENTS, Component, ExitCode
from gliderplan.contract.files import InputFileError
from gliderplan.language import check_source
from gliderplan.language.source import read_mission
from gliderplan.planner.plan import plan_mission
from gliderplan.planner.planfile import (
    Assumption,
    PlanFileError,
    number,
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
    return m, plan_mission(m).plan


@pytest.mark.parametrize("path", EXAMPLES)
def test_bytes_follow_the_format(path):
    m = mission(path)
    data = write_plan_bytes(plan_mission(m).plan)
    assert data.endswith(b"\n") and b"\r" not in data and b"\t" not in data
    assert set(data) <= {*range(0x20, 0x7F), 0x0A}  # printable ASCII and LF
    lines = data.decode("ascii").split("\n")[:-1]
    assert all(0 < len(line) + 1 <= 255 and "  " not in line and line == line.strip()
               for line in lines)
    assert lines[:2] == ["GPPLAN 3", f"mission {m.name}"]
    assert lines[2] == f"hash {m.hash}"
    assert f"states {len(m.states)}" in lines
    assert [line.split()[1] for line in lines if line.startswith("state ")] == \
        [s.name for s in m.states]
    body = data[: data.rindex(b"crc32 ")]
    assert lines[-1] == f"crc32 {zlib.crc32(body):08x}"
    number_re = re.compile(r"-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?\Z")
    for line in lines:
        if line.startswith(("sensor ", "profile ", "budget_j ", "predicted_j ", "predict ",
                            "energy ")):
            assert all(number_re.match(f) for f in line.split()[2 if line[0] == "s" else 1:])


@pytest.mark.parametrize("path", EXAMPLES)
def test_round_trip_gives_the_same_plan(path):
    m = mission(path)
    plan = plan_mission(m).plan
    assert read_plan_bytes(write_plan_bytes(plan), m) == plan


def test_the_file_alone_carries_the_prediction(annotated):
    m, plan = annotated
    back = read_plan_bytes(write_plan_bytes(plan), m)
    shared = len(VEHICLE_COMPONENTS) + 1
    assert back.components[:shared] == (*VEHICLE_COMPONENTS, Component.COMPUTER)
    assert set(back.components[shared:]) == {"ctd", "optode"}  # the devices the mission logs
    for state in back.states:
        assert state.time_s > 0 and state.visits >= 1 and state.inflections > 0
        assert state.energy_by_component_j[Component.HOTEL] > 0
    assert sum(s.energy_j for s in back.states) == pytest.approx(back.predicted_j, rel=1e-8)
    assert back.budget_j == plan.budget_j > back.predicted_j


def test_assumptions_travel_in_the_file_with_their_subject():
    m = mission("examples/fig2.mission")  # unannotated: the defaults are assumptions
    plan = plan_mission(m).plan
    assert Assumption("mission", "vehicle slocum_g2_shallow (default)") in plan.assumptions
    assert read_plan_bytes(write_plan_bytes(plan)).assumptions == plan.assumptions
    assert Assumption.from_note("s2: planned at its expect upper bound (60 s per visit)") == \
        Assumption("s2", "planned at its expect upper bound (60 s per visit)")
    assert str(Assumption.from_note("no sensor is marked `duty auto`: every sensor runs")) == \
        "no sensor is marked `duty auto`: every sensor runs"
    accented = replace(plan, assumptions=(Assumption("s1", "d\u00e9faut"),))
    with pytest.raises(PlanFileError, match="no plan file can carry this plan"):
        write_plan_bytes(accented)


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
    (b"GPPLAN 3", b"GPPLAN 2", 1, "version"),
    (b"mission sampleMission", b"mission 9bad", 2, "NAME"),
    (b"budget_j ", b"budget_j  ", 5, "one space"),
    (b"components hotel pump", b"components hotel hotel", 7, "named twice"),
    # two assumptions (lines 9, 10): the tracking band s2 is planned at, and sebastian's
    # hotel load holding the CTD
    (b"assumptions 2", b"assumptions 3", 11, "expected 'assume'"),
    (b"states 3", b"states 65", 11, "out of range"),
    (b"predict 1000 2", b"predict -1000 2", 13, "predicted time must be >= 0"),
    (b"predict 1000 2", b"predict 1000 2.5", 13, "COUNT"),
    (b"energy 1373.64 ", b"energy ", 14, "takes 9 fields"),
    (b"energy 1373.64 ", b"energy -1373.64 ", 14, "energy of hotel must be >= 0"),
    (b"\nend\n", b"\nend \n", 17, "one space"),
    (b"sensor temp 300 300", b"sensor temp 300 301", 15, "ON_S"),
    (b"profile 0 1 ", b"profile 0 0.5 ", 16, "sum to"),
    (b"profile 0 1 ", b"profile 1 1 ", 16, "out of order"),
    (b"computer ts7800 300", b"computer ts7800 inf", 4, "NUMBER"),
    (b"budget_j ", b"budget_j -", 5, "budget_j must be >= 0"),
    (b"predicted_j ", b"predicted_j -", 6, "predicted_j must be >= 0"),
    (b"\nend\n", b"\nfin\n", 17, "expected 'end'"),
    (b"sensor temp 300 300", b"sensor temp 300", 15, "3 fields"),
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
    with pytest.raises(InputFileError, match="missing.plan: no such file") as info:
        read_plan_file(tmp_path / "missing.plan")
    assert info.value.exit_code == ExitCode.USAGE


@pytest.mark.parametrize("path", EXAMPLES)
def test_our_files_fit_their_mission(tmp_path, path):
    m = mission(path)
    plan = plan_mission(m).plan
    out = tmp_path / "x.plan"
    out.write_bytes(write_plan_bytes(plan))
    assert read_plan_file(out, m) == plan

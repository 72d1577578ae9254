"""`gliderplan fmt`: a canonical layout that keeps the mission's meaning and its comments."""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gliderplan.cli.main import main
from gliderplan.language import check_source
from gliderplan.language.formatter import FormatError, format_source
from gliderplan.language.parser import parse

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
MISSIONS = sorted(EXAMPLES.glob("*.mission"))


def _comments(text: str) -> list[str]:
    return sorted(m.group().rstrip() for m in re.finditer(r"(#|//)[^\n]*", text))


@pytest.mark.parametrize("path", MISSIONS, ids=lambda p: p.name)
def test_examples_keep_meaning_comments_and_hash(path):
    source = path.read_text()
    formatted = format_source(source)
    assert format_source(formatted) == formatted
    assert parse(formatted) == parse(source)
    assert _comments(formatted) == _comments(source)
    assert check_source(formatted).mission.hash == check_source(source).mission.hash


def test_canonical_layout():
    source = ("mission   m # why\nvar x=1\nstate s1 begin flightprofile yo(5,20,.454,.454)\n"
              "sensors depth,temp duty auto events case depth>3&&!(x<2) set x=-x*(2+3) exit end\n")
    assert format_source(source) == (
        "mission m  # why\n"
        "\n"
        "var x = 1\n"
        "\n"
        "state s1\n"
        "begin\n"
        "  flightprofile yo(5, 20, .454, .454)\n"
        "  sensors depth, temp duty auto\n"
        "  events\n"
        "    case depth > 3 && !(x < 2) set x = -x * (2 + 3) exit\n"
        "end\n"
    )


def test_fmt_keeps_a_yo_s_altimeter_stop():
    source = ("mission m\nstate s1 begin flightprofile yo(3,50,.405,.405,4)|"
              "thermotrackyo(3,50,.4,.4,2,6,  4.5) sensors depth events case depth>60 exit end\n")
    formatted = format_source(source)
    assert "flightprofile yo(3, 50, .405, .405, 4) | thermotrackyo(3, 50, .4, .4, 2, 6, 4.5)" \
        in formatted
    assert check_source(formatted).mission.hash == check_source(source).mission.hash


def test_comments_inside_a_statement_move_before_it():
    source = ("mission m\nstate s1\n# before begin\nbegin\n  flightprofile yo(5, 20,\n"
              "    # inside\n    .454, .454)\n  events\n    case depth > 3 &&  # mid\n"
              "      depth < 9 exit\n  # last\nend  # after\n\n# tail\n")
    formatted = format_source(source)
    assert formatted == (
        "mission m\n\nstate s1\n# before begin\nbegin\n"
        "  # inside\n  flightprofile yo(5, 20, .454, .454)\n"
        "  events\n    # mid\n    case depth > 3 && depth < 9 exit\n"
        "  # last\nend  # after\n\n# tail\n")
    assert format_source(formatted) == formatted


def test_long_statements_are_broken_and_stay_stable():
    sensors = ", ".join(f"{s} duty auto" for s in ("temp", "oxygen", "chlorophyll",
                                                    "backscatter", "conductivity"))
    source = (f"mission m\nstate s1\nbegin\n  flightprofile yo(5, 20, .454, .454)\n"
              f"  sensors depth, {sensors}\n  events\n"
              "    case missiontime >= 100000 set a = missiontime + 900, "
              "b = missiontime + 21600 goto s1\nend\n")
    source = source.replace("mission m\n", "mission m\nvar a = 0\nvar b = 0\n")
    formatted = format_source(source)
    assert max(len(line) for line in formatted.splitlines()) <= 88
    assert format_source(formatted) == formatted
    assert parse(formatted) == parse(source)


# ---- generated missions ---------------------------------------------------------

_SENSORS = ["missiontime", "depth", "pitch", "temp", "oxygen"]
_NUMBER = st.sampled_from(["0", "1", "2.5", ".454", "10", "500", "1e3", "3."])
_COMMENT = st.sampled_from(["", "", "  # note", " // why"])
_SPACE = st.sampled_from([" ", "  ", "\n  ", " \n\n "])


def _expressions(names: list[str]) -> st.SearchStrategy[str]:
    atoms = st.one_of(_NUMBER, st.sampled_from(names))

    def extend(inner: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
        binary = st.tuples(inner, st.sampled_from(["+", "-", "*", "/", "<", ">=", "==", "&&",
                                                   "||"]), inner)
        return st.one_of(
            binary.map(lambda t: f"({t[0]} {t[1]} {t[2]})"),
            inner.map(lambda e: f"-({e})"),
            inner.map(lambda e: f"(!({e}))"),
            st.tuples(inner, inner).map(lambda t: f"max({t[0]}, {t[1]})"),
        )

    return st.recursive(atoms, extend, max_leaves=6)


@st.composite
def missions(draw) -> str:
    names = ["v"] + _SENSORS
    count = draw(st.integers(1, 4))
    states = [f"s{i}" for i in range(count)]
    space = draw(_SPACE)
    lines = [f"mission gen{draw(_COMMENT)}", f"var v ={space}{draw(_expressions(['v']))}"]
    if draw(st.booleans()):
        lines.append("battery 60 Ah at 14.4 V reserve 15 %" + draw(_COMMENT))
    if draw(st.booleans()):
        lines.append("sensor temp weight 3 duty >= 0.25" + draw(_COMMENT))
    for state in states:
        lines.append(f"state {state}{draw(_COMMENT)}")
        lines.append("begin")
        profiles = draw(st.lists(st.sampled_from(["yo(5, 20, .454, .454)", "surface",
                                                  "hover(v)", "yo(v, 30, .4, .5)"]),
                                 min_size=1, max_size=3))
        lines.append("  flightprofile " + " | ".join(profiles) + draw(_COMMENT))
        logged = draw(st.lists(st.sampled_from(_SENSORS), min_size=1, unique=True))
        lines.append("  sensors " + ", ".join(logged))
        lines.append("  events")
        for _ in range(draw(st.integers(0, 3))):
            condition = draw(_expressions(names))
            action = draw(st.sampled_from(["exit", "return", *(f"goto {s}" for s in states),
                                           *(f"call {s}" for s in states)]))
            assign = draw(st.sampled_from(["", f" set v = {draw(_expressions(names))}"]))
            lines.append(f"    case{space}{condition}{assign} {action}{draw(_COMMENT)}")
        lines.append("end")
    if draw(st.booleans()):
        lines.append("# the end")
    return "\n".join(lines) + "\n"


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(missions())
def test_fmt_round_trip_on_generated_missions(source):
    formatted = format_source(source)
    assert format_source(formatted) == formatted
    assert parse(formatted) == parse(source)
    assert _comments(formatted) == _comments(source)
    before, after = check_source(source), check_source(formatted)
    assert [d.message for d in after.diagnostics] == [d.message for d in before.diagnostics]
    if before.ok:
        assert after.mission.hash == before.mission.hash


# ---- the command ---------------------------------------------------------------


def test_fmt_prints_canonical_text(capsys):
    assert main(["fmt", str(EXAMPLES / "fig2.mission")]) == 0
    out = capsys.readouterr().out
    assert "  flightprofile thermotrackyo(5, 20, .454, .454, 10, 10)\n" in out


def test_fmt_check_lists_files_that_would_change(tmp_path, capsys):
    messy = tmp_path / "messy.mission"
    messy.write_text("mission m\nstate s begin flightprofile surface end\n")
    tidy = tmp_path / "tidy.mission"
    tidy.write_text(format_source(messy.read_text()))
    assert main(["fmt", "--check", str(messy), str(tidy)]) == 1
    out = capsys.readouterr().out
    assert f"{messy}: would be reformatted" in out
    assert str(tidy) not in out
    assert main(["fmt", "--check", str(tidy)]) == 0


def test_fmt_write_rewrites_in_place(tmp_path, capsys):
    path = tmp_path / "m.mission"
    path.write_text("mission m # keep me\nstate s begin flightprofile surface end\n")
    assert main(["fmt", "--write", str(path)]) == 0
    assert path.read_text() == "mission m  # keep me\n\nstate s\nbegin\n" \
                               "  flightprofile surface\nend\n"
    assert capsys.readouterr().out == ""


@pytest.mark.parametrize("mode", [0o600, 0o640, 0o755])
def test_fmt_write_keeps_a_link_a_link_and_the_file_its_permissions(tmp_path, mode):
    target = tmp_path / "missions" / "m.mission"
    target.parent.mkdir()
    target.write_text("mission m\nstate s begin flightprofile surface end\n")
    target.chmod(mode)
    link = tmp_path / "current.mission"
    link.symlink_to(Path("missions") / "m.mission")
    assert main(["fmt", "--write", str(link)]) == 0
    assert link.is_symlink() and os.readlink(link) == str(Path("missions") / "m.mission")
    assert target.read_text() == "mission m\n\nstate s\nbegin\n  flightprofile surface\nend\n"
    assert stat.S_IMODE(target.stat().st_mode) == mode
    assert sorted(p.name for p in target.parent.iterdir()) == ["m.mission"]  # no leftovers


def test_fmt_leaves_a_file_with_syntax_errors_alone(tmp_path, capsys):
    path = tmp_path / "bad.mission"
    source = "mission m\nstate s begin flightprofile surface\n"
    path.write_text(source)
    assert main(["fmt", "--write", str(path)]) == 1
    assert f"{path}:2:7: error: state 's' has no 'end'" in capsys.readouterr().err
    assert path.read_text() == source


def test_format_file_is_the_fmt_command_as_one_call(tmp_path):
    from gliderplan.contract import ExitCode
    from gliderplan.contract.files import InputFileError
    from gliderplan.language.diagnostics import MissionError
    from gliderplan.language.formatter import format_file

    path = tmp_path / "m.mission"
    path.write_text("mission m # keep me\nstate s begin flightprofile surface end\n")
    assert format_file(path) == (path.read_text(), format_source(path.read_text()))
    path.write_text("mission m\nstate s begin flightprofile surface\n")
    with pytest.raises(MissionError, match="does not parse") as bad:
        format_file(path)
    assert f"{path}:2:7: error: state 's' has no 'end'" in bad.value.details
    with pytest.raises(InputFileError) as missing:
        format_file(tmp_path / "none.mission")
    assert missing.value.exit_code == ExitCode.USAGE


@pytest.mark.parametrize("make", [lambda p: p, lambda p: p / "missing.mission"])
def test_fmt_bad_path_is_usage_error(tmp_path, capsys, make):
    assert main(["fmt", str(make(tmp_path))]) == 2
    assert "Traceback" not in capsys.readouterr().err


def test_fmt_check_and_write_together_is_usage_error(tmp_path):
    with pytest.raises(SystemExit) as exit_:
        main(["fmt", "--check", "--write", str(tmp_path / "m.mission")])
    assert exit_.value.code == 2


def test_too_deep_to_format_is_refused_not_a_crash():
    source = "mission m\nstate s begin flightprofile surface sensors depth events case " \
             + "-" * 400 + "depth > 1 exit end\n"
    with pytest.raises(FormatError, match="nested too deeply"):
        format_source(source)

"""Random and mutated input never crashes the front end: it gives diagnostics instead."""

from __future__ import annotations

from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gliderplan.cli.main import main
from gliderplan.language import check_source
from gliderplan.language.diagnostics import MissionSyntaxError
from gliderplan.language.formatter import FormatError, format_source

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
SOURCES = [p.read_text() for p in sorted(EXAMPLES.glob("*.mission"))]

VOCABULARY = [
    "mission", "state", "begin", "end", "events", "case", "goto", "call", "return", "exit",
    "set", "var", "sensor", "sensors", "flightprofile", "flightroute", "expect", "require",
    "vehicle", "computer", "battery", "horizon", "objective", "stack", "duty", "auto",
    "weight", "quality", "reserve", "at", "maximize", "minimize", "energy", "yo",
    "thermotrackyo", "nav", "noheading", "sweep", "waypoints", "surface", "hover",
    "missiontime", "depth", "temp", "s1", "s2", "x", "max", "abs", "0", "5", ".454", "1e400",
    "-7349.8", "(", ")", ",", "|", "..", "@", "%", "=", "==", ">=", "<", "&&", "||", "!", "+",
    "-", "*", "/", "kWh", "Ah", "V", "h", "min", "MHz", "\"b.toml\"", "#c", "\n", "\t", "é",
    ";",
]

_FUZZ = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _front_end_survives(source: str) -> None:
    result = check_source(source, "fuzz.mission")
    assert result.ok or any(d.is_error for d in result.diagnostics)
    result.render()  # rendering any diagnostic must work too
    try:
        format_source(source)
    except (MissionSyntaxError, FormatError):
        pass


# Prefixes that get the parser past the header, so the soup reaches deeper rules.
_PREFIXES = ["", "mission m\n", "mission m\nstate s1 begin flightprofile surface events case "]


@_FUZZ
@given(st.sampled_from(_PREFIXES), st.lists(st.sampled_from(VOCABULARY), max_size=80))
def test_token_soup(prefix, tokens):
    _front_end_survives(prefix + " ".join(tokens))


@_FUZZ
@given(st.text(max_size=300))
def test_random_text(source):
    _front_end_survives(source)


def mutated(source: str, data: st.DataObject) -> str:
    """The source with one to four of its space-separated words deleted, doubled or
    replaced by a word of the vocabulary."""
    tokens = source.split(" ")
    for _ in range(data.draw(st.integers(1, 4))):
        at = data.draw(st.integers(0, len(tokens) - 1))
        kind = data.draw(st.sampled_from(["delete", "duplicate", "replace"]))
        if kind == "delete":
            del tokens[at]
        elif kind == "duplicate":
            tokens.insert(at, tokens[at])
        else:
            tokens[at] = data.draw(st.sampled_from(VOCABULARY))
    return " ".join(tokens)


@_FUZZ
@given(st.sampled_from(SOURCES), st.data())
def test_mutated_examples(source, data):
    _front_end_survives(mutated(source, data))


@settings(max_examples=100, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(st.binary(max_size=300))
def test_random_bytes_through_the_command(tmp_path, capsys, data):
    path = tmp_path / "fuzz.mission"
    path.write_bytes(data)
    code = main(["check", str(path)])
    err = capsys.readouterr().err
    assert code in (0, 1), err
    assert "internal error" not in err
    assert "Traceback" not in err

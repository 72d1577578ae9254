"""Random and mutated input never crashes the front end: it gives diagnostics instead, each
error at a line and column of the source (only a file with no mission text in it at all
is refused as a whole), and a mission it accepts generates C or a clear CodegenError."""

from __future__ import annotations

import os
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gliderplan.cli.main import main
from gliderplan.contract import FlightLimits
from gliderplan.language import check_source
from gliderplan.language.codegen_c import generate_c
from gliderplan.language.diagnostics import Diagnostic, MissionSyntaxError
from gliderplan.language.formatter import FormatError, format_source
from gliderplan.language.syntax_errors import empty_file, is_blank
from gliderplan.power_models import load_vehicle

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

# Examples per test; a long run: GLIDERPLAN_FUZZ_EXAMPLES=20000 pytest tests/test_lang_fuzz.py
EXAMPLES_PER_TEST = int(os.environ.get("GLIDERPLAN_FUZZ_EXAMPLES", "200"))
_FUZZ = settings(max_examples=EXAMPLES_PER_TEST, deadline=None,
                 suppress_health_check=[HealthCheck.too_slow])


def _located(diagnostic: Diagnostic, source: str) -> bool:
    """At a line of the source (or just past its last line) and a column on it."""
    span = diagnostic.span
    return 1 <= span.line <= len(source.splitlines()) + 1 and span.column >= 1


def _front_end_survives(source: str) -> None:
    result = check_source(source, "fuzz.mission")
    errors = [d for d in result.diagnostics if d.is_error]
    assert result.ok == (not errors), result.diagnostics
    rendered = result.render()  # rendering any diagnostic must work too
    if is_blank(source):  # no mission at all: one error about the whole file
        assert [(d.message, d.span) for d in errors] == \
            [(empty_file(source).message, empty_file(source).span)]
    else:
        for d in errors:
            assert _located(d, source), d
            assert f"fuzz.mission:{d.span.line}:{d.span.column}: error: " in rendered
    if result.ok:  # check accepts nothing the code generator refuses
        generate_c(result.mission, FlightLimits(200.0, 233.0, (300.0,),
                                                  envelope=load_vehicle("slocum_g2_shallow")
                                                  .envelope))
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


# Characters that, put into an example, give half-typed words, a stray quote or bracket,
# a number cut short: the lexer's and the checker's corners.
_CHARACTERS = list("()|,.:;\"'#@%=<>!&+-*/0519eE\n\t x")


def _edited(pieces: list[str], data: st.DataObject, most: int, alphabet: list[str]) -> list[str]:
    """`pieces` after 1..`most` random edits: one deleted or doubled, or one of `alphabet`
    inserted or put in its place."""
    for _ in range(data.draw(st.integers(1, most))):
        at = data.draw(st.integers(0, len(pieces) - 1))
        kind = data.draw(st.sampled_from(["delete", "duplicate", "insert", "replace"]))
        if kind == "delete":
            del pieces[at]
        elif kind == "duplicate":
            pieces.insert(at, pieces[at])
        elif kind == "insert":
            pieces.insert(at, data.draw(st.sampled_from(alphabet)))
        else:
            pieces[at] = data.draw(st.sampled_from(alphabet))
    return pieces


def mutated(source: str, data: st.DataObject) -> str:
    """The source with one to four of its space-separated words deleted or doubled, or a
    word of the vocabulary inserted or put in a word's place."""
    return " ".join(_edited(source.split(" "), data, 4, VOCABULARY))


@_FUZZ
@given(st.sampled_from(SOURCES), st.data())
def test_mutated_examples(source, data):
    _front_end_survives(mutated(source, data))


@_FUZZ
@given(st.sampled_from(SOURCES), st.data())
def test_examples_with_characters_edited(source, data):
    _front_end_survives("".join(_edited(list(source), data, 6, _CHARACTERS)))


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

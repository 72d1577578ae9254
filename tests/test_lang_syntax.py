"""Syntax errors: several per run, each in the words of the mistake the writer made."""

from __future__ import annotations

import pytest

from gliderplan.contract import MAX_EXPRESSION_DEPTH, MAX_PARSE_DEPTH
from gliderplan.language import check_source
from gliderplan.language.diagnostics import closest

HEADER = "mission m\nstate s1\nbegin\n  flightprofile yo(5, 20, .454, .454)\n" \
         "  sensors missiontime, depth\n  events\n"


def _errors(source: str) -> list[str]:
    result = check_source(source, "m.mission")
    assert not result.ok
    return [f"{d.span.line}:{d.span.column}: {d.message} | {d.hint}" for d in result.diagnostics]


def _event_error(event: str) -> str:
    errors = _errors(HEADER + f"    {event}\nend\n")
    assert len(errors) == 1, errors
    return errors[0]


@pytest.mark.parametrize(
    ("event", "expected"),
    [
        ("case depth = 3 exit", "7:16: '=' assigns; a condition compares with '=='"),
        ("case depth > 3 | depth < 1 exit", "7:20: '|' is not an operator in a condition"),
        ("case depth > 3 & depth < 1 exit", "7:20: '&' is not an operator | write '&&'"),
        ("case depth > 3 and depth < 1 exit", "7:20: 'and' is not an operator here"),
        ("case depth > 3 goto", "8:1: 'goto' needs the name of a state"),
        ("case goto s1", "7:10: 'case' needs a condition before 'goto'"),
        ("case return", "7:10: 'case' needs a condition before 'return'"),
        ("case missiontime > 500 s exit", "7:28: no unit allowed here: 's'"),
        ("case (depth > 3 exit", "7:21: missing ')' before 'exit' | the '(' on line 7 column 10"),
        ("case depth > 3) exit", "7:19: ')' has no matching '('"),
        ("case depth > 3 exti", "7:20: unexpected 'exti' | did you mean 'exit'?"),
        ("case depth >= 2 3 exit", "7:21: unexpected number '3' right after another"),
        ("case depth > 3 ; exit", "7:20: unexpected ';'"),
        ("case depth > 3 goto s1 $", "7:28: unexpected character '$'"),
    ],
)
def test_common_mistakes_in_events_have_friendly_messages(event, expected):
    assert _event_error(event).startswith(expected)


def test_missing_end_before_next_state_names_the_open_state():
    source = HEADER + "    case depth > 3 exit\n\nstate s2\nbegin\n  flightprofile surface\nend\n"
    assert _errors(source)[0].startswith("9:1: missing 'end' of state 's1' before the next state")


def test_missing_end_at_end_of_file_points_at_the_state():
    assert _errors(HEADER + "    case depth > 3 exit\n")[0].startswith(
        "2:7: state 's1' has no 'end' | the file ends inside it")


def test_missing_begin():
    source = "mission m\nstate s1\n  flightprofile surface\nend\n"
    assert _errors(source)[0].startswith("3:3: missing 'begin' before 'flightprofile'")


def test_unit_in_a_profile_argument():
    source = "mission m\nstate s1\nbegin\n  flightprofile yo(5 m, 20, .454, .454)\nend\n"
    assert _errors(source)[0].startswith("4:22: no unit allowed here: 'm'")


def test_unclosed_parenthesis_across_lines():
    source = "mission m\nstate s1\nbegin\n  flightprofile yo(5, 20, .454, .454\n" \
             "  sensors depth\nend\n"
    assert _errors(source)[0].startswith("5:3: missing ')' before 'sensors' | the '(' on line 4")


def test_line_that_ends_too_early_is_reported_at_its_end():
    source = "mission m\nbattery 1.2 kWh reserve\nstate s1\nbegin\n  flightprofile surface\nend\n"
    assert _errors(source)[0].startswith("2:24: the line ends too early, after 'reserve'")


def test_misspelt_keyword_gets_a_suggestion():
    source = "mission m\nstate s1\nbegin\n  flightprofle surface\nend\n"
    assert _errors(source)[0] == "4:3: unexpected 'flightprofle' | did you mean 'flightprofile'?"


def test_missing_mission_header():
    assert _errors("state s1 begin flightprofile surface end\n")[0].startswith(
        "1:1: a mission file must start with 'mission NAME'")


@pytest.mark.parametrize(("source", "what"), [("", "is empty"), ("  \n\n", "is empty"),
                                              ("# nothing yet\n// really\n", "has only comments")])
def test_empty_file_says_so_and_what_a_mission_starts_with(source, what):
    (message,) = _errors(source)
    assert message.startswith(f"0:0: the file {what}: there is no mission in it")
    assert "a mission starts with 'mission NAME'" in message


def test_several_syntax_errors_in_one_run():
    source = (
        "mission m\n"
        "battery 1.2 kWh reserve\n"          # 2: ends early
        "sensor temp weight 3\n"
        "state s1\nbegin\n"
        "  flightprofile yo(5 m, 20, .454, .454)\n"  # 6: unit
        "end\n"
        "state s2\n"
        "  flightprofile surface\n"          # 9: missing begin
        "end\n"
        "state s3\nbegin\n"
        "  flightprofle surface\n"           # 13: misspelt
        "end\n"
        "state s4 begin flightprofile surface\n"  # 15: no end
    )
    lines = [e.split(":")[0] for e in _errors(source)]
    assert lines == ["2", "6", "9", "13", "15"]


def test_errors_after_a_syntax_error_are_not_invented():
    # Only the broken state is reported; the states after it parse cleanly again.
    source = HEADER + "    case depth = 3 exit\nend\n" + \
        "state s2\nbegin\n  flightprofile surface\nend\n" * 3
    assert len(_errors(source.replace("state s2", "state s2", 1))) == 1


def test_non_finite_number_is_an_error():
    assert _event_error("case missiontime >= 1e400 exit").startswith(
        "7:25: 1e400 is too large for a number")


@pytest.mark.parametrize(
    ("word", "candidates", "expected"),
    [
        ("temperature", ["temp", "depth", "salinity"], "temp"),
        ("Depth", ["depth", "pitch"], "depth"),
        ("dpeth", ["depth", "pitch"], "depth"),
        ("oxy", ["oxygen", "depth"], "oxygen"),
        ("thermotrack", ["yo", "thermotrackyo"], "thermotrackyo"),
        ("sa", ["salinity", "s1"], None),
        ("zzz", ["depth"], None),
    ],
)
def test_closest_name(word, candidates, expected):
    assert closest(word, candidates) == expected


def test_deeply_nested_expressions_are_an_error_not_a_crash():
    """Refused where the nesting passes the parser's limit, before any stage recurses."""
    source = HEADER + "    case " + "-" * 5000 + "depth > 1 exit\nend\n"
    (message,) = _errors(source)
    where, said = message.split(": ", 1)
    assert said == (f"nested more than {MAX_PARSE_DEPTH} deep (brackets and operators "
                    "together) | split the expression with a variable ('set v = ...')")
    line, column = map(int, where.split(":"))
    # at the minus that passes the limit: the parser's stack holds the mission's items too
    assert line == 7 and len("    case ") < column <= len("    case ") + MAX_PARSE_DEPTH


@pytest.mark.parametrize("nest", [
    lambda n: "-" * n + "depth",
    lambda n: " + ".join(["depth"] * (n + 1)),
    lambda n: "abs(" * n + "depth" + ")" * n,
    lambda n: "(" * n + " || ".join(["depth"] * (n + 1)) + ")" * n,
    lambda n: "".join("abs(" if i % 2 else "-" for i in range(n)) + "depth" + ")" * (n // 2),
], ids=["unary", "sum", "calls", "or", "mixed"])
def test_an_expression_may_nest_as_deep_as_the_contract_says(nest):
    """As deep as the limit, every stage takes it (tests/test_sim_cli.py flies one); one
    level more is refused where it is written, however it nests."""
    deepest = nest(MAX_EXPRESSION_DEPTH - 1)  # and `> 1` makes the limit
    assert check_source(HEADER + f"    case {deepest} > 1 exit\nend\n").ok
    too_deep = nest(MAX_EXPRESSION_DEPTH)
    assert _errors(HEADER + f"    case {too_deep} > 1 exit\nend\n") == [
        f"7:10: expression nested {MAX_EXPRESSION_DEPTH + 1} operators deep, more than the "
        f"{MAX_EXPRESSION_DEPTH} a mission may hold | split the expression with a variable "
        "('set v = ...')"]
    with_variable = HEADER.replace("mission m\n", "mission m\nvar v = 0\n")
    assert _errors(with_variable + f"    case depth > 1 set v = {too_deep} > 1 exit\nend\n")[0] \
        .startswith(f"8:28: expression nested {MAX_EXPRESSION_DEPTH + 1} operators deep")


def test_parentheses_do_not_nest_the_tree():
    deep = MAX_PARSE_DEPTH // 2  # brackets each hold a parser state or two
    source = HEADER + "    case " + "(" * deep + "depth" + ")" * deep + " > 1 exit\nend\n"
    assert check_source(source).ok


def test_brackets_past_the_parser_s_limit_are_refused_at_once_whatever_their_number():
    """A megabyte of brackets is refused at the first past the limit, not parsed for
    minutes (the parse is linear, and bounded)."""
    source = HEADER + "    case " + "(" * 1_000_000 + "depth" + ")" * 1_000_000 + " > 1 exit"
    (message,) = _errors(source + "\nend\n")
    where = message.split(": ", 1)[0]
    assert message.split(": ", 1)[1].startswith(f"nested more than {MAX_PARSE_DEPTH} deep")
    line, column = map(int, where.split(":"))
    assert line == 7 and column <= len("    case ") + MAX_PARSE_DEPTH

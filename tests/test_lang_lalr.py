"""The parse driver (language/lalr.py) against lark's own parser on the same grammar:
the same tree with the same positions for every text lark accepts, and lark's own
error (same token, same expected terminals) for every text it refuses."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lark import Lark, Token, Tree, UnexpectedInput
from lark.exceptions import UnexpectedCharacters, UnexpectedToken
from test_lang_fuzz import VOCABULARY, mutated

from gliderplan.language.lalr import Parser
from gliderplan.language.parser import _lark

REPO = Path(__file__).resolve().parent.parent
MISSIONS = sorted((REPO / "examples").rglob("*.mission")) + sorted(
    (REPO / "tests" / "missions").glob("*.mission"))


class _Record:
    """A builder that makes every rule a (name, position, children) tuple."""

    def __getattr__(self, name: str):
        return lambda where, children: (name, where, children)


def _from_lark(node: object) -> object:
    """lark's tree in the recording builder's form."""
    if isinstance(node, Token):
        return (str(node), node.line, node.column, node.end_line, node.end_column)
    if isinstance(node, Tree):
        meta = node.meta
        where = ((0, 0, 0, 0) if meta.empty
                 else (meta.line, meta.column, meta.end_line, meta.end_column))
        return (str(node.data), where, [_from_lark(c) for c in node.children])
    return node  # None for a missing [optional] part


def _error(err: UnexpectedInput) -> tuple:
    """What a syntax error says: its kind, where, and what was expected there."""
    if isinstance(err, UnexpectedToken):
        token = err.token
        return ("token", token.type, str(token), token.start_pos, token.line, token.column,
                token.end_line, token.end_column, sorted(err.expected))
    assert isinstance(err, UnexpectedCharacters), err
    return ("characters", err.pos_in_stream, err.line, err.column, sorted(err.allowed))


def _outcome(parse, text: str, start: str) -> tuple:
    try:
        return ("tree", parse(text, start))
    except UnexpectedInput as err:
        return ("error", _error(err))


_DRIVER = Parser(_lark(), _Record())


def _agrees_with_lark(text: str, lark: Lark | None = None, driver: Parser = _DRIVER) -> None:
    lark = lark or _lark()
    for start in lark.options.start:
        expected = _outcome(lambda t, s: _from_lark(lark.parse(t, start=s)), text, start)
        assert _outcome(driver.parse, text, start) == expected, (start, text)


@pytest.mark.parametrize("path", MISSIONS, ids=lambda p: p.name)
def test_every_example_parses_as_lark_parses_it(path):
    _agrees_with_lark(path.read_text())


@pytest.mark.parametrize("text", [
    "",
    "   \n\t ",
    "# only a comment",
    "mission",
    "mission m",
    "mission m\n",
    "mission m state",
    "mission m\nstate s begin flightprofile yo(5, 20, .454, .454) events case x > 1 goto end",
    "mission m\nstate s begin end\nstate end begin end",
    "mission m\nsensor temp weight 3 duty >= 0.25 quality >= .5\n",
    "mission m\nobjective maximize quality quality >= 0.5\n",
    "mission m\nbattery 60 Ah at 14.4 V reserve 15 %\ncomputer \"boards/x.toml\" @ 300 MHz\n",
    "mission m\nvar a = -(1 + 2) * 3 / -4 - 5\nstate s begin events case !(a >= 1) || a < 2 "
    "&& a != 3 set a = max(a, abs(a - 1)) exit end",
    "mission m\nstate s begin flightroute waypoints((1, 2), (3, 4)) flightprofile f() end",
    "mission m\nstate s begin sensors temp duty auto, depth duty 0.5, pitch end",
    "mission m\nstate s begin expect 20 min .. 2 h require temp duty >= 0.1 end",
    "mission m\nstate s begin events case a > 1 and b < 2 exit end",
    "mission m\nstate s begin events case a > 1 exit end;",
    "mission m\nstate s begin events case a = 1 exit end",
    "mission m\nvehicle \"unterminated\n",
    "mission m\nstate s begin flightprofile yo(5, 20\nend",
    "mission m\nstate s begin\n\n\n  events case a > 1 exit\n# trailing comment",
    "mission m\nstate s begin events case a > 1 exit end\n\u00e9",
    # reductions before the error: lark must lex the token in the state before them
    "mission m\nhorizon 36 h expect 1",
])
def test_edge_cases_parse_as_lark_parses_them(text):
    _agrees_with_lark(text)


_PREFIXES = ["", "mission m\n", "mission m\nstate s1 begin flightprofile surface events case ",
             "mission m\nstate s1 begin flightprofile yo("]


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(_PREFIXES), st.lists(st.sampled_from(VOCABULARY), max_size=60))
def test_token_soup_parses_as_lark_parses_it(prefix, tokens):
    _agrees_with_lark(prefix + " ".join(tokens))


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from([p.read_text() for p in MISSIONS]), st.data())
def test_mutated_examples_parse_as_lark_parses_them(source, data):
    _agrees_with_lark(mutated(source, data))


# Tokens across lines (strings here; mission.lark has none) and a rule with one child
# or several.
_MULTILINE = Lark(r"""
    start: item+
    ?item: STRING | NAME [":" NAME] -> pair | "(" item+ ")" -> group
    STRING: /"[^"]*"/
    NAME: /[a-z]+/
    %ignore /[ \t\n]+/
""", parser="lalr", lexer="contextual", propagate_positions=True, maybe_placeholders=True)


@pytest.mark.parametrize("text", [
    'a "x\ny" b:c "\n" d',
    '"one\ntwo\nthree" a',
    'a ("x\ny")',
    'a ("x\ny" b)',
    'a: "x\ny"',
    'a "x\ny"\n :',
    '"x\ny" ?',
])
def test_tokens_across_lines_are_positioned_as_lark_positions_them(text):
    _agrees_with_lark(text, _MULTILINE, Parser(_MULTILINE, _Record()))


@pytest.mark.parametrize("rule", ['?item: "(" NAME ")" | NAME',
                                  '?item: "(" _names ")" | NAME\n_names: NAME+',
                                  '?item: "(" inner ")" | NAME\n?inner: NAME | NAME NAME'])
def test_a_lone_token_handed_up_between_brackets_is_refused(rule):
    """lark would position the rule at the token, without its brackets."""
    lark = Lark(f"start: item+\n{rule}\nNAME: /[a-z]+/\n%ignore \" \"\n", parser="lalr",
                propagate_positions=True, maybe_placeholders=True)
    with pytest.raises(TypeError, match="lone token"):
        Parser(lark, _Record())


def test_a_rule_the_builder_cannot_make_is_refused_when_the_parser_is_made():
    class Partial:
        def start(self, where, children):
            return children

    with pytest.raises(TypeError, match="has no method for rule"):
        Parser(_lark(), Partial())

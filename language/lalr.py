"""Runs the LALR(1) tables that lark builds from mission.lark, building the syntax tree
as it parses.

lark's own parse loop costs about 13 us per token on a large mission, most of it in
wrappers around each token and each rule (token objects, child filters, position
propagation) and in the chain of single-child reductions every operand goes through
(`expr` -> `or_expr` -> ... -> `atom`: nine of them). This driver reads lark's parse
table, its contextual lexer's regular expressions and its tree-shaping rules (keywords
left out, `_rule`s inlined, a `?rule` with one child replaced by it, `None` where an
`[optional]` part is missing) once, and applies them in one loop: a token is a tuple,
a chain of single-child reductions is one dictionary look-up, and each rule that makes
a node calls the builder's method named after the rule (or its alias).

The grammar stays in mission.lark alone. On a syntax error the driver hands the text
to lark at the token it could not take, in the same parser states, so the error is
lark's own `UnexpectedInput` (same token, same expected terminals) and costs nothing
until then.

On the stack, a token is `(text, line, column, end_line, end_column)` (1-based, end
exclusive, as lark counts) and a rule's result is `(value, line, column, end_line,
end_column)`; an inlined `_rule`'s value is the list of its children. A builder method
takes `(where, children)`: `where` is `(line, column, end_line, end_column)` from the
first to the last symbol of the rule, keywords and brackets included (lark's
`propagate_positions`), and the children are values, tokens and `None`s.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import FunctionType
from typing import Any

from lark import Lark, Token, Tree
from lark.lexer import UnlessCallback
from lark.utils import TextSlice

_NO_POSITION = (0, 0, 0, 0)
Entry = tuple  # (value or token text, line, column, end_line, end_column)


class TooDeep(Exception):
    """The text nests deeper than the parser's stack may grow, at `token` (its entry)."""

    def __init__(self, token: Entry, depth: int) -> None:
        super().__init__(f"nested more than {depth} deep")
        self.token, self.depth = token, depth


class _Rule:
    """One grammar rule: its length, the symbol it makes, and a function that takes its
    symbols off the stack and returns its entry (lark's parse_tree_builder, compiled)."""

    __slots__ = ("size", "origin", "single", "parts", "unit", "name", "source", "build")

    def __init__(self, rule: Any, builder: object) -> None:
        self.size = len(rule.expansion)
        self.origin = rule.origin.name
        # lark's maybe_placeholders: a None child where an [optional] part is missing
        nones_before = [0] * (self.size + 1)
        symbol = 0
        for missing in rule.options.empty_indices:
            if missing:
                nones_before[symbol] += 1
            else:
                symbol += 1
        children = []  # Python expressions over the entries e0, e1, ...
        self.parts: list[tuple[str, str]] = []  # (what, symbol) for each child
        for i, sym in enumerate(rule.expansion):
            children += ["None"] * nones_before[i]
            self.parts += [("none", "")] * nones_before[i]
            if rule.options.keep_all_tokens or not (sym.is_term and sym.filter_out):
                what = ("token" if sym.is_term else
                        "inlined" if sym.name.startswith("_") else "value")
                self.parts.append((what, sym.name))
                children.append({"token": f"e{i}",  # the whole token, with its position
                                 "inlined": f"*e{i}[0]", "value": f"e{i}[0]"}[what])
        children += ["None"] * nones_before[self.size]
        self.parts += [("none", "")] * nones_before[self.size]
        self.single = single = bool(rule.options.expand1) and not rule.alias  # a `?rule`
        always_one = single and len(children) == 1 and children[0].startswith("e")
        # One symbol whose value passes up as it is: only the parser's state changes.
        self.unit = always_one and self.size == 1 and children[0] == "e0[0]"
        name = rule.alias or self.origin
        self.name = str(rule)
        build = getattr(builder, name, None)
        if children and children[0].startswith("*"):  # grow the inlined list in place,
            rest = ", ".join(children[1:])               # as lark does for left recursion
            listed = f"    c = {children[0][1:]}\n    c += [{rest}]\n"
        else:
            listed = f"    c = [{', '.join(children)}]\n"
        if self.origin.startswith("_"):
            value = "c"
        elif always_one:
            value, listed = children[0], ""
        elif build is None:
            raise TypeError(f"{type(builder).__name__} has no method for rule '{name}'")
        elif single:  # one child or several, depending on the inlined ones
            value = "(c[0] if len(c) == 1 else build(where, c))"
        else:
            value = "build(where, c)"
        if self.size:
            last = self.size - 1
            entries = "".join(f"e{i}, " for i in range(self.size))
            body = (f"    {entries}= stack[-{self.size}:]\n"
                    f"    del stack[-{self.size}:]\n"
                    f"    del states[-{self.size}:]\n"
                    f"    where = (e0[1], e0[2], e{last}[3], e{last}[4])\n")
        else:
            body = "    where = _NO_POSITION\n"
        # The body of the rule's reduction: it takes the rule's symbols off both stacks,
        # pushes its entry and the state `goto` leads to from the state below, and
        # returns that state.
        self.source = (f"{body}{listed}"
                       f"    stack.append(({value}, *where))\n"
                       "    states.append(state := goto[states[-1]])\n"
                       "    return state\n")
        self.build = build


def _compile_reductions(rules: list[_Rule], gotos: dict[str, dict[int, int]]) -> list:
    """Each rule's reduction function (None for a unit rule). Rules of the same shape
    share one compiled body (compiling is most of the parser's start-up)."""
    shapes = sorted({rule.source for rule in rules if not rule.unit})
    source = "".join(f"def shape_{i}(stack, states, build, goto):\n{body}"
                     for i, body in enumerate(shapes))
    namespace = {"_NO_POSITION": _NO_POSITION}
    exec(compile(source, "<reductions>", "exec"), namespace)
    code = {body: namespace[f"shape_{i}"].__code__ for i, body in enumerate(shapes)}
    return [None if rule.unit else
            FunctionType(code[rule.source], namespace, rule.name,
                         (rule.build, gotos[rule.origin]))
            for rule in rules]


class _Keywords(dict):
    """Text -> terminal, as lark's keyword look-up (UnlessCallback) types a token that
    its regular expression matched as `type_` (a NAME `end` is the keyword END)."""

    def __init__(self, type_: str, callback: UnlessCallback) -> None:
        super().__init__()
        self.type_, self.callback = type_, callback

    def __missing__(self, text: str) -> str:
        found = self[text] = self.callback(Token(self.type_, text)).type
        return found


def _state_lexer(lexer: Any) -> tuple[Callable, frozenset[str], dict[str, _Keywords]]:
    """What one state's lexer of lark's contextual lexer does, for the driver's loop: its
    match function, the terminals it skips, and its keyword look-ups."""
    patterns = [mre.match for mre in lexer.scanner._mres]
    if len(patterns) == 1:
        match = patterns[0]
    else:  # lark splits a lexer of more than 100 terminals into several expressions
        def match(text: str, pos: int) -> Any:
            for pattern in patterns:
                if (found := pattern(text, pos)) is not None:
                    return found
            return None
    keywords = {}
    for type_, callback in lexer.callback.items():
        if not isinstance(callback, UnlessCallback):
            raise TypeError(f"lexer callback {callback!r} is not a keyword look-up")
        keywords[type_] = _Keywords(type_, callback)
    return match, lexer.ignore_types, keywords


def _refuse_lone_tokens_in_brackets(rules: list[_Rule]) -> None:
    """lark positions a `?rule` that hands up a lone token at the token, without the
    rule's other symbols (the brackets of `?x: "(" NAME ")"`), while the driver positions
    every rule from its first symbol to its last: refuse a grammar where that can
    happen (mission.lark has no such rule)."""
    inlined_rules = [r for r in rules if r.origin.startswith("_")]
    fewest: dict[str, float] = {r.origin: math.inf for r in inlined_rules}
    for _ in inlined_rules:  # fewest children an inlined `_rule` adds (Bellman-Ford)
        for rule in inlined_rules:
            count = sum(fewest[name] if what == "inlined" else 1 for what, name in rule.parts)
            fewest[rule.origin] = min(fewest[rule.origin], count)
    token_like: set[str] = set()  # symbols whose value, or a child of which, may be a token

    def lone_token(rule: _Rule) -> bool:
        """The rule's children may be exactly one token."""
        return any((what == "token" or name in token_like)
                   and all(fewest.get(other, 1) == 0 for j, (_, other) in enumerate(rule.parts)
                           if j != i)
                   for i, (what, name) in enumerate(rule.parts))

    while True:
        grown = {r.origin for r in rules
                 if (r.origin.startswith("_") and any(what == "token" or name in token_like
                                                      for what, name in r.parts))
                 or (r.single and lone_token(r))} - token_like
        if not grown:
            break
        token_like |= grown
    for rule in rules:
        if rule.single and rule.size > 1 and lone_token(rule):
            raise TypeError(f"rule {rule.name} may hand up a lone token among other "
                            "symbols, which lark positions differently: give it an alias")


class Parser:
    """lark's LALR(1) parser for one grammar, run by one loop that builds the tree with
    `builder` (an object with one method per rule that makes a node)."""

    def __init__(self, lark: Lark, builder: object) -> None:
        self._lark = lark
        probe = lark.parse_interactive("", start=lark.options.start[0])
        table = probe.parser_state.parse_conf.parse_table
        self._contextual_lexers = probe.lexer_thread.lexer.lexers
        if sorted(table.states) != list(range(len(table.states))):
            raise TypeError("lark's parse table is not numbered 0..n-1")
        rules: dict[Any, int] = {}
        # Per state, symbol -> a state >= 0 to shift to (or go to after a reduction),
        # or ~r < 0 to reduce by rule r.
        self._actions: list[dict[str, int]] = []
        for state in range(len(table.states)):
            row = {}
            for symbol, (action, arg) in table.states[state].items():
                shift = action.name == "Shift"
                row[symbol] = arg if shift else ~rules.setdefault(arg, len(rules))
            self._actions.append(row)
        self._rules = [_Rule(rule, builder) for rule in rules]
        gotos: dict[str, dict[int, int]] = {}  # symbol -> {state below: state after}
        for state, row in enumerate(self._actions):
            for symbol, code in row.items():
                if not symbol.isupper() and symbol != "$END":
                    gotos.setdefault(symbol, {})[state] = code
        for rule in self._rules:
            if rule.size == 0 and rule.origin not in table.start_states:
                raise TypeError(f"empty rule {rule.name}: it would have no position")
        _refuse_lone_tokens_in_brackets(self._rules)
        self._reductions = _compile_reductions(self._rules, gotos)
        self._start_states = table.start_states
        self._end_states = table.end_states
        self._lexers: list[tuple | None] = [None] * len(table.states)
        # (state below, state on top, lookahead) -> the state after the chain of unit
        # reductions the lookahead causes
        self._units: dict[tuple[int, int, str], int] = {}

    def _lexer(self, state: int) -> tuple:
        lexer = self._lexers[state] = _state_lexer(self._contextual_lexers[state])
        return lexer

    def _unit_chain(self, below: int, top: int, lookahead: str) -> int:
        actions, rules = self._actions, self._rules
        state = top
        while (code := actions[state].get(lookahead)) is not None and code < 0 \
                and rules[~code].unit:
            state = actions[below][rules[~code].origin]
        self._units[below, top, lookahead] = state
        return state

    def parse(self, text: str, start: str, max_depth: int | None = None) -> object:
        """The builder's value for the whole text; lark's UnexpectedInput on a syntax error,
        TooDeep at the token that would make the stack deeper than `max_depth` entries."""
        actions, reductions, units, lexers = (self._actions, self._reductions, self._units,
                                              self._lexers)
        rules = self._rules
        end_state = self._end_states[start]
        state = self._start_states[start]
        states = [state]
        stack: list[Entry] = []
        pos, end = 0, len(text)
        # the line of the last token, where it starts, and the first newline after it
        line, line_start, newline = 1, 0, _find_newline(text, 0)
        last_token = None  # (type, start, end), for lark's end-of-input token
        while True:
            # ---- the next token, lexed in this state as lark's contextual lexer does
            if pos < end:
                match, ignore, keywords = lexers[state] or self._lexer(state)
                found = match(text, pos)
                if found is None:
                    self._fail(text, start, states, pos, last_token)
                type_ = found.lastgroup
                token_start, pos = pos, found.end()
                if type_ in ignore:
                    continue
                value = found.group()
                if type_ in keywords:
                    type_ = keywords[type_][value]
                if token_start > newline:
                    line += text.count("\n", line_start, token_start)
                    line_start = text.rfind("\n", 0, token_start) + 1
                    newline = _find_newline(text, token_start)
                column = token_start - line_start + 1
                if pos <= newline:
                    token = (value, line, column, line, column + pos - token_start)
                else:  # a token across lines
                    end_line = line + value.count("\n")
                    token = (value, line, column, end_line, pos - text.rfind("\n", 0, pos))
            else:
                type_, token, token_start = "$END", None, pos
            # ---- the reductions it causes, then its shift
            # lark must see the states this token was lexed in if it fails: the states the
            # reductions replace are kept, in chunks from the top down, only those, so that
            # a deep stack is not copied at every token (states[:kept_from] and the chunks
            # reversed are that stack)
            kept_from, kept = len(states), []
            while True:
                code = actions[state].get(type_)
                if code is None:
                    lexed = states[:kept_from] + [s for chunk in reversed(kept) for s in chunk]
                    self._fail(text, start, lexed, token_start, last_token)
                if code >= 0:
                    if max_depth is not None and len(stack) >= max_depth and token:
                        raise TooDeep(token, max_depth)
                    states.append(code)
                    stack.append(token)
                    state = code
                    break
                reduce = reductions[~code]
                reach = len(states) - (1 if reduce is None else rules[~code].size)
                if reach < kept_from:
                    kept.append(states[reach:kept_from])
                    kept_from = reach
                if reduce is None:  # a unit rule, and the unit rules after it
                    key = (states[-2], state, type_)
                    state = units.get(key)
                    if state is None:
                        state = self._unit_chain(*key)
                    states[-1] = state
                    continue
                state = reduce(stack, states)
                if state == end_state and token is None:
                    return stack[-1][0]
            last_token = (type_, token_start, pos)

    def _fail(self, text: str, start: str, states: list[int], pos: int,
              last_token: tuple[str, int, int] | None) -> None:
        """Raise lark's own error for the token at `pos`, lexed and parsed by lark from
        the same parser states."""
        interactive = self._lark.parse_interactive(TextSlice(text, pos, len(text)), start)
        parser_state = interactive.parser_state
        parser_state.state_stack[:] = states
        # lark builds its own tree from here, thrown away: empty trees stand for values
        parser_state.value_stack[:] = [Tree("", []) for _ in states[1:]]
        if last_token is not None:
            interactive.lexer_thread.state.last_token = _lark_token(text, *last_token)
        interactive.resume_parse()
        raise AssertionError("lark took the token the driver refused")  # same tables


def _find_newline(text: str, start: int) -> int:
    """Offset of the first newline at or after start (len(text) if none)."""
    found = text.find("\n", start)
    return len(text) if found < 0 else found


def _lark_token(text: str, type_: str, start: int, end: int) -> Token:
    """The lark token of type `type_` from offset `start` to `end`, positioned as lark's
    lexer positions it."""
    def line_and_column(offset: int) -> tuple[int, int]:
        return text.count("\n", 0, offset) + 1, offset - text.rfind("\n", 0, offset)

    return Token(type_, text[start:end], start, *line_and_column(start),
                 *line_and_column(end), end)

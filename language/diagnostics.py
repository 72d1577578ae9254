"""Compiler-style diagnostics: `file:line:col: error: message`, the line, a caret, a hint."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from gliderplan.contract.errors import GliderplanError, diagnostic_json
from gliderplan.language.ast import NO_SPAN, Span


@dataclass(frozen=True)
class Diagnostic:
    severity: str  # "error" or "warning"
    message: str
    span: Span = NO_SPAN
    hint: str | None = None

    @property
    def is_error(self) -> bool:
        return self.severity == "error"

    def to_json(self, filename: str) -> dict:
        """As a JSON object (contract.errors.diagnostic_json; no place: line None)."""
        line, column, end_line, end_column = self.span if self.span.line else (None,) * 4
        return diagnostic_json(self.message, severity=self.severity, file=filename,
                               line=line, column=column, end_line=end_line,
                               end_column=end_column, hint=self.hint)


def error(message: str, span: Span = NO_SPAN, hint: str | None = None) -> Diagnostic:
    return Diagnostic("error", message, span, hint)


def warning(message: str, span: Span = NO_SPAN, hint: str | None = None) -> Diagnostic:
    return Diagnostic("warning", message, span, hint)


def closest(word: str, candidates: Iterable[str]) -> str | None:
    """The candidate the writer most likely meant, or None when nothing is close.

    In order: the same word in another case (`Depth`), a candidate that is a prefix
    of the word or the word a prefix of it (`temperature` for `temp`, `miss` for
    `missiontime`), one containing the other (`watertemp`), then spelling
    similarity (`dpeth`). Prefix and substring matches need 3 letters in common so
    that `s` does not suggest every state starting with s.
    """
    pool = sorted(set(candidates))
    lowered = word.lower()
    for candidate in pool:
        if candidate.lower() == lowered:
            return candidate
    for related in (_prefix_related, _substring_related):
        matches = [c for c in pool if related(lowered, c.lower())]
        if matches:
            return min(matches, key=lambda c: (abs(len(c) - len(word)), c))
    import difflib  # only when a name is wrong: keeps it out of a clean check's start-up

    close = difflib.get_close_matches(word, pool, n=1, cutoff=0.6)
    return close[0] if close else None


def _prefix_related(word: str, candidate: str) -> bool:
    shorter = min(len(word), len(candidate))
    return shorter >= 3 and (word.startswith(candidate) or candidate.startswith(word))


def _substring_related(word: str, candidate: str) -> bool:
    shorter = min(len(word), len(candidate))
    return shorter >= 3 and (word in candidate or candidate in word)


def did_you_mean(word: str, candidates: Iterable[str]) -> str | None:
    """A hint naming the closest candidate, or None when nothing is close."""
    match = closest(word, candidates)
    return f"did you mean '{match}'?" if match else None


class MissionError(GliderplanError):
    """A mission with errors; `details` holds its rendered diagnostics."""


class MissionSyntaxError(Exception):
    """Raised by the parser; carries every diagnostic it found."""

    def __init__(self, diagnostics: list[Diagnostic]):
        super().__init__("; ".join(d.message for d in diagnostics))
        self.diagnostics = diagnostics


def render_all(diagnostics: Iterable[Diagnostic], filename: str, source: str) -> str:
    """Format each diagnostic with the offending source line underlined; the source is
    split into lines once for all of them, so the time grows with their number."""
    source_lines = source.splitlines()
    return "\n".join(_render(d, filename, source_lines) for d in diagnostics)


def _render(diagnostic: Diagnostic, filename: str, source_lines: list[str]) -> str:
    span = diagnostic.span
    if span.line <= 0:
        lines = [f"{filename}: {diagnostic.severity}: {diagnostic.message}"]
    else:
        where = f"{filename}:{span.line}:{span.column}"
        lines = [f"{where}: {diagnostic.severity}: {diagnostic.message}"]
        if span.line <= len(source_lines):
            text = source_lines[span.line - 1].expandtabs(1)
            gutter = f"{span.line:>5} | "
            end = span.end_column if span.end_line == span.line else len(text) + 1
            width = max(1, end - span.column)
            lines.append(gutter + text)
            lines.append(" " * (len(gutter) - 2) + "| " + " " * (span.column - 1) + "^" * width)
    if diagnostic.hint:
        lines.append(f"      = hint: {diagnostic.hint}")
    return "\n".join(lines)

"""Compiler-style diagnostics: `file:line:col: error: message`, the line, a caret, a hint."""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from dataclasses import dataclass

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


def error(message: str, span: Span = NO_SPAN, hint: str | None = None) -> Diagnostic:
    return Diagnostic("error", message, span, hint)


def warning(message: str, span: Span = NO_SPAN, hint: str | None = None) -> Diagnostic:
    return Diagnostic("warning", message, span, hint)


def did_you_mean(word: str, candidates: Iterable[str]) -> str | None:
    """A hint naming the closest candidate, or None when nothing is close."""
    close = difflib.get_close_matches(word, sorted(set(candidates)), n=1, cutoff=0.6)
    return f"did you mean '{close[0]}'?" if close else None


class MissionSyntaxError(Exception):
    """Raised by the parser; carries every diagnostic it found."""

    def __init__(self, diagnostics: list[Diagnostic]):
        super().__init__("; ".join(d.message for d in diagnostics))
        self.diagnostics = diagnostics


def render(diagnostic: Diagnostic, filename: str, source: str) -> str:
    """Format one diagnostic with the offending source line underlined."""
    span = diagnostic.span
    if span.line <= 0:
        lines = [f"{filename}: {diagnostic.severity}: {diagnostic.message}"]
    else:
        where = f"{filename}:{span.line}:{span.column}"
        lines = [f"{where}: {diagnostic.severity}: {diagnostic.message}"]
        source_lines = source.splitlines()
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


def render_all(diagnostics: Iterable[Diagnostic], filename: str, source: str) -> str:
    return "\n".join(render(d, filename, source) for d in diagnostics)

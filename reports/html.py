"""One self-contained HTML page: inline CSS, inline SVG figures, sortable tables, no request
to anything outside the file (a Content-Security-Policy says so to the browser too).

A page is a title and `Section`s; a section is prose, an optional figure (SVG text) with
the CSV files behind it, and tables. Everything that comes from the mission is escaped.
"""

from __future__ import annotations

import html
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field

import pandas as pd

# Nothing may be fetched: styles and the sort script are inline, images are data: URIs.
CSP = ("default-src 'none'; style-src 'unsafe-inline'; script-src 'unsafe-inline'; "
       "img-src data:")

CSS = """
body { font-family: sans-serif; margin: 2em auto; max-width: 62em; padding: 0 1em;
       color: #1b1b1b; line-height: 1.45; overflow-wrap: break-word; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { font-size: 1.25em; border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 2em; }
p.sub { color: #555; margin-top: 0; }
nav ol { columns: 2; font-size: 0.95em; }
figure { margin: 1em 0; break-inside: avoid; }
figure svg { width: 100%; height: auto; }
figcaption { font-size: 0.85em; color: #444; }
div.table { max-width: 100%; overflow-x: auto; margin: 0.8em 0; }
table { border-collapse: collapse; font-size: 0.88em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.55em; overflow-wrap: break-word; }
th { background: #f2f2f2; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
td.num span.n { white-space: nowrap; }
table.sortable th { cursor: pointer; }
table.sortable th::after { content: " \\2195"; color: #999; font-size: 0.8em; }
tr { break-inside: avoid; }
dl.facts { display: grid; grid-template-columns: max-content auto; gap: 0.2em 1.2em; }
dl.facts dt { font-weight: bold; }
dl.facts dd { margin: 0; overflow-wrap: anywhere; }
@media (max-width: 60em) {
  table { font-size: 0.82em; }
  th, td { padding: 0.2em 0.35em; }
}
@media (max-width: 40em) {
  dl.facts { display: block; }
  dl.facts dd { margin: 0 0 0.4em 1em; }
}
.verdict-pass { color: #1a6e1a; font-weight: bold; }
.verdict-violation { color: #b00020; font-weight: bold; }
.verdict-over-prediction { color: #a15c00; font-weight: bold; }
ul.notes { font-size: 0.88em; color: #333; }
@media print {
  body { margin: 0; max-width: none; font-size: 10pt; }
  nav, table.sortable th::after { display: none; }
  div.table { overflow: visible; }
  h2 { break-after: avoid; }
  section { break-before: auto; }
  a { color: inherit; text-decoration: none; }
}
"""

# Click a header to sort by that column; numbers sort by their value (data-v).
SORT_SCRIPT = """
document.querySelectorAll("table.sortable").forEach(function (table) {
  table.querySelectorAll("th").forEach(function (th, column) {
    th.addEventListener("click", function () {
      var body = table.tBodies[0];
      var rows = Array.prototype.slice.call(body.rows);
      var up = th.getAttribute("data-order") !== "up";
      table.querySelectorAll("th").forEach(function (h) { h.removeAttribute("data-order"); });
      th.setAttribute("data-order", up ? "up" : "down");
      function key(row) {
        var cell = row.cells[column];
        var v = cell.getAttribute("data-v");
        return v === null ? cell.textContent : parseFloat(v);
      }
      rows.sort(function (a, b) {
        var x = key(a), y = key(b);
        var order = (typeof x === "number" && typeof y === "number")
          ? (isNaN(x) ? 1 : isNaN(y) ? -1 : x - y) : String(x).localeCompare(String(y));
        return up ? order : -order;
      });
      rows.forEach(function (row) { body.appendChild(row); });
    });
  });
});
"""


@dataclass(frozen=True)
class Table:
    """A table of `frame`; `headers` maps a column to its heading with its unit, `formats`
    a column to a format spec for its numbers, `units` a column of numbers in different
    units to the column that names each row's unit (shown after the number, not as a
    column of its own)."""

    frame: pd.DataFrame
    headers: dict[str, str] = field(default_factory=dict)
    formats: dict[str, str] = field(default_factory=dict)
    caption: str = ""
    units: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Section:
    id: str
    title: str
    paragraphs: tuple[str, ...] = ()  # HTML, already escaped
    figure: str | None = None  # SVG document text
    caption: str = ""
    csv: tuple[str, ...] = ()  # files behind the figure and tables
    tables: tuple[Table, ...] = ()
    notes: tuple[str, ...] = ()  # plain text: assumptions, sources


def esc(text: object) -> str:
    return html.escape(str(text), quote=True)


def inline_svg(svg: str, prefix: str) -> str:
    """An SVG document as an element of the page: without its XML prolog and doctype,
    every id (and every reference to one) prefixed so that figures cannot clash."""
    body = svg[svg.index("<svg"):]
    return re.sub(r'(\bid="|href="#|url\(#)', lambda m: m.group(1) + prefix, body)


def _cell(value: object, fmt: str | None, unit: str = "") -> str:
    if isinstance(value, bool) or value is None:
        return f"<td>{esc('-' if value is None else value)}</td>"
    if isinstance(value, int | float):
        number = float(value)
        shown = "-" if math.isnan(number) else format(number, fmt or ",.4g")
        with_unit = f" {esc(unit)}" if unit not in ("", "1") and not math.isnan(number) else ""
        # the number never wraps (2.4e-09 would break after its minus); its unit may
        return (f'<td class="num" data-v="{number!r}"><span class="n">{esc(shown)}</span>'
                f"{with_unit}</td>")
    return f"<td>{breakable(esc(value))}</td>"


def breakable(text: str) -> str:
    """Escaped text with a line-break opportunity (<wbr>) after each _ . / inside a word:
    an identifier (pump_out_energy_per_volume) or a path wraps there instead of widening
    its table past the page."""
    return re.sub(r"([_./])(?=\w)", r"\1<wbr>", text)


def table_html(table: Table) -> str:
    frame = table.frame
    columns = [c for c in frame.columns if c not in table.units.values()]
    head = "".join(f"<th>{esc(table.headers.get(c, c))}</th>" for c in columns)
    rows = "".join(
        "<tr>" + "".join(_cell(row[c], table.formats.get(c),
                               str(row[table.units[c]]) if c in table.units else "")
                         for c in columns) + "</tr>"
        for row in frame.to_dict("records"))
    caption = f"<caption>{esc(table.caption)}</caption>" if table.caption else ""
    return (f'<div class="table"><table class="sortable">{caption}<thead><tr>{head}</tr>'
            f"</thead><tbody>{rows}</tbody></table></div>")


def facts_html(facts: Sequence[tuple[str, str]]) -> str:
    """A definition list of (label, HTML value) pairs."""
    return '<dl class="facts">' + "".join(
        f"<dt>{esc(k)}</dt><dd>{v}</dd>" for k, v in facts) + "</dl>"


def section_html(section: Section) -> str:
    parts = [f'<section id="{esc(section.id)}"><h2>{esc(section.title)}</h2>']
    parts += list(section.paragraphs)
    if section.figure is not None:
        links = ", ".join(f'<a href="{esc(name)}">{esc(name)}</a>' for name in section.csv)
        data = f" Data: {links}." if links else ""
        parts.append(f'<figure data-figure="{esc(section.id)}">'
                     f"{inline_svg(section.figure, f'{section.id}-')}"
                     f"<figcaption>{esc(section.caption)}{data}</figcaption></figure>")
    parts += [table_html(t) for t in section.tables]
    if section.notes:
        parts.append('<ul class="notes">' + "".join(f"<li>{esc(n)}</li>"
                                                    for n in section.notes) + "</ul>")
    parts.append("</section>")
    return "\n".join(parts)


def page(title: str, subtitle: str, sections: Sequence[Section]) -> str:
    """The whole HTML document."""
    toc = "".join(f'<li><a href="#{esc(s.id)}">{esc(s.title)}</a></li>' for s in sections)
    body = "\n".join(section_html(s) for s in sections)
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta http-equiv="Content-Security-Policy" content="{CSP}">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{esc(title)}</title>
<style>{CSS}</style>
</head>
<body>
<header><h1>{esc(title)}</h1><p class="sub">{esc(subtitle)}</p></header>
<nav><ol>{toc}</ol></nav>
<main>
{body}
</main>
<script>{SORT_SCRIPT}</script>
</body>
</html>
"""

"""Slocum layered-control mission files as written: a `.mi` file's `sensor:` lines and
its behaviors in priority order (first = highest), each with the `b_arg`s of the `.mi`
and of the `.ma` file its `args_from_file` names, and a goto list's waypoints.

Every value keeps the file and line it came from, for the translation's comments and
warnings. As the glider reads them, arguments apply in order: an `args_from_file` line
reads its `.ma` file at that point, and a later line of the `.mi` overrides it. A
`.ma` file is `mafiles/<first 6 letters of the behavior><N>.ma`, N written with at
least two digits (`yo10.ma`, `surfac01.ma`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from gliderplan.contract.errors import GliderplanError
from gliderplan.contract.files import read_input


class SlocumFileError(GliderplanError):
    """A file that cannot be read as a Slocum mission; the message starts `FILE:LINE:`."""


@dataclass(frozen=True)
class Where:
    path: Path
    line: int

    def __str__(self) -> str:
        return f"{self.path}:{self.line}"


@dataclass(frozen=True)
class Arg:
    """One `b_arg: name(unit) value` or `sensor: name(unit) value`."""

    name: str
    unit: str
    value: float
    text: str  # the value as written
    where: Where
    comment: str = ""  # the line's comment, without '#'


@dataclass(frozen=True)
class Waypoint:
    """A goto list's waypoint in the file's order: longitude first, DDMM.MMMM."""

    lon: float
    lat: float
    where: Where


@dataclass
class Behavior:
    name: str  # lower case, e.g. "goto_list"
    where: Where  # its `behavior:` line
    args: dict[str, Arg] = field(default_factory=dict)
    mafile: Path | None = None
    missing_mafile: Path | None = None  # named by args_from_file but not found
    waypoints: list[Waypoint] = field(default_factory=list)

    def value(self, name: str, default: float | None = None) -> float | None:
        arg = self.args.get(name)
        return arg.value if arg is not None else default

    @property
    def source(self) -> str:
        """Where the behavior is, as comments name it: `m.mi:75, sample10.ma`."""
        where = f"{self.where.path.name}:{self.where.line}"
        return f"{where}, {self.mafile.name}" if self.mafile else where


@dataclass(frozen=True)
class SlocumMission:
    path: Path
    sensors: tuple[Arg, ...]
    behaviors: tuple[Behavior, ...]


_SETTING = re.compile(r"^(b_arg|sensor):\s*([A-Za-z_][A-Za-z0-9_]*)\s*\(([^)]*)\)\s+(\S+)\s*$")
_BEHAVIOR = re.compile(r"^behavior:\s*([A-Za-z_][A-Za-z0-9_]*)\s*$")
_NUMBER = re.compile(r"^[-+]?(\d+(\.\d*)?|\.\d+)([eE][-+]?\d+)?$")


def number_text(value: float) -> str:
    """A value as the translated mission writes it: 50, 0.43, 43200."""
    return f"{value:.10g}"


def _split_comment(raw: str) -> tuple[str, str]:
    text, _, comment = raw.partition("#")
    return text.strip(), comment.strip()


def _setting(kind: str, text: str, comment: str, where: Where) -> Arg:
    match = _SETTING.match(text)
    if match is None or match[1] != kind:
        raise SlocumFileError(f"{where}: malformed line {text!r}: expected "
                              f"'{kind}: name(unit) value'")
    if not _NUMBER.match(match[4]) or not math.isfinite(float(match[4])):
        raise SlocumFileError(f"{where}: {match[2]}: {match[4]!r} is not a number")
    return Arg(match[2], match[3], float(match[4]), match[4], where, comment)


def mafile_name(behavior: str, number: int) -> str:
    return f"{behavior[:6]}{number:02d}.ma"


def read_mafile(path: Path, behavior: Behavior) -> None:
    """Add a .ma file's b_args (and waypoints) to the behavior, in file order."""
    lines = _lines(path, "Slocum behavior argument (.ma) file")
    section = None  # None before <start:b_arg>, then "b_arg", "between", "waypoints", "end"
    header_seen = False
    for number, raw in enumerate(lines, start=1):
        where = Where(path, number)
        text, comment = _split_comment(raw)
        if not text:
            continue
        if not header_seen:
            name = text.replace(" ", "").partition("behavior_name=")[2]
            if not text.replace(" ", "").startswith("behavior_name="):
                raise SlocumFileError(f"{where}: expected 'behavior_name={behavior.name}' "
                                      "as the first line of a .ma file")
            if name.lower() != behavior.name:
                raise SlocumFileError(f"{where}: this file is for behavior {name!r}, but "
                                      f"{behavior.where} reads it for {behavior.name!r}")
            header_seen = True
            continue
        tag = text.lower()
        if tag == "<start:b_arg>" and section is None:
            section = "b_arg"
        elif tag == "<end:b_arg>" and section == "b_arg":
            section = "between"
        elif tag == "<start:waypoints>" and section == "between":
            section = "waypoints"
        elif tag == "<end:waypoints>" and section == "waypoints":
            section = "end"
        elif section == "b_arg":
            arg = _setting("b_arg", text, comment, where)
            behavior.args[arg.name] = arg
        elif section == "waypoints":
            behavior.waypoints.append(_waypoint(text, where))
        else:
            raise SlocumFileError(f"{where}: unexpected line {text!r}"
                                  + (" before <start:b_arg>" if section is None else ""))
    if section in (None, "b_arg", "waypoints"):
        missing = {None: "<start:b_arg>", "b_arg": "<end:b_arg>",
                   "waypoints": "<end:waypoints>"}[section]
        raise SlocumFileError(f"{path}:{len(lines)}: no {missing} in this .ma file")


def _waypoint(text: str, where: Where) -> Waypoint:
    fields = text.split()
    if len(fields) != 2 or not all(_NUMBER.match(f) for f in fields):
        raise SlocumFileError(f"{where}: a waypoint is two numbers, longitude then latitude "
                              f"(DDMM.MMMM), not {text!r}")
    lon, lat = float(fields[0]), float(fields[1])
    for value, text, limit, what in ((lon, fields[0], 18000.0, "longitude"),
                                     (lat, fields[1], 9000.0, "latitude")):
        if abs(value) > limit or abs(value) % 100 >= 60:
            raise SlocumFileError(f"{where}: {what} {text} is not DDMM.MMMM (a waypoint line "
                                  "gives longitude, then latitude)")
    return Waypoint(lon, lat, where)


def read_mission(path: str | Path, mafiles: str | Path | None = None,
                 allow_missing_mafiles: bool = False) -> SlocumMission:
    """Read a .mi file and the .ma files it names (in `mafiles`, by default the
    `mafiles` directory beside the .mi or beside its `missions` directory)."""
    path = Path(path)
    lines = _lines(path, "Slocum mission (.mi) file")
    ma_dir = Path(mafiles) if mafiles is not None else _default_mafiles(path)
    sensors: list[Arg] = []
    behaviors: list[Behavior] = []
    for number, raw in enumerate(lines, start=1):
        where = Where(path, number)
        text, comment = _split_comment(raw)
        if not text:
            continue
        if match := _BEHAVIOR.match(text):
            behaviors.append(Behavior(match[1].lower(), where))
        elif text.startswith("sensor:"):
            sensors.append(_setting("sensor", text, comment, where))
        elif text.startswith("b_arg:"):
            if not behaviors:
                raise SlocumFileError(f"{where}: b_arg before any 'behavior:' line")
            arg = _setting("b_arg", text, comment, where)
            behavior = behaviors[-1]
            behavior.args[arg.name] = arg
            if arg.name == "args_from_file" and arg.value >= 0:
                _load_mafile(behavior, arg, ma_dir, allow_missing_mafiles)
        else:
            raise SlocumFileError(f"{where}: malformed line {text!r}: expected "
                                  "'behavior: NAME', 'b_arg: name(unit) value' or "
                                  "'sensor: name(unit) value'")
    return SlocumMission(path, tuple(sensors), tuple(behaviors))


def _lines(path: Path, what: str) -> list[str]:
    """The lines of a Slocum file; a byte that is not UTF-8 (a comment written on an old
    card) becomes U+FFFD rather than an error. InputFileError (`usage` for a path that
    names no such file) as for every file gliderplan reads."""
    return read_input(path, what).decode("utf-8", errors="replace").splitlines()


def _default_mafiles(mission: Path) -> Path:
    beside = mission.parent / "mafiles"
    if beside.is_dir() or mission.parent.name != "missions":
        return beside
    return mission.parent.parent / "mafiles"


def _load_mafile(behavior: Behavior, arg: Arg, ma_dir: Path, allow_missing: bool) -> None:
    if arg.value != int(arg.value):
        raise SlocumFileError(f"{arg.where}: args_from_file {arg.text} is not a whole number")
    number = int(arg.value)
    # file names as the glider's card has them, in any case
    available = {p.name.lower(): p for p in sorted(ma_dir.glob("*.ma"))} \
        if ma_dir.is_dir() else {}
    for name in (mafile_name(behavior.name, number), f"{behavior.name[:6]}{number}.ma"):
        if (found := available.get(name.lower())) is not None:
            behavior.mafile = found
            read_mafile(found, behavior)
            return
    wanted = ma_dir / mafile_name(behavior.name, number)
    if not allow_missing:
        raise SlocumFileError(f"{arg.where}: args_from_file {number}: no file {wanted} "
                              "(give the .ma directory with --mafiles)")
    behavior.missing_mafile = wanted

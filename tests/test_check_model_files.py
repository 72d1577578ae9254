"""`gliderplan check` opens every file a mission names (vehicle, board, battery) and holds
its figures to physical ranges (power_models/plausible.py): a file that cannot be read or
describes no real hardware fails the check at the mission's line naming the file and the
key, and so does a yo the vehicle cannot fly, at its profile."""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.power_models.plausible import RANGES

ROOT = Path(__file__).resolve().parents[1]
MISSION = (ROOT / "examples" / "fig2_annotated.mission").read_text()
DATA = ROOT / "power_models" / "data"
# where each kind of file is named in the mission, and the line it is named on
NAMED = {"vehicle": ("vehicle slocum_g2_shallow", 6),
         "board": ("computer ts7800 @ 300 MHz", 7),
         "battery": ("battery 1.2 kWh reserve 15 %", 8)}
PRESET = {"vehicle": "vehicle_slocum_g2_shallow.toml", "board": "board_ts7800.toml",
          "battery": "battery_alkaline.toml"}


def naming(kind: str, file: str) -> str:
    """The annotated Fig. 2 with its `kind` given as the file `file`."""
    line = {"vehicle": f'vehicle "{file}"', "board": f'computer "{file}" @ 300 MHz',
            "battery": f'battery "{file}"'}[kind]
    assert NAMED[kind][0] in MISSION
    return MISSION.replace(NAMED[kind][0], line)


def preset_with(kind: str, old: str, new: str) -> Callable[[Path], None]:
    """Writes the shipped `kind` file with `old` replaced by `new`."""
    def write(path: Path) -> None:
        text = (DATA / PRESET[kind]).read_text()
        assert old in text, old
        path.write_text(text.replace(old, new, 1))
    return write


def nothing(path: Path) -> None:
    """No file at all."""


def directory(path: Path) -> None:
    path.mkdir()


def fifo(path: Path) -> None:
    os.mkfifo(path)


def symlink_loop(path: Path) -> None:
    os.symlink(path.name + ".other", path)
    os.symlink(path.name, path.parent / (path.name + ".other"))


CASES = [
    ("vehicle missing", "vehicle", nothing, "no such file"),
    ("vehicle directory", "vehicle", directory, "is a directory, not a vehicle file"),
    ("vehicle fifo", "vehicle", fifo, r"is not a regular file \(a device, pipe or socket\)"),
    ("vehicle symlink loop", "vehicle", symlink_loop,
     "cannot open: Too many levels of symbolic links"),
    ("vehicle nan", "vehicle", preset_with("vehicle", "value = 42.0947", "value = nan"),
     "pump_rate: value must be a finite number, got nan"),
    ("vehicle pump 1e-300 cc/s", "vehicle",
     preset_with("vehicle", "value = 42.0947", "value = 1e-300"),
     r"pump_rate: 1e-300 cc/s lies outside the plausible 0.5 to 500 cc/s \(glidersim"),
    ("vehicle hotel 5 kW", "vehicle",
     preset_with("vehicle", "value = 2.41364", "value = 5000"),
     "hotel_power: 5000 W lies outside the plausible 0.05 to 50 W"),
    ("vehicle water 1 kg/m3", "vehicle",
     preset_with("vehicle", "value = 1024.31", "value = 1.0"),
     "flight.water_density: 1.0 kg/m3 lies outside the plausible 950 to 1100 kg/m3"),
    ("board missing", "board", nothing, "no such file"),
    ("board directory", "board", directory, "is a directory, not a board file"),
    ("board nan power", "board", preset_with("board", "value = 3.42", "value = nan"),
     r"mode\[0\].active_power: value must be a finite number, got nan"),
    ("board 1e9 MHz", "board", preset_with("board", "value = 500, unit", "value = 5e8, unit"),
     r"mode\[1\].clock: 500000000.0 MHz lies outside the plausible 1 to 10000 MHz"),
    ("board boot 1e6 s", "board", preset_with("board", "value = 2.0", "value = 1e6"),
     "boot_time: 1000000.0 s lies outside the plausible 0 to 600 s"),
    ("battery missing", "battery", nothing, "no such file"),
    ("battery fifo", "battery", fifo, "is not a regular file"),
    ("battery 7.8 TJ", "battery", preset_with("battery", "value = 7.8", "value = 7.8e6"),
     "energy: 7800000.0 MJ lies outside the plausible 0.001 to 100 MJ"),
    ("battery nan volts", "battery", preset_with("battery", "value = 15", "value = nan"),
     "voltage: value must be a finite number, got nan"),
]


@pytest.mark.parametrize(("kind", "make", "said"), [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_a_bad_file_the_mission_names_fails_the_check(tmp_path, capsys, kind, make, said):
    make(tmp_path / "model.toml")
    mission = tmp_path / "fig2.mission"
    mission.write_text(naming(kind, "model.toml"))
    assert main(["check", str(mission)]) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    line = NAMED[kind][1]
    assert re.search(rf"fig2.mission:{line}:\d+: error: {kind} model.toml: "
                     rf"{re.escape(str(tmp_path / 'model.toml'))}: {said}", err), err
    assert "Traceback" not in err


@pytest.mark.parametrize("kind", list(PRESET))
def test_a_sound_file_passes_the_check(tmp_path, capsys, kind):
    (tmp_path / "model.toml").write_text((DATA / PRESET[kind]).read_text())
    mission = tmp_path / "fig2.mission"
    mission.write_text(naming(kind, "model.toml"))
    assert main(["check", str(mission)]) == ExitCode.OK, capsys.readouterr().err


def test_a_yo_the_vehicle_cannot_fly_fails_at_its_profile(tmp_path, capsys):
    preset_with("vehicle", "value = 233", "value = 50")(tmp_path / "weak.toml")
    mission = tmp_path / "fig2.mission"
    mission.write_text(naming("vehicle", "weak.toml"))
    assert main(["check", str(mission)]) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert "fig2.mission:19:17: error: s1: flightprofile 0: a yo 5-10 m on vehicle " \
           "slocum_g2_shallow: the glider cannot dive below 5 m" in err
    assert "fig2.mission:42:41: error: s3: flightprofile 1: a yo 5-30 m" in err  # each one
    assert "hint: a deeper pump (max_ballast), a lighter trim or a shallower yo" in err


def test_every_range_states_its_source_and_holds_the_shipped_files():
    from gliderplan.power_models import load_board, load_vehicle
    from gliderplan.power_models.battery import load_battery
    from gliderplan.power_models.catalog import preset_names

    assert all(r.low < r.high and r.source.strip() for r in RANGES.values())
    for kind, load in (("vehicle", load_vehicle), ("board", load_board),
                       ("battery", load_battery)):
        for name in preset_names(kind):
            load(name)  # refused if a shipped figure left its range

"""A user's own model file loads like a preset, and every mistake names the file and the key."""

from __future__ import annotations

import math
import re
import tomllib

import pytest

from gliderplan.contract import ExitCode
from gliderplan.contract.files import InputFileError
from gliderplan.contract.units import UNITS
from gliderplan.power_models import load_battery, load_board, load_sensor, load_vehicle
from gliderplan.power_models.catalog import DATA_DIR, preset_path
from gliderplan.power_models.errors import ModelFileError


def _copy_with(tmp_path, kind, preset, old, new, name="mine.toml"):
    text = preset_path(kind, preset).read_text()
    assert old in text, old
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


def test_a_users_vehicle_file_loads_like_the_preset(tmp_path):
    path = _copy_with(tmp_path, "vehicle", "slocum_g3", 'name = "slocum_g3"', 'name = "my_g3"')
    mine, preset = load_vehicle(str(path)), load_vehicle("slocum_g3")
    assert mine.name == "my_g3"
    assert mine.pump_energy_j(50.0, 300.0) == preset.pump_energy_j(50.0, 300.0)


def test_units_are_converted(tmp_path):
    path = _copy_with(
        tmp_path, "sensor", "ctd", 'value = 240, unit = "mW"', 'value = 0.24, unit = "W"'
    )
    assert load_sensor(str(path)).on_power_w == load_sensor("ctd").on_power_w
    path = _copy_with(
        tmp_path,
        "vehicle",
        "slocum_g3",
        'value = 26, unit = "deg"',
        'value = 0.4537856, unit = "rad"',
    )
    assert load_vehicle(str(path)).nominal_pitch_rad == pytest.approx(0.4537856)


@pytest.mark.parametrize(
    ("kind", "preset", "old", "new", "key", "message"),
    [
        ("vehicle", "slocum_g3", "hotel_power = ", "hotel_powr = ", "hotel_power", "missing"),
        (
            "vehicle",
            "slocum_g3",
            'value = 1.158, unit = "W"',
            'value = 1.155, unit = "Wh"',
            "hotel_power",
            "not a unit of power",
        ),
        (
            "vehicle",
            "slocum_g3",
            'value = 1.158, unit = "W"',
            'value = -1.158, unit = "W"',
            "hotel_power",
            "must be >= 0",
        ),
        (
            "vehicle",
            "slocum_g3",
            'value = 0.15, unit = "1", source = "Merckelbach et al. 2019: 0.15-0.17" ',
            'value = 0.15, unit = "1" ',
            "flight.drag_cd0",
            "missing 'source'",
        ),
        (
            "board",
            "ts5500",
            'value = 2.7, unit = "W"',
            'value = "2.7", unit = "W"',
            "mode[0].active_power",
            "finite number",
        ),
        (
            "board",
            "ts5500",
            'value = 2.2, unit = "W"',
            'value = 3.2, unit = "W"',
            "mode[0].idle_power",
            "must not exceed active_power",
        ),
        (
            "board",
            "ts7800",
            'wake_energy = { value = 1.03, unit = "J", source = "assumption: wake_latency at '
            'active power (the CPU resumes the drivers at full load): 0.3 s x 3.42 W" }',
            "",
            "mode[0].wake_energy",
            "missing",
        ),
        (
            "board",
            "ts5500",
            'idle_power = { value = 2.2, unit = "W",',
            'wake_energy = { value = 1, unit = "J", source = "x" }\n'
            'idle_power = { value = 2.2, unit = "W",',
            "mode[0].wake_energy",
            "no [sleep] table",
        ),
        (
            "board",
            "ts7800",
            'wake_on = ["serial", "timer"]',
            "wake_on = []",
            "sleep.wake_on",
            "expected some of serial, timer",
        ),
        (
            "battery",
            "alkaline",
            'value = 85, unit = "%"',
            'value = 120, unit = "%"',
            "usable_fraction",
            "must be <= 100",
        ),
        (
            "sensor",
            "ctd",
            'kind = "sensor"',
            'kind = "sensor"\nsample_hz = 3',
            "sample_hz",
            "unknown key",
        ),
        ("sensor", "ctd", 'kind = "sensor"', 'kind = "board"', "kind", "expected a 'sensor'"),
        ("sensor", "dvl", "low = 0.75, high = 3.5", "low = 3.5, high = 0.75", "power_range",
         "low 3.5 W is above high 0.75 W"),
        ("sensor", "dvl", 'high = 3.5, unit = "W"', 'high = 3.5, unit = "Wh"', "power_range",
         "not a unit of power"),
        ("sensor", "dvl", "low = 0.75, high = 3.5", "low = 0.75", "power_range",
         "missing 'high'"),
        ("sensor", "dvl", "low = 0.75, high = 3.5", "low = -1, high = 3.5", "power_range",
         "low must be a finite number >= 0"),
        ("sensor", "logger", 'unit = "W", source = "assumption: 0.75-3 W', 'unit = "W", '
         'source = "", note = "assumption: 0.75-3 W', "power_range", "source must say"),
    ],
)
def test_mistakes_name_the_file_and_the_key(tmp_path, kind, preset, old, new, key, message):
    path = _copy_with(tmp_path, kind, preset, old, new)
    loader = {
        "vehicle": load_vehicle,
        "board": load_board,
        "battery": load_battery,
        "sensor": load_sensor,
    }[kind]
    with pytest.raises(ModelFileError) as caught:
        loader(str(path))
    assert str(caught.value).startswith(f"{path}: {key}: ")
    assert message in str(caught.value)


def test_a_sensor_file_without_a_power_range_loads_without_one(tmp_path):
    text = preset_path("sensor", "dvl").read_text()
    path = tmp_path / "mine.toml"
    path.write_text("\n".join(line for line in text.splitlines()
                              if not line.startswith("power_range")))
    assert load_sensor(str(path)).power_range_w is None
    assert load_sensor("dvl").power_range_w == pytest.approx((0.75, 3.5))


def test_unknown_key_suggests_the_right_one(tmp_path):
    path = _copy_with(tmp_path, "vehicle", "slocum_g3", "pump_rate = ", "pump_rat = ")
    with pytest.raises(ModelFileError, match="pump_rate: missing .*'pump_rat' a misspelling"):
        load_vehicle(str(path))


def test_broken_or_missing_files(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("kind = \n")
    with pytest.raises(ModelFileError, match=r"bad\.toml: not valid TOML"):
        load_vehicle(str(bad))
    with pytest.raises(InputFileError, match=r"nowhere\.toml: no such file") as missing:
        load_board(str(tmp_path / "nowhere.toml"))
    assert missing.value.exit_code == ExitCode.USAGE
    with pytest.raises(ModelFileError, match="unknown vehicle preset"):
        load_vehicle("slocum_g9")


def test_a_figure_may_carry_its_standard_deviation_in_its_own_unit(tmp_path):
    path = _copy_with(
        tmp_path, "vehicle", "slocum_g3", 'value = 1.158, unit = "W"',
        'value = 1158, unit = "mW", sd = 50'
    )
    vehicle = load_vehicle(str(path))
    assert vehicle.hotel_w == pytest.approx(1.158)
    assert vehicle.uncertainty.keys == ("hotel_power",)
    assert vehicle.uncertainty.sd == pytest.approx([0.05])
    assert load_vehicle("slocum_g3").uncertainty is None


UNCERTAINTY = '\n[uncertainty]\nfigures = ["hotel_power"]\ncorrelation = [[{}]]\nsource = "x"\n'


@pytest.mark.parametrize(
    ("sd", "tail", "key", "message"),
    [
        (", sd = -1", "", "hotel_power", "sd must be a finite number >= 0"),
        ("", UNCERTAINTY.format(1), "uncertainty.figures", "no sd next to the figure"),
        (", sd = 0.1", UNCERTAINTY.format(0.5), "uncertainty.correlation",
         "expected a symmetric 1 x 1 matrix"),
        (', sd = 0.1, at_least = "yes"', "", "hotel_power", "at_least must be true or false"),
    ],
)
def test_uncertainty_is_checked(tmp_path, sd, tail, key, message):
    path = _copy_with(tmp_path, "vehicle", "slocum_g3", 'value = 1.158, unit = "W"',
                      f'value = 1.158, unit = "W"{sd}')
    path.write_text(path.read_text() + tail)
    with pytest.raises(ModelFileError) as caught:
        load_vehicle(str(path))
    assert str(caught.value).startswith(f"{path}: {key}: ")
    assert message in str(caught.value)


def test_the_hotel_load_names_known_devices(tmp_path):
    path = _copy_with(tmp_path, "vehicle", "slocum_g3", "devices = []",
                      'devices = ["ctd", "sonar"]')
    with pytest.raises(ModelFileError, match=r"hotel_includes\.devices: unknown device 'sonar'"):
        load_vehicle(str(path))
    assert load_vehicle("slocum_g2_shallow").hotel_includes == ("ctd", "optics", "fin")


DVL = """
[devices.dvl]
kind = "sensor"
on_power = { value = 1.0, unit = "W", sd = 0.1, source = "test" }
"""


def test_a_device_table_gives_each_device_its_figures(tmp_path):
    path = tmp_path / "dvl.toml"
    path.write_text(preset_path("vehicle", "slocum_g3").read_text() + DVL)
    vehicle = load_vehicle(str(path))
    assert vehicle.device("dvl").on_power_w == 1.0 and vehicle.device("dvl").kind == "sensor"
    assert "devices.dvl.on_power" in vehicle.uncertainty.keys


@pytest.mark.parametrize("old, new, message", [
    ('kind = "sensor"', 'kind = "motor"', r"devices\.dvl\.kind: expected one of sensor, actuator"),
    ("[devices.dvl]", "[devices.sonar]", r"devices\.sonar: unknown sensor device 'sonar'"),
    ('value = 1.0, unit = "W"', 'value = 1.0, unit = "J"', r"devices\.dvl\.on_power: unit 'J'"),
    ('value = 1.0, unit = "W"', 'value = -1.0, unit = "W"', r"devices\.dvl\.on_power: must be"),
    ("on_power", "on_pwer", r"devices\.dvl\.on_power: missing"),
])
def test_a_bad_device_table_is_refused_naming_the_key(tmp_path, old, new, message):
    path = tmp_path / "dvl.toml"
    path.write_text(preset_path("vehicle", "slocum_g3").read_text() + DVL.replace(old, new))
    with pytest.raises(ModelFileError, match=message):
        load_vehicle(str(path))


def test_a_hotel_load_smaller_than_the_instruments_it_holds_is_refused(tmp_path):
    text = preset_path("vehicle", "slocum_g2_shallow").read_text()
    path = tmp_path / "small.toml"
    path.write_text(text.replace("hotel_power = { value = 2.41364", "hotel_power = { value = 0.5"))
    with pytest.raises(ModelFileError, match=r"hotel_power: 0\.5 W is less than the "
                                             r"instruments hotel_includes says it holds"):
        load_vehicle(str(path))


# ---- every preset figure agrees with the numbers its source quotes ------------------------
_NUMBER = r"[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?"


def _quoted(source: str, unit: str) -> list[float]:
    """Numbers the source gives in `unit`: "32 cc/s", a range "3-38 m" (both ends), a
    spread "+-233 cc" (its size)."""
    number = rf"(\+-)?({_NUMBER})"
    pattern = (rf"(?<![\w.]){number}(?:\s*(?:-|\.\.|to)\s*{number})?"
               rf"\s*{re.escape(unit)}(?![\w/])")
    found = []
    for spread, first, spread2, second in re.findall(pattern, source):
        found.append(abs(float(first)) if spread else float(first))
        if second:
            found.append(abs(float(second)) if spread2 else float(second))
    return found


def _quoted_in_any_unit(source: str, unit: str) -> list[float]:
    """Numbers the source gives in `unit` or in another unit of its dimension, converted
    ("0.454 rad" for a figure in deg, "0.0716 m3" for one in l)."""
    found = _quoted(source, unit)
    for table in (t for t in UNITS.values() if unit in t):
        found += [q * factor / table[unit] for other, factor in table.items() if other != unit
                  for q in _quoted(source, other)]
    return found


def _figures(name, prefix, table):
    for key, item in table.items():
        if isinstance(item, dict) and "value" in item:
            yield name, prefix + key, item
        elif isinstance(item, dict):
            yield from _figures(name, f"{prefix}{key}.", item)
        elif isinstance(item, list):
            for i, sub in enumerate(item):
                if isinstance(sub, dict):
                    yield from _figures(name, f"{prefix}{key}[{i}].", sub)


def _preset_figures():
    for path in sorted(DATA_DIR.glob("*.toml")):
        with open(path, "rb") as handle:
            yield from _figures(path.name, "", tomllib.load(handle))


QUOTING = [(f, k, e) for f, k, e in _preset_figures()
           if _quoted_in_any_unit(e["source"], e["unit"])]


@pytest.mark.parametrize(("file", "key", "entry"), QUOTING,
                         ids=[f"{f}:{k}" for f, k, _ in QUOTING])
def test_a_preset_figure_is_a_number_its_source_quotes(file, key, entry):
    quoted = _quoted_in_any_unit(entry["source"], entry["unit"])
    assert any(math.isclose(entry["value"], q, rel_tol=1e-3) for q in quoted), (
        f"{file}: {key} = {entry['value']} {entry['unit']}, but its source quotes "
        f"{quoted}: {entry['source']}")


SPANS = [(path.name, tomllib.loads(path.read_text())["power_range"])
         for path in sorted(DATA_DIR.glob("sensor_*.toml"))]


@pytest.mark.parametrize(("file", "span"), SPANS, ids=[f for f, _ in SPANS])
def test_a_sensor_presets_power_range_is_what_its_source_quotes(file, span):
    quoted = _quoted_in_any_unit(span["source"], span["unit"])
    for end in ("low", "high"):
        assert any(math.isclose(span[end], q, rel_tol=1e-3) for q in quoted), (
            f"{file}: power_range {end} = {span[end]} {span['unit']}, but its source quotes "
            f"{quoted}: {span['source']}")


def test_the_source_check_reads_ranges_and_spreads():
    assert _quoted("shallow pump +-233 cc (the log: -231..+234 cc)", "cc") == [233, -231, 234]
    assert len(QUOTING) > 20  # most figures quote their number
    assert _quoted("yo 3-38 m; 2.4888 J/cc", "m") == [3, 38]
    assert _quoted_in_any_unit("Vg ~ 0.0716 m3", "l") == pytest.approx([71.6])
    assert _quoted("oil in E = dV (-0.17935 + ...), i.e. 0.17935 J/cc and -0.005574 J/(cc m)",
                   "J/(cc m)") == [-0.005574]

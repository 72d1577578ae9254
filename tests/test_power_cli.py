"""`gliderplan power` as a user runs it: tables, JSON, and clear errors for bad input."""

from __future__ import annotations

import json

import pytest

from gliderplan.cli.main import main
from gliderplan.power_models import load_vehicle


def _json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_list_names_every_kind(capsys):
    data = _json(capsys, ["power", "list", "--json"])
    assert data["board"] == ["ts5500", "ts7800"]
    assert "slocum_g2_shallow" in data["vehicle"]


def test_show_board_gives_each_figure_with_unit_and_source(capsys):
    data = _json(capsys, ["power", "show", "board", "ts7800@500", "--json"])
    actives = {r["key"]: r["value"] for r in data["figures"] if r["key"].endswith("active_power")}
    assert sorted(actives.values()) == [3.42, 4.14]
    assert all(r["source"] and r["unit"] for r in data["figures"])
    assert main(["power", "show", "board", "ts5500"]) == 0
    assert "Woithe & Kremer, Table I" in capsys.readouterr().out


def test_show_vehicle_text_table(capsys):
    assert main(["power", "show", "vehicle", "slocum_g3"]) == 0
    out = capsys.readouterr().out
    assert "pump_out_energy_per_volume" in out and "J/(cc m)" in out and "optimal speed" in out


@pytest.mark.parametrize(("name", "span"), [("dvl", "0.75-3.5"), ("logger", "0.75-3"),
                                            ("ctd", "21-240")])
def test_show_sensor_prints_its_published_power_range(capsys, name, span):
    assert main(["power", "show", "sensor", name]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("power_range"))
    assert line.split()[1:3] == [span, "mW" if name == "ctd" else "W"]
    data = _json(capsys, ["power", "show", "sensor", name, "--json"])
    (entry,) = data["ranges"]
    assert entry["key"] == "power_range" and f"{entry['low']:g}-{entry['high']:g}" == span
    assert entry["source"] in line
    assert _json(capsys, ["power", "show", "vehicle", "slocum_g3", "--json"])["ranges"] == []


def test_energy_table_matches_the_model(capsys):
    data = _json(
        capsys,
        [
            "power",
            "energy",
            "--vehicle",
            "slocum_g3",
            "--min-depth",
            "5",
            "--max-depth",
            "20,100",
            "--speed",
            "0.2,0.3",
            "--json",
        ],
    )
    vehicle = load_vehicle("slocum_g3")
    pitch = data["pitch_rad"]
    ballast = vehicle.ballast_for_speed(0.3, pitch)
    expected = vehicle.energy_per_km_j(5, 100, pitch, ballast) / 1e3
    assert data["energy_per_km_kj"][1][1] == pytest.approx(float(expected))
    assert data["energy_per_km_kj"][0][0] > data["energy_per_km_kj"][1][0]


def test_energy_marks_speeds_beyond_the_pump(capsys):
    data = _json(capsys, ["power", "energy", "--speed", "0.2,0.6", "--json"])
    assert all(row[1] is None for row in data["energy_per_km_kj"])
    assert all(row[0] is not None for row in data["energy_per_km_kj"])


def test_optimal_speed_grows_with_hotel_load(capsys):
    data = _json(
        capsys,
        [
            "power",
            "speed",
            "--vehicle",
            "slocum_g3",
            "--hotel-w",
            "0.5,1,2",
            "--max-depth",
            "200",
            "--json",
        ],
    )
    speeds = [r["speed_mps"] for r in data["rows"]]
    assert speeds == sorted(speeds) and speeds[0] < speeds[-1]


@pytest.mark.parametrize(
    ("argv", "code", "message"),
    [
        (["power", "show", "vehicle", "nosuch"], 2, "unknown vehicle preset"),
        (["power", "show", "board", "ts7800@400"], 2, "no 400 MHz clock"),
        (["power", "show", "vehicle", "missing.toml"], 2, "missing.toml: no such file"),
        (["power", "energy", "--min-depth", "30", "--max-depth", "20"], 2, "deeper than"),
        (["power", "energy", "--speed", "fast"], 2, "expected numbers"),
        (["power", "speed", "--hotel-w", "-1"], 2, "--hotel-w"),
        (["power", "show", "sensor", "ctd", "--clock", "300"], 2, "--clock only applies"),
    ],
)
def test_bad_input_is_a_clear_error(capsys, argv, code, message):
    try:
        result = main(argv)
    except SystemExit as exit_:  # argparse rejects a malformed value before run()
        result = exit_.code
    assert result == code
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_the_tables_are_python_calls():
    from gliderplan.contract.errors import UsageError
    from gliderplan.power_models import tables

    assert tables.presets("board") == {"board": ["ts5500", "ts7800"]}
    data = tables.energy_per_km("slocum_g3", min_depth_m=5, max_depths_m=[20, 100],
                                speeds_mps=[0.2, 0.3])
    vehicle = load_vehicle("slocum_g3")
    ballast = vehicle.ballast_for_speed(0.3, data["pitch_rad"])
    expected = vehicle.energy_per_km_j(5, 100, data["pitch_rad"], ballast) / 1e3
    assert data["energy_per_km_kj"][1][1] == pytest.approx(float(expected))
    hungry = tables.optimal_speeds([1.0, 4.0], "slocum_g3")["rows"]
    assert hungry[0]["speed_mps"] < hungry[1]["speed_mps"]  # a hungrier load flies faster
    assert tables.model_figures("board", "ts7800", 500.0)["name"] == "ts7800"
    with pytest.raises(UsageError, match="--clock only applies to a board"):
        tables.model_figures("sensor", "ctd", 300.0)

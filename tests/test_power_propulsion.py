"""Propulsion models: the hybrid's thruster and the AUV's propeller load from their sourced
figures, the best speed matches the closed form, and a bad [propulsion] table names its key."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gliderplan.cli.main import main
from gliderplan.planner.speed import NoHeadway, best_speed, choice_at, head_current
from gliderplan.power_models import load_vehicle
from gliderplan.power_models.catalog import preset_path
from gliderplan.power_models.errors import ModelFileError
from gliderplan.power_models.propulsion import (
    SpeedOutOfRange,
    ground_speed_mps,
    thrust_assisted_speed,
)

POWER_LAW = """
[propulsion]
model = "power_law"
reference_power = { value = 20, unit = "W", source = "test" }
reference_speed = { value = 1, unit = "m/s", source = "test" }
exponent = { value = 3, unit = "1", source = "test" }
min_speed = { value = 0.3, unit = "m/s", source = "test" }
max_speed = { value = 2, unit = "m/s", source = "test" }
"""


def _auv_file(tmp_path, propulsion: str = POWER_LAW, extra: str = ""):
    text = preset_path("vehicle", "lauv").read_text()
    head = text[:text.index("[propulsion]")]
    path = tmp_path / "auv.toml"
    path.write_text(head.replace('name = "lauv"', f'name = "cubic"{extra}') + propulsion)
    return path


def test_the_presets_are_a_glider_a_hybrid_and_an_auv():
    assert load_vehicle("slocum_g3").kind == "glider"
    assert load_vehicle("slocum_g3").propulsion is None
    hybrid, auv = load_vehicle("slocum_g3_hybrid"), load_vehicle("lauv")
    assert (hybrid.kind, hybrid.propulsion.model) == ("hybrid", "thruster")
    assert (auv.kind, auv.propulsion.model) == ("auv", "table")
    assert not auv.has_buoyancy_engine and auv.max_ballast_cc == 0.0


def test_the_auv_table_is_its_motor_power_against_rpm():
    lauv = load_vehicle("lauv").propulsion
    # 1 m/s near 900 RPM: 500 RPM is 0.556 m/s, 1400 RPM 1.556 m/s
    assert lauv.min_speed_mps == pytest.approx(500 / 900)
    assert lauv.max_speed_mps == pytest.approx(1400 / 900)
    assert float(lauv.power_w(1250 / 900)) == pytest.approx(54.0)
    # linear between the rows
    assert float(lauv.power_w((850 + 1250) / 2 / 900)) == pytest.approx((23.5 + 54) / 2)
    assert math.isnan(float(lauv.power_w(0.3)))
    with pytest.raises(SpeedOutOfRange, match=r"2 m/s is beyond the propulsion's 0\.556-1\.56"):
        lauv.check_speed(2.0)


def test_the_hybrid_draws_the_fitted_thruster_power_at_the_speed_its_command_flies():
    hybrid = load_vehicle("slocum_g3_hybrid")
    p = hybrid.propulsion
    # efficiency x commanded power = 1/2 rho S Cd0 U^3 at the hull's figures
    drag = 0.5 * hybrid.flight.rho_kg_m3 * hybrid.flight.wing_area_m2 * hybrid.flight.drag_cd0
    assert p.max_speed_mps == pytest.approx((0.5 * 9.0 / drag) ** (1 / 3))
    assert p.command_w(p.max_speed_mps) == pytest.approx(9.0)
    # the battery draws 4.3378 W + 2.0227 x the commanded watts while it runs
    assert float(p.power_w(p.max_speed_mps)) == pytest.approx(4.3378 + 2.0227 * 9.0)
    assert p.assist_draw_w(3.0) == pytest.approx(4.3378 + 2.0227 * 3.0)
    assert p.assist_draw_w(0.0) == 0.0
    with pytest.raises(SpeedOutOfRange, match="12 W is beyond the thruster's power-command"):
        p.check_command(12.0)


@pytest.mark.parametrize("vehicle", ["slocum_g3_hybrid", "cubic"])
def test_the_best_speed_matches_the_closed_form_of_the_cubic_model(tmp_path, vehicle):
    model = load_vehicle(vehicle if vehicle != "cubic" else str(_auv_file(tmp_path)))
    for load in (model.hotel_w, 5.0, 40.0):
        closed = model.propulsion.optimal_speed_mps(load)
        running = model.propulsion.running_w
        k = model.propulsion.coefficient
        assert closed == pytest.approx(((load + running) / (2 * k)) ** (1 / 3))
        chosen = best_speed(model.propulsion, load).speed_mps
        if model.propulsion.min_speed_mps < closed < model.propulsion.max_speed_mps:
            assert chosen == pytest.approx(closed, rel=0.01)
            assert chosen == pytest.approx(closed, rel=1e-6)  # to the search's precision
        else:  # held to the range
            assert chosen == pytest.approx(np.clip(closed, model.propulsion.min_speed_mps,
                                                   model.propulsion.max_speed_mps), rel=1e-6)


def test_a_head_current_makes_the_best_speed_faster_and_each_km_dearer():
    lauv = load_vehicle("lauv")
    still = best_speed(lauv.propulsion, lauv.hotel_w)
    against = best_speed(lauv.propulsion, lauv.hotel_w, head_current(0.5))
    assert against.speed_mps > still.speed_mps - 1e-9
    assert against.energy_per_m_j > still.energy_per_m_j
    # energy per metre over ground: (hotel + propulsion) / (U - 0.5)
    assert against.energy_per_m_j == pytest.approx(
        (lauv.hotel_w + against.propulsion_w) / (against.speed_mps - 0.5))
    with pytest.raises(NoHeadway):
        best_speed(lauv.propulsion, lauv.hotel_w, head_current(2.0))
    with pytest.raises(NoHeadway):
        choice_at(lauv.propulsion, lauv.hotel_w, 0.6, head_current(0.7))


def test_ground_speed_crabs_into_a_cross_current():
    assert float(ground_speed_mps(1.0, 0.0, 0.6)) == pytest.approx(0.8)
    assert float(ground_speed_mps(1.0, -0.3, 0.0)) == pytest.approx(0.7)
    assert math.isnan(float(ground_speed_mps(0.5, 0.0, 0.6)))


def test_a_thruster_adds_speed_along_the_glide_path():
    drag = 0.2
    assert float(thrust_assisted_speed(0.3, 0.0, 1025, 0.1, drag)) == 0.3
    u = float(thrust_assisted_speed(0.3, 2.0, 1025, 0.1, drag))
    a = 2 * 2.0 / (1025 * 0.1 * drag)
    assert u**3 - 0.3**2 * u - a == pytest.approx(0.0, abs=1e-12)
    assert u > 0.3
    # thrust alone (no buoyancy): drag power equals the thrust's
    assert float(thrust_assisted_speed(0.0, 2.0, 1025, 0.1, drag)) == pytest.approx(a ** (1 / 3))


@pytest.mark.parametrize(("old", "new", "key", "message"), [
    ("values = [14, 23.5, 54, 70]", "values = [14, -23.5, 54, 70]", "propulsion.power",
     "must be >= 0 W, got -23.5 W"),
    ("values = [500, 850, 1250, 1400]", "values = [500, 850, 850, 1400]", "propulsion.rpm",
     "the rows must increase"),
    ("values = [14, 23.5, 54, 70]", "values = [14, 23.5, 54]", "propulsion.power",
     "one power per rpm row"),
    ('model = "table"', 'model = "jet"', "propulsion.model", "expected one of power_law"),
    ('model = "table"', 'model = "thruster"', "propulsion.model",
     "an auv has no hull drag figures"),
    ('vehicle_kind = "auv"', 'vehicle_kind = "submarine"', "vehicle_kind",
     "expected one of glider, hybrid, auv"),
    ("nominal_max_depth", 'pump_rate = { value = 1, unit = "cc/s", source = "x" }\n'
     "nominal_max_depth", "pump_rate", "an AUV has no buoyancy engine"),
    ('unit = "rpm", source = "LSTS DUNE lauv-noptilus-1.ini: 1 m/s',
     'unit = "W", source = "LSTS DUNE lauv-noptilus-1.ini: 1 m/s', "propulsion.reference_rpm",
     "not a unit of rotation"),
])
def test_a_bad_propulsion_table_names_its_key(tmp_path, old, new, key, message):
    text = preset_path("vehicle", "lauv").read_text()
    assert old in text, old
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(ModelFileError) as caught:
        load_vehicle(str(path))
    assert str(caught.value).startswith(f"{path}: {key}: "), str(caught.value)
    assert message in str(caught.value)


def test_an_auv_and_a_hybrid_need_their_propulsion(tmp_path):
    path = _auv_file(tmp_path, propulsion="")
    with pytest.raises(ModelFileError, match="propulsion: missing .a auv needs a"):
        load_vehicle(str(path))
    text = preset_path("vehicle", "slocum_g3").read_text()
    hybrid = tmp_path / "h.toml"
    hybrid.write_text('vehicle_kind = "hybrid"\n' + text)
    with pytest.raises(ModelFileError, match="a hybrid needs a .propulsion. table"):
        load_vehicle(str(hybrid))
    glider = tmp_path / "g.toml"
    glider.write_text(text + POWER_LAW)
    with pytest.raises(ModelFileError, match="propulsion: a glider has no propulsion"):
        load_vehicle(str(glider))
    bad = _auv_file(tmp_path, POWER_LAW.replace('value = 2, unit = "m/s"',
                                                'value = 0.1, unit = "m/s"'))
    with pytest.raises(ModelFileError, match="max_speed: must be at least min_speed"):
        load_vehicle(str(bad))


def test_power_show_prints_the_propulsion_figures(capsys):
    assert main(["power", "show", "vehicle", "slocum_g3_hybrid", "--json"]) == 0
    import json

    data = json.loads(capsys.readouterr().out)
    assert data["vehicle_kind"] == "hybrid"
    propulsion = data["propulsion"]
    assert propulsion["model"] == "thruster"
    assert propulsion["best_speed_mps"] == pytest.approx(propulsion["closed_form_speed_mps"],
                                                         rel=1e-6)
    assert {f["key"] for f in data["figures"]} >= {"propulsion.offset_power",
                                                   "propulsion.power_slope"}
    assert main(["power", "show", "vehicle", "lauv"]) == 0
    text = capsys.readouterr().out
    assert "propulsion.power" in text and "14, 23.5, 54, 70" in text
    assert "propulsion (auv): table, 0.556-1.56 m/s" in text


def test_calibrate_refuses_an_auv_for_a_base(tmp_path, capsys):
    assert main(["calibrate", str(tmp_path), "--base", "lauv"]) == 2
    assert "an auv has no buoyancy engine" in capsys.readouterr().err

"""`gliderplan replan` (planner/replan.py): the rest of a mission planned again from a
surfacing's telemetry at the plan's confidence, warm from the model built once, written as a
signed plan update; what changed and why said; bad telemetry and a budget that cannot hold
the rest refused with a message, no update written, the glider flying its plan on."""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode, UpdateStatus
from gliderplan.language import check_file
from gliderplan.planner import make_plan
from gliderplan.planner.plan import PlanningError
from gliderplan.planner.planfile import read_plan_bytes
from gliderplan.planner.replan import ReplanInfeasible, Replanner, replan_mission
from gliderplan.planner.update import apply_update
from gliderplan.power_models.telemetry import J_PER_AH, SurfacingReport, write_json_telemetry
from gliderplan.sim.scenarios import read_spec

ROOT = Path(__file__).resolve().parents[1]
SHORT = str(ROOT / "tests" / "missions" / "replan_short.mission")
KEY = bytes(range(32))


@pytest.fixture(scope="module")
def short():
    return check_file(SHORT).checked()


@pytest.fixture
def signed(tmp_path, short):
    """The short line survey's plan, signed as plan 5, and the key."""
    key = tmp_path / "vehicle.key"
    key.write_text(KEY.hex() + "\n")
    key.chmod(0o600)
    plan = tmp_path / "held.plan"
    make_plan(short, output=plan, sign=key, seq=5)
    return plan, key


def telemetry(plan_file: Path, hours: tuple[float, ...], dvl: float = 1.0, energy: float = 1.0,
              **last) -> list[SurfacingReport]:
    """Reports of a glider that flies the plan as predicted (surfacing at each of `hours`),
    its DVL drawing `dvl` times its figure, everything else `energy` times the model."""
    plan = read_plan_bytes(plan_file.read_bytes())
    duties = {x.device: x.duty for x in plan.states[1].sensors}
    watts = {s.name: {c: j / s.time_s for c, j in s.energy_by_component_j.items()}
             for s in plan.states}
    reports = []
    for h in hours:
        t = h * 3600.0
        flown = {"launch": 600.0, "survey": t - 600.0, "surface_fix": 0.0}
        on = {d: duty * flown["survey"] for d, duty in duties.items()}
        used = sum(w * flown[s] * (dvl if c == "dvl" else energy)
                   for s, rates in watts.items() for c, w in rates.items())
        reports.append(SurfacingReport(t, used / J_PER_AH, 14.95, state="survey",
                                       device_on_s=on, state_time_s=flown, plan_seq=plan.seq))
    if last:
        from dataclasses import replace

        reports[-1] = replace(reports[-1], **last)
    return reports


def write(tmp_path: Path, reports: list[SurfacingReport]) -> Path:
    path = tmp_path / "telemetry.json"
    path.write_text(write_json_telemetry(reports))
    return path


def test_replan_writes_an_update_the_glider_applies_to_the_plan_it_holds(tmp_path, signed,
                                                                         short, capsys):
    plan, key = signed
    reports = write(tmp_path, telemetry(plan, (3, 6, 9), dvl=1.3))
    out = tmp_path / "u1"
    code = main(["replan", SHORT, "--plan", str(plan), "--telemetry", str(reports), "--key",
                 str(key), "-o", str(out)])
    said = capsys.readouterr().out
    assert code == ExitCode.OK, said
    assert "figures moved:" in said and "dvl +" in said and "duties:" in said
    update = out.read_bytes()
    assert len(update) <= 270
    applied = apply_update(plan.read_bytes(), update, KEY,
                           check=lambda d: read_plan_bytes(d, short))
    assert applied.status == UpdateStatus.APPLIED and applied.seq == 6
    assert applied.plan_file == (tmp_path / "u1.plan").read_bytes()
    report = json.loads((tmp_path / "u1.json").read_text())
    assert report["update_bytes"] == [len(update)] and report["status"] == "updated"
    assert {"figures", "changes", "shadow_price", "battery_usable", "quality"} <= set(report)


def test_an_earlier_chain_s_updates_are_not_left_beside_the_new_one(tmp_path, signed):
    """A longer chain written before under the same name (u1.1, u1.2) would read as part of
    the new single update: it is removed once the new one is in place; other files stay."""
    plan, key = signed
    reports = write(tmp_path, telemetry(plan, (3, 6, 9), dvl=1.3))
    out = tmp_path / "u1"
    for name in ("u1.1", "u1.2", "u1.4", "u1.notes"):
        (tmp_path / name).write_bytes(b"from an earlier replan")
    assert main(["replan", SHORT, "--plan", str(plan), "--telemetry", str(reports), "--key",
                 str(key), "-o", str(out)]) == ExitCode.OK
    assert out.is_file() and len(out.read_bytes()) <= 270
    assert not (tmp_path / "u1.1").exists() and not (tmp_path / "u1.2").exists()
    # not a member of the chain (u1.3 is missing): the file is not this command's to remove
    assert (tmp_path / "u1.4").exists() and (tmp_path / "u1.notes").exists()


def test_a_hungrier_device_is_found_and_the_plan_spends_less_on_it(tmp_path, signed, short):
    plan, _ = signed
    held = plan.read_bytes()
    results = {}
    for dvl in (1.0, 1.3, 0.7):
        replanner = Replanner(short, held, confidence=0.95, spec=read_spec())
        reports = telemetry(plan, (3, 6, 9, 12), dvl=dvl)
        for r in reports:
            replanner.observe(r)
        results[dvl] = replanner.replan(held, reports[-1])
    moved = {dvl: {m.name: m.posterior for m in r.moves} for dvl, r in results.items()}
    # the same duty all along: the excess is shared with the figures flown with the DVL
    assert moved[1.3]["dvl"] > moved[1.0]["dvl"] + 0.05 > moved[0.7]["dvl"] + 0.1
    assert abs(moved[1.0]["dvl"] - 1.0) < 0.02
    # the DVL taking the most of the excess watts (its prior is the least sure in watts; the
    # optode's relative spread is wider, but of a figure of a few milliwatts)
    excess_w = {m.name: (m.posterior - 1.0) * m.nominal_w for m in results[1.3].moves
                if m.nominal_w is not None}
    assert excess_w["dvl"] > 0.2 and excess_w["dvl"] > 3 * max(
        w for n, w in excess_w.items() if n != "dvl")
    dvl_on = {dvl: next(x.on_s for x in r.target.states[1].sensors if x.name == "groundspeed")
              for dvl, r in results.items()}
    assert dvl_on[1.3] < dvl_on[1.0] < dvl_on[0.7]
    assert results[0.7].quality > results[1.0].quality > results[1.3].quality  # kinder: more


def test_a_warm_replan_reuses_the_compiled_model_and_follows_the_telemetry(signed, short):
    plan, _ = signed
    held = plan.read_bytes()
    replanner = Replanner(short, held, confidence=0.95, spec=read_spec())
    model = replanner.chance
    first = replanner.replan(held, telemetry(plan, (3,))[-1])
    again = replanner.replan(held, telemetry(plan, (3,))[-1])
    assert replanner.chance is model and again.target == first.target
    for report in telemetry(plan, (3, 6), energy=1.15):
        replanner.observe(report)
    hungrier = replanner.replan(held, telemetry(plan, (3, 6), energy=1.15)[-1])
    assert hungrier.quality < first.quality and replanner.chance is model


def test_a_replan_solved_once_plans_what_the_compiled_model_plans(signed, short):
    """`gliderplan replan` solves without compiling the parameters: the same plan."""
    plan, _ = signed
    held = plan.read_bytes()
    reports = telemetry(plan, (3, 6), energy=1.15)
    results = []
    for once in (False, True):
        replanner = Replanner(short, held, confidence=0.95, spec=read_spec(), once=once)
        for report in reports:
            replanner.observe(report)
        results.append(replanner.replan(held, reports[-1]))
    compiled, solved_once = results
    assert solved_once.target == compiled.target and solved_once.changes
    assert solved_once.quality == pytest.approx(compiled.quality, abs=1e-6)


def test_a_budget_that_cannot_hold_the_rest_is_refused_and_no_update_is_written(
        tmp_path, signed, capsys):
    plan, key = signed
    reports = write(tmp_path, telemetry(plan, (3, 6, 24), energy=2.2))
    out = tmp_path / "u"
    code = main(["replan", SHORT, "--plan", str(plan), "--telemetry", str(reports), "--key",
                 str(key), "-o", str(out)])
    said = capsys.readouterr().err
    assert code == ExitCode.BAD_INPUT
    assert "cannot hold the rest of the mission at confidence" in said
    assert f"{reports.name}: report 3: at 24.0 h the budget left" in said  # where
    assert "No update is made: the glider keeps flying its current plan" in said
    assert not list(tmp_path.glob("u*"))
    run = replan_mission(check_file(SHORT).checked(), plan, reports, key_path=key,
                         if_infeasible="least-energy")
    assert run.result.status == "least-energy" and len(run.updates) == 1


@pytest.mark.parametrize("reports, said", [
    (lambda plan: telemetry(plan, (3, 6))[::-1], "reports out of order"),
    (lambda plan: [*telemetry(plan, (3, 6)), *telemetry(plan, (9,), energy=0.1)],
     "the coulomb counter runs backwards"),
    (lambda plan: telemetry(plan, (3, 6), plan_seq=4),
     "the glider reports plan 4 in force; .* is plan 5: an update must be made against the "
     "plan the glider holds"),
    (lambda plan: telemetry(plan, (3, 6), state="hover"), "the mission has no such state"),
])
def test_telemetry_no_replan_can_rest_on_is_refused_naming_why(tmp_path, signed, capsys,
                                                               reports, said):
    plan, key = signed
    path = write(tmp_path, reports(plan))
    code = main(["replan", SHORT, "--plan", str(plan), "--telemetry", str(path), "--key",
                 str(key), "-o", str(tmp_path / "u")])
    assert code == ExitCode.BAD_INPUT
    import re

    assert re.search(said, capsys.readouterr().err)
    assert not (tmp_path / "u").exists()


def test_telemetry_with_gaps_still_replans_and_says_so(tmp_path, signed, capsys):
    plan, key = signed
    reports = telemetry(plan, (3, 6, 9))
    from dataclasses import replace

    reports[1] = replace(reports[1], coulomb_amphr_total=None, battery_v=None)
    path = write(tmp_path, reports)
    code = main(["replan", SHORT, "--plan", str(plan), "--telemetry", str(path)])
    said = capsys.readouterr().out
    assert code == ExitCode.OK
    assert "no coulomb counter reading (a gap)" in said


def test_a_last_report_without_a_counter_still_counts_what_was_drawn_since(signed, short):
    """The span since the last counter reading is estimated from the figures learned, not
    taken as unspent: the budget left is close to what a full report would give."""
    plan, _ = signed
    held = plan.read_bytes()
    full = telemetry(plan, (3, 6, 9, 12), dvl=1.3)
    gap = telemetry(plan, (3, 6, 9, 12), dvl=1.3, coulomb_amphr_total=None, battery_v=None)
    results = []
    for reports in (full, gap):
        replanner = Replanner(short, held, confidence=0.95, spec=read_spec())
        for r in reports:
            replanner.observe(r)
        results.append(replanner.replan(held, reports[-1]))
    drawn_since = full[-1].energy_used_j - full[-2].energy_used_j
    assert abs(results[1].used_j - results[0].used_j) < 0.05 * drawn_since
    assert abs(results[1].budget_left_j - results[0].budget_left_j) < 0.05 * drawn_since
    assert any("no counter reading at 12.0 h" in n for n in results[1].notes)


def test_reports_in_several_json_files_are_read_in_order(tmp_path, signed, capsys):
    plan, _ = signed
    reports = telemetry(plan, (3, 6))
    files = [tmp_path / "s1.json", tmp_path / "s2.json"]
    for path, r in zip(files, reports, strict=True):
        path.write_text(write_json_telemetry([r]))
    code = main(["replan", SHORT, "--plan", str(plan), "--telemetry", *map(str, files)])
    assert code == ExitCode.OK and "at 6.0 h" in capsys.readouterr().out
    code = main(["replan", SHORT, "--plan", str(plan), "--telemetry", *map(str, files[::-1])])
    assert code == ExitCode.BAD_INPUT and "reports out of order" in capsys.readouterr().err
    code = main(["replan", SHORT, "--plan", str(plan), "--telemetry", str(files[0]),
                 str(tmp_path)])
    assert code == ExitCode.BAD_INPUT
    assert "JSON telemetry and Slocum logs cannot be mixed" in capsys.readouterr().err


@pytest.mark.parametrize("argv, said", [
    (["sim", SHORT, "--confidence", "0.9", "-o", "run"], "--confidence works only with "
     "--replan-every"),
    (["sim", SHORT, "--scenario-file", "x.toml", "-o", "run"], "--scenario-file works only "
     "with --replan-every"),
    (["montecarlo", SHORT, "--scenarios", "2", "--key", "k", "-o", "mc"], "--key works only "
     "with --replan"),
    (["montecarlo", SHORT, "--scenarios", "2", "--replan", "--confidence", "1", "-o", "mc"],
     "expected a probability in [0.5, 1), got '1'"),
    (["montecarlo", SHORT, "--scenarios", "2", "--confidence", "0.9", "-o", "mc"],
     "--confidence works only with --replan"),
    (["sim", SHORT, "--replan-every", "surfacing", "--confidence", "0.4", "-o", "run"],
     "expected a probability in [0.5, 1), got '0.4'"),
    (["replan", SHORT, "--plan", "p", "--telemetry", "t", "--confidence", "lots"],
     "expected a probability in [0.5, 1), got 'lots'"),
    (["replan", SHORT, "--plan", "p", "--telemetry", "t", "--seq", "3"], "--seq works only "
     "with --key"),
])
def test_replanning_options_without_what_they_need_are_refused(tmp_path, capsys, monkeypatch,
                                                                argv, said):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as done:
        code = main(argv)
        raise SystemExit(code)
    assert done.value.code == ExitCode.USAGE
    assert said in capsys.readouterr().err
    assert not (tmp_path / "run").exists() and not (tmp_path / "mc").exists()


def test_an_update_needs_the_vehicles_key(tmp_path, signed, capsys):
    plan, _ = signed
    path = write(tmp_path, telemetry(plan, (3,)))
    code = main(["replan", SHORT, "--plan", str(plan), "--telemetry", str(path), "-o",
                 str(tmp_path / "u")])
    assert code == ExitCode.USAGE and "give --key KEYFILE" in capsys.readouterr().err


def test_a_transit_leg_keeps_its_planned_speed_and_time(tmp_path):
    """Replanning takes each state's time left from the plan: a transit leg's speed (its
    pitch and buoyancy) is the plan's, and only the duties change."""
    mission = check_file(str(ROOT / "tests" / "missions" / "planner_transit.mission")).checked()
    from gliderplan.planner.planfile import write_plan_bytes
    from gliderplan.planner.signing import sign_plan

    held = sign_plan(write_plan_bytes(make_plan(mission).plan), KEY, 1)
    replanner = Replanner(mission, held)
    result = replanner.replan(held, SurfacingReport(3600.0, 0.1, 15.0))
    before = read_plan_bytes(held)
    assert [s.profiles for s in result.target.states] == [s.profiles for s in before.states]


def test_replan_infeasible_is_a_planning_error():
    assert issubclass(ReplanInfeasible, PlanningError)


def test_an_update_its_plan_and_its_report_are_written_together(tmp_path, signed, monkeypatch,
                                                                 capsys):
    """A disk that fills as the report is written leaves none of the three (an update
    beside the plan of another would desynchronise the next replan), nor an earlier
    update touched; an interrupted replan writes nothing."""
    from gliderplan.contract import files

    plan, key = signed
    reports = write(tmp_path, telemetry(plan, (3, 6, 9), dvl=1.3))
    out = tmp_path / "u1"
    out.write_bytes(b"an earlier update")
    real = files.write_atomically

    def full_at_the_report(path, data, **kwargs):
        if str(path).endswith("u1.json"):
            raise files.OutputFileError(f"{path}: cannot write: No space left on device")
        return real(path, data, **kwargs)
    monkeypatch.setattr(files, "write_atomically", full_at_the_report)
    argv = ["replan", SHORT, "--plan", str(plan), "--telemetry", str(reports), "--key",
            str(key), "-o", str(out)]
    assert main(argv) == ExitCode.USAGE
    assert "No space left on device" in capsys.readouterr().err
    assert out.read_bytes() == b"an earlier update"
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "held.plan", "held.plan.json", "telemetry.json", "u1", "vehicle.key"]
    monkeypatch.setattr(files, "write_atomically", real)
    from gliderplan.planner import update

    made = update.make_updates

    def swallowing(*args, **kwargs):  # Ctrl-C that something on the way caught
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)  # the handler raises here
        except KeyboardInterrupt:
            pass
        return made(*args, **kwargs)
    monkeypatch.setattr(update, "make_updates", swallowing)
    assert main(argv) == ExitCode.INTERRUPTED
    assert out.read_bytes() == b"an earlier update"
    assert not (tmp_path / "u1.plan").exists()

"""Plans at a confidence: the scenario approach's numbers, and a plan whose budget holds
on fresh scenarios at least as often as it says (within the sampling error)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.planner.confidence import achieved_confidence, scenarios_needed

REPO = Path(__file__).resolve().parents[1]
SEPARABLE = REPO / "tests" / "missions" / "planner_separable.mission"


def test_scenario_counts_follow_campi_and_garatti():
    n = scenarios_needed(0.95, 10, 1e-3)
    # within the design note's sufficient bound (2 / eps)(ln(1 / beta) + d), and tight
    assert n <= math.ceil(2 / 0.05 * (math.log(1e3) + 10))
    assert achieved_confidence(n, 10, 1e-3) >= 0.95 > achieved_confidence(n - 5, 10, 1e-3)
    assert scenarios_needed(0.99, 10, 1e-3) > n > scenarios_needed(0.95, 5, 1e-3)
    assert achieved_confidence(5, 10) == 0.0  # fewer scenarios than decisions: no guarantee


def _hold_rate(tmp_path: Path, plan: Path, name: str) -> float:
    out = tmp_path / name
    assert main(["montecarlo", str(SEPARABLE), "--plan", str(plan), "--scenarios", "120",
                 "--seed", "9001", "--workers", "2", "-o", str(out)]) == 0
    return json.loads((out / "summary.json").read_text())["probability_budget_holds"]


def test_fresh_scenarios_hold_the_budget_as_often_as_the_plan_says(tmp_path, capsys):
    confident = tmp_path / "confident.plan"
    nominal = tmp_path / "nominal.plan"
    common = [str(SEPARABLE), "--battery", "13Wh"]
    assert main(["plan", *common, "-o", str(nominal)]) == 0
    assert main(["plan", *common, "--confidence", "0.8", "--seed", "1", "--workers", "2",
                 "-o", str(confident)]) == 0
    out = capsys.readouterr().out
    report = json.loads(Path(f"{confident}.json").read_text())
    stated = report["confidence"]
    assert stated["method"].startswith("scenario approach")
    assert stated["achieved"] >= 0.8 and stated["scenarios"] >= stated["dimension"]
    assert f"confidence {stated['achieved']:.3g} (asked 0.8)" in out
    held = _hold_rate(tmp_path, confident, "mc_confident")
    # one-sided 99 % sampling error of 120 fresh scenarios
    error = 2.33 * math.sqrt(stated["achieved"] * (1 - stated["achieved"]) / 120)
    assert held >= stated["achieved"] - error
    # the nominal plan spends its whole budget: fresh scenarios break it far more often
    assert _hold_rate(tmp_path, nominal, "mc_nominal") < held
    assert report["energy_j"] < json.loads(Path(f"{nominal}.json").read_text())["energy_j"]


@pytest.mark.parametrize(("extra", "message"), [
    (["--confidence", "1.5"], "--confidence 1.5: must lie strictly between 0 and 1"),
    (["--confidence", "0.9", "--risk", "0"], "--risk 0: must lie strictly between 0 and 1"),
    (["--confidence", "0.9", "--scenarios", "0"], "--scenarios 0: must be between 1 and 1,000,000"),
])
def test_bad_confidence_options_exit_2(capsys, extra, message):
    assert main(["plan", str(SEPARABLE), *extra]) == 2
    assert message in capsys.readouterr().err


def test_a_budget_no_plan_can_keep_says_so(capsys):
    code = main(["plan", str(SEPARABLE), "--battery", "11.5Wh", "--confidence", "0.8",
                 "--scenarios", "30", "--workers", "1"])
    err = capsys.readouterr().err
    assert code == 1 and "Traceback" not in err
    # 11.5 Wh less the 10 % reserve
    assert "no plan keeps the budget of 10.35 Wh in all 30 scenarios (infeasible)" in err


def test_a_confidence_that_needs_more_scenarios_than_a_run_may_fly_is_refused(capsys):
    """0.999999 needs some 24 million scenarios: refused at once, naming the cap, before a
    single one is flown."""
    from gliderplan.cli.main import main
    from gliderplan.contract import MAX_SCENARIOS, ExitCode

    code = main(["plan", str(Path(__file__).parents[1] / "examples" / "fig2_annotated.mission"),
                 "--confidence", "0.999999"])
    err = capsys.readouterr().err
    assert code == ExitCode.USAGE
    assert f"more than the {MAX_SCENARIOS:,} a run may fly" in err and "Traceback" not in err

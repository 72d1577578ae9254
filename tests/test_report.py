"""`gliderplan report`: the page a scientist opens, checked in a real browser (headless
Chromium driven by Playwright), its CSV files, its sensitivity numbers, and bad input.

The browser test keeps a screenshot of the page as a test artifact in
out/test-artifacts/report.png (and the page's PDF print beside it).
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from gliderplan.cli.common import check_file
from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, TICK_S
from gliderplan.planner.hardware import load_hardware
from gliderplan.planner.plan import plan_mission
from gliderplan.power_models import load_board
from gliderplan.power_models.vehicle import with_figures
from gliderplan.reports.report import make_report

ROOT = Path(__file__).resolve().parents[1]
ANNOTATED = str(ROOT / "examples" / "fig2_annotated.mission")
SURVEY = str(ROOT / "examples" / "thermocline_survey.mission")
ARTIFACTS = ROOT / "out" / "test-artifacts"
CHROMIUM = "/usr/bin/chromium"
SECTIONS = ["summary", "pareto", "energy", "plan-vs-simulation", "profile", "track", "sbc",
            "sensitivity", "montecarlo"]
CSV = ["pareto.csv", "energy_by_state.csv", "plan_vs_simulation.csv", "profile.csv",
       "track.csv",
       "sbc_boards.csv", "sbc_workload.csv", "sbc_crossovers.csv", "sensitivity.csv",
       "montecarlo.csv"]
SCENARIOS = 6
# Arguments for a browser run as root in a container, with nothing in the background.
BROWSER_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--no-first-run"]


def gliderplan(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "gliderplan.cli", *args],
                          capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def report_dir(tmp_path_factory) -> Path:
    """The report of the annotated Fig. 2, planned and flown by `report` itself, with a
    small Monte Carlo of the same plan."""
    work = tmp_path_factory.mktemp("montecarlo")
    plan = work / "fig2.plan"
    assert gliderplan("plan", ANNOTATED, "-o", str(plan)).returncode == 0
    carlo = gliderplan("montecarlo", ANNOTATED, "--plan", str(plan), "--scenarios",
                       str(SCENARIOS), "--workers", "1", "-o", str(work / "mc"))
    assert carlo.returncode == 0, carlo.stderr
    out = tmp_path_factory.mktemp("report")
    run = gliderplan("report", ANNOTATED, "--montecarlo", str(work / "mc"), "-o", str(out))
    assert run.returncode == 0, run.stderr
    assert f"wrote {out / 'report.html'}" in run.stdout
    return out


def test_the_page_is_one_offline_file_with_every_section(report_dir):
    page = (report_dir / "report.html").read_text()
    assert len(page.encode()) < 2_000_000
    for section in SECTIONS:
        assert f'<section id="{section}">' in page
    # nothing to fetch: no external script, style, font or image
    assert not re.search(r'(src|href)="(https?:)?//', page)
    assert "@import" not in page and "url(http" not in page
    assert 'http-equiv="Content-Security-Policy"' in page
    # numbers carry units; the verdict compares the run with the prediction
    for text in ("[Wh]", "[W]", "[h]", "quality per extra Wh", "% used", "predicted ("):
        assert text in page
    assert f"sampleMission ({ANNOTATED})" in page.replace("<wbr>", "")  # the file it read


@pytest.fixture(scope="module")
def survey_dir(tmp_path_factory) -> Path:
    """The report of the thermocline survey: a minimize-energy mission whose plan draws
    less than the budget it takes (warm-ups of an optode it keeps off), and that costs no
    more for the quality of sensors the hotel load powers."""
    out = tmp_path_factory.mktemp("survey")
    run = gliderplan("report", SURVEY, "-o", str(out))
    assert run.returncode == 0, run.stderr
    return out


def test_the_plans_star_is_on_or_under_the_pareto_curve(survey_dir):
    planned = json.loads((survey_dir / "thermoclineSurvey.plan.json").read_text())
    curve = pd.read_csv(survey_dir / "pareto.csv")
    budgeted = planned["budgeted_energy_j"]
    # the curve starts at the least budget of any quality; the survey's floor (0.5) costs
    # energy (its sensors are billed), and the minimum-energy plan takes just what it needs
    assert curve["budget_j"].iloc[0] <= planned["minimum_energy_j"] * (1 + 1e-9)
    assert budgeted == pytest.approx(planned["minimum_energy_j"], rel=1e-6)
    # of the plans with that energy it flies the best: on the curve, which rises with the
    # budget, so between the curve's points below and above its budget
    below = curve[curve["budget_j"] <= budgeted]["quality"].max()
    above = curve[curve["budget_j"] >= budgeted]["quality"].min()
    assert below - 1e-6 <= planned["quality"] <= above + 1e-6
    assert planned["quality"] >= 0.5 - 1e-6
    # it draws less than it takes; the star is drawn at what it takes, and the page says so
    assert planned["energy_j"] < budgeted
    page = (survey_dir / "report.html").read_text()
    assert f"the plan: {budgeted / 3600:.4g} Wh of budget" in page
    if f"{planned['energy_j'] / 3600:.4g}" != f"{budgeted / 3600:.4g}":  # not the same here
        assert f"the plan: {planned['energy_j'] / 3600:.4g} Wh" not in page
    assert "The star is the plan" in page and "predicted to draw" in page
    assert "It lies on the curve" in page


def test_every_figure_has_its_csv_and_the_plan_and_run_are_kept(report_dir):
    for name in CSV:
        frame = pd.read_csv(report_dir / name)
        assert len(frame) > 0, name
    assert (report_dir / "sampleMission.plan").is_file()
    summary = json.loads((report_dir / "run" / "summary.json").read_text())
    flown = pd.read_csv(report_dir / "plan_vs_simulation.csv").set_index("state")
    for state, entry in summary["states"].items():
        assert flown.loc[state, "simulated_wh"] == pytest.approx(entry["simulated_j"] / 3600)
    scenarios = pd.read_csv(report_dir / "montecarlo.csv")
    assert len(scenarios) == SCENARIOS and scenarios["energy_wh"].gt(0).all()
    page = (report_dir / "report.html").read_text()
    assert "of the scenarios (95 % interval" in page
    energy = pd.read_csv(report_dir / "energy_by_state.csv")
    planned = json.loads((report_dir / "sampleMission.plan.json").read_text())
    assert energy["total_wh"].sum() == pytest.approx(planned["energy_j"] / 3600)


def test_the_board_section_says_what_workload_it_compares_at_and_where_it_comes_from(
        report_dir):
    page = (report_dir / "report.html").read_text().replace("<wbr>", "")
    section = page[page.index('<section id="sbc">'):page.index('<section id="sensitivity">')]
    assert f"{RUNTIME_CYCLES_PER_TICK:,.0f} cycles, the runtime&#x27;s whole {TICK_S:g} s tick " \
        "on every board, an assumption (contract.RUNTIME_CYCLES_PER_TICK)" in section
    own = load_board("ts5500").runtime_code_cycles
    assert f"ts5500: the runtime&#x27;s own code is {own:,.0f} cycles a tick" in section
    boards = pd.read_csv(report_dir / "sbc_boards.csv").set_index("board")
    assert (boards["workload_cycles_per_tick"] == RUNTIME_CYCLES_PER_TICK).all()
    assert boards.loc["ts5500", "runtime_code_cycles_per_tick"] == \
        load_board("ts5500").runtime_code_cycles
    assert boards["runtime_code_cycles_per_tick"].isna().sum() == 2  # the TS-7800's ARM


def test_sensitivity_is_the_plan_made_again_with_the_figure_moved(report_dir):
    table = pd.read_csv(report_dir / "sensitivity.csv").set_index("figure")
    row = table.loc["vehicle hotel_power"]
    assert row["basis"].startswith("1 sd")  # the calibrated preset states its spread
    mission = check_file(ANNOTATED).mission
    hardware = load_hardware(mission)
    spread = dict(zip(hardware.vehicle.uncertainty.keys, hardware.vehicle.uncertainty.sd,
                      strict=True))
    raised = hardware.vehicle.hotel_w + spread["hotel_power"]
    assert row["value"] + row["step"] == pytest.approx(raised)
    from dataclasses import replace

    up = plan_mission(mission, replace(hardware, vehicle=with_figures(
        hardware.vehicle, {"hotel_power": raised})))
    assert row["energy_up_wh"] == pytest.approx(up.plan.predicted_j / 3600, rel=1e-6)
    assert row["energy_up_wh"] > row["energy_down_wh"]
    names = list(table.index)
    assert any(n.startswith("board ts7800 idle_power") for n in names)
    assert any(n.startswith("sensor ctd on_power") for n in names)
    # where a figure is an assumption, the table and the page say so, from its data file
    assert not row["assumed"] and row["source"].startswith("gliderplan calibrate")
    idle = table.loc["board ts7800 idle_power"]
    assert idle["assumed"] and idle["source"].startswith("assumption: ARM926")
    assert not table.loc["board ts7800 active_power"]["assumed"]
    page = (report_dir / "report.html").read_text().replace("<wbr>", "")
    assert "board ts7800 idle_power *" in page and "board ts7800 active_power *" not in page


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    """Headless Chromium (the distribution's) under Playwright; skipped (failed under
    CI=true) when either is missing: `make test` installs both."""
    playwright = pytest.importorskip("playwright.sync_api", reason="pip install playwright "
                                     "(the test extra)")
    if shutil.which(CHROMIUM) is None:
        pytest.skip("chromium not installed (make sysdeps)")
    with playwright.sync_playwright() as driver:
        context = driver.chromium.launch_persistent_context(
            str(tmp_path_factory.mktemp("chromium-profile")), executable_path=CHROMIUM,
            headless=True, args=BROWSER_ARGS, viewport={"width": 1200, "height": 900})
        yield context
        context.close()


def test_the_page_in_chromium_has_no_error_no_request_and_no_empty_figure(report_dir,
                                                                         browser):
    page = browser.new_page()
    problems, requests = [], []
    page.on("console", lambda m: problems.append(f"console {m.type}: {m.text}")
            if m.type in ("error", "warning") else None)
    page.on("pageerror", lambda e: problems.append(f"page error: {e}"))
    page.on("requestfailed", lambda r: problems.append(f"failed request: {r.url}"))
    page.on("request", lambda r: requests.append(r.url))
    url = (report_dir / "report.html").as_uri()
    page.goto(url, wait_until="load")
    assert page.eval_on_selector_all("main > section", "s => s.map(e => e.id)") == SECTIONS
    figures = page.eval_on_selector_all("figure[data-figure]", """figs => figs.map(f => {
        const svg = f.querySelector("svg"); const box = svg.getBoundingClientRect();
        return [f.dataset.figure, box.width, box.height,
                svg.querySelectorAll("path, use, image, rect").length];
    })""")
    assert [f[0] for f in figures] == [s for s in SECTIONS if s != "summary"]
    for name, width, height, marks in figures:
        assert width > 300 and height > 150, name
        assert marks > 20, f"{name}: an empty figure ({marks} marks)"
    # tables sort: the boards by board energy, largest first on the second click
    header = page.locator("#sbc table").first.locator("th", has_text="board energy")
    header.click()
    header.click()
    energies = [float(v) for v in page.locator("#sbc table").first.locator(
        "tbody td:nth-child(4)").evaluate_all("c => c.map(e => e.dataset.v)")]
    assert energies == sorted(energies, reverse=True)
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / "report.png"), full_page=True)
    page.emulate_media(media="print")  # prints well: no navigation, figures whole
    assert page.eval_on_selector("nav", "n => getComputedStyle(n).display") == "none"
    (ARTIFACTS / "report.pdf").write_bytes(page.pdf(format="A4"))
    page.close()
    assert problems == []
    assert requests == [url]  # the page itself, nothing else
    assert (ARTIFACTS / "report.png").stat().st_size > 50_000


# Each section's width beyond the page's, and each table's beyond the box that holds it.
WIDER = """() => {
  const page = document.documentElement.clientWidth;
  return [...document.querySelectorAll("header, nav, main > section")].flatMap(s => {
    const box = s.getBoundingClientRect();
    const out = [[s.id || s.tagName, Math.max(box.right - page, s.scrollWidth - s.clientWidth)]];
    s.querySelectorAll("div.table").forEach((t, i) =>
      out.push([`${s.id} table ${i + 1}`, t.scrollWidth - t.clientWidth]));
    return out;
  }).filter(([, excess]) => excess > 0.5);
}"""


@pytest.mark.parametrize("which", ["report_dir", "survey_dir"])
def test_no_section_is_wider_than_the_page_on_screen_or_in_print(which, request, browser):
    """On a screen of the test's width (and 800 px) and on an A4 page in print, every
    section and every table fits: nothing scrolls sideways (the sensitivity table, with
    a figure's source in words, did). On a phone the page still does not; a table wider
    than the phone scrolls inside its own box."""
    page = browser.new_page()
    page.goto((request.getfixturevalue(which) / "report.html").as_uri(), wait_until="load")
    for width in (1200, 800):
        page.set_viewport_size({"width": width, "height": 900})
        assert page.evaluate(WIDER) == [], f"{width} px"
    page.set_viewport_size({"width": 390, "height": 900})
    assert page.evaluate("document.documentElement.scrollWidth") <= 390
    page.emulate_media(media="print")
    page.set_viewport_size({"width": 794, "height": 1123})  # A4 at 96 px/in, no margins
    assert page.evaluate(WIDER) == [], "A4 print"
    page.close()


def test_a_plan_and_a_run_given_are_used_as_they_are(tmp_path):
    plan = tmp_path / "fig2.plan"
    assert gliderplan("plan", ANNOTATED, "-o", str(plan)).returncode == 0
    assert gliderplan("sim", ANNOTATED, "--plan", str(plan), "-o", str(tmp_path / "run")
                      ).returncode == 0
    out = tmp_path / "report"
    # the library call the command wraps
    report = make_report(check_file(ANNOTATED).checked(), out, plan_path=plan,
                         run_dir=tmp_path / "run", source=ANNOTATED)
    assert report.html == out / "report.html" and report.files[0] == report.html
    assert all(f.parent == out and f.stat().st_size > 0 for f in report.files)
    assert "montecarlo" not in report.sections and "sensitivity" in report.sections
    assert not (out / "run").exists() and not (out / "sampleMission.plan").exists()
    page = (out / "report.html").read_text()
    assert str(plan) in page
    assert 'id="montecarlo"' not in page  # only with --montecarlo


def test_a_plan_made_on_other_hardware_is_said_to_be_no_point_of_the_curve(tmp_path):
    """The curve is the mission's own hardware; a plan for the 500 MHz clock needs more
    than the curve's least budget, and the page does not pass its star off as a point
    of the curve."""
    plan = tmp_path / "fast.plan"
    assert gliderplan("plan", ANNOTATED, "--computer", "ts7800@500", "-o", str(plan)
                      ).returncode == 0
    make_report(check_file(ANNOTATED).checked(), tmp_path / "out", plan_path=plan)
    page = (tmp_path / "out" / "report.html").read_text()
    assert "is not a point of this curve" in page and "It lies on the curve" not in page
    own = tmp_path / "own.plan"
    assert gliderplan("plan", ANNOTATED, "-o", str(own)).returncode == 0
    make_report(check_file(ANNOTATED).checked(), tmp_path / "own", plan_path=own)
    assert "It lies on the curve" in (tmp_path / "own" / "report.html").read_text()


@pytest.mark.parametrize(("args", "code", "message"), [
    (["--run", "no/such/run"], 2, "no such directory"),
    (["--montecarlo", "no/such/dir"], 2, "no such directory"),
    (["--plan", "no/such.plan"], 2, "no such file"),
    ([], 2, "-o"),
])
def test_bad_usage_is_one_line(tmp_path, args, code, message):
    out = [] if not args else ["-o", str(tmp_path / "out")]
    run = gliderplan("report", ANNOTATED, *args, *out)
    assert run.returncode == code
    assert message in run.stderr and "Traceback" not in run.stderr


def test_results_of_another_mission_are_refused(tmp_path):
    other = ROOT / "examples" / "fig2.mission"
    assert gliderplan("sim", str(other), "-o", str(tmp_path / "run")).returncode == 0
    run = gliderplan("report", ANNOTATED, "--run", str(tmp_path / "run"),
                     "-o", str(tmp_path / "out"))
    assert run.returncode == 2 and "another mission" in run.stderr
    assert gliderplan("montecarlo", str(other), "--scenarios", "2", "--workers", "1",
                      "-o", str(tmp_path / "mc")).returncode == 0
    run = gliderplan("report", ANNOTATED, "--montecarlo", str(tmp_path / "mc"),
                     "-o", str(tmp_path / "out"))
    assert run.returncode == 2 and "another mission" in run.stderr


def test_two_plans_of_one_mission_make_two_reports_of_their_own(tmp_path):
    """Each page reads the plan it was given and that plan's JSON: the mission's own
    1.2 kWh less 15 % (1,020 Wh), or a 1 kWh pack less 15 % (850 Wh). A JSON that is
    not its plan's, or none, is refused in one line."""
    own, less = tmp_path / "own.plan", tmp_path / "less.plan"
    assert gliderplan("plan", ANNOTATED, "-o", str(own)).returncode == 0
    assert gliderplan("plan", ANNOTATED, "--battery", "1kWh", "-o", str(less)
                      ).returncode == 0
    run = tmp_path / "run"
    assert gliderplan("sim", ANNOTATED, "--plan", str(own), "-o", str(run)).returncode == 0
    for plan, usable, other in ((own, "1,020 Wh usable", "850 Wh usable"),
                                (less, "850 Wh usable", "1,020 Wh usable")):
        out = tmp_path / plan.stem
        assert gliderplan("report", ANNOTATED, "--plan", str(plan), "--run", str(run),
                          "-o", str(out)).returncode == 0
        page = (out / "report.html").read_text()
        assert usable in page and other not in page
    shutil.copy(f"{own}.json", f"{less}.json")  # the other plan's report beside it
    swapped = gliderplan("report", ANNOTATED, "--plan", str(less), "-o", str(tmp_path / "x"))
    assert swapped.returncode == 2 and "Traceback" not in swapped.stderr
    assert f"{less}.json: not the report of {less} (budget_j" in swapped.stderr
    Path(f"{less}.json").unlink()
    missing = gliderplan("report", ANNOTATED, "--plan", str(less), "-o", str(tmp_path / "y"))
    assert missing.returncode == 2 and "Traceback" not in missing.stderr
    assert f"{less}.json" in missing.stderr and "no such file" in missing.stderr
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()

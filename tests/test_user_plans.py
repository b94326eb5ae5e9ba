"""A user's plans and strategies as files, modules of the current folder and entry points,
in `run`, `bench` (resumed, reported, on Dask) and `cramlite plans`; the examples run.
(Kinematic backend: these are about loading and bookkeeping, on every Python.)"""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pytest

from cramlite.plugins import load_reference
from tests.conftest import ROOT, run_cli

EXAMPLES = ROOT / "examples"
PLAN = f"{EXAMPLES / 'fetch_two.py'}:fetch_two"
FARTHEST = f"{EXAMPLES / 'farthest_first.py'}:FarthestFirst"


def _rows(folder: Path) -> list[dict[str, str]]:
    with (folder / "trials.csv").open(newline="") as handle:
        return list(csv.DictReader(handle))


def test_the_examples_run_a_plan_and_a_strategy_from_files() -> None:
    done = run_cli("run", "c1", "--plan", PLAN, "--strategy", FARTHEST, "--backend",
                   "kinematic", "--json")
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result["success"] and len(result["order"]) == 2
    # farthest first: from the start (-0.5, -1.8) the cup in the cupboard (y 1.6) is
    # farther than anything on the counter
    assert result["order"][0] == "cup"
    names = [a["name"] for a in result["actions"]]
    assert "OpenAction" in names and "CloseAction" in names  # (drawer_1, looked into)
    assert result["straight_line_m"] > 1.0  # (the example reports its legs)
    setup = run_cli("run", str(EXAMPLES / "breakfast_for_one.yaml"), "--strategy", "opm",
                    "--backend", "kinematic", "--json")
    assert setup.returncode == 0, setup.stderr
    assert json.loads(setup.stdout)["order"] == ["bowl", "milk", "cup"]


def test_a_plan_that_fails_its_own_check_is_a_failed_trial(tmp_path: Path) -> None:
    (tmp_path / "picky.py").write_text(
        '"""Asks for nothing and says it failed."""\n'
        "from cramlite import PlanReport\n\n"
        "def picky(ctx, setup, strategy):\n"
        "    return PlanReport(order=['nothing'], success=False)\n")
    done = run_cli("run", "v1", "--plan", f"{tmp_path / 'picky.py'}:picky", "--backend",
                   "kinematic", "--json")
    assert done.returncode == 1, done.stderr
    assert json.loads(done.stdout)["order"] == ["nothing"]


def test_a_file_plan_does_not_shadow_the_standard_library_and_finds_its_siblings(
        tmp_path: Path) -> None:
    # (colorsys: a standard module nothing imported before the plan)
    (tmp_path / "colorsys.py").write_text("raise RuntimeError('the standard colorsys was "
                                          "shadowed')\n")
    (tmp_path / "helpers.py").write_text("ITEMS = 1\n")
    (tmp_path / "mine.py").write_text(
        "import colorsys\nimport helpers\n\n"
        "from cramlite import PlanReport\n\n"
        "def mine(ctx, setup, strategy):\n"
        "    colorsys.rgb_to_hsv(1, 0, 0)\n"
        "    return PlanReport(order=[setup.items[0].name][:helpers.ITEMS])\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    done = run_cli("run", "v1", "--plan", "../mine.py:mine", "--backend", "kinematic",
                   "--json", cwd=elsewhere)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["order"] == ["spoon"]


def test_a_strategy_module_in_the_current_folder_loads_without_pythonpath(
        tmp_path: Path) -> None:
    shutil.copy(EXAMPLES / "farthest_first.py", tmp_path / "farthest.py")
    done = run_cli("run", "v1", "--strategy", "farthest:FarthestFirst", "--backend",
                   "kinematic", "--json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["order"][0] == "breakfast-cereal"  # (on the island, far)


@pytest.mark.parametrize(("plan", "expected"), [
    ("nope", "unknown plan 'nope'; expected one of set-table, clear-table"),
    ("./missing.py:plan", "no such file"),
    (f"{EXAMPLES / 'fetch_two.py'}:fetch_three",
     f"{EXAMPLES / 'fetch_two.py'} has no 'fetch_three'; it has fetch_two, "),
    (FARTHEST, "is a class; expected a function (ctx, setup, strategy)"),
    ("json:dumps_nothing", "has no 'dumps_nothing'"),
])
def test_a_plan_that_cannot_load_is_one_line_and_exit_2(plan: str, expected: str) -> None:
    for command in (["run", "v1"], ["bench", "--setups", "v1", "--out", "/tmp/never"]):
        done = run_cli(*command, "--plan", plan)
        assert done.returncode == 2, done.stderr
        assert expected in done.stderr and "--plan" in done.stderr, done.stderr
        assert "Traceback" not in done.stderr
    assert not Path("/tmp/never/trials.csv").exists()


def test_a_plan_of_the_wrong_shape_is_one_line_and_exit_2(tmp_path: Path) -> None:
    (tmp_path / "shapes.py").write_text("def two(ctx, setup):\n    pass\n\n\n"
                                        "def number(ctx, setup, strategy):\n    return 42\n")
    for plan, expected in (("two", "is a function (ctx, setup); expected a function (ctx, "
                                   "setup, strategy) -> PlanReport"),
                           ("number", "returned int; expected a PlanReport")):
        done = run_cli("run", "v1", "--plan", f"{tmp_path / 'shapes.py'}:{plan}", "--backend",
                       "kinematic")
        assert done.returncode == 2, done.stderr
        assert expected in done.stderr and "--plan" in done.stderr, done.stderr
        assert "Traceback" not in done.stderr and len(done.stderr.splitlines()) == 1


def test_a_bug_in_a_plan_is_one_line_naming_where_and_a_bench_row(tmp_path: Path) -> None:
    """A plan that raises (not a PlanFailure) is a mistake of the user's: one line with
    what it raised and the line of the plan's file, exit 2, as for a strategy; a bench
    records it in the trial's row and goes on."""
    (tmp_path / "buggy.py").write_text("def plan(ctx, setup, strategy):\n"
                                       "    ctx.observe()\n"
                                       "    return 1 / 0\n")
    plan = f"{tmp_path / 'buggy.py'}:plan"
    done = run_cli("run", "v1", "--plan", plan, "--backend", "kinematic")
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.splitlines()) == 1, done.stderr
    assert (f"--plan: plan {plan} raised ZeroDivisionError: division by zero (at "
            f"{tmp_path / 'buggy.py'}, line 3)") in done.stderr, done.stderr
    # (a designator refusing its argument where the plan writes it: the plan's line, not
    # the "<string>" of the dataclass's own __init__)
    (tmp_path / "badarg.py").write_text("from cramlite import ParkArmsAction\n\n\n"
                                        "def plan(ctx, setup, strategy):\n"
                                        "    ParkArmsAction('middle').perform(ctx)\n")
    done = run_cli("run", "v1", "--plan", f"{tmp_path / 'badarg.py'}:plan", "--backend",
                   "kinematic")
    assert done.returncode == 2 and f"(at {tmp_path / 'badarg.py'}, line 5)" in done.stderr, \
        done.stderr
    out = tmp_path / "b"
    bench = run_cli("bench", "--setups", "v1", "--plan", plan, "--strategies", "opm",
                    "--trials", "1", "--backend", "kinematic", "--out", str(out), "--no-plots")
    assert bench.returncode == 1, bench.stderr
    (row,) = _rows(out)
    assert row["success"] == "False" and row["error_type"] == "PlanCrashed"
    assert "ZeroDivisionError" in row["error"] and "line 3" in row["error"]


def test_carry_2_with_a_plan_that_carries_one_at_a_time_says_so() -> None:
    """`--carry` is an option the plan reads: where every trip carried one item, `run`
    says so instead of reading as if two were carried at once."""
    done = run_cli("run", "v1", "--carry", "2", "--plan", PLAN, "--backend", "kinematic")
    assert done.returncode == 0, done.stderr
    line = next(x for x in done.stdout.splitlines() if "carrying up to 2" in x)
    assert line.endswith("no trip carried more than one item (a plan option: the plan "
                         "decides)"), line
    together = run_cli("run", "v1", "--carry", "2", "--backend", "kinematic")
    assert "no trip carried more than one" not in together.stdout
    assert " + " in together.stdout


def test_a_plan_that_raises_on_import_is_named(tmp_path: Path) -> None:
    (tmp_path / "broken.py").write_text("import no_such_module_anywhere\n")
    done = run_cli("run", "v1", "--plan", f"{tmp_path / 'broken.py'}:plan")
    assert done.returncode == 2
    assert "cannot load plan" in done.stderr and "no_such_module_anywhere" in done.stderr


def test_bench_runs_resumes_and_reports_a_plan_file_keyed_by_its_content(
        tmp_path: Path) -> None:
    plan_file = tmp_path / "fetch_two.py"
    shutil.copy(EXAMPLES / "fetch_two.py", plan_file)
    out = tmp_path / "out"
    args = ("bench", "--plan", "./fetch_two.py:fetch_two", "--setups", "v1,c1", "--trials",
            "2", "--strategies", "opm", "--backend", "kinematic", "--workers", "2",
            "--out", str(out))
    done = run_cli(*args, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    rows = _rows(out)
    assert len(rows) == 4 and all(r["success"] == "True" for r in rows)
    assert {r["plan"] for r in rows} == {"./fetch_two.py:fetch_two"}
    first_hash = rows[0]["code_hash"]
    assert len(first_hash) == 16 and {r["code_hash"] for r in rows} == {first_hash}
    page = (out / "report.html").read_text()
    assert "fetch_two" in page and "Open</td>" in page  # (its task trees)
    again = run_cli(*args, cwd=tmp_path)
    assert again.returncode == 0 and len(_rows(out)) == 4  # resumed: nothing to run
    assert "0 to run" in again.stderr + again.stdout or "already" in again.stderr
    plan_file.write_text(plan_file.read_text().replace("COUNT = 2", "COUNT = 1"))
    changed = run_cli(*args, cwd=tmp_path)  # other code: other trials
    assert changed.returncode == 0, changed.stderr[-2000:]
    rows = _rows(out)
    assert len(rows) == 8
    assert {len(r["order"].split()) for r in rows if r["code_hash"] != first_hash} == {1}
    # the report shows this command's trials, not the earlier version's beside them
    page = (out / "report.html").read_text()
    assert "4 trials in trials.csv" in page and "4 more of earlier bench commands" in page


def test_legs_a_plan_does_not_report_are_missing_not_zero(tmp_path: Path) -> None:
    """A plan that never calls `PlanReport.add_leg`: `run` says so, and a bench stores no
    straight-line distance (not 0 m, which summaries and paired tests would take for one)."""
    plan_file = tmp_path / "no_legs.py"
    source = (EXAMPLES / "fetch_two.py").read_text()
    assert "report.add_leg(" in source
    plan_file.write_text(source.replace("report.add_leg(", "(lambda *legs: None)("))
    ran = run_cli("run", "v1", "--plan", "./no_legs.py:fetch_two", "--backend", "kinematic",
                  "--json", cwd=tmp_path)
    assert ran.returncode == 0, ran.stderr[-2000:]
    assert json.loads(ran.stdout)["straight_line_m"] is None
    out = tmp_path / "out"
    done = run_cli("bench", "--plan", "./no_legs.py:fetch_two", "--setups", "v1",
                   "--trials", "2", "--strategies", "opm,baseline", "--backend", "kinematic",
                   "--no-plots", "--out", str(out), cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    rows = _rows(out)
    assert len(rows) == 4 and all(r["success"] == "True" for r in rows)
    assert {r["straight_line_m"] for r in rows} == {""}
    assert all(float(r["base_path_m"]) > 1.0 for r in rows)
    with (out / "summary.csv").open() as handle:
        summary = list(csv.DictReader(handle))
    assert {s["straight_line_m_mean"] for s in summary} == {"nan"}
    tests = json.loads((out / "tests.json").read_text())["wilcoxon"][0]
    assert tests["straight_line_m"]["mean"] is None
    assert tests["straight_line_m"]["note"].startswith("not reported")
    assert "did not report its legs" in (out / "summary.md").read_text()
    assert tests["base_path_m"]["mean"] > 1.0  # (the other measures are compared as ever)
    # a folder written before: such a plan's legs as 0 m, read as not reported (a resume
    # and the report), a built-in plan's as they are
    from cramlite.bench.store import TrialStore
    from cramlite.report.folder import read_folder

    trials = out / "trials.csv"
    with trials.open(newline="") as handle:
        rows = list(csv.reader(handle))
    column = rows[0].index("straight_line_m")
    for row in rows[1:]:
        row[column] = "0.0"
    with trials.open("w", newline="") as handle:
        csv.writer(handle).writerows(rows)
    assert {r["straight_line_m"] for r in TrialStore(out).rows()} == {""}
    assert {r["straight_line_m"] for r in read_folder(out).rows} == {""}
    # adding to the field directly (as the API allowed before `add_leg`) reports legs
    leg = "report.add_leg(robot_position(ctx)[:2], chosen.position[:2], target.xyz[:2])"
    assert leg in source
    plan_file.write_text(source.replace(leg, "report.straight_line_m += 1.25"))
    ran = run_cli("run", "v1", "--plan", "./no_legs.py:fetch_two", "--backend", "kinematic",
                  "--json", cwd=tmp_path)
    assert ran.returncode == 0, ran.stderr[-2000:]
    assert json.loads(ran.stdout)["straight_line_m"] == 2.5  # (two items)


def test_bench_on_dask_runs_a_plan_file(tmp_path: Path) -> None:
    pytest.importorskip("distributed")
    out = tmp_path / "out"
    done = run_cli("bench", "--plan", PLAN, "--setups", "v1", "--trials", "1",
                   "--strategies", "opm", "--backend", "kinematic", "--executor", "dask",
                   "--workers", "1", "--no-plots", "--out", str(out))
    assert done.returncode == 0, done.stderr[-2000:]
    (row,) = _rows(out)
    assert row["success"] == "True" and len(row["order"].split()) == 2


@pytest.fixture
def plugin_package(tmp_path: Path) -> dict[str, str]:
    """The example plugin package, visible as installed (its dist-info on the path)."""
    package = EXAMPLES / "cramlite_farthest"
    dist = tmp_path / "cramlite_farthest-0.1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: cramlite-farthest\n"
                                   "Version: 0.1.0\n")
    import tomllib

    entry_points = tomllib.loads((package / "pyproject.toml").read_text())["project"][
        "entry-points"]
    (dist / "entry_points.txt").write_text("".join(
        f"[{group}]\n" + "".join(f"{k} = {v}\n" for k, v in eps.items())
        for group, eps in entry_points.items()))
    return {"PYTHONPATH": f"{tmp_path}:{package}"}


def test_entry_point_plans_and_strategies_are_listed_and_run(plugin_package) -> None:
    import os
    import subprocess
    import sys

    env = {**os.environ, **plugin_package}

    def cli(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "cramlite", *args], capture_output=True,
                              text=True, env=env, cwd=ROOT, timeout=300)

    plans = cli("plans")
    assert plans.returncode == 0, plans.stderr
    assert "set-table" in plans.stdout and "clear-table" in plans.stdout
    assert "fetch-two" in plans.stdout and "Fetch the strategy's first two items" in \
        plans.stdout
    strategies = cli("strategies")
    assert "farthest-first" in strategies.stdout and "farthest from the robot" in \
        strategies.stdout
    done = cli("run", "v1", "--plan", "fetch-two", "--strategy", "farthest-first",
               "--backend", "kinematic", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["order"] == ["breakfast-cereal", "bowl"]


def test_the_plugin_package_holds_the_examples_as_they_are() -> None:
    package = EXAMPLES / "cramlite_farthest" / "cramlite_farthest"
    assert (package / "plan.py").read_text() == (EXAMPLES / "fetch_two.py").read_text()
    assert (package / "strategy.py").read_text() == \
        (EXAMPLES / "farthest_first.py").read_text()


def test_load_reference_names_what_is_missing() -> None:
    from cramlite.errors import UserInputError

    assert load_reference("json:dumps", "plan", "--plan") is json.dumps
    with pytest.raises(UserInputError, match="expected plan as package.module:name"):
        load_reference("json", "plan", "--plan")


def test_a_plan_named_as_a_module_is_keyed_by_its_file_s_content(tmp_path: Path,
                                                                 monkeypatch) -> None:
    from cramlite.plugins import trial_code_hash

    monkeypatch.chdir(tmp_path)  # (a module of the current folder, as the tutorial runs it)
    (tmp_path / "my_fixed_plan.py").write_text("def plan(ctx, setup, strategy):\n    pass\n")
    first = trial_code_hash("my_fixed_plan:plan", "opm")
    (tmp_path / "my_fixed_plan.py").write_text("def plan(ctx, setup, strategy):\n    return\n")
    second = trial_code_hash("my_fixed_plan:plan", "opm")
    assert first and second and first != second
    # an importable module's source file, as well
    assert trial_code_hash("json:dumps", "opm") == trial_code_hash("json:loads", "opm") != ""



def test_a_plan_that_puts_an_item_where_it_wants_reports_it_delivered(tmp_path: Path) -> None:
    """(The setup's target is the built-in plans' goal, not a user's plan's.)"""
    (tmp_path / "own_spot.py").write_text(
        "from cramlite import PlanReport, TransportAction\n\n\n"
        "def plan(ctx, setup, strategy):\n"
        "    report = PlanReport(order=['milk'])\n"
        "    TransportAction('milk', target=(-0.9, 1.3, 0.86)).perform(ctx)\n"
        "    report.success = True\n"
        "    return report\n")
    done = run_cli("run", "v1", "--plan", f"{tmp_path / 'own_spot.py'}:plan", "--backend",
                   "kinematic")
    assert done.returncode == 0, done.stdout + done.stderr
    assert ": success" in done.stdout and "  order: milk\n" in done.stdout, done.stdout

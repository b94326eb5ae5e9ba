"""`cramlite bench` as a user runs it: reproducible, resumable, robust to failures."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cramlite.bench.store import TIMING_COLUMNS
from tests.conftest import ROOT, run_cli

SMALL = ["--setups", "v1", "--strategies", "opm,random", "--trials", "2", "--no-plots"]

PLUGIN = '''
import os
from cramlite.strategies import Strategy

class Boom(Strategy):
    name = "boom"
    def choose(self, remaining, agent):
        raise RuntimeError("strategy exploded (injected)")

class Crash(Strategy):
    name = "crash"
    def choose(self, remaining, agent):
        os._exit(3)  # the worker process dies
'''


def rows(folder: Path) -> list[dict[str, str]]:
    with (folder / "trials.csv").open() as handle:
        return list(csv.DictReader(handle))


def comparable(folder: Path) -> list[tuple]:
    return sorted(tuple((k, v) for k, v in r.items() if k not in TIMING_COLUMNS)
                  for r in rows(folder))


def bench(out: Path, *args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    full = {**os.environ, **(env or {})}
    return subprocess.run([sys.executable, "-m", "cramlite", "bench", "--out", str(out), *args],
                          capture_output=True, text=True, cwd=ROOT, env=full, timeout=600)


def test_same_seed_same_rows_and_a_trial_reruns_alone(tmp_path: Path) -> None:
    a, b = tmp_path / "a", tmp_path / "b"
    first = bench(a, *SMALL, "--workers", "2")
    assert first.returncode == 0, first.stderr
    second = bench(b, *SMALL, "--workers", "1")
    assert second.returncode == 0, second.stderr
    assert comparable(a) == comparable(b)
    assert len(rows(a)) == 4
    meta = json.loads((a / "metadata.json").read_text())
    assert {"pybullet", "pin", "ompl", "numpy"} <= set(meta["versions"])
    assert all(r["worker"] for r in rows(a))
    row = next(r for r in rows(a) if r["strategy"] == "random")
    alone = run_cli("run", row["setup"], "--strategy", "random", "--seed", row["seed"], "--json")
    data = json.loads(alone.stdout)
    assert " ".join(data["order"]) == row["order"]
    assert f"{data['base_path_m']}" == row["base_path_m"]
    summary = (a / "summary.md").read_text()
    assert "| v1 | opm | 2 | 100% |" in summary


def test_interrupted_run_resumes_with_the_remaining_trials(tmp_path: Path) -> None:
    out = tmp_path / "r"
    args = [sys.executable, "-m", "cramlite", "bench", "--out", str(out), "--setups", "v1,v2",
            "--strategies", "opm,baseline", "--trials", "3", "--workers", "1", "--no-plots"]
    proc = subprocess.Popen(args, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    deadline = time.time() + 120
    while time.time() < deadline:
        path = out / "trials.csv"
        if path.exists() and len(path.read_text().splitlines()) >= 4:  # header + 3 rows
            break
        time.sleep(0.2)
    proc.send_signal(signal.SIGINT)  # Ctrl-C
    _, err = proc.communicate(timeout=120)
    print(err[-500:])
    assert proc.returncode == 130
    assert "Traceback" not in err and "interrupted" in err
    partial = rows(out)
    assert 3 <= len(partial) < 12
    assert all(r["success"] == "True" for r in partial)  # finished trials are complete rows
    again = bench(out, "--setups", "v1,v2", "--strategies", "opm,baseline", "--trials", "3",
                  "--workers", "1", "--no-plots")
    assert again.returncode == 0, again.stderr
    assert f"({len(partial)} already in" in again.stderr
    final = rows(out)
    assert len(final) == 12
    keys = [(r["setup"], r["strategy"], r["trial"]) for r in final]
    assert len(set(keys)) == 12  # nothing ran twice
    assert final[:len(partial)] == partial


def test_failing_and_crashing_trials_are_recorded_and_the_batch_goes_on(tmp_path: Path) -> None:
    plugin_dir = tmp_path / "plugin"
    plugin_dir.mkdir()
    (plugin_dir / "badstrategies.py").write_text(PLUGIN)
    env = {"PYTHONPATH": os.pathsep.join([str(plugin_dir), str(ROOT)])}
    out = tmp_path / "f"
    result = bench(out, "--setups", "v1", "--strategies",
                   "baseline,badstrategies:Boom,badstrategies:Crash", "--trials", "2",
                   "--workers", "2", "--no-plots", env=env)
    print(result.stderr[-800:])
    assert result.returncode == 1
    table = rows(out)
    assert len(table) == 6
    by_strategy = {}
    for r in table:
        by_strategy.setdefault(r["strategy"], []).append(r)
    assert all(r["success"] == "True" for r in by_strategy["baseline"])
    for r in by_strategy["badstrategies:Boom"]:
        assert r["success"] == "False" and r["error_type"] == "StrategyError"
        assert "badstrategies.Boom" in r["error"] and "RuntimeError: strategy exploded" in \
            r["error"]
    for r in by_strategy["badstrategies:Crash"]:
        assert r["success"] == "False" and r["error_type"] == "WorkerDied"


@pytest.mark.parametrize(("args", "expected"), [
    (["--setups", "v1,v9"], "v9"),
    (["--strategies", "opm,greedy"], "greedy"),
    (["--trials", "0"], "positive"),
    (["--workers", "-2"], "positive"),
    (["--random-setups", "0"], "positive"),
    (["--scheduler", "tcp://127.0.0.1:1"], "--executor dask"),
    (["--executor", "slurm"], "local"),
])
def test_bad_arguments_exit_2_and_list_the_choices(tmp_path: Path, args, expected) -> None:
    result = bench(tmp_path / "x", *args)
    assert result.returncode == 2
    assert expected in result.stderr
    assert "Traceback" not in result.stderr
    if "--setups" in args:
        assert "v1, v2, v3, v4, v5" in result.stderr
    if "--strategies" in args:
        assert "opm, baseline, random" in result.stderr


def test_dask_executor_gives_the_same_rows_as_the_local_one(tmp_path: Path) -> None:
    pytest.importorskip("distributed")
    local, dask = tmp_path / "local", tmp_path / "dask"
    assert bench(local, *SMALL, "--workers", "2").returncode == 0
    result = bench(dask, *SMALL, "--workers", "2", "--executor", "dask")
    assert result.returncode == 0, result.stderr[-2000:]
    assert comparable(local) == comparable(dask)


def test_all_orders_and_random_setups(tmp_path: Path) -> None:
    three = (ROOT / "worlds" / "setups" / "v1.yaml").read_text()
    # a three-item setup (spoon, cup, bowl) so all orders are 3! = 6 trials
    items = three.split("items:\n")[1].split("baseline_order")[0].split("  - name: ")[1:]
    keep = [i for i in items if i.split("\n")[0] in ("spoon", "cup", "bowl")]
    text = (three.split("items:\n")[0].replace("name: v1", "name: three") + "items:\n"
            + "".join("  - name: " + i for i in keep)
            + "baseline_order: [cup, bowl, spoon]\n")
    setup = tmp_path / "three.yaml"
    setup.write_text(text)
    out = tmp_path / "o"
    result = bench(out, "--setups", str(setup), "--trials", "1", "--all-orders",
                   "--workers", "2")
    print(result.stdout[-1500:], result.stderr[-1500:])
    assert result.returncode == 0
    table = rows(out)
    fixed = [r for r in table if r["strategy"] == "fixed-order"]
    assert len(fixed) == 6
    assert {r["given_order"] for r in fixed if r["setup"] == "three"} == {
        "cup bowl spoon", "cup spoon bowl", "bowl cup spoon", "bowl spoon cup",
        "spoon cup bowl", "spoon bowl cup"}
    for r in fixed:
        assert r["order"] == r["given_order"]
    assert "Among all fixed orders" in (out / "summary.md").read_text()
    assert (out / "all_orders_base_path.png").stat().st_size > 10_000
    randoms = tmp_path / "rs"
    result = bench(randoms, "--setups", "v1", "--strategies", "opm", "--trials", "1",
                   "--random-setups", "2", "--workers", "2", "--no-plots")
    assert result.returncode == 0, result.stderr[-1500:]
    saved = sorted((randoms / "setups").glob("random-0-*.yaml"))
    assert len(saved) == 2
    assert {r["setup"] for r in rows(randoms)} == {"v1", saved[0].stem, saved[1].stem}
    rerun = run_cli("run", str(saved[0]), "--json")
    assert rerun.returncode == 0, rerun.stderr

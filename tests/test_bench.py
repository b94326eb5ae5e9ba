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
from cramlite.safe_names import trial_stem
from cramlite.trace import read_trace
from tests.conftest import HAS_PYBULLET, ROOT, run_cli

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
    first = bench(a, *SMALL, "--workers", "2", "--traces")
    assert first.returncode == 0, first.stderr
    second = bench(b, *SMALL, "--workers", "1")
    assert second.returncode == 0, second.stderr
    assert comparable(a) == comparable(b)
    assert len(rows(a)) == 4
    meta = json.loads((a / "metadata.json").read_text())
    assert {"pin", "coal", "ompl", "numpy"} <= set(meta["versions"])
    assert ("pybullet" in meta["versions"]) == HAS_PYBULLET
    assert all(r["worker"] for r in rows(a))
    row = next(r for r in rows(a) if r["strategy"] == "random")
    alone = run_cli("run", row["setup"], "--strategy", "random", "--seed", row["seed"], "--json")
    data = json.loads(alone.stdout)
    assert " ".join(data["order"]) == row["order"]
    assert f"{data['base_path_m']}" == row["base_path_m"]
    summary = (a / "summary.md").read_text()
    assert "| v1 | opm | 2 | 100% |" in summary
    # --traces: one trace per trial, named by setup, plan, strategy and trial, timed like
    # the row
    traces = sorted(p.name for p in (a / "traces").iterdir())
    assert traces == sorted(f"{trial_stem('v1', 'set-table', s, t)}.jsonl"
                            for s in ("opm", "random") for t in (0, 1))
    assert "v1-set-table-random-0-" in " ".join(traces)  # (a readable slug, then a hash)
    recorded = read_trace(a / "traces" / f"{trial_stem('v1', 'set-table', 'random', row['trial'])}"
                                         ".jsonl")
    assert recorded.header["seed"] == int(row["seed"])
    assert recorded.duration_s == pytest.approx(float(row["robot_time_s"]), rel=0.01)
    assert float(row["robot_time_s"]) < float(row["drive_s"]) + float(row["arm_s"])  # (both
    # at once: the torso rising and the arms parking while the base drives)
    assert not (b / "traces").exists()


def test_workers_are_forked_where_safe_with_the_same_rows(tmp_path: Path) -> None:
    """A bench forks its workers when it runs no other thread (they start with its
    imports) and spawns them when it does; the rows are the same either way."""
    code = """
import sys, threading
import cramlite.bench.execute as execute
from cramlite.cli import main
if sys.argv[2] == "thread":
    stop = threading.Event()
    threading.Thread(target=stop.wait, daemon=True).start()
made = execute.LocalPool.__init__
def init(self, workers):
    made(self, workers)
    print("start method:", self.start_method, file=sys.stderr)
execute.LocalPool.__init__ = init
sys.exit(main(["bench", "--out", sys.argv[1], *sys.argv[3:]]))
"""
    folders = {}
    for case, method in (("plain", "fork" if sys.platform.startswith("linux") else "spawn"),
                         ("thread", "spawn")):
        folders[case] = tmp_path / case
        done = subprocess.run([sys.executable, "-c", code, str(folders[case]), case, *SMALL,
                               "--workers", "2"], capture_output=True, text=True, cwd=ROOT,
                              timeout=600)
        assert done.returncode == 0, done.stderr
        assert f"start method: {method}" in done.stderr
    assert comparable(folders["plain"]) == comparable(folders["thread"])
    assert len(rows(folders["plain"])) == 4


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
        assert r["success"] == "False" and r["error_type"] == "StrategyCrashed"
        assert "badstrategies.Boom" in r["error"] and "RuntimeError: strategy exploded" in \
            r["error"]
    for r in by_strategy["badstrategies:Crash"]:
        assert r["success"] == "False" and r["error_type"] == "WorkerDied"
    assert "a worker process died with" in result.stderr
    assert "trial v1/badstrategies:Crash/0 killed its worker process: recorded as WorkerDied" \
        in result.stderr


@pytest.mark.parametrize(("args", "expected"), [
    (["--setups", "v1,v9"], "v9"),
    (["--strategies", "opm,greedy"], "greedy"),
    (["--strategies", "opm,baseline,opm"], "'opm' is listed twice"),
    (["--strategies", ","], "at least one strategy"),
    (["--setups", "v1,v1"], "two setups are named 'v1'"),
    (["--setups", ""], "--setups: expected at least one setup"),
    (["--trials", "0"], "[1, 1000000]"),
    (["--trials", "1000000001"], "[1, 1000000]"),
    (["--workers", "-2"], "[1, 1024]"),
    (["--workers", "1000"], "--workers: 1000 local workers"),
    (["--workers", "100000"], "[1, 1024]"),
    (["--random-setups", "0"], "[1, 100000]"),
    (["--trial-timeout", "0"], "seconds > 0"),
    (["--trial-timeout", "nan"], "seconds > 0"),
    (["--scheduler", "tcp://127.0.0.1:1"], "--executor dask"),
    (["--executor", "slurm"], "local"),
    (["--executor", "dask", "--scheduler", "tcp://127.0.0.1:1"],
     "--scheduler: cannot reach the Dask scheduler at tcp://127.0.0.1:1"),
    (["--executor", "dask", "--scheduler", "tcp://no-such-host.invalid:8786"],
     "cannot reach the Dask scheduler at tcp://no-such-host.invalid:8786"),
    (["--executor", "dask", "--scheduler", "tcp://127.0.0.1"], "malformed"),
    (["--executor", "dask", "--scheduler", "127.0.0.1:port"], "malformed"),
    (["--executor", "dask", "--scheduler", "foo://bar:1"], "malformed"),
    (["--executor", "dask", "--scheduler", "tcp://127.0.0.1:70000"], "malformed"),
    (["--executor", "dask", "--scheduler", "ucx://127.0.0.1:1"], "ucx:// protocol needs UCX"),
])
def test_bad_arguments_exit_2_and_list_the_choices(tmp_path: Path, args, expected) -> None:
    start = time.perf_counter()
    result = bench(tmp_path / "x", *args)
    print(result.stderr)
    assert result.returncode == 2
    assert expected in result.stderr
    assert "Traceback" not in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert time.perf_counter() - start < 20  # fails fast (no 30 s connection wait)
    assert not (tmp_path / "x").exists()  # refused before the results folder is made
    if "--setups" in args and "v9" in args[1]:
        assert "v1, v2, v3, v4, v5" in result.stderr
    if "greedy" in args[-1]:
        assert "opm, baseline, random" in result.stderr


def test_out_that_cannot_be_a_results_folder(tmp_path: Path) -> None:
    afile = tmp_path / "afile"
    afile.write_text("not a folder")
    for out, expected in ((afile, "is a file; expected a folder"),
                          (afile / "below", "cannot create or write the folder"),
                          (Path("/sys/cramlite-results"), "cannot create or write the folder"),
                          (ROOT / "worlds" / "results", "inside cramlite's own worlds")):
        result = bench(out, *SMALL)
        print(result.stderr)
        assert result.returncode == 2 and "Traceback" not in result.stderr
        assert result.stderr.strip().startswith(f"cramlite bench: error: {out}: --out: ")
        assert expected in result.stderr


def test_a_second_bench_into_the_same_folder_is_refused_naming_the_first(
        tmp_path: Path) -> None:
    from cramlite.bench.lock import FolderLock

    out = tmp_path / "shared"
    out.mkdir()
    with FolderLock(out):  # this test process plays the first bench
        second = bench(out, *SMALL)
        print(second.stderr)
        assert second.returncode == 2
        assert f"in use by another bench (pid {os.getpid()} on " in second.stderr
        assert not (out / "trials.csv").exists()
    after = bench(out, "--setups", "v1", "--strategies", "baseline", "--trials", "1",
                  "--no-plots", "--workers", "1")
    assert after.returncode == 0, after.stderr  # the lock went with its holder


def test_a_process_forked_from_the_holder_does_not_keep_the_folder_locked(
        tmp_path: Path) -> None:
    """The bench's workers are forked from it: they must not keep its lock once it is
    gone (a killed bench's folder stayed locked while a worker was busy)."""
    import multiprocessing

    from cramlite.bench.lock import FolderBusy, FolderLock
    from cramlite.forking import quiet_fork

    holder = FolderLock(tmp_path)
    holder.acquire()
    holder.release()
    holder.acquire()  # (taken again: it still lets go in a child)
    fork = multiprocessing.get_context("fork")
    started = fork.Event()
    child = fork.Process(target=_say_started_and_sleep, args=(started,))
    with quiet_fork():
        child.start()
    try:
        assert started.wait(30)  # (the child's fork handlers have run by then)
        with pytest.raises(FolderBusy):
            FolderLock(tmp_path).acquire()  # (the holder still has it)
        holder.release()
        after = FolderLock(tmp_path)
        after.acquire()  # the child, still running, does not hold it
        after.release()
    finally:
        child.kill()
        child.join()


def _say_started_and_sleep(started) -> None:
    started.set()
    time.sleep(60)


def test_the_progress_bar_on_a_terminal_starts_no_thread() -> None:
    """tqdm's monitor thread would keep a bench on a terminal from forking its workers
    (a fresh interpreter: this one may have made a bar already)."""
    code = """
import io, threading
from cramlite.bench.progress import Progress
class Terminal(io.StringIO):
    def isatty(self):
        return True
before = threading.active_count()
progress = Progress(10, stream=Terminal())
progress.update({"success": True})
print(progress._bar is not None, threading.active_count() - before)
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "0"]


def test_resume_is_keyed_by_setup_content_and_plan(tmp_path: Path) -> None:
    out = tmp_path / "s"
    args = ["--strategies", "baseline", "--trials", "1", "--no-plots", "--workers", "1"]
    assert bench(out, "--setups", "v1", *args).returncode == 0
    moved = tmp_path / "my.yaml"  # still named v1 inside, another start pose
    moved.write_text((ROOT / "worlds" / "setups" / "v1.yaml").read_text().replace(
        "start: [-0.5, -1.8, 1.5708]", "start: [-0.4, -1.6, 1.5708]"))
    refused = bench(out, "--setups", str(moved), *args)
    print(refused.stderr)
    assert refused.returncode == 2
    assert "holds trials of another setup named 'v1'" in refused.stderr
    assert len(rows(out)) == 1
    same = bench(out, "--setups", "v1", *args)
    assert "(1 already in" in same.stderr and len(rows(out)) == 1
    other_plan = bench(out, "--setups", "v1", *args, "--plan", "clear-table")
    assert other_plan.returncode == 0, other_plan.stderr
    assert "(0 already in" in other_plan.stderr
    assert sorted(r["plan"] for r in rows(out)) == ["clear-table", "set-table"]
    (out / "trials.csv").write_text("setup,plan,strategy\nv1,set-table,opm\n")  # old format
    old = bench(out, "--setups", "v1", *args)
    assert old.returncode == 2 and "has other columns" in old.stderr


def test_a_closed_progress_stream_changes_no_result(tmp_path: Path) -> None:
    out = tmp_path / "p"
    proc = subprocess.Popen([sys.executable, "-m", "cramlite", "bench", "--out", str(out),
                             *SMALL, "--workers", "2"], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT)  # as `2>&1 | head -1`
    print(proc.stdout.readline())
    proc.stdout.close()
    assert proc.wait(timeout=300) in (0, 141)
    table = rows(out)
    print([(r["strategy"], r["trial"], r["success"], r["error_type"]) for r in table])
    assert len(table) == 4 and all(r["success"] == "True" for r in table)
    again = bench(out, *SMALL)
    assert "(4 already in" in again.stderr and "| v1 | opm | 2 | 100% |" in again.stdout


HANGING = """
import time
from cramlite.strategies import Strategy

class Hang(Strategy):
    name = "hang"
    def choose(self, remaining, agent):
        while True:
            time.sleep(0.05)
"""


def _children(pid: int) -> list[int]:
    import psutil

    return [p.pid for p in psutil.Process(pid).children(recursive=True)]


def _gone(pids: list[int], within_s: float) -> bool:
    import psutil

    deadline = time.time() + within_s
    while time.time() < deadline:
        alive = [p for p in pids if psutil.pid_exists(p)
                 and psutil.Process(p).status() != psutil.STATUS_ZOMBIE]
        if not alive:
            return True
        time.sleep(0.1)
    return False


@pytest.fixture
def hanging(tmp_path: Path) -> dict:
    (tmp_path / "hanging.py").write_text(HANGING)
    return {"PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT)])}


def test_a_hanging_trial_times_out_and_the_batch_goes_on(tmp_path: Path, hanging) -> None:
    out = tmp_path / "t"
    result = bench(out, "--setups", "v1", "--strategies", "baseline,hanging:Hang", "--trials",
                   "2", "--workers", "2", "--trial-timeout", "4", "--no-plots", env=hanging)
    print(result.stderr[-1500:])
    assert result.returncode == 1
    table = rows(out)
    assert len(table) == 4
    for r in table:
        if r["strategy"] == "baseline":
            assert r["success"] == "True"
        else:
            assert r["success"] == "False" and r["error_type"] == "Timeout"
            assert "trial timeout (4 s)" in r["error"]
    assert "exceeded the trial timeout (4 s): recorded as Timeout, its worker killed" in \
        result.stderr


@pytest.mark.parametrize("how", ["SIGTERM", "SIGINT twice", "SIGKILL"])
def test_stopping_a_bench_leaves_no_worker_behind(tmp_path: Path, hanging, how: str) -> None:
    out = tmp_path / "k"
    proc = subprocess.Popen([sys.executable, "-m", "cramlite", "bench", "--out", str(out),
                             "--setups", "v1", "--strategies", "baseline,hanging:Hang",
                             "--trials", "3", "--workers", "2", "--no-plots"], cwd=ROOT,
                            env={**os.environ, **hanging}, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while time.time() < deadline and len(rows(out) if (out / "trials.csv").exists()
                                         else []) < 1:
        time.sleep(0.2)  # a baseline trial is written; a hanging one is running
    workers = _children(proc.pid)
    assert len(workers) >= 2
    start = time.time()
    if how == "SIGTERM":
        proc.terminate()
    elif how == "SIGKILL":
        proc.kill()
    else:
        proc.send_signal(signal.SIGINT)
        time.sleep(1.0)
        proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    print(how, proc.returncode, round(time.time() - start, 1), err[-600:])
    assert time.time() - start < 15  # no wait for the hanging trial
    assert proc.returncode == {"SIGTERM": 143, "SIGINT twice": 130, "SIGKILL": -9}[how]
    assert _gone(workers, within_s=10), f"orphaned workers: {workers}"
    if how != "SIGKILL":
        assert "Traceback" not in err
        assert "Run the same command again" in err
    if how == "SIGINT twice":
        assert "Ctrl-C again to stop now" in err


def test_huge_trial_counts_stream() -> None:
    from cramlite.bench.specs import BatchPlan, SetupEntry

    setups = {f"s{i}": SetupEntry(f"s{i}.yaml", "h", ("a", "b", "c", "d", "e"))
              for i in range(5)}
    plan = BatchPlan(setups, ["opm", "baseline"], 10**6, 0, all_orders=True)
    assert plan.total() == 5 * 2 * 10**6 + 5 * 120
    start = time.perf_counter()
    first = [spec for _, spec in zip(range(3), plan, strict=False)]
    assert time.perf_counter() - start < 1.0  # a list of ten million specs would take long
    assert [(s.setup, s.strategy, s.trial) for s in first] == [
        ("s0", "opm", 0), ("s0", "baseline", 0), ("s0", "opm", 1)]
    assert plan.contains(first[0].key)
    assert not plan.contains(("s0", "other-hash", *first[0].key[2:]))


def test_all_orders_is_bounded(tmp_path: Path) -> None:
    from tests.setup_files import many_cups, write

    result = bench(tmp_path / "a", "--setups", str(write(tmp_path, many_cups(11))),
                   "--all-orders", "--no-plots")
    print(result.stderr)
    assert result.returncode == 2 and "expects at most 10 items" in result.stderr


def _free_port() -> int:
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@pytest.fixture
def dask_worker_on_loopback():
    """A real `dask scheduler` and a stock multi-threaded `dask worker` (with its nanny)
    on loopback; yields (address, the worker command's pid); stops both afterwards."""
    pytest.importorskip("distributed")
    from distributed import Client

    address = f"tcp://127.0.0.1:{_free_port()}"
    dask = [sys.executable, "-m", "dask"]
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    scheduler = subprocess.Popen([*dask, "scheduler", "--host", "127.0.0.1", "--port",
                                  address.rsplit(":", 1)[1], "--no-dashboard"], **quiet)
    worker = subprocess.Popen([*dask, "worker", address, "--nthreads", "4",
                               "--no-dashboard"], **quiet)
    try:
        with Client(address, timeout=60) as client:
            client.wait_for_workers(1, timeout=60)
            threads = sum(client.nthreads().values())
        assert threads == 4
        yield address, worker.pid
    finally:
        for proc in (worker, scheduler):
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


def test_dask_on_a_threaded_worker_runs_the_trials_and_gives_the_local_rows(
        tmp_path: Path, dask_worker_on_loopback) -> None:
    address, worker_pid = dask_worker_on_loopback
    args = ["--setups", "v1,v2", "--strategies", "opm,baseline", "--trials", "2", "--seed",
            "7", "--no-plots"]
    local, dask = tmp_path / "local", tmp_path / "dask"
    assert bench(local, *args, "--workers", "2").returncode == 0
    worker_processes = {f"{p}" for p in _children(worker_pid)} | {str(worker_pid)}
    result = bench(dask, *args, "--executor", "dask", "--scheduler", address)
    print(result.stderr[-1500:])
    assert result.returncode == 0
    assert f"Dask scheduler {address}" in result.stderr
    ran_on = {r["worker"].rsplit(":", 1)[1] for r in rows(dask)}
    print("dask worker processes", worker_processes, "rows ran on", ran_on)
    assert ran_on and ran_on <= worker_processes  # Dask's worker ran them, not a local pool
    assert comparable(local) == comparable(dask)


def test_dask_local_cluster_gives_the_same_rows_as_the_local_one(tmp_path: Path) -> None:
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
    # (a random setup may hold a task the robot fails at: exit 1, the failure recorded)
    assert result.returncode in (0, 1), result.stderr[-1500:]
    saved = sorted((randoms / "setups").glob("random-0-*.yaml"))
    assert len(saved) == 2
    table = rows(randoms)
    assert {r["setup"] for r in table} == {"v1", saved[0].stem, saved[1].stem}
    for r in table:
        assert r["success"] == "True" or json.loads(r["failures"]), r
    assert (result.returncode == 1) == any(r["success"] != "True" for r in table)
    rerun = run_cli("run", str(saved[0]), "--json")
    assert rerun.returncode == 0, rerun.stderr


def test_random_setups_store_items_in_the_containers_and_are_all_valid(tmp_path: Path) -> None:
    import yaml

    from cramlite.bench.random_setups import generate_setups

    made = generate_setups(12, seed=3, folder=tmp_path)
    # every generated setup loads (none is thrown away and replaced by the next index)
    assert list(made) == [f"random-3-{i:03d}" for i in range(12)]
    stored = [item for path in made.values()
              for item in yaml.safe_load(path.read_text())["items"] if "in" in item]
    print(len(stored), [(i["name"], i["in"]) for i in stored])
    assert {i["in"] for i in stored} == {"drawer_1", "drawer_2", "cupboard"}
    assert all(i["name"] in ("spoon", "cup", "bowl") for i in stored if i["in"] != "cupboard")


def test_summary_shows_a_dash_where_no_trial_succeeded() -> None:
    from cramlite.bench.summary import summarise, write_summary

    rows = [{"setup": "unreachable", "strategy": "opm", "success": "False", "order": "cup",
             "wall_s": "1.5", "robot_time_s": "120.0", "drive_s": "20", "arm_s": "99",
             "open_close_s": "0", "base_path_m": "9", "straight_line_m": "9"}]
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        text = write_summary(Path(folder), summarise(rows, {}), [], [])
    line = next(x for x in text.splitlines() if x.startswith("| unreachable"))
    assert "nan" not in line and "| 0% | – / – |" in line


def test_the_paired_tests_compare_with_the_reference_asked_for(tmp_path: Path) -> None:
    out = tmp_path / "ref"
    common = ("--setups", "v1,v2", "--trials", "2", "--backend", "kinematic", "--no-plots",
              "--workers", "2")
    done = bench(out, *common, "--strategies", "opm,nearest")  # no baseline: the first
    assert done.returncode == 0, done.stderr[-1500:]
    tests = json.loads((out / "tests.json").read_text())["wilcoxon"]
    assert {(t["strategy"], t["reference"]) for t in tests} == {("nearest", "opm")}
    asked = tmp_path / "asked"
    done = bench(asked, *common, "--strategies", "opm,nearest", "--reference", "nearest")
    assert done.returncode == 0, done.stderr[-1500:]
    tests = json.loads((asked / "tests.json").read_text())["wilcoxon"]
    assert {(t["strategy"], t["reference"]) for t in tests} == {("opm", "nearest")}
    page = (asked / "report.html").read_text()
    assert "against nearest" in page and "nearest mean" in page
    wrong = bench(tmp_path / "wrong", *common, "--strategies", "opm", "--reference", "nope")
    assert wrong.returncode == 2 and "--reference" in wrong.stderr


EXITING = '''
from cramlite.strategies import Strategy

class Exits(Strategy):
    name = "exits"
    def choose(self, remaining, agent):
        raise SystemExit(3)

class Interrupts(Strategy):
    name = "interrupts"
    def choose(self, remaining, agent):
        raise KeyboardInterrupt
'''


def test_a_trial_raising_system_exit_or_keyboard_interrupt_is_a_row(tmp_path: Path) -> None:
    (tmp_path / "exiting.py").write_text(EXITING)
    out = tmp_path / "x"
    names = [f"{tmp_path / 'exiting.py'}:{cls}" for cls in ("Exits", "Interrupts")]
    args = ("--setups", "v1", "--strategies", ",".join(["baseline", *names]), "--trials", "1",
            "--workers", "2", "--no-plots", "--backend", "kinematic")
    result = bench(out, *args)
    assert result.returncode == 1, result.stderr[-1500:]  # (failed trials, not a stop)
    table = {r["strategy"]: r for r in rows(out)}
    assert len(table) == 3 and table["baseline"]["success"] == "True"
    assert table[names[0]]["error_type"] == "SystemExit"
    assert table[names[1]]["error_type"] == "KeyboardInterrupt"
    assert "raised by the trial's code" in table[names[1]]["error"]
    again = bench(out, *args)  # resumed: nothing left to run, no trial stops it again
    assert again.returncode == 1 and len(rows(out)) == 3


def test_the_default_reference_follows_the_order_asked_not_the_order_finished() -> None:
    from cramlite.bench.summary import default_reference, reference_tests

    assert default_reference(["opm", "nearest"]) == "opm"
    assert default_reference(["nearest", "baseline"]) == "baseline"
    rows = [{"setup": "v1", "trial": t, "strategy": s, "success": "True", "robot_time_s": "1",
             "wall_s": "1", "drive_s": "1", "arm_s": "1", "open_close_s": "0",
             "base_path_m": "1", "straight_line_m": "1", "order": "", "given_order": ""}
            for t in (0, 1) for s in ("nearest", "opm")]  # (nearest's rows came in first)
    tests = reference_tests(rows, default_reference(["opm", "nearest"]))
    assert [(t["strategy"], t["reference"]) for t in tests] == [("nearest", "opm")]

"""The bench report page as a user gets it: `cramlite bench` writes it, `cramlite report`
rebuilds it (also for an interrupted or still running bench), every setup, strategy and
picture is there, nothing is fetched from the network; bad folders exit 2."""

from __future__ import annotations

import csv
import html.parser
import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cramlite.bench.lock import FolderLock
from cramlite.report.trials import trial_id
from cramlite.safe_names import safe_stem
from cramlite.trace.path import simplify_path
from tests.conftest import ROOT

SETUPS = ("v1", "unreachable")
STRATEGIES = ("baseline", "opm")


def cli(*args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "cramlite", *args], capture_output=True,
                          text=True, cwd=ROOT, timeout=600, env=env)


@pytest.fixture(scope="module")
def bench_dir(tmp_path_factory) -> Path:
    """A tiny bench with traces (one trial of each setup and strategy; the milk of
    `unreachable` cannot be reached, so its trials fail), and its report with pictures."""
    out = tmp_path_factory.mktemp("report") / "results"
    done = cli("bench", "--out", str(out), "--setups", ",".join(SETUPS), "--strategies",
               ",".join(STRATEGIES), "--trials", "1", "--workers", "2", "--traces",
               "--no-plots")
    assert done.returncode == 1, done.stderr  # the unreachable trials fail
    assert done.stdout.strip().splitlines()[-1] == f"report: {(out / 'report.html').resolve()}"
    built = cli("report", str(out), "--max-replays", "1")
    assert built.returncode == 0, built.stderr
    assert built.stdout.strip() == f"wrote {out / 'report.html'}"
    return out


class Page(html.parser.HTMLParser):
    """The page's ids, links, pictures and text."""

    def __init__(self, text: str):
        super().__init__()
        self.ids: set[str] = set()
        self.links: list[str] = []
        self.images: list[str] = []
        self.tags: set[str] = set()
        self.text: list[str] = []
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        self.tags.add(tag)
        values = dict(attrs)
        if "id" in values:
            self.ids.add(values["id"])
        if tag == "img":
            self.images.append(values["src"])
        for key in ("href", "src", "srcset", "action", "data"):
            if values.get(key):
                self.links.append(values[key])

    def handle_data(self, data):
        self.text.append(data)


def rows(folder: Path) -> list[dict[str, str]]:
    with (folder / "trials.csv").open() as handle:
        return list(csv.DictReader(handle))


def test_page_shows_every_setup_strategy_order_and_failure_offline(bench_dir: Path) -> None:
    text = (bench_dir / "report.html").read_text()
    page = Page(text)
    # no network: no script, no stylesheet or picture from elsewhere
    assert "script" not in page.tags and "link" not in page.tags
    assert all("://" not in link and not link.startswith("//") for link in page.links)
    assert "url(" not in text and "@import" not in text
    # every referenced picture is a file beside the page
    assert page.images
    for src in page.images:
        assert (bench_dir / src).is_file(), src
    for setup in SETUPS:
        assert f"setup-{setup}" in page.ids
        assert f"report/map-{safe_stem(setup)}.png" in page.images
    plain = " ".join(page.text)
    for row in rows(bench_dir):
        trial = trial_id(row)
        assert f"trial-{trial}" in page.ids  # first trial of each setup and strategy
        assert f"report/timeline-{trial}.png" in page.images
        numbered = " → ".join(f"{k}\xa0{n}" for k, n in enumerate(row["order"].split(), 1))
        assert numbered in plain  # the order it chose, numbered
        if row["success"] != "True":
            assert "ObjectUnreachable" in plain and "milk" in plain
    assert plain.count("FAILED") >= 2
    # failed trials: the banner says so (not the green "complete" one)
    assert 'class="status failures"' in text and "Complete, with failures" in plain
    # one replay drawn (--max-replays 1), the others say why not
    gifs = [src for src in page.images if src.endswith(".gif")]
    assert len(gifs) == 1 and "replay not drawn" in plain
    for strategy in STRATEGIES:
        assert strategy in plain
    # robot time as the summary files define it: the robot's own, without the host's time
    assert "Robot time: the robot's own time" in plain and "Robot time = wall" not in plain


def test_driven_path_column_follows_the_executed_path(bench_dir: Path) -> None:
    for row in rows(bench_dir):
        path = json.loads(row["driven_path"])
        assert path[0] == [-0.5, -1.8]  # the robot's start
        length = sum(math.dist(a, b) for a, b in zip(path, path[1:], strict=False))
        assert length == pytest.approx(float(row["base_path_m"]), rel=0.1)
        assert len(row["driven_path"]) < 2000


def test_simplify_path_keeps_the_shape_within_a_centimetre() -> None:
    line = np.c_[np.linspace(0, 3, 1000), np.zeros(1000)]
    assert simplify_path(line) == [[0.0, 0.0], [3.0, 0.0]]
    corner = np.r_[line, np.c_[np.full(500, 3.0), np.linspace(0, 2, 500)]]
    assert simplify_path(corner) == [[0.0, 0.0], [3.0, 0.0], [3.0, 2.0]]
    t = np.linspace(0, 2 * np.pi, 2000)
    curve = np.c_[np.cos(t), np.sin(2 * t)]
    simple = np.array(simplify_path(curve))
    assert len(simple) < 120
    # every original point is within ~1 cm (+ rounding) of the simplified polyline
    worst = max(min(_segment_distance(p, a, b) for a, b in zip(simple, simple[1:],
                                                             strict=False)) for p in curve)
    assert worst < 0.02


def _segment_distance(p, a, b) -> float:
    ab, ap = b - a, p - a
    s = np.clip(np.dot(ap, ab) / max(np.dot(ab, ab), 1e-12), 0, 1)
    return float(np.hypot(*(ap - s * ab)))


def test_report_of_an_interrupted_and_of_a_running_bench(bench_dir: Path, tmp_path) -> None:
    folder = tmp_path / "cut"
    folder.mkdir()
    shutil.copy(bench_dir / "metadata.json", folder)
    lines = (bench_dir / "trials.csv").read_text().splitlines(keepends=True)
    # the header, one finished trial and one cut short by a kill
    (folder / "trials.csv").write_text(lines[0] + lines[1] + lines[2][:120])
    done = cli("report", str(folder), "--no-plots")
    assert done.returncode == 0, done.stderr
    page = Page((folder / "report.html").read_text())
    plain = " ".join(page.text)
    assert "Incomplete: 1 of the 4 trials" in plain and "interrupted" in plain
    for setup in SETUPS:  # setups without a trial yet are there, saying so
        assert f"setup-{setup}" in page.ids
    assert "no trial yet" in plain
    with FolderLock(folder):  # a bench still writing into the folder
        done = cli("report", str(folder), "--no-plots")
    assert done.returncode == 0, done.stderr
    assert "a bench is still writing into this folder" in (folder / "report.html").read_text()


def test_a_report_removes_only_its_own_old_pictures(bench_dir: Path, tmp_path) -> None:
    copy = tmp_path / "mine"
    shutil.copytree(bench_dir, copy, ignore=shutil.ignore_patterns("traces"))
    media = copy / "report"
    (media / "figure1.png").write_bytes(b"a user's figure")
    (media / "anim.gif").write_bytes(b"a user's animation")
    stale = media / "timeline-v1-opm-99.png"  # (a picture an earlier report drew)
    stale.write_bytes(b"old")
    assert cli("report", str(copy), "--no-plots").returncode == 0
    assert (media / "figure1.png").read_bytes() == b"a user's figure"
    assert (media / "anim.gif").read_bytes() == b"a user's animation"
    assert not stale.exists()


def test_report_is_the_same_when_built_twice(bench_dir: Path, tmp_path) -> None:
    copy = tmp_path / "again"
    shutil.copytree(bench_dir, copy, ignore=shutil.ignore_patterns("report*", "traces"))
    for _ in range(2):
        assert cli("report", str(copy)).returncode == 0
        first = {p.name: p.read_bytes() for p in (copy / "report").iterdir()}
        page = (copy / "report.html").read_bytes()
    assert cli("report", str(copy)).returncode == 0
    assert (copy / "report.html").read_bytes() == page
    assert {p.name: p.read_bytes() for p in (copy / "report").iterdir()} == first


def test_without_matplotlib_the_page_has_its_tables(bench_dir: Path, tmp_path) -> None:
    copy = tmp_path / "plain"
    shutil.copytree(bench_dir, copy, ignore=shutil.ignore_patterns("report*", "traces"))
    code = ("import sys; sys.modules['matplotlib'] = None; from cramlite.cli import main; "
            f"sys.exit(main(['report', {str(copy)!r}]))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, timeout=300)
    assert done.returncode == 0, done.stderr
    page = Page((copy / "report.html").read_text())
    assert not page.images
    plain = " ".join(page.text)
    assert "pip install 'cramlite[plots]'" in plain and "setup-v1" in page.ids
    assert "ObjectUnreachable" in plain


def test_a_matplotlib_that_does_not_start_is_one_line_naming_mplbackend(bench_dir: Path,
                                                                        tmp_path) -> None:
    """MPLBACKEND naming no backend makes matplotlib refuse to import: `report` says so in
    one line naming the variable (exit 2), with no traceback."""
    import os

    copy = tmp_path / "copy"
    shutil.copytree(bench_dir, copy, ignore=shutil.ignore_patterns("report*", "traces"))
    done = cli("report", str(copy), env={**os.environ, "MPLBACKEND": "nosuch"})
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "MPLBACKEND=nosuch" in lines[0], lines


@pytest.mark.parametrize("case, expected", [
    ("missing", "no such folder; expected a results folder"),
    ("file", "is a file; expected a results folder"),
    ("empty", "holds no trials.csv or metadata.json"),
    ("no rows", "no finished trial yet"),
    ("columns", "has no column setup"),
    ("json", "line 2: actions: expected a JSON list"),
    ("metadata", "metadata.json: not valid JSON"),
])
def test_a_folder_that_is_not_a_bench_folder_exits_2(bench_dir: Path, tmp_path, case: str,
                                                     expected: str) -> None:
    folder = tmp_path / "bad"
    if case == "file":
        folder.write_text("x")
    elif case != "missing":
        folder.mkdir()
    header = (bench_dir / "trials.csv").read_text().splitlines()[0]
    row = rows(bench_dir)[0]
    if case == "no rows":
        (folder / "trials.csv").write_text(header + "\n")
    elif case == "columns":
        (folder / "trials.csv").write_text("a,b\n1,2\n")
    elif case == "json":
        with (folder / "trials.csv").open("w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(row))
            writer.writeheader()
            writer.writerow({**row, "actions": "{oops"})
    elif case == "metadata":
        (folder / "metadata.json").write_text("{")
    done = cli("report", str(folder))
    assert done.returncode == 2
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert done.stderr.startswith("cramlite report: error: ") and expected in done.stderr


def test_show_top_draws_the_labelled_map(tmp_path) -> None:
    out = tmp_path / "v1-top.png"
    done = cli("show", "v1", "--top", "--out", str(out), "--width", "500", "--height", "400")
    assert done.returncode == 0, done.stderr
    from PIL import Image

    assert Image.open(out).size == (500, 400)


def test_labels_are_spread_and_points_project_onto_the_image() -> None:
    from cramlite.render.camera import SHOW_CAMERA, camera
    from cramlite.world.topdown import spread

    placed = spread([1.0, 1.01, 1.02, 3.0, 0.99], 0.2, 0.0, 5.0)
    ordered = sorted(placed)
    assert all(b - a >= 0.2 - 1e-9 for a, b in zip(ordered, ordered[1:], strict=False))
    assert placed[3] == 3.0  # a label with room stays where its spot is
    u, v = camera(None, SHOW_CAMERA).project(np.array([SHOW_CAMERA["target"]]), 640, 480)[0]
    assert (u, v) == pytest.approx((320, 240), abs=0.5)  # the camera looks at its target


def test_the_rerun_command_of_a_setup_file_runs_as_printed(tmp_path) -> None:
    import re
    import shlex

    setup = tmp_path / "mine.yaml"
    setup.write_text((ROOT / "worlds" / "setups" / "v1.yaml").read_text()
                     .replace("name: v1", "name: my6"))
    out = tmp_path / "out"
    done = cli("bench", "--out", str(out), "--setups", str(setup), "--strategies", "opm",
               "--trials", "1", "--backend", "kinematic", "--no-plots")
    assert done.returncode == 0, done.stderr
    text = html.unescape((out / "report.html").read_text())
    # the parameters as used: the default's workers (one per CPU), not "None"
    import os

    assert f"workers</th><td>{os.cpu_count()}<" in text
    params = text.split("Parameters (last bench command)")[1].split("</table>")[0]
    assert "None" not in params and "backends_list" not in params
    assert "scheduler</th><td>(not given: the default)<" in params
    assert "backends</th><td>kinematic<" in params
    (command,) = set(re.findall(r"Rerun it alone: <code>(.*?)</code>", text))
    words = shlex.split(command)
    assert words[:3] == ["cramlite", "run", str(setup)]  # its path, not its name (my6)
    rerun = cli(*words[1:], "--json")
    assert rerun.returncode == 0, rerun.stderr
    (row,) = rows(out)
    assert json.loads(rerun.stdout)["order"] == row["order"].split()


def test_the_rerun_command_of_relative_plan_and_strategy_files_runs_from_anywhere(
        tmp_path) -> None:
    """`--plan ./fetch_two.py:fetch_two` typed in the bench's folder: the report's rerun
    command names the file by its absolute path (as typed, it failed elsewhere)."""
    import re
    import shlex
    import shutil

    shutil.copy(ROOT / "examples" / "fetch_two.py", tmp_path / "fetch_two.py")
    shutil.copy(ROOT / "examples" / "farthest_first.py", tmp_path / "farthest_first.py")
    done = subprocess.run([sys.executable, "-m", "cramlite", "bench", "--out", "out",
                           "--setups", "v1", "--plan", "./fetch_two.py:fetch_two",
                           "--strategies", "./farthest_first.py:FarthestFirst", "--trials",
                           "1", "--backend", "kinematic", "--no-plots"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert done.returncode == 0, done.stderr
    text = html.unescape((tmp_path / "out" / "report.html").read_text())
    (command,) = set(re.findall(r"Rerun it alone: <code>(.*?)</code>", text))
    words = shlex.split(command)
    assert f"{tmp_path}/fetch_two.py:fetch_two" in words, words
    assert f"{tmp_path}/farthest_first.py:FarthestFirst" in words, words
    rerun = cli(*words[1:], "--json")  # (from the repository's folder)
    assert rerun.returncode == 0, rerun.stderr
    (row,) = rows(tmp_path / "out")
    assert json.loads(rerun.stdout)["order"] == row["order"].split()


def test_a_strategy_keeps_its_colour_from_one_report_to_the_next() -> None:
    from cramlite.bench.plots import strategy_colours

    one = strategy_colours(["baseline", "farthest"])
    two = strategy_colours(["opm", "farthest", "baseline", "random"])
    assert one["baseline"] == two["baseline"] and one["farthest"] == two["farthest"]
    assert len(set(two.values())) == 4  # (no two strategies of a report share one)
    assert strategy_colours(["opm@kinematic"])["opm@kinematic"] == two["opm"]


def test_plot_titles_are_not_clipped_and_few_trials_are_dots(tmp_path) -> None:
    pytest.importorskip("matplotlib")
    from PIL import Image

    from cramlite.bench.plots import write_plots

    rows = [{"setup": "v1", "strategy": s, "trial": str(t), "success": "True",
             "robot_time_s": 80 + t + k, "base_path_m": 12 + t + k, "straight_line_m": 20,
             "drive_s": 30, "arm_s": 50, "open_close_s": 0, "wall_s": 0.5}
            for k, s in enumerate(("baseline", "opm")) for t in range(2)]
    written = write_plots(rows, tmp_path)
    for path in written:
        image = np.asarray(Image.open(path).convert("L"))
        band = image[: image.shape[0] // 8]  # the title's rows
        # the title starts inside the picture: its first columns are background
        assert band[:, :4].min() > 200, path.name
        assert band.min() < 100, path.name  # (and there is a title)


def test_pictures_that_cannot_be_written_are_one_line(bench_dir: Path, tmp_path) -> None:
    folder = tmp_path / "copy"
    shutil.copytree(bench_dir, folder)
    blocked = folder / "report" / f"map-{safe_stem(SETUPS[0])}.png"
    if blocked.exists():
        blocked.unlink()
    blocked.mkdir(parents=True)  # (a folder where the map's picture goes: it cannot be written)
    done = cli("report", str(folder))
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert "Traceback" not in done.stderr and "cannot write the report's pictures" in lines[-1]


def test_pictures_are_drawn_on_several_processes_in_order() -> None:
    """The report's pictures are drawn on forked processes where there are several CPUs
    (each result in its job's place), and one by one in a process that runs another
    thread or has JAX loaded (a fresh interpreter each: this one may have either)."""
    code = """
import os, sys, threading
from cramlite.report.build import _draw_all
case = sys.argv[1]
if case == "thread":
    stop = threading.Event()
    threading.Thread(target=stop.wait, daemon=True).start()
if case == "jax":
    sys.modules.setdefault("jax", type(sys)("jax"))
import time
def job():  # (long enough that the pool starts its second process: it starts them as needed)
    time.sleep(0.3)
    return os.getpid()
results = _draw_all([(job, ())] * 6 + [(abs, (-7,))])
print(results[-1], len({pid for pid in results[:-1]}), os.getpid() in results)
"""
    import os

    for case, many in (("plain", (os.cpu_count() or 1) > 1), ("thread", False),
                       ("jax", False)):
        done = subprocess.run([sys.executable, "-c", code, case], capture_output=True,
                              text=True, cwd=ROOT, timeout=120)
        assert done.returncode == 0, done.stderr
        last, pids, here = done.stdout.split()
        assert last == "7"  # (in its job's place)
        assert (int(pids) > 1 and here == "False") if many else (pids, here) == ("1", "True")


@pytest.mark.skipif(not sys.platform.startswith("linux") or (os.cpu_count() or 1) < 2,
                    reason="pictures are drawn on forked processes on Linux with 2+ CPUs")
def test_drawing_processes_end_with_a_killed_report(tmp_path: Path) -> None:
    """A report killed while it draws leaves no drawing process behind (they held the
    bench's folder lock, and lived on for ever)."""
    import signal
    import time

    code = """
import os, sys, time
from pathlib import Path
from cramlite.report.build import _draw_all
def job(k):
    Path(sys.argv[1], f"{os.getpid()}.pid").write_text("")
    time.sleep(60)
_draw_all([(job, (k,)) for k in range(2)])
"""
    parent = subprocess.Popen([sys.executable, "-c", code, str(tmp_path)], cwd=ROOT)
    try:
        deadline = time.monotonic() + 60
        while len(list(tmp_path.glob("*.pid"))) < 2 and time.monotonic() < deadline:
            time.sleep(0.1)
        children = [int(p.stem) for p in tmp_path.glob("*.pid")]
        assert len(children) == 2
        parent.send_signal(signal.SIGKILL)
        parent.wait()
        def alive(pid: int) -> bool:  # (a zombie has ended: its parent is gone)
            try:
                return Path(f"/proc/{pid}/stat").read_text().split(") ")[1][0] != "Z"
            except (OSError, IndexError):
                return False

        deadline = time.monotonic() + 10
        while any(alive(pid) for pid in children) and time.monotonic() < deadline:
            time.sleep(0.1)
        left = [pid for pid in children if alive(pid)]
        for pid in left:
            os.kill(pid, signal.SIGKILL)
        assert left == []
    finally:
        parent.kill()


def test_pictures_drawn_at_once_are_those_drawn_one_by_one(bench_dir: Path, tmp_path) -> None:
    """A report built by `cramlite report` (its pictures on several processes) has the
    very pictures one built here one by one has (a thread runs: no fork)."""
    import threading

    from cramlite.report import build_report

    apart, together = tmp_path / "apart", tmp_path / "together"
    for folder in (apart, together):
        shutil.copytree(bench_dir, folder, ignore=shutil.ignore_patterns("report*"))
    assert cli("report", str(together), "--max-replays", "1").returncode == 0
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        build_report(apart, max_replays=1)
    finally:
        stop.set()
        other.join()
    drawn = {p.name: p.read_bytes() for p in (together / "report").iterdir()}
    assert any(name.endswith(".gif") for name in drawn) and len(drawn) > 5
    assert {p.name: p.read_bytes() for p in (apart / "report").iterdir()} == drawn


def test_the_plots_drawn_for_the_report_are_copied_where_asked(bench_dir: Path,
                                                               tmp_path) -> None:
    """`cramlite bench` no longer draws its plots itself: the report draws them (with its
    other pictures) and copies them into the bench's folder, the same bytes."""
    from cramlite.bench.plots import write_plots
    from cramlite.report import build_report

    folder = tmp_path / "results"
    shutil.copytree(bench_dir, folder, ignore=shutil.ignore_patterns("report*"))
    build_report(folder, max_replays=0, plots_to=folder)
    copied = sorted(p.name for p in folder.glob("*.png"))
    assert copied == ["base_path_m_aggregated.png", "base_path_m_by_setup.png",
                      "robot_time_s_aggregated.png", "robot_time_s_by_setup.png"]
    alone = write_plots(rows(folder), tmp_path)  # (drawn here, one by one)
    for path in alone:
        assert (folder / path.name).read_bytes() == path.read_bytes()
        assert (folder / "report" / path.name).read_bytes() == path.read_bytes()


def test_a_report_run_from_elsewhere_finds_a_setup_named_relative_to_the_bench(
        tmp_path: Path) -> None:
    from tests.conftest import run_cli

    (tmp_path / "mine.yaml").write_text((ROOT / "examples" / "breakfast_for_one.yaml")
                                        .read_text())
    done = run_cli("bench", "--setups", "mine.yaml", "--strategies", "opm", "--trials", "1",
                   "--backend", "kinematic", "--no-plots", "--out", "out", cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    again = run_cli("report", str(tmp_path / "out"), cwd=ROOT)
    assert again.returncode == 0, again.stderr
    page = (tmp_path / "out" / "report.html").read_text()
    assert "setup file was not found" not in page and "map-breakfast-for-one" in page

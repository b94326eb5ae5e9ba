"""Building the report: read the folder, draw the pictures into `DIR/report/`, write
`DIR/report.html` (atomically: a browser never sees half a page)."""

from __future__ import annotations

import fnmatch
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from cramlite.bench.specs import FIXED_ORDER
from cramlite.errors import UserInputError
from cramlite.report.folder import BenchFolder, read_folder
from cramlite.report.page import MEDIA, PageData, render_page
from cramlite.report.trials import trial_id, trials_of_interest
from cramlite.safe_names import safe_stem

PAGE = "report.html"
#: Default number of replay animations a report draws (each takes a few seconds).
DEFAULT_MAX_REPLAYS = 12
NO_MATPLOTLIB = "Pictures (plots, maps, timelines) need matplotlib: pip install 'cramlite[plots]'."


def build_report(folder: str | Path, *, figures: bool = True,
                 max_replays: int = DEFAULT_MAX_REPLAYS, speed: float | None = None,
                 running: bool | None = None,
                 say: Callable[[str], None] | None = None,
                 plots_to: Path | None = None) -> Path:
    """Write DIR/report.html (and its pictures in DIR/report/); returns the page's path.
    `figures`: draw pictures (needs matplotlib); `max_replays`: at most this many replay
    GIFs of traced trials; `running`: whether a bench is still filling the folder (None:
    ask its lock); `plots_to`: put copies of the plots there too (the bench's folder: they
    are drawn once)."""
    from cramlite.bench.plots import strategy_colours
    from cramlite.bench.summary import order_percentiles, reference_tests, summarise
    from cramlite.report.replays import DEFAULT_SPEED

    data = read_folder(folder, running=running)
    rows = data.rows
    baseline = {n: tuple(s.baseline_order) for n, s in data.setups.items() if s is not None}
    summary = summarise(rows, baseline)
    tests = reference_tests(rows, (data.metadata.get("arguments") or {}).get("reference"))
    page = PageData(data, summary, [t for t in tests if t["pairs"]],
                    order_percentiles(rows), strategy_colours(data.strategies), baseline)
    from cramlite.bench.agreement import backend_agreement, injection_counts

    page.agreement = backend_agreement(rows)
    page.injection = injection_counts(rows)
    from cramlite.bench.carrying import carry_savings

    page.carrying = carry_savings(rows)
    page.interest, page.failed_left_out = trials_of_interest(rows)
    media = data.path / MEDIA
    try:
        media.mkdir(exist_ok=True)
    except OSError as exc:
        raise UserInputError(f"cannot write the report's pictures ({exc.strerror or exc})",
                             source=str(media)) from None
    written: set[str] = set()
    if not figures:
        page.figures_note = ("Pictures skipped (--no-plots); `cramlite report DIR` draws "
                             "them.")
    elif not have_matplotlib():
        page.figures_note = NO_MATPLOTLIB
    try:
        if figures and have_matplotlib():
            _pictures(data, page, media, written, say, plots_to)
        if max_replays > 0:
            _replays(data, page, media, written, max_replays, speed or DEFAULT_SPEED, say)
        _tidy(media, written)
    except OSError as exc:  # a full disk, a read-only folder
        raise UserInputError(f"cannot write the report's pictures ({exc.strerror or exc})",
                             source=str(getattr(exc, "filename", None) or media)) from None
    out = data.path / PAGE
    partial = data.path / f"{PAGE}.{os.getpid()}.part"  # two builds at once never mix
    try:
        partial.write_text(render_page(page), encoding="utf-8")
        os.replace(partial, out)
    except OSError as exc:
        raise UserInputError(f"cannot write the report ({exc.strerror or exc})",
                             source=str(out)) from None
    return out


def have_matplotlib() -> bool:
    """Whether matplotlib is installed (an environment it refuses to start in, e.g.
    MPLBACKEND naming no backend, is the user's to fix: UserInputError)."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return False
    except ValueError as exc:  # (matplotlib checks its settings, MPLBACKEND's too, on import)
        raise UserInputError(f"matplotlib does not start: {exc}",
                             source="the environment" if "MPLBACKEND" not in os.environ
                             else f"MPLBACKEND={os.environ['MPLBACKEND']}") from None
    return True


def _pictures(data: BenchFolder, page: PageData, media: Path, written: set[str],
              say: Callable[[str], None] | None, plots_to: Path | None = None) -> None:
    from cramlite.bench.plots import write_plots
    from cramlite.report.figures import pyplot, setup_map, timeline
    from cramlite.world.topdown import load_layout

    captions = {"robot_time_s_by_setup.png": "Robot time per setup and strategy.",
                "base_path_m_by_setup.png": "Driven base path per setup and strategy.",
                "robot_time_s_aggregated.png": "Robot time, all setups together.",
                "base_path_m_aggregated.png": "Driven base path, all setups together."}
    # every picture is drawn on its own (the plots, a map per setup, a timeline per trial
    # of interest): on a few processes at once where that is safe (`_draw_all`)
    jobs: list[tuple[Callable[..., Any], tuple]] = [(write_plots, (data.rows, media, plots_to))]
    maps: list[tuple[str, str]] = []
    for name in data.setup_names:
        setup = data.setups[name]
        if setup is None:
            continue
        try:
            layout = load_layout(setup)
        except UserInputError as exc:
            page.map_notes[name] = f"no map: {exc}"
            continue
        rows = [r for r in data.rows if r["setup"] == name and r["strategy"] != FIXED_ORDER]
        highlighted = {}
        for row in rows:
            best = highlighted.get(row["strategy"])
            if best is None or int(row["trial"]) < int(best["trial"]):
                highlighted[row["strategy"]] = row
        file = f"map-{safe_stem(name)}.png"
        jobs.append((setup_map, (layout, rows, data.strategies, page.colours, highlighted,
                                 media / file)))
        maps.append((name, file))
    if say:
        say(f"report: drawing {len(page.interest)} timelines")
    for row in page.interest:
        jobs.append((timeline, (row, media / f"timeline-{trial_id(row)}.png")))
    results = _draw_all(jobs, pyplot)
    for path in results[0]:
        written.add(path.name)
        if path.name in captions:
            page.plots.append((path.name, captions[path.name]))
        else:
            page.all_orders_plot = path.name
    for name, file in maps:
        page.maps[name] = file
        written.add(file)
    for row, path in zip(page.interest, results[1 + len(maps):], strict=True):
        page.timelines[trial_id(row)] = path.name
        written.add(path.name)


#: The report's pictures are drawn on at most this many processes.
MAX_DRAWING_PROCESSES = 4


def _draw_all(jobs: list[tuple[Callable[..., Any], tuple]],
              before: Callable[[], Any] | None = None) -> list[Any]:
    """Each job's result (`function(*arguments)`), in order. Drawn on a few forked
    processes when there are several CPUs and `cramlite.forking.fork_is_safe()` (a fork
    copies what `before()` imports, once), else here one after the other: the same
    pictures either way. The first job that fails stops the rest and raises here."""
    import multiprocessing

    from cramlite.forking import exit_with_parent, fork_is_safe, quiet_fork

    processes = min(os.cpu_count() or 1, MAX_DRAWING_PROCESSES, len(jobs))
    if processes < 2 or not fork_is_safe():
        return [function(*arguments) for function, arguments in jobs]
    from concurrent.futures import ProcessPoolExecutor

    if before is not None:
        before()
    # (a drawing process ends with this one, even killed: none is left behind)
    pool = ProcessPoolExecutor(processes, mp_context=multiprocessing.get_context("fork"),
                               initializer=exit_with_parent, initargs=(os.getpid(),))
    try:
        with quiet_fork():
            futures = [pool.submit(function, *arguments) for function, arguments in jobs]
        return [future.result() for future in futures]
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _replays(data: BenchFolder, page: PageData, media: Path, written: set[str],
             max_replays: int, speed: float, say: Callable[[str], None] | None) -> None:
    from cramlite.report.replays import ensure_replay, replay_name

    traced = [(r, data.trace(r)) for r in page.interest]
    traced = [(r, t) for r, t in traced if t is not None]
    if say and traced:
        say(f"report: {min(len(traced), max_replays)} replay animations (kept between builds)")
    drawn = []
    for k, (row, trace) in enumerate(traced):
        tid = trial_id(row)
        if k >= max_replays:
            page.replay_notes[tid] = (f"replay not drawn (the report draws at most "
                                      f"{max_replays}; raise --max-replays, or `cramlite "
                                      f"replay {trace} --out FILE.gif`)")
            continue
        drawn.append((tid, replay_name(tid, speed), trace))
    problems = _draw_all([(ensure_replay, (trace, media / file, speed))
                          for _, file, trace in drawn], _import_replays)
    for (tid, file, _), problem in zip(drawn, problems, strict=True):
        if problem:
            page.replay_notes[tid] = problem
        else:
            page.replays[tid] = file
            written.add(file)


def _import_replays() -> None:
    import cramlite.trace.replay  # noqa: F401


#: The names of the pictures a report draws (and so may remove again): a file of any
#: other name in the folder is not the report's, and stays.
REPORT_PICTURES = ("map-*.png", "timeline-*.png", "replay-*.gif", "*_by_setup.png",
                   "*_aggregated.png", "all_orders_base_path.png", "*.part", "*.part.*")


def _tidy(media: Path, written: set[str]) -> None:
    """Remove the pictures of earlier builds that this page does not show (only files
    named as the report names its pictures: a user's own files in the folder stay)."""
    for path in media.iterdir():
        if path.is_file() and path.name not in written and \
                any(fnmatch.fnmatch(path.name, pattern) for pattern in REPORT_PICTURES):
            path.unlink(missing_ok=True)


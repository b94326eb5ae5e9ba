"""Parameter recovery: simulate episodes with known parameters, fit them, compare.

The generating sets are drawn from the Table 3.4 grid; each is simulated on recorded
tasks (`simulate`) with several seeds and fitted by the grid search of `fit` (expected
APE, xy). A parameter counts as recovered when the fit's best value is within one grid
step (0.1) of the generating one; the plateau of equally good values is kept too.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cramlite.evaluation.data import Episode, parse_row
from cramlite.evaluation.fit import PARAM_NAMES, fit, source_grid
from cramlite.evaluation.options import DEFAULT_TEMPERATURE
from cramlite.evaluation.simulate import episode_row, simulate

STEP = 0.1 + 1e-9


@dataclass(frozen=True)
class Recovery:
    truth: dict[str, float]
    seed: int
    best: dict[str, float]
    plateau: dict[str, tuple[float, float]]

    def recovered(self, name: str) -> bool:
        return abs(self.best[name] - self.truth[name]) <= STEP

    def on_plateau(self, name: str) -> bool:
        lo, hi = self.plateau[name]
        return lo - STEP <= self.truth[name] <= hi + STEP


def recover_one(like: Sequence[Episode], truth: dict[str, float], episodes: int,
                temperature: float, seed: int) -> Recovery:
    drawn = simulate(like, episodes, "opm", truth, temperature, seed)
    # (through the published format, as `cramlite simulate` writes it and `fit` reads it)
    synthetic = [parse_row(episode_row(e)) for e in drawn]
    result = fit(synthetic, "opm", ("xy",), "expected-ape")
    _, index = result.best("xy")
    return Recovery(truth, seed, result.params(index), result.tied_best("xy"))


def recovery_study(like: Sequence[Episode], sets: int = 20, seeds: int = 3,
                   episodes: int | None = None, temperature: float = DEFAULT_TEMPERATURE,
                   draw_seed: int = 2026) -> list[Recovery]:
    """`sets` generating parameter sets from the grid (drawn with `draw_seed`), each
    simulated with seeds 0..seeds-1 (`episodes` each, default twice the recorded ones)."""
    grid = source_grid()
    picks = np.random.default_rng(draw_seed).choice(len(grid), size=min(sets, len(grid)),
                                                    replace=False)
    count = episodes or 2 * len(like)
    return [recover_one(like, dict(zip(PARAM_NAMES, map(float, grid[g]), strict=True)),
                        count, temperature, seed)
            for g in picks for seed in range(seeds)]


def recovery_table(runs: Sequence[Recovery]) -> list[dict[str, float | str]]:
    """Per parameter: share recovered within 0.1, share whose plateau holds the truth,
    mean plateau width."""
    return [{"parameter": name,
             "recovered": float(np.mean([r.recovered(name) for r in runs])),
             "on_plateau": float(np.mean([r.on_plateau(name) for r in runs])),
             "plateau_width": float(np.mean([r.plateau[name][1] - r.plateau[name][0]
                                             for r in runs]))}
            for name in PARAM_NAMES]

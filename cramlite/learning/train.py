"""`cramlite train`: fit one model on the episodes of a file, write the model file and a
training report (loss curves as PNG, next-item accuracies per split)."""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.errors import UserInputError
from cramlite.evaluation.data import Episode, load_episodes
from cramlite.learning.backend import cpt_class, versions
from cramlite.learning.encoding import (
    PER_ITEM,
    SPLIT_NAMES,
    Vocabulary,
    nn_arrays,
    rnn_arrays,
    split_episodes,
)
from cramlite.learning.modelfile import load_model, save_model
from cramlite.learning.models import (
    KINDS,
    History,
    TrainSettings,
    describe,
    train_nn,
    train_rnn,
)
from cramlite.learning.scoring import file_sha256


def parse_split(text: str) -> tuple[float, float, float]:
    """`0.7,0.15,0.15` -> fractions of train, validation, test (each > 0, sum 1)."""
    try:
        parts = tuple(float(p) for p in text.split(","))
    except ValueError:
        parts = ()
    if len(parts) != 3 or not all(0 < p < 1 for p in parts) or abs(sum(parts) - 1) > 1e-6:
        raise UserInputError(f"expected three fractions > 0 that sum to 1 (train,validation,"
                             f"test), got {text!r}", field="--split")
    return parts  # type: ignore[return-value]


def train_model(data: str | Path, kind: str, out: str | Path, seed: int = 0,
                split: Sequence[float] = (0.7, 0.15, 0.15), epochs: int = 300,
                ) -> dict[str, Any]:
    """Train, write `out` (the model) and `out`.report.json / `out`.loss.png; the report."""
    if kind not in KINDS:
        raise UserInputError(f"expected one of {', '.join(KINDS)}, got {kind!r}",
                             field="--model")
    out = Path(out)
    if out.is_dir():
        raise UserInputError("expected a model file path, got a folder", source=str(out),
                             field="--out")
    if kind == "cpt":
        cpt_class()  # fail now, with the install hint, if cpt is missing
    episodes, _ = load_episodes(data)
    ids = split_episodes(episodes, split, seed)
    parts = {name: [ep for ep in episodes if ep.id in set(ids[name])] for name in SPLIT_NAMES}
    for name in ("train", "validation"):
        if not parts[name]:
            raise UserInputError(f"the {name} split is empty ({len(episodes)} episodes); "
                                 "expected more episodes or larger fractions", source=str(data))
    vocab = Vocabulary.of(episodes)
    settings = TrainSettings(epochs=epochs, seed=seed)
    started = time.perf_counter()
    weights, sequences, history = _fit(kind, parts, vocab, settings)
    seconds = time.perf_counter() - started
    meta = {"kind": kind, "vocabulary": list(vocab.names), "features": _features(kind),
            "architecture": describe(kind),
            "split": {"fractions": list(split), "seed": seed, "ids": ids,
                      "stratified_by": "data source (letter prefix of the ID)"},
            "data": {"file": Path(data).name, "sha256": file_sha256(data),
                     "episodes": len(episodes)},
            "versions": versions(),
            "training": {"epochs_max": epochs, "epochs_run": len(history.loss),
                         "best_epoch": history.best_epoch, "seconds": round(seconds, 2),
                         "loss": history.loss, "val_loss": history.val_loss}}
    save_model(out, meta, weights, sequences)
    model = load_model(out)
    meta["training"]["accuracy"] = {name: accuracy(model, parts[name]) for name in SPLIT_NAMES}
    save_model(out, meta, weights, sequences)
    report = {"model": str(out), **{k: meta[k] for k in ("kind", "data", "training")},
              "split_sizes": {name: len(parts[name]) for name in SPLIT_NAMES},
              "vocabulary_size": len(vocab)}
    report_path = out.with_name(out.name + ".report.json")
    report["files"] = {"model": str(out), "report": str(report_path)}
    if history.loss and plot_losses(history, kind, out.with_name(out.name + ".loss.png")):
        report["files"]["loss_curves"] = str(out.with_name(out.name + ".loss.png"))
    report_path.write_text(json.dumps(report, indent=2))
    return report


def _fit(kind: str, parts: dict[str, list[Episode]], vocab: Vocabulary,
         settings: TrainSettings) -> tuple[list[np.ndarray], list[list[str]], History]:
    if kind == "cpt":
        return [], [list(ep.sequence) for ep in parts["train"]], History()
    if kind == "rnn":
        x, y, mask = rnn_arrays(parts["train"], vocab)
        validation = rnn_arrays(parts["validation"], vocab)
        weights, history = train_rnn(x, y, mask, validation, len(vocab), settings)
        return weights, [], history
    x, y = nn_arrays(parts["train"], vocab)
    validation = nn_arrays(parts["validation"], vocab)
    weights, history = train_nn(x, y, validation, len(vocab), settings)
    return weights, [], history


def _features(kind: str) -> dict[str, Any]:
    if kind == "nn":
        return {"per_item": list(PER_ITEM), "then": ["person x", "person y", "person z"],
                "k_c": "the OPM's best fit (strong 0.2, mid 0.3, food 1.2, c 1.7)"}
    return {"input": "the item sequence (a start token, then one item per step)"}


def accuracy(model, episodes: Sequence[Episode]) -> float | None:
    """Share of steps where the best-scored remaining item is the one taken."""
    from cramlite.evaluation.metrics import expected_ape
    from cramlite.learning.strategy import LearnedStrategy

    strategy = LearnedStrategy(model=model.source, rng=0)
    steps = sum(len(ep) - 1 for ep in episodes)
    if not steps:
        return None
    errors = sum(expected_ape(strategy, ep) for ep in episodes)
    return round(1.0 - errors / steps, 4)


def plot_losses(history: History, kind: str, path: Path) -> bool:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    fig, ax = plt.subplots(figsize=(6, 4))
    epochs = np.arange(1, len(history.loss) + 1)
    ax.plot(epochs, history.loss, label="training")
    ax.plot(epochs, history.val_loss, label="validation")
    ax.axvline(history.best_epoch, color="grey", linestyle="--",
               label=f"kept: epoch {history.best_epoch}")
    ax.set_xlabel("epoch")
    ax.set_ylabel("cross-entropy")
    ax.set_title(f"{kind.upper()} training")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True

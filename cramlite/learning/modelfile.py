"""Model files: one zip holding `model.json` (kind, vocabulary, features, split, the
training data's hash, library versions, training report) and the parameters as plain
arrays (`weights.npz`, read with allow_pickle=False) or, for CPT, the training sequences
(`sequences.json`, refitted on load). Loading never executes code from the file.
"""

from __future__ import annotations

import functools
import io
import json
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.errors import UserInputError
from cramlite.file_limits import check_size, checked_file
from cramlite.learning.encoding import Vocabulary, nn_features
from cramlite.learning.models import KINDS, CPTModel, NNModel, RNNModel
from cramlite.safe_json import parse_json
from cramlite.strategies.candidates import Candidate

FORMAT = "cramlite-model"
FORMAT_VERSION = 1


class ModelFileError(UserInputError):
    """A model file that is missing, corrupt or of another format."""


@dataclass
class LearnedModel:
    """A loaded model: its metadata and a scorer for the next item."""

    meta: dict[str, Any]
    net: RNNModel | NNModel | CPTModel
    source: str = ""

    @property
    def kind(self) -> str:
        return self.meta["kind"]

    @functools.cached_property
    def vocab(self) -> Vocabulary:
        return Vocabulary(tuple(self.meta["vocabulary"]))

    @functools.cached_property
    def index(self) -> dict[str, int]:
        return self.vocab.index()

    def scores(self, taken: Sequence[str], remaining: Sequence[Candidate],
               agent: Sequence[float], prime_only: bool = False) -> np.ndarray:
        """A score per vocabulary item for the next step (higher = more likely); `taken`
        and the names of `remaining` are vocabulary names."""
        if isinstance(self.net, RNNModel):
            return self.net.logits([self.index[n] for n in taken], prime_only)
        if isinstance(self.net, NNModel):
            return self.net.logits(nn_features(self.index, remaining, taken, agent))
        return self.net.scores(taken)

    def test_ids(self) -> list[str]:
        return list(self.meta["split"]["ids"]["test"])


def save_model(path: Path, meta: dict[str, Any], weights: Sequence[np.ndarray] = (),
               sequences: Sequence[Sequence[str]] = ()) -> None:
    meta = {"format": FORMAT, "format_version": FORMAT_VERSION, **meta}
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("model.json", json.dumps(meta, indent=2))
        if meta["kind"] == "cpt":
            archive.writestr("sequences.json", json.dumps([list(s) for s in sequences]))
        else:
            buffer = io.BytesIO()
            np.savez(buffer, *[np.asarray(w) for w in weights])
            archive.writestr("weights.npz", buffer.getvalue())


def load_model(path: str | Path) -> LearnedModel:
    """A model file, checked; the same file is loaded once per process."""
    path = Path(path)
    try:
        stat = path.stat()
    except OSError as exc:
        raise ModelFileError(f"cannot read model file ({exc.strerror})",
                             source=str(path)) from None
    if not path.is_file():
        raise ModelFileError("expected a model file, got a folder", source=str(path))
    checked_file(path, "model", ModelFileError)
    return _load(str(path.resolve()), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=16)
def _load(path: str, mtime_ns: int, size: int) -> LearnedModel:
    def fail(message: str, field: str | None = None) -> ModelFileError:
        return ModelFileError(message, source=path, field=field)

    try:
        with zipfile.ZipFile(path) as archive:
            for entry in archive.infolist():  # (before anything is extracted)
                check_size(entry.file_size, "model entry", f"{path}: {entry.filename}",
                           ModelFileError)
            names = set(archive.namelist())
            if "model.json" not in names:
                raise fail("not a cramlite model file (no model.json inside); expected a file "
                           "written by `cramlite train`")
            meta = parse_json(archive.read("model.json").decode("utf-8"))
            if not isinstance(meta, dict) or meta.get("format") != FORMAT:
                raise fail(f"expected {FORMAT!r}", "format")
            if meta.get("format_version") != FORMAT_VERSION:
                raise fail(f"expected version {FORMAT_VERSION}, got "
                           f"{meta.get('format_version')!r}: retrain with this cramlite",
                           "format_version")
            kind = meta.get("kind")
            if kind not in KINDS:
                raise fail(f"expected one of {', '.join(KINDS)}, got {kind!r}", "kind")
            vocab = meta.get("vocabulary")
            if not isinstance(vocab, list) or not vocab or \
                    not all(isinstance(v, str) for v in vocab):
                raise fail("expected a non-empty list of item names", "vocabulary")
            data = meta.get("data", {})
            if not isinstance(data, dict) or not isinstance(data.get("sha256", ""), str):
                raise fail("expected an object with the training file's name and sha256",
                           "data")
            split = meta.get("split", {"ids": {"test": []}})
            test = split.get("ids", {}).get("test") if isinstance(split, dict) and \
                isinstance(split.get("ids"), dict) else None
            if not isinstance(test, list) or not all(isinstance(i, str) for i in test):
                raise fail("expected the episode IDs of the split (ids.test: a list of IDs)",
                           "split")
            if kind == "cpt":
                sequences = parse_json(archive.read("sequences.json").decode("utf-8"))
                net: RNNModel | NNModel | CPTModel = CPTModel(sequences, vocab)
            else:
                with np.load(io.BytesIO(archive.read("weights.npz")),
                             allow_pickle=False) as data:
                    weights = [data[f"arr_{i}"] for i in range(len(data.files))]
                net = RNNModel(weights) if kind == "rnn" else NNModel(weights)
                _check_shapes(net, len(vocab), fail)
    except ModelFileError:
        raise
    except (zipfile.BadZipFile, KeyError, ValueError, OSError, EOFError) as exc:
        raise fail(f"corrupt or not a cramlite model file ({exc}); expected a file written "
                   "by `cramlite train`") from None
    return LearnedModel(meta, net, path)


def _check_shapes(net: RNNModel | NNModel, vocab_size: int, fail) -> None:
    out = net.out_bias if isinstance(net, RNNModel) else net.layers[-1][1]
    if out.shape != (vocab_size,):
        raise fail(f"the output layer has {out.shape} units for {vocab_size} items",
                   "weights.npz")

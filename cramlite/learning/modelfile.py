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
from cramlite.learning.encoding import FIRST_ITEM, PER_ITEM, Vocabulary, nn_features
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
            if type(meta.get("format_version")) is not int or \
                    meta.get("format_version") != FORMAT_VERSION:  # (true == 1)
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
                _check_sequences(sequences, vocab, fail)
                net: RNNModel | NNModel | CPTModel = CPTModel(sequences, vocab)
            else:
                with np.load(io.BytesIO(archive.read("weights.npz")),
                             allow_pickle=False) as data:
                    weights = [data[f"arr_{i}"] for i in range(len(data.files))]
                check = _check_rnn_weights if kind == "rnn" else _check_nn_weights
                check(weights, len(vocab), fail)
                net = RNNModel(weights) if kind == "rnn" else NNModel(weights)
    except ModelFileError:
        raise
    except (zipfile.BadZipFile, KeyError, ValueError, OSError, EOFError) as exc:
        raise fail(f"corrupt or not a cramlite model file ({exc}); expected a file written "
                   "by `cramlite train`") from None
    return LearnedModel(meta, net, path)


def _check_sequences(sequences: Any, vocab: Sequence[str], fail) -> None:
    """CPT's training sequences: a non-empty list of lists of vocabulary names."""
    known = set(vocab)
    if not isinstance(sequences, list) or not sequences or not all(
            isinstance(seq, list) and all(isinstance(n, str) and n in known for n in seq)
            for seq in sequences):
        raise fail("expected a non-empty list of sequences, each a list of the vocabulary's "
                   "item names", "sequences.json")


def _shaped(weights: Sequence[np.ndarray], shapes: Sequence[tuple[int | None, ...]],
            fail) -> None:
    """Each array numeric, finite and of its shape (None: any length on that axis)."""
    for i, (array, shape) in enumerate(zip(weights, shapes, strict=True)):
        if array.dtype.kind not in "fiu" or array.ndim != len(shape) or any(
                want is not None and got != want for got, want in zip(array.shape, shape,
                                                                      strict=True)):
            wanted = " x ".join("n" if n is None else str(n) for n in shape)
            raise fail(f"array {i} is {array.dtype} of shape {array.shape}; expected numbers "
                       f"of shape {wanted}", "weights.npz")
        if not np.all(np.isfinite(array)):
            raise fail(f"array {i} holds NaN or infinite numbers", "weights.npz")


def _check_rnn_weights(weights: Sequence[np.ndarray], vocab_size: int, fail) -> None:
    """The GRU's six arrays: embedding, kernel, recurrent kernel, biases, output layer."""
    if len(weights) != 6:
        raise fail(f"{len(weights)} arrays; expected the GRU's 6", "weights.npz")
    if weights[2].ndim != 2:
        raise fail("array 2 (the recurrent kernel) is not a matrix", "weights.npz")
    units, embed = weights[2].shape[0], weights[0].shape[-1] if weights[0].ndim else 0
    _shaped(weights, [(None, embed), (embed, 3 * units), (units, 3 * units), (2, 3 * units),
                      (units, vocab_size), (vocab_size,)], fail)
    if weights[0].shape[0] < vocab_size + FIRST_ITEM:
        raise fail(f"the embedding has {weights[0].shape[0]} rows for {vocab_size} items",
                   "weights.npz")


def _check_nn_weights(weights: Sequence[np.ndarray], vocab_size: int, fail) -> None:
    """The feed-forward network: kernel and bias per layer, each layer fed by the one
    before, the first by the context vector, the last giving a score per item."""
    if not weights or len(weights) % 2:
        raise fail(f"{len(weights)} arrays; expected a kernel and a bias per layer",
                   "weights.npz")
    inputs = vocab_size * len(PER_ITEM) + 3
    shapes: list[tuple[int | None, ...]] = []
    for i in range(0, len(weights), 2):
        last = i == len(weights) - 2
        width = vocab_size if last else (weights[i].shape[-1] if weights[i].ndim == 2 else -1)
        shapes += [(inputs, width), (width,)]
        inputs = width
    _shaped(weights, shapes, fail)



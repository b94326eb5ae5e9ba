"""The three learned models of thesis 3.3.4: how they are built and trained (keras 3 on jax,
`cpt`) and how they score the next item (numpy forward passes from the stored weights:
a decision in microseconds, no keras needed to run a model).

- RNN: embedding -> one GRU layer (hidden 100) -> decoder; Adam, cross-entropy; trained
  on whole episodes (start token, then each item predicts the next).
- NN: context features -> dense 512 -> dropout 0.5 -> dense 256 -> dropout 0.5 -> items;
  Adam, cross-entropy.
- CPT: CPT+ (Gueniche et al. 2015) from the `cpt` package, fitted on the training
  sequences; it ranks the items that follow similar training sequences.
Both networks stop early on the validation loss (patience 5, best weights kept).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cramlite.learning.encoding import FIRST_ITEM, START

KINDS = ("rnn", "nn", "cpt")
HIDDEN = 100
DENSE = (512, 256)
DROPOUT = 0.5
PATIENCE = 5


@dataclass
class TrainSettings:
    """What a training run may vary (the architecture is fixed by the thesis)."""

    epochs: int = 300
    batch_size: int = 16
    learning_rate: float = 0.005
    seed: int = 0


@dataclass
class History:
    loss: list[float] = field(default_factory=list)
    val_loss: list[float] = field(default_factory=list)
    best_epoch: int = 0


def _fit(keras, model, x, y, weights, validation, settings: TrainSettings) -> History:
    stop = keras.callbacks.EarlyStopping(monitor="val_loss", patience=PATIENCE,
                                         restore_best_weights=True)
    result = model.fit(x, y, sample_weight=weights, validation_data=validation,
                       epochs=settings.epochs, batch_size=settings.batch_size, shuffle=True,
                       callbacks=[stop], verbose=0)
    loss = [float(v) for v in result.history["loss"]]
    val = [float(v) for v in result.history["val_loss"]]
    return History(loss, val, int(np.argmin(val)) + 1 if val else 0)


def train_rnn(x: np.ndarray, y: np.ndarray, mask: np.ndarray, validation: tuple,
              vocab_size: int, settings: TrainSettings) -> tuple[list[np.ndarray], History]:
    """Weights [embedding, GRU kernel, recurrent kernel, bias, dense kernel, bias]."""
    from cramlite.learning.backend import keras as load_keras

    keras = load_keras()
    keras.utils.set_random_seed(settings.seed)
    layers = keras.layers
    inputs = keras.Input((None,), dtype="int32")
    hidden = layers.Embedding(vocab_size + FIRST_ITEM, HIDDEN, mask_zero=True)(inputs)
    hidden = layers.GRU(HIDDEN, return_sequences=True)(hidden)
    model = keras.Model(inputs, layers.Dense(vocab_size)(hidden))
    model.compile(optimizer=keras.optimizers.Adam(settings.learning_rate),
                  loss=keras.losses.SparseCategoricalCrossentropy(from_logits=True))
    history = _fit(keras, model, x, y, mask, validation, settings)
    return [np.asarray(w) for w in model.get_weights()], history


def train_nn(x: np.ndarray, y: np.ndarray, validation: tuple, vocab_size: int,
             settings: TrainSettings) -> tuple[list[np.ndarray], History]:
    """Weights [dense 512 kernel, bias, dense 256 kernel, bias, output kernel, bias]."""
    from cramlite.learning.backend import keras as load_keras

    keras = load_keras()
    keras.utils.set_random_seed(settings.seed)
    layers = keras.layers
    inputs = keras.Input((x.shape[1],))
    hidden = inputs
    for units in DENSE:
        hidden = layers.Dropout(DROPOUT)(layers.Dense(units, activation="relu")(hidden))
    model = keras.Model(inputs, layers.Dense(vocab_size)(hidden))
    model.compile(optimizer=keras.optimizers.Adam(settings.learning_rate / 5),
                  loss=keras.losses.SparseCategoricalCrossentropy(from_logits=True))
    history = _fit(keras, model, x, y, None, validation, settings)
    return [np.asarray(w) for w in model.get_weights()], history


def _sigmoid(v: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-v))


class RNNModel:
    """The GRU's forward pass in numpy (keras 3 GRU: gates z, r, h; reset after)."""

    def __init__(self, weights: Sequence[np.ndarray]):
        (self.embedding, self.kernel, self.recurrent, self.bias, self.out_kernel,
         self.out_bias) = (np.asarray(w, dtype=np.float64) for w in weights)
        self.units = self.recurrent.shape[0]

    def step(self, h: np.ndarray, token: int) -> np.ndarray:
        u = self.units
        x = self.embedding[token] @ self.kernel + self.bias[0]
        rec = h @ self.recurrent + self.bias[1]
        z = _sigmoid(x[:u] + rec[:u])
        r = _sigmoid(x[u:2 * u] + rec[u:2 * u])
        candidate = np.tanh(x[2 * u:] + r * rec[2 * u:])
        return z * h + (1.0 - z) * candidate

    def logits(self, history: Sequence[int], prime_only: bool = False) -> np.ndarray:
        """Next-item logits after the history (item indices). `prime_only`: from a fresh
        state primed with the previous item only (the thesis's protocol)."""
        tokens = [START] + [FIRST_ITEM + i for i in history]
        if prime_only:
            tokens = tokens[-1:]
        h = np.zeros(self.units)
        for token in tokens:
            h = self.step(h, token)
        return h @ self.out_kernel + self.out_bias


class NNModel:
    """The feed-forward network's forward pass in numpy (dropout is off at inference)."""

    def __init__(self, weights: Sequence[np.ndarray]):
        self.layers = [(np.asarray(weights[i], dtype=np.float64),
                        np.asarray(weights[i + 1], dtype=np.float64))
                       for i in range(0, len(weights), 2)]

    def logits(self, features: np.ndarray) -> np.ndarray:
        h = np.asarray(features, dtype=np.float64)
        for i, (kernel, bias) in enumerate(self.layers):
            h = h @ kernel + bias
            if i < len(self.layers) - 1:
                h = np.maximum(h, 0.0)
        return h


class CPTModel:
    """CPT+ over the training sequences (rebuilt from them when a model file loads)."""

    def __init__(self, sequences: Sequence[Sequence[str]], vocab: Sequence[str]):
        from cramlite.learning.backend import cpt_class

        self.sequences = [list(s) for s in sequences]
        self.vocab = list(vocab)
        self.index = {n: i for i, n in enumerate(self.vocab)}
        self.model = cpt_class()(split_length=0, noise_ratio=0, MBR=0)
        self.model.fit(self.sequences)

    def scores(self, history: Sequence[str]) -> np.ndarray:
        """A score per vocabulary item: higher for items CPT+ ranks first; -inf for items
        it does not rank after this prefix."""
        ranked = self.model.predict_k([list(history)], len(self.vocab),
                                      multithreading=False)[0]
        out = np.full(len(self.vocab), -np.inf)
        for rank, name in enumerate(ranked):
            if name in self.index:
                out[self.index[name]] = -float(rank)
        return out


def describe(kind: str) -> dict[str, Any]:
    """The architecture, for a model's metadata."""
    if kind == "rnn":
        return {"embedding": HIDDEN, "gru": HIDDEN, "decoder": "dense to items",
                "optimizer": "adam", "loss": "cross-entropy", "early_stopping": PATIENCE}
    if kind == "nn":
        return {"dense": list(DENSE), "dropout": DROPOUT, "optimizer": "adam",
                "loss": "cross-entropy", "early_stopping": PATIENCE}
    return {"algorithm": "CPT+", "split_length": 0, "noise_ratio": 0, "MBR": 0}

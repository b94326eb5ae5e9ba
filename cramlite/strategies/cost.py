"""The OPM's weighted cost C(p, q) (Eq. 3.1-3.3) in a chosen projection (3.3.2).

    power:    C = d ** k * c        (Eq. 3.1, the model)
    additive: C = d - k + c         (Eq. 3.2)
    product:  C = d * k * c         (Eq. 3.3)

d is the Euclidean distance over the projected axes, optionally with axis weights
w_a (Eq. 3.5/3.6): d = sqrt(sum_a w_a (p_a - q_a)^2). Eq. 3.1 is kept exact,
including its quirk that d ** k > d for d < 1 and k < 1.

`cost` is a plain-Python scalar path (fast for a handful of items); `costs` is the
vectorised numpy path (fast for many). Both compute the same numbers.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # numpy is imported where it is used: a few-item decision needs none
    import numpy as np

DIMS: dict[str, tuple[int, ...]] = {
    "x": (0,), "y": (1,), "z": (2,), "xy": (0, 1), "xz": (0, 2), "yz": (1, 2),
    "xyz": (0, 1, 2),
}
FORMS = ("power", "additive", "product")


def span_weights(points: Sequence[Sequence[float]]) -> tuple[float, float, float]:
    """Axis weights from the spans of the given points (Eq. 3.5): w_a = span_a / sum."""
    import numpy as np

    arr = np.asarray(points, dtype=float).reshape(-1, 3)
    spans = arr.max(axis=0) - arr.min(axis=0)
    total = float(spans.sum())
    if total <= 0:
        return (1 / 3, 1 / 3, 1 / 3)
    return tuple(float(s / total) for s in spans)  # type: ignore[return-value]


@dataclass(frozen=True)
class CostModel:
    """Distance projection, functional form and optional axis weights of the OPM."""

    dims: str = "xy"
    form: str = "power"
    axis_weights: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        if self.dims not in DIMS:
            raise ValueError(f"dims must be one of {', '.join(DIMS)}, got {self.dims!r}")
        if self.form not in FORMS:
            raise ValueError(f"form must be one of {', '.join(FORMS)}, got {self.form!r}")

    def distance(self, p: Sequence[float], q: Sequence[float]) -> float:
        w = self.axis_weights
        total = 0.0
        for a in DIMS[self.dims]:
            diff = p[a] - q[a]
            total += diff * diff if w is None else w[a] * diff * diff
        return math.sqrt(total)

    def cost(self, p: Sequence[float], q: Sequence[float], k: float, c: float) -> float:
        d = self.distance(p, q)
        if self.form == "power":
            return d**k * c
        if self.form == "additive":
            return d - k + c
        return d * k * c

    def costs(self, p: Sequence[float], q: np.ndarray, k: np.ndarray | float,
              c: np.ndarray | float) -> np.ndarray:
        """Costs from one point p to many points q (N x 3), vectorised."""
        import numpy as np

        idx = list(DIMS[self.dims])
        diff = np.asarray(q, dtype=float)[:, idx] - np.asarray(p, dtype=float)[idx]
        sq = diff * diff
        if self.axis_weights is not None:
            sq = sq * np.asarray(self.axis_weights, dtype=float)[idx]
        d = np.sqrt(sq.sum(axis=1))
        if self.form == "power":
            return np.power(d, k) * c
        if self.form == "additive":
            return d - k + c
        return d * k * c

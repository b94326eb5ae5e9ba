"""What a strategy chooses among: candidates, and the OPM's item parameters.

Pure data, no PyBullet: strategies must stay fast and testable alone.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

Position = tuple[float, float, float]
CATEGORIES = ("strong", "mid", "food", "none")


@dataclass(frozen=True)
class Candidate:
    """An item the agent may fetch next.

    `k` and `c` override what `category` and `contained` would give; `then_at` is where
    the agent will stand after delivering this item (e.g. its target), which strategies
    that look ahead need (if None they assume the agent stays at the item); `fetch_at` is
    where the agent stands when it takes the item (the 2-step model chooses its second
    item from there; if None, the item's own position).
    """

    name: str
    position: Position
    category: str = "none"
    contained: bool = False
    k: float | None = None
    c: float | None = None
    then_at: Position | None = None
    fetch_at: Position | None = None
    metadata: Mapping[str, Any] = field(default_factory=dict, compare=False, hash=False)

    def after_position(self) -> Position:
        return self.then_at if self.then_at is not None else self.position

    def fetch_position(self) -> Position:
        return self.fetch_at if self.fetch_at is not None else self.position


@dataclass(frozen=True)
class OPMParams:
    """Relational-dependency k per category and the containment factor c (SPEC section 1).

    Defaults are the source's best fit (3.3.4): strong 0.2, mid 0.3, food 1.2, c 1.7.
    """

    strong_k: float = 0.2
    mid_k: float = 0.3
    food_k: float = 1.2
    c: float = 1.7

    def k_of(self, candidate: Candidate) -> float:
        if candidate.k is not None:
            return candidate.k
        return {"strong": self.strong_k, "mid": self.mid_k, "food": self.food_k}.get(
            candidate.category, 1.0)

    def c_of(self, candidate: Candidate) -> float:
        if candidate.c is not None:
            return candidate.c
        return self.c if candidate.contained else 1.0

    @classmethod
    def names(cls) -> list[str]:
        return [f.name for f in fields(cls)]

    @classmethod
    def from_mapping(cls, values: Mapping[str, float] | None) -> OPMParams:
        """Build from a mapping; an unknown name raises KeyError naming it."""
        values = dict(values or {})
        unknown = sorted(set(values) - set(cls.names()))
        if unknown:
            raise KeyError(unknown[0])
        return cls(**{k: float(v) for k, v in values.items()})


def as_position(values: Sequence[float]) -> Position:
    x, y, z = (float(v) for v in values)
    return (x, y, z)

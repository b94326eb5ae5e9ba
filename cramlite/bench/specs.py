"""What a batch runs: one `TrialSpec` per trial, each with its own seed.

A trial's seed comes from the batch seed, the setup's name and the trial index (not from
the strategy, so trial i of every strategy is paired), through numpy's SeedSequence and
a CRC of the name, which are the same in every process and on every machine. Any trial
can be rerun alone with `cramlite run SETUP --strategy S --seed SEED`.
"""

from __future__ import annotations

import itertools
import zlib
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

FIXED_ORDER = "fixed-order"


def trial_seed(batch_seed: int, setup_name: str, trial: int) -> int:
    sequence = np.random.SeedSequence([batch_seed, zlib.crc32(setup_name.encode()), trial])
    return int(sequence.generate_state(1, dtype=np.uint32)[0])


@dataclass(frozen=True)
class TrialSpec:
    setup: str  #: setup name (as in the results)
    setup_path: str  #: file the worker loads
    strategy: str  #: strategy name, or "fixed-order" with `given_order`
    trial: int
    seed: int
    batch_seed: int
    plan: str = "set-table"
    given_order: tuple[str, ...] = ()
    #: Write the trial's trace (cramlite-trace/1) to this file ("" = no trace).
    trace: str = ""

    @property
    def key(self) -> tuple[str, ...]:
        """Identity of a trial in a results file (used to resume)."""
        return (self.setup, self.plan, self.strategy, " ".join(self.given_order),
                str(self.trial), str(self.batch_seed))

    def as_dict(self) -> dict:
        return asdict(self)


def make_specs(setups: dict[str, Path], strategies: list[str], trials: int, batch_seed: int,
               plan: str = "set-table", all_orders: dict[str, list[str]] | None = None,
               ) -> list[TrialSpec]:
    """Trials setup by setup; with `all_orders` (setup -> item names) every permutation of
    each setup's items is added as one fixed-order trial."""
    specs = []
    for name, path in setups.items():
        for trial in range(trials):
            seed = trial_seed(batch_seed, name, trial)
            specs.extend(TrialSpec(name, str(path), strategy, trial, seed, batch_seed, plan)
                         for strategy in strategies)
        if all_orders and name in all_orders:
            for index, order in enumerate(itertools.permutations(all_orders[name])):
                specs.append(TrialSpec(name, str(path), FIXED_ORDER, index,
                                       trial_seed(batch_seed, name, index), batch_seed, plan,
                                       tuple(order)))
    return specs

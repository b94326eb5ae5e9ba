"""What a batch runs: one `TrialSpec` per trial, each with its own seed.

A trial's seed comes from the batch seed, the setup's name and the trial index (not from
the strategy, so trial i of every strategy is paired), through numpy's SeedSequence and
a CRC of the name, which are the same in every process and on every machine. Any trial
can be rerun alone with `cramlite run SETUP --strategy S --seed SEED`.

A `BatchPlan` describes the whole batch and yields its specs one at a time, so that a
batch of a billion trials starts at once and holds only the trials in flight.
"""

from __future__ import annotations

import itertools
import math
import zlib
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

from cramlite.safe_names import inside, trial_stem

FIXED_ORDER = "fixed-order"


def trace_file(folder: str | Path, setup: str, plan: str, strategy: str, trial: int | str,
               backend: str = "") -> str:
    """Where a bench writes a trial's trace: `folder/SLUG-HASH.jsonl`, a name made safe
    from the setup, plan, strategy, index and backend (a strategy `learned:../nn.model`
    stays in the folder, and no two trials share a file)."""
    return str(inside(folder, trial_stem(setup, plan, strategy, trial, backend) + ".jsonl"))


def trial_seed(batch_seed: int, setup_name: str, trial: int) -> int:
    import numpy as np

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
    #: content hash of the setup (file and URDFs): the worker refuses a file that changed
    setup_hash: str = ""
    #: Write the trial's trace (cramlite-trace/2) to this file ("" = no trace).
    trace: str = ""
    #: What executes the trial (see cramlite.backends).
    backend: str = "pybullet"
    #: The hash of the code the names stand for: a plan file's, a learned model file's.
    code_hash: str = ""
    #: The folder the bench ran in: a plan or strategy file named relative to it loads
    #: from there in any worker (see `cramlite.plugins.absolute_reference`).
    cwd: str = ""
    #: Failures injected (`--inject`, canonical: cramlite.designators.injection); "" none.
    inject: str = ""
    #: How many items the plan carries at once (`--carry`, a plan option).
    carry: int = 1

    @property
    def key(self) -> tuple[str, ...]:
        """Identity of a trial in a results file (used to resume)."""
        return (self.setup, self.setup_hash, self.plan, self.strategy, self.code_hash,
                " ".join(self.given_order), self.backend, str(self.trial),
                str(self.batch_seed), self.inject, str(self.carry))

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class SetupEntry:
    path: str
    content_hash: str
    items: tuple[str, ...]  #: item names in baseline order (for all orders)


@dataclass(frozen=True)
class BatchPlan:
    """Setups x strategies x trials (plus, with `all_orders`, every permutation of each
    setup's items as one fixed-order trial), for one plan and batch seed."""

    setups: dict[str, SetupEntry]
    strategies: Sequence[str]
    trials: int
    batch_seed: int
    plan: str = "set-table"
    all_orders: bool = False
    #: Folder for the trials' traces ("" = no traces): see `trace_file`.
    trace_dir: str = ""
    #: What executes the trials: each trial runs on every one of them.
    backends: Sequence[str] = ("pybullet",)
    #: Strategy (or FIXED_ORDER) -> the hash of the code its trials run (see `code_hash`).
    code_hashes: dict[str, str] | None = None

    #: The folder relative names of plan and strategy files are resolved against.
    cwd: str = ""
    #: Failures injected into every trial (canonical `--inject` text; "" none).
    inject: str = ""
    #: How many items the plan carries at once: each trial runs with every one of them.
    carries: Sequence[int] = (1,)

    def code_hash(self, strategy: str) -> str:
        return (self.code_hashes or {}).get(strategy, "")

    def _trace(self, setup: str, strategy: str, trial: int, backend: str,
               carry: int = 1) -> str:
        if not self.trace_dir:
            return ""
        variant = "-".join(([backend] if len(self.backends) > 1 else []) +
                           ([f"carry{carry}"] if len(self.carries) > 1 else []))
        return trace_file(self.trace_dir, setup, self.plan, strategy, trial, variant)

    def total(self) -> int:
        per_setup = self.trials * len(self.strategies)
        orders = sum(math.factorial(len(s.items)) for s in self.setups.values()) \
            if self.all_orders else 0
        return (per_setup * len(self.setups) + orders) * len(self.backends) * \
            len(self.carries)

    def __iter__(self) -> Iterator[TrialSpec]:
        for name, entry in self.setups.items():
            for trial in range(self.trials):
                seed = trial_seed(self.batch_seed, name, trial)
                for strategy in self.strategies:
                    for backend, carry in itertools.product(self.backends, self.carries):
                        yield TrialSpec(name, entry.path, strategy, trial, seed,
                                        self.batch_seed, self.plan, (), entry.content_hash,
                                        self._trace(name, strategy, trial, backend, carry),
                                        backend, self.code_hash(strategy), self.cwd,
                                        self.inject, carry)
            if self.all_orders:
                for index, order in enumerate(itertools.permutations(entry.items)):
                    for backend, carry in itertools.product(self.backends, self.carries):
                        yield TrialSpec(name, entry.path, FIXED_ORDER, index,
                                        trial_seed(self.batch_seed, name, index),
                                        self.batch_seed, self.plan, tuple(order),
                                        entry.content_hash,
                                        self._trace(name, FIXED_ORDER, index, backend, carry),
                                        backend, self.code_hash(FIXED_ORDER), self.cwd,
                                        self.inject, carry)

    def contains(self, key: Sequence[str]) -> bool:
        """Whether a results row's key (see `TrialSpec.key`) is one of this batch's trials."""
        setup, setup_hash, plan, strategy, code, given, backend, trial, batch_seed, inject, \
            carry = key
        entry = self.setups.get(setup)
        if entry is None or entry.content_hash != setup_hash or plan != self.plan \
                or inject != self.inject or carry not in {str(c) for c in self.carries} \
                or code != self.code_hash(strategy) \
                or batch_seed != str(self.batch_seed) or not trial.isdigit() \
                or backend not in self.backends:
            return False
        if strategy == FIXED_ORDER:
            return (self.all_orders and int(trial) < math.factorial(len(entry.items))
                    and sorted(given.split()) == sorted(entry.items))
        return strategy in self.strategies and not given and int(trial) < self.trials

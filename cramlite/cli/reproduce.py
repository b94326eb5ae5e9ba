"""`cramlite reproduce`: every table the README claims, rebuilt, beside the published ones."""

from __future__ import annotations

import argparse
import sys

from cramlite.cli.common import (
    EXIT_OK,
    comma_list,
    command_help,
    episodes_int,
    epochs_int,
    repeats_int,
    seed_int,
    whole_number,
    writable_folder,
)


def cmd_reproduce(args: argparse.Namespace) -> int:
    import time

    from cramlite.errors import UserInputError
    from cramlite.reproduce import Options, reproduce, write_page
    from cramlite.world.setup import load_setup

    out = writable_folder(args.out)
    setups = comma_list(args.setups)
    if not setups:
        raise UserInputError("expected comma-separated setups, got nothing", field="--setups")
    for setup in setups:
        load_setup(setup)  # (a bad name or file is one line now, not after the fit)
    options = Options(out=out, episodes=args.episodes, setups=setups, epochs=args.epochs,
                      recovery_sets=args.recovery_sets, recovery_seeds=args.recovery_seeds,
                      repeats=args.repeats, seed=args.seed)
    started = time.perf_counter()
    sections = reproduce(options, say=lambda text: print(text, file=sys.stderr, flush=True))
    md, page = write_page(sections, out)
    print(f"rebuilt {len(sections)} sections in {time.perf_counter() - started:.0f} s")
    print(f"wrote {md}")
    print(f"wrote {page}")
    return EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("reproduce", help=command_help("reproduce"),
                       description="Rebuilds every table the README claims from scratch "
                                   "(the OPM's fit, Tables 4.2-4.4, the learned models on "
                                   "three activities with an ablation, parameter recovery), "
                                   "training included, into OUT/reproduce.md and .html.")
    p.add_argument("--out", default="reproduce",
                   help="folder for the page and the models (default reproduce)")
    p.add_argument("--episodes", type=episodes_int,
                   help="at most this many episodes of each data set (a quick look)")
    p.add_argument("--setups", default="v1,v2,v3,v4,v5", help="robot setups (default v1-v5)")
    p.add_argument("--epochs", type=epochs_int, default=300,
                   help="most training epochs (early stopping; default 300)")
    p.add_argument("--recovery-sets", type=whole_number(1, 10_000), default=20,
                   help="generating parameter sets of the recovery (default 20)")
    p.add_argument("--recovery-seeds", type=whole_number(1, 100), default=3,
                   help="seeds per generating set (default 3)")
    p.add_argument("--repeats", type=repeats_int, default=100,
                   help="repeats of random choices (default 100)")
    p.add_argument("--seed", type=seed_int, default=0, help="random seed")
    p.set_defaults(func=cmd_reproduce)

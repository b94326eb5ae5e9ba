"""`cramlite train` and `cramlite compare`: learned ordering strategies (thesis 3.3.4)."""

from __future__ import annotations

import argparse

from cramlite.cli.common import (
    EXIT_OK,
    comma_list,
    command_help,
    epochs_int,
    progress_bar,
    repeats_int,
    seed_int,
    strategy_checked,
    writable_file,
    writable_folder,
)
from cramlite.cli.evaluation import add_protocol_argument, quiet_broken_pipe
from cramlite.errors import UserInputError
from cramlite.evaluation.options import METRICS
from cramlite.strategies.base import StrategyError

MODEL_KINDS = ("cpt", "rnn", "nn")


def _data_path(text: str) -> str:
    from cramlite.resources import resolve_data_path

    return str(resolve_data_path(text))


def cmd_train(args: argparse.Namespace) -> int:
    import json

    from cramlite.learning.train import parse_split, train_model

    split = parse_split(args.split)
    writable_file(args.out, "--out")
    report = train_model(_data_path(args.data), args.model, args.out, seed=args.seed,
                         split=split, epochs=args.epochs)
    with quiet_broken_pipe():
        if args.json:
            print(json.dumps(report))
            return EXIT_OK
        training = report["training"]
        sizes = report["split_sizes"]
        print(f"{args.model} trained on {sizes['train']} episodes (validation "
              f"{sizes['validation']}, test {sizes['test']}) in {training['seconds']:.1f} s"
              + (f", {training['epochs_run']} epochs (best {training['best_epoch']})"
                 if training["epochs_run"] else ""))
        for split_name, value in training["accuracy"].items():
            if value is not None:
                print(f"  next-item accuracy ({split_name}): {value:.3f}")
        if not sizes["test"]:
            print(f"  warning: the test split is empty: `evaluate` and `compare` cannot score "
                  f"this model on {args.data} under --protocol heldout")
        for kind, path in report["files"].items():
            print(f"wrote {kind}: {path}")
    return EXIT_OK


def cmd_compare(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    from cramlite.evaluation.data import load_episodes
    from cramlite.learning.compare import compare, plot_distributions
    from cramlite.learning.scoring import file_sha256

    strategies = comma_list(args.strategies)
    if len(strategies) < 2:
        raise UserInputError(f"expected at least two comma-separated strategies, got "
                             f"{args.strategies!r}", field="--strategies")
    twice = sorted({n for n in strategies if strategies.count(n) > 1})
    if twice:
        raise UserInputError(f"{', '.join(twice)} named twice; expected different strategies "
                             "to compare", field="--strategies")
    for name in strategies:
        strategy_checked(name)
    out = writable_folder(args.out) if args.out else None
    data = _data_path(args.data)
    episodes, _ = load_episodes(data)
    with progress_bar(len(episodes) * len(strategies), "compare") as bar:
        try:
            result = compare(episodes, strategies, args.metric, args.protocol, args.repeats,
                             args.seed, data_sha256=file_sha256(data), progress=bar.update)
        except StrategyError as exc:  # a plugin that raises or returns a non-candidate
            raise UserInputError(str(exc), field="--strategies") from None
        except ValueError as exc:
            raise UserInputError(str(exc), field="--metric") from None
    summary = result["summary"]
    from cramlite.evaluation.published import published_ape

    for name, row in summary["strategies"].items():
        row["published"] = published_ape(args.data, name, args.metric, args.protocol)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        summary["files"] = {"summary": str(out / "compare.json")}
        figure = out / "error_distributions.png"
        if plot_distributions(result["table"], args.metric,
                              f"{Path(data).name}, protocol {args.protocol}, "
                              f"{summary['episodes']} episodes", figure):
            summary["files"]["figure"] = str(figure)
        (out / "compare.json").write_text(json.dumps(summary, indent=2))
    with quiet_broken_pipe():
        if args.json:
            print(json.dumps(summary))
            return EXIT_OK
        print(f"{summary['episodes']} episodes, metric {args.metric}, protocol {args.protocol}")
        first = strategies[0]
        for name, row in summary["strategies"].items():
            test = summary["wilcoxon_vs_first"].get(name)
            versus = "" if test is None else (
                f"   vs {first}: Wilcoxon W = {test['statistic']}, p = {test['p']:.3g}")
            thesis = "" if row["published"] is None else f" (thesis {row['published']:.2f})"
            if row["mean"] is None:  # (no episode every strategy could score)
                print(f"  {name}: no episode scored{thesis}")
                continue
            print(f"  {name}: mean {row['mean']:.3f}{thesis}, median {row['median']:.3f}"
                  f"{versus}")
        for kind, path in summary.get("files", {}).items():
            print(f"wrote {kind}: {path}")
    return EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    train = sub.add_parser("train", help=command_help("train"),
                           description="Trains on the episodes of a file in the published "
                                       "format; writes MODEL, MODEL.report.json and (the "
                                       "RNN and NN, trained by epochs) MODEL.loss.png. Needs "
                                       "the learn extra.")
    train.add_argument("data", help="CSV of recorded sequences, or a shipped set: table-setting, "
                                    "cooking, clearing-up, all")
    train.add_argument("--model", required=True, choices=MODEL_KINDS,
                       help="cpt: CPT+; rnn: GRU on item sequences; nn: context network")
    train.add_argument("--out", required=True, help="the model file to write")
    train.add_argument("--seed", type=seed_int, default=0,
                       help="seed of the split and of training (default 0)")
    train.add_argument("--split", default="0.7,0.15,0.15",
                       help="train,validation,test fractions of the episodes (default "
                            "0.7,0.15,0.15; stratified by data source)")
    train.add_argument("--epochs", type=epochs_int, default=300,
                       help="most epochs (early stopping on validation loss, patience 5)")
    train.add_argument("--json", action="store_true", help="print the report as JSON")
    train.set_defaults(func=cmd_train)

    cmp = sub.add_parser("compare", help=command_help("compare"))
    cmp.add_argument("data", help="CSV of recorded sequences, or a shipped set: table-setting, "
                                    "cooking, clearing-up, all")
    cmp.add_argument("--strategies", required=True,
                     help="comma-separated, the first is the reference of the tests, e.g. "
                          "opm,learned:rnn.model,learned:nn.model,learned:cpt.model")
    cmp.add_argument("--metric", default="ape", choices=METRICS,
                     help="ape (default), expected-ape, edit, edit-unrestricted")
    add_protocol_argument(cmp)
    cmp.add_argument("--repeats", type=repeats_int, default=100,
                     help="repeats of random choices (default 100)")
    cmp.add_argument("--seed", type=seed_int, default=0, help="random seed")
    cmp.add_argument("--out", help="folder for compare.json and error_distributions.png")
    cmp.add_argument("--json", action="store_true", help="print one JSON object")
    cmp.set_defaults(func=cmd_compare)

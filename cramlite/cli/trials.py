"""`cramlite show` and `cramlite run`: one setup, one world."""

from __future__ import annotations

import argparse

from cramlite.cli.common import (
    EXIT_OK,
    EXIT_PLAN_FAILED,
    non_negative_int,
    parse_params,
    strategy_checked,
)
from cramlite.errors import UserInputError
from cramlite.plan_names import PLAN_NAMES
from cramlite.strategies.cost import DIMS


def cmd_show(args: argparse.Namespace) -> int:
    from cramlite.world import World, load_setup
    from cramlite.world.render import render, save_png

    setup = load_setup(args.setup)
    out = args.out or f"{setup.name}.png"
    with World.from_setup(setup) as world:
        path = save_png(render(world, args.width, args.height), out)
    print(f"wrote {path} ({setup.name}: {len(setup.items)} items)")
    return EXIT_OK




def cmd_run(args: argparse.Namespace) -> int:
    import json

    from cramlite.trial import TrialRunner
    from cramlite.world import load_setup

    params = parse_params(args.params)
    strategy_checked(args.strategy, params=params, dims=args.dims)
    setup = load_setup(args.setup)
    try:
        runner = TrialRunner(setup, gui=args.gui)
    except RuntimeError as exc:  # no display for --gui
        raise UserInputError(str(exc), field="--gui") from None
    with runner:
        result = runner.run(args.strategy, args.plan, args.seed, params=params, dims=args.dims,
                            trace=args.trace)
        if args.image:
            from cramlite.world.render import render, save_png

            save_png(render(runner.world), args.image)
    if args.json:
        data = result.as_dict()
        if not args.log:
            data.pop("log")
        print(json.dumps(data))
    else:
        status = "success" if result.success else "FAILED"
        print(f"{result.setup} {result.plan} with {result.strategy} (seed {result.seed}): {status}")
        print(f"  order: {', '.join(result.order)}")
        print(f"  driven base path {result.base_path_m:.2f} m, straight-line legs "
              f"{result.straight_line_m:.2f} m")
        print(f"  robot time {result.robot_time_s:.2f} s = wall {result.wall_s:.2f} s + driving "
              f"{result.drive_s:.2f} s + arm {result.arm_s:.2f} s "
              f"({result.planned_arm_motions} of {result.arm_motions} arm motions planned "
              "around obstacles)")
        if args.trace:
            print(f"  trace: {args.trace}")
        for failure in result.failures:
            print(f"  failure: {failure['type']}: {failure['message']}")
        if args.log:
            for line in result.log:
                print(f"  log: {line}")
    return EXIT_OK if result.success else EXIT_PLAN_FAILED




def register(sub: argparse._SubParsersAction) -> None:
    show = sub.add_parser("show", help="draw a setup headless into a PNG")
    show.add_argument("setup", help="v1..v5 or a path to a setup YAML file")
    show.add_argument("--out", help="PNG file to write (default: SETUPNAME.png)")
    show.add_argument("--width", type=int, default=1024, help="image width in pixels")
    show.add_argument("--height", type=int, default=768, help="image height in pixels")
    show.set_defaults(func=cmd_show)

    run = sub.add_parser("run", help="run one trial of a plan in a setup (headless)",
                         description="Exit code 0: success, 1: the plan failed, 2: bad input.")
    run.add_argument("setup", help="v1..v5, another shipped setup, or a path to a setup file")
    run.add_argument("--plan", default="set-table", choices=PLAN_NAMES, help="which plan")
    run.add_argument("--strategy", default="baseline",
                     help="ordering strategy (see `cramlite strategies`; default baseline)")
    run.add_argument("--params", help="strategy parameters, e.g. mid_k=0.3,c=1.7")
    run.add_argument("--dims", default="xy", choices=list(DIMS), help="strategy projection")
    run.add_argument("--seed", type=non_negative_int, default=0, help="random seed")
    run.add_argument("--gui", action="store_true", help="show the PyBullet GUI (needs a display)")
    run.add_argument("--json", action="store_true", help="print one JSON object")
    run.add_argument("--log", action="store_true", help="also print what the plan did")
    run.add_argument("--image", help="write a PNG of the scene after the trial")
    run.add_argument("--trace", help="write every executed state to this JSON Lines file "
                                     "(cramlite-trace/1; `cramlite replay` shows it)")
    run.set_defaults(func=cmd_run)

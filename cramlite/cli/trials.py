"""`cramlite show` and `cramlite run`: one setup, one world."""

from __future__ import annotations

import argparse
import sys

from cramlite.cli.common import (
    BACKEND_HELP,
    CARRY_HELP,
    EXIT_OK,
    EXIT_PLAN_FAILED,
    INJECT_HELP,
    carry_int,
    chosen_backend,
    command_help,
    image_path,
    int_in_range,
    parse_params,
    seed_int,
    strategy_checked,
    writable_file,
)
from cramlite.errors import UserInputError
from cramlite.plan_names import PLAN_HELP
from cramlite.strategies.cost import DIMS

#: Largest image side `show` renders (either renderer takes about a second per megapixel
#: or ten).
MAX_IMAGE_SIDE = 4096


def _save_image(image, path: str, option: str) -> str:
    from cramlite.render import save_image

    try:
        return str(save_image(image, path))
    except (OSError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        raise UserInputError(f"cannot write the image ({reason})", source=path,
                             field=option) from None


def cmd_show(args: argparse.Namespace) -> int:
    from cramlite.scene.scene import PlanningScene
    from cramlite.scene.validate import check_setup, reach_problems
    from cramlite.world import load_setup

    setup = load_setup(args.setup)
    out = args.out or f"{setup.name}{'-top' if args.top else ''}.png"
    writable_file(out, "--out", [("setup file", setup.source)])
    scene = PlanningScene(setup)
    check_setup(scene)
    for problem in reach_problems(scene):  # (a run will fail there; the setup is valid)
        print(f"cramlite show: warning: {setup.source}: {problem}", file=sys.stderr)
    if args.top:
        return _show_top(setup, args, out)
    from cramlite.render import draw_setup

    backend = chosen_backend(args.backend)
    path = _save_image(draw_setup(setup, args.width, args.height, backend), out, "--out")
    print(f"wrote {path} ({setup.name}: {len(setup.items)} items; drawn as the {backend} "
          "backend draws)")
    return EXIT_OK


def _show_top(setup, args: argparse.Namespace, out: str) -> int:
    """`show --top`: the top-down map (matplotlib)."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise UserInputError("the top-down map needs matplotlib: pip install "
                             "'cramlite[plots]'", field="--top") from None
    from cramlite.world.topdown import save_top_view

    try:
        path = save_top_view(setup, out, args.width, args.height)
    except (OSError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        raise UserInputError(f"cannot write the image ({reason})", source=out,
                             field="--out") from None
    print(f"wrote {path} ({setup.name} from above: {len(setup.items)} items, their targets "
          "and the robot's start)")
    return EXIT_OK


def _order(text: str | None, setup, strategy: str) -> list[str] | None:
    """--order A,B,...: every item of the setup once, for the baseline strategy."""
    if text is None:
        return None
    order = [name.strip() for name in text.split(",") if name.strip()]
    names = [spec.name for spec in setup.items]
    if strategy != "baseline":
        raise UserInputError(f"--order is for --strategy baseline, got {strategy!r}",
                             field="--order")
    if sorted(order) != sorted(names):
        raise UserInputError(f"expected each item of {setup.name} once ({', '.join(names)}), "
                             f"got {', '.join(order) or 'nothing'}", field="--order")
    return order


def cmd_run(args: argparse.Namespace) -> int:
    import json

    from cramlite.plan_registry import PlanCrashed, plan_function
    from cramlite.strategies import StrategyError
    from cramlite.trial import TrialRunner
    from cramlite.world import load_setup

    params = parse_params(args.params)
    strategy_checked(args.strategy, params=params, dims=args.dims)
    plan_function(args.plan)  # (a plan that cannot load: one line, exit 2)
    setup = load_setup(args.setup)
    order = _order(args.order, setup, args.strategy)
    from cramlite.designators.injection import parse_inject

    inject = parse_inject(args.inject)
    from cramlite.plugins import code_file

    inputs = [("setup file", setup.source), ("plan file", code_file(args.plan)),
              ("strategy file", code_file(args.strategy))]
    for path, option in ((args.trace, "--trace"), (args.image, "--image")):
        if path:
            writable_file(path, option, inputs)
    from cramlite.designators.context import ExecutionOptions

    options = ExecutionOptions(keep_containers_open=args.keep_open)
    backend = chosen_backend(args.backend)
    try:
        runner = TrialRunner(setup, gui=args.gui, options=options, backend=backend)
    except RuntimeError as exc:  # no display for --gui
        raise UserInputError(str(exc), field="--gui") from None
    with runner:
        try:
            result = runner.run(args.strategy, args.plan, args.seed, params=params,
                                dims=args.dims, trace=args.trace, order=order,
                                inject=inject, carry=args.carry)
        except StrategyError as exc:  # e.g. optimal with too many items, a broken plugin
            raise UserInputError(str(exc), field="--strategy") from None
        except PlanCrashed as exc:  # a bug in the user's plan: where it is, in one line
            raise UserInputError(str(exc), field="--plan") from None
        if args.image:
            _save_image(_final_image(runner, backend), args.image, "--image")
    if args.json:
        data = result.as_dict()
        if not args.log:
            data.pop("log")
        print(json.dumps(data))
    else:
        status = "success" if result.success else "FAILED"
        print(f"{result.setup} {result.plan} with {result.strategy} (seed {result.seed}) on "
              f"{result.backend}: {status}")
        from cramlite.plan_registry import is_builtin

        failed = {f.get("item") for f in result.failures}
        if is_builtin(result.plan):  # (a user's plan puts items where it wants them)
            failed |= {name for name, item in result.items.items() if not item.get("ok", True)}
        delivered = [n for n in result.order if n not in failed]
        missed = [n for n in result.order if n in failed]
        print(f"  order: {', '.join(delivered) or '(nothing delivered)'}"
              + (f"; tried and failed: {', '.join(missed)}" if missed else ""))
        if result.carry > 1:
            print(f"  carrying up to {result.carry} at once: {len(result.trips)} trips ("
                  + "; ".join(" + ".join(trip) for trip in result.trips) + ")"
                  + ("; no trip carried more than one item (a plan option: the plan "
                     "decides)" if all(len(trip) < 2 for trip in result.trips) else ""))
        legs = (f"{result.straight_line_m:.2f} m" if result.straight_line_m is not None
                else "not reported by the plan (PlanReport.add_leg)")
        print(f"  driven base path {result.base_path_m:.2f} m, straight-line legs {legs}")
        together = (f", {result.parallel_s:.2f} s of them at once"
                    if result.parallel_s else "")
        print(f"  robot time {result.robot_time_s:.2f} s (driving {result.drive_s:.2f} s, arm "
              f"{result.arm_s:.2f} s{together}; {result.planned_arm_motions} of "
              f"{result.arm_motions} arm motions planned around obstacles); computing "
              f"{result.wall_s:.2f} s")
        if result.open_close_s:
            print(f"  opening and closing drawers and doors took {result.open_close_s:.2f} s of "
                  "that")
        if inject:
            injected = ", ".join(f"{k} {n}" for k, n in sorted(result.injected.items()))
            print(f"  injected failures: {injected or 'none drawn'}"
                  + ("; every one recovered" if result.injected and result.success else ""))
        if args.trace:
            print(f"  trace: {args.trace}")
        for failure in result.failures:
            print(f"  failure: {failure['type']}: {failure['message']}")
        if args.log:
            for line in result.log:
                print(f"  log: {line}")
    return EXIT_OK if result.success else EXIT_PLAN_FAILED


def _final_image(runner, backend: str):
    """A picture of the world after the trial (as the backend draws)."""
    from cramlite.render import SHOW_CAMERA, camera, scene_image, uses_pybullet

    if uses_pybullet(backend):
        from cramlite.backends.pybullet.render import render

        return render(runner.world)
    runner.scene.observe(runner.modules)
    return scene_image(runner.scene, 1024, 768, camera(SHOW_CAMERA, SHOW_CAMERA))


def _setup_help() -> str:
    from cramlite.resources import worlds_dir

    shipped = sorted(p.stem for p in (worlds_dir() / "setups").glob("*.yaml"))
    return f"a shipped setup ({', '.join(shipped)}) or a path to a setup YAML file"


def cmd_plans(args: argparse.Namespace) -> int:
    from cramlite.plan_registry import available_plans

    for name, summary in available_plans().items():
        print(f"{name:16s} {summary}")
    print(f"{'MODULE:FUNCTION':16s} a plan of yours: package.module:function or "
          "path/to/file.py:function (see examples/)")
    return EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    setup_help = _setup_help()
    side = int_in_range(1, f"a whole number of pixels in [1, {MAX_IMAGE_SIDE}]", MAX_IMAGE_SIDE)
    show = sub.add_parser("show", help=command_help("show"),
                          description="Loads and checks a setup (every mistake is reported as "
                                      "FILE: FIELD: what was expected, exit code 2) and draws "
                                      "it headless (PyBullet's TinyRenderer for the pybullet "
                                      "backend, MuJoCo's offscreen renderer for mujoco, "
                                      "cramlite's own renderer for the others): "
                                      "each item labelled, each target marked (red square) "
                                      "and the robot's start (blue ring). --top draws the "
                                      "kitchen from above instead (matplotlib).")
    show.add_argument("setup", metavar="SETUP", help=setup_help)
    show.add_argument("--out", type=image_path,
                      help="image file to write: .png (default SETUPNAME.png, with --top "
                           "SETUPNAME-top.png), .jpg, .bmp, .tif")
    show.add_argument("--width", type=side, default=1024,
                      help=f"image width in pixels, 1-{MAX_IMAGE_SIDE} (default 1024)")
    show.add_argument("--height", type=side, default=768,
                      help=f"image height in pixels, 1-{MAX_IMAGE_SIDE} (default 768)")
    show.add_argument("--backend", help=BACKEND_HELP)
    show.add_argument("--top", action="store_true",
                      help="draw the top-down map instead: furniture, drawers and cupboard, "
                           "the robot's start, each item's start spot and target, labelled "
                           "(needs matplotlib: pip install 'cramlite[plots]')")
    show.set_defaults(func=cmd_show)

    run = sub.add_parser("run", help=command_help("run"),
                         description="Runs one trial headless and reports the order, the "
                                     "driven and straight-line distances and the times. Exit "
                                     "code 0: success, 1: the plan failed, 2: bad input.")
    run.add_argument("setup", metavar="SETUP", help=setup_help)
    run.add_argument("--plan", default="set-table", help=PLAN_HELP)
    run.add_argument("--strategy", default="baseline",
                     help="ordering strategy: a name from `cramlite strategies` or "
                          "package.module:Class (default baseline)")
    run.add_argument("--params",
                     help="strategy parameters, e.g. strong_k=0.2,mid_k=0.3,food_k=1.2,c=1.7 "
                          "(k in [0, 10], c in (0, 1000]; defaults: the source's best fit)")
    run.add_argument("--dims", default="xy", choices=list(DIMS),
                     help="projection the strategy measures distance in (default xy)")
    run.add_argument("--seed", type=seed_int, default=0,
                     help="random seed of the trial (default 0)")
    run.add_argument("--order", metavar="A,B,...",
                     help="with --strategy baseline: fetch in this order instead of the "
                          "setup's baseline_order (a bench's fixed-order trial, rerun)")
    run.add_argument("--keep-open", action="store_true",
                     help="leave the drawers and doors the robot opens open until the plan "
                          "ends (default: each is closed as soon as its item is out or in)")
    run.add_argument("--backend", help=BACKEND_HELP)
    run.add_argument("--inject", metavar="KIND=P,...", help=INJECT_HELP)
    run.add_argument("--carry", type=carry_int, default=1, help=CARRY_HELP)
    run.add_argument("--gui", action="store_true",
                     help="show the PyBullet GUI (the pybullet backend; needs a display)")
    run.add_argument("--json", action="store_true", help="print one JSON object")
    run.add_argument("--log", action="store_true", help="also print what the plan did")
    run.add_argument("--image", type=image_path,
                     help="write an image of the scene after the trial (.png, .jpg, ...)")
    run.add_argument("--trace", help="write every executed state to this JSON Lines file "
                                     "(cramlite-trace/2; `cramlite replay` shows it)")
    run.set_defaults(func=cmd_run)

    plans = sub.add_parser(
        "plans", help=command_help("plans"),
        description="Lists the plans: the built-in ones and those that installed packages "
                    "register under the entry-point group cramlite.plans. `run` and `bench` "
                    "also take --plan package.module:function or path/to/file.py:function.")
    plans.set_defaults(func=cmd_plans)

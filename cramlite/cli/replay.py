"""`cramlite replay`: a trace as an animated GIF, in the GUI, or checked for collisions."""

from __future__ import annotations

import argparse
import sys

from cramlite.cli.common import (
    BACKEND_HELP,
    EXIT_OK,
    EXIT_PLAN_FAILED,
    Parser,
    chosen_backend,
    command_help,
    float_in_range,
    int_in_range,
    writable_file,
)
from cramlite.errors import UserInputError
from cramlite.render.camera_modes import CAMERA_MODES

MAX_SIDE_PX = 4096


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


#: A GIF's width or height in pixels.
image_side = int_in_range(16, f"a whole number of pixels from 16 to {MAX_SIDE_PX}",
                          MAX_SIDE_PX)


def cmd_replay(args: argparse.Namespace) -> int:
    from cramlite.trace import read_trace
    from cramlite.trace.format import TraceError

    trace = read_trace(args.trace)
    try:
        return _replay(args, trace)
    except TraceError as exc:  # (found while checking: the file is named here)
        if exc.source:
            raise
        raise TraceError(exc.detail, source=args.trace, field=exc.field) from None


def _replay(args: argparse.Namespace, trace) -> int:
    if not (args.out or args.gui or args.check):
        raise UserInputError("say what to do: --out FILE.gif, --gui or --check", field="--out")
    if args.out and not args.out.lower().endswith(".gif"):
        raise UserInputError(f"expected a file name ending in .gif, got {args.out!r}",
                             field="--out")
    if args.out:
        writable_file(args.out, "--out")
    backend = chosen_backend(args.backend)
    if args.gui and backend != "pybullet":
        raise UserInputError(f"the {backend} backend has no GUI; expected --backend pybullet "
                             "with --gui", field="--gui")
    status = EXIT_OK
    if args.check:
        from cramlite.trace.physics import physics_findings
        from cramlite.trace.replay import penetrations

        found = penetrations(trace, tolerance_m=args.tolerance_cm / 100)
        for item in found:
            print(f"inside: {item.describe()}")
        print(f"checked {len(trace.states)} states of {args.trace} and the motion between "
              f"them: {'nothing' if not found else len(found)} penetrating deeper than "
              f"{args.tolerance_cm:g} cm")
        physics = physics_findings(trace)
        for finding in physics:
            print(f"not physical: {finding.describe()}")
        print(f"physics (fingers against what they hold, held items within the fingers' "
              f"reach and a hand's payload, upright items, base and joint speeds and "
              f"accelerations, items moving only in a hand, with their drawer or falling, "
              f"yaw at the targets, items standing on something, the trace whole): "
              f"{'nothing' if not physics else len(physics)} found")
        status = EXIT_PLAN_FAILED if found or physics else EXIT_OK
    if args.out:
        from cramlite.trace.replay import frame_count, render_gif

        total = frame_count(trace.duration_s, args.fps, args.speed)
        from tqdm import tqdm

        with tqdm(total=total, desc="frames", disable=not sys.stderr.isatty(),
                  leave=False) as bar:
            frames = render_gif(trace, args.out, args.fps, args.speed, args.width, args.height,
                                progress=bar.update, backend=backend, camera=args.camera)
        print(f"wrote {args.out}: {frames} frames, {trace.duration_s:.1f} s of robot time at "
              f"{args.fps:g} fps, speed x{args.speed:g} (drawn as the {backend} backend "
              "draws)")
    if args.gui:
        from cramlite.trace.replay import replay_gui

        try:
            replay_gui(trace, args.speed)
        except RuntimeError as exc:  # no display
            raise UserInputError(str(exc), field="--gui") from None
    return status


def register(sub: argparse._SubParsersAction) -> None:
    replay: Parser = sub.add_parser(
        "replay", help=command_help("replay"),
        description="Exit code 0: done (and, with --check, nothing inside anything and "
                    "nothing physically impossible), 1: --check found a penetration or a "
                    "physics finding, 2: bad input (a malformed trace names its line).")
    replay.add_argument("trace", help="a trace file written by `cramlite run --trace` or "
                                      "`cramlite bench --traces`")
    replay.add_argument("--out", help="write an animated GIF here (headless)")
    replay.add_argument("--backend", help="whose renderer draws the GIF (and whose window "
                                          "--gui opens): " + BACKEND_HELP)
    replay.add_argument("--fps", default=10.0,
                        type=float_in_range(0, 120, "frames per second > 0 and <= 120",
                                            open_minimum=True),
                        help="frames per second of the GIF as it plays (default 10); with "
                             "--speed S a frame shows S/fps s of robot time")
    replay.add_argument("--speed", default=1.0,
                        type=float_in_range(0.01, 1000, "a speed-up from 0.01 to 1000"),
                        help="play this many times faster than the robot moved (default 1)")
    replay.add_argument("--width", type=image_side, default=480, help="GIF width (default 480)")
    replay.add_argument("--height", type=image_side, default=360,
                        help="GIF height (default 360)")
    replay.add_argument("--camera", default="fixed", choices=CAMERA_MODES,
                        help="fixed: the kitchen from above its south end (default); top: "
                             "straight down on the whole kitchen; follow: behind and above "
                             "the robot, looking where it works")
    replay.add_argument("--gui", action="store_true",
                        help="play it in the PyBullet window (needs a display)")
    replay.add_argument("--check", action="store_true",
                        help="re-check every state and the motion between them: no robot "
                             "link inside the kitchen, an item or the robot itself, no held "
                             "or standing item inside the kitchen or another item (the real "
                             "meshes; independent of the planner's check); and physics: "
                             "fingertips at most 2 mm inside what they hold, a held item "
                             "within 3 cm of its gripper and at most 1.8 kg, upright items "
                             "within their tilt, base speeds and accelerations within the "
                             "header's limits, each joint's speed within its velocity limit "
                             "and its acceleration within that limit reached in 0.25 s, "
                             "items moving only in a hand, with their drawer or by falling, "
                             "items at their targets within 10 degrees of yaw, every item "
                             "out of the hand standing on something, the trace not cut "
                             "short (its end marked)")
    replay.add_argument("--tolerance-cm", default=1.0,
                        type=float_in_range(0, 100, "centimetres > 0 and <= 100",
                                            open_minimum=True),
                        help="penetration allowed by --check (default 1 cm)")
    replay.set_defaults(func=cmd_replay)

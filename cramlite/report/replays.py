"""Replay animations of traced trials for the report (GIFs beside the page, kept between
builds: one is drawn again only when its trace is newer)."""

from __future__ import annotations

import os
from pathlib import Path

from cramlite.errors import UserInputError

#: Quick to draw: a replay of a 90 s trial is ~55 frames, ~3-5 s to draw; large enough to
#: see the items, the camera following the robot (into the drawer it opens).
FPS = 5.0
WIDTH, HEIGHT = 560, 420
DEFAULT_SPEED = 8.0
CAMERA = "follow"


def replay_name(trial: str, speed: float) -> str:
    return f"replay-{trial}-x{speed:g}.gif"


def ensure_replay(trace: Path, out: Path, speed: float = DEFAULT_SPEED) -> str:
    """Draw the trace into `out` unless an up-to-date one is there; returns "" or why it
    could not be drawn (a malformed trace, a setup that is gone)."""
    if out.exists() and out.stat().st_size > 0 and out.stat().st_mtime >= trace.stat().st_mtime:
        return ""
    from cramlite.trace import read_trace
    from cramlite.trace.replay import render_gif

    partial = out.with_name(out.stem + ".part.gif")
    try:
        render_gif(read_trace(trace), partial, fps=FPS, speed=speed, width=WIDTH,
                   height=HEIGHT, camera=CAMERA)
    except UserInputError as exc:
        partial.unlink(missing_ok=True)
        return f"replay not drawn: {exc}"
    os.replace(partial, out)
    return ""

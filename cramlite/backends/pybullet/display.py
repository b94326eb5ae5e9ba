"""Whether PyBullet's GUI can reach an X display, asked before PyBullet connects: where it
cannot, PyBullet prints "cannot connect to X server" and ends the whole process from C
(exit code 1, which reads as "the plan failed"), so the command line checks first and says
why in its own one line.

Only X on Linux is checked (what PyBullet's GUI uses there): `DISPLAY` set, and for a local
display (`:N`, `unix:N`) a server listening on its socket, for a remote one (`host:N`) on
TCP port 6000 + N.
"""

from __future__ import annotations

import os
import re
import socket
import sys
from collections.abc import Mapping

#: How long a remote display may take to accept a connection (s).
CONNECT_TIMEOUT_S = 2.0

_DISPLAY = re.compile(r"^(?P<host>[^:]*):(?P<number>\d+)(\.\d+)?$")


def display_problem(environ: Mapping[str, str] | None = None) -> str | None:
    """Why the GUI cannot open a window here (one line), or None if an X server answers
    (or the platform is not Linux, where PyBullet reports its own problems)."""
    env = os.environ if environ is None else environ
    if not sys.platform.startswith("linux"):
        return None
    display = env.get("DISPLAY", "")
    if not display:
        return "the GUI needs a display, and DISPLAY is not set"
    match = _DISPLAY.match(display)
    if match is None:
        return None  # (a form this check does not know: PyBullet tries it)
    host, number = match["host"], int(match["number"])
    if host in ("", "unix"):
        path = f"/tmp/.X11-unix/X{number}"
        for address in (path, "\0" + path):  # (the file, then Linux's abstract socket)
            if _answers(socket.AF_UNIX, address):
                return None
        return f"no X server answers on display {display!r} (DISPLAY; its socket {path})"
    if _answers(socket.AF_INET, (host, 6000 + number)):
        return None
    return f"no X server answers on display {display!r} (DISPLAY; {host}, port {6000 + number})"


def _answers(family: int, address) -> bool:
    try:
        with socket.socket(family, socket.SOCK_STREAM) as connection:
            connection.settimeout(CONNECT_TIMEOUT_S)
            connection.connect(address)
        return True
    except OSError:
        return False

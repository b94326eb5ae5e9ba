"""--gui where no X server answers: one line and exit 2, before PyBullet connects (it
printed "cannot connect to X server" and ended the process with exit code 1, the code of a
failed plan)."""

from __future__ import annotations

import os
import socket
import sys
import uuid

import pytest

from cramlite.backends.pybullet.display import display_problem
from tests.conftest import ROOT

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="the X display is checked on Linux only")


def _free_display_number() -> int:
    """A display number with no socket of any X server."""
    number = 90 + uuid.uuid4().int % 900
    while os.path.exists(f"/tmp/.X11-unix/X{number}"):
        number += 1
    return number


@linux_only
def test_no_display_and_a_display_nobody_serves_are_named() -> None:
    assert display_problem({}) == "the GUI needs a display, and DISPLAY is not set"
    number = _free_display_number()
    assert f"no X server answers on display ':{number}'" in display_problem(
        {"DISPLAY": f":{number}"})
    assert "port 6000" in display_problem({"DISPLAY": "nohost.invalid:0"})


@linux_only
def test_a_display_whose_socket_answers_passes(tmp_path) -> None:
    """A server listening on the display's socket (the file, or Linux's abstract socket
    of the same name): nothing to say."""
    number = _free_display_number()
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        server.bind(f"\0/tmp/.X11-unix/X{number}")  # (abstract: no file left behind)
        server.listen(1)
        assert display_problem({"DISPLAY": f":{number}.0"}) is None
    finally:
        server.close()
    assert display_problem({"DISPLAY": f":{number}"}) is not None


@linux_only
@pytest.mark.parametrize("command", [["run", "v1"]])
def test_gui_with_a_display_nobody_serves_is_one_line_and_exit_2(command) -> None:
    pytest.importorskip("pybullet", reason="the GUI is PyBullet's")
    import subprocess

    number = _free_display_number()
    done = subprocess.run([sys.executable, "-m", "cramlite", *command, "--gui"],
                          capture_output=True, text=True, cwd=ROOT, timeout=120,
                          env={**os.environ, "DISPLAY": f":{number}"})
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.strip().splitlines() == [
        f"cramlite {command[0]}: error: --gui: no X server answers on display ':{number}' "
        f"(DISPLAY; its socket /tmp/.X11-unix/X{number})"], done.stderr

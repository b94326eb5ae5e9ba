"""The trace format `cramlite-trace/2`: every executed state of a trial, JSON Lines.

Line 1 is a header:
    {"format": "cramlite-trace/2", "setup": <name or absolute path load_setup accepts>,
     "plan": ..., "strategy": ..., "seed": ..., "joints": [PR2 joint names, order of "q"],
     "world_joints": [the world's movable joints, order of "w"],
     "backend": what executed it, "cramlite": the version that wrote it,
     "robot": {"urdf": path, "sha256": ..., "joint_limits": {name: [lower, upper,
               velocity]}}, "setup_hash": the setup's content hash (a replay of a setup
     changed since is refused)}
then one line per executed state, in order:
    {"t": robot time since the plan started (s, non-decreasing), "base": [x, y, yaw],
     "q": [...], "w": [...], "held": {object: arm},
     "objects": {name: [x, y, z, qx, qy, qz, qw]},
     "action": {"name": "PickUpAction", "object": "cup"} or null}
Every state lists the same objects. A header with `"end_marked": true` promises that a
whole trace ends with its last state written once more with `"end": true` (the trial ran
to its end: a trace whose writer was interrupted, or which lost its last lines, has no
such state; `replay --check` says so). Readers that know neither key read the extra state
as the same state written twice, which moves nothing.

`joints` lists the joints cramlite moves (torso, both arms, every finger joint of both
grippers); the others keep their default. `t` is the robot's own time. `cramlite-trace/1`
(the same without `backend`, `cramlite` and `robot`) is read too. Reading validates every
line and names the one at fault.
"""

from __future__ import annotations

import contextlib
import json
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from cramlite.errors import UserInputError
from cramlite.file_limits import checked_file
from cramlite.safe_json import JSONInputError, parse_json

TRACE_FORMAT = "cramlite-trace/2"
#: The formats read (a /1 trace still replays and checks).
READ_FORMATS = ("cramlite-trace/1", TRACE_FORMAT)
HEADER_KEYS = ("format", "setup", "plan", "strategy", "seed", "joints", "world_joints")
#: What /2 adds to the header (optional on reading: /1 has none of them).
HEADER_KEYS_2 = ("backend", "cramlite", "robot", "base_limits", "setup_hash")
STATE_KEYS = ("t", "base", "q", "w", "held", "objects", "action")
#: The arms that can hold an object in a trace (the PR2's).
HELD_BY = ("left", "right")
#: The header's promise that a whole trace ends with a state marked `"end": true`.
END_MARKED = "end_marked"
DIGITS = 6


class TraceError(UserInputError):
    """A trace file that is missing or malformed (names the line)."""


class TraceWriteError(UserInputError):
    """The trace file cannot be written (a full disk, a read-only folder): names it."""


class TraceWriter:
    """Writes a trace line by line (the header first); a failed write raises
    TraceWriteError naming the file and the reason."""

    def __init__(self, path: str | Path, header: dict[str, Any]):
        missing = [k for k in HEADER_KEYS if k not in header and k != "format"]
        if missing:
            raise ValueError(f"trace header misses {missing}")
        self.path = Path(path)
        self.joints = list(header["joints"])
        self.world_joints = list(header["world_joints"])
        self._handle: IO[str] | None = None
        with self._reporting():
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._handle = self.path.open("w", encoding="utf-8")
        self._write({"format": TRACE_FORMAT, **{k: header[k] for k in HEADER_KEYS[1:]},
                     **{k: header[k] for k in HEADER_KEYS_2 if k in header},
                     END_MARKED: True})
        self.states = 0
        self.last_t = 0.0
        self._last: dict[str, Any] | None = None

    @contextlib.contextmanager
    def _reporting(self) -> Iterator[None]:
        try:
            yield
        except OSError as exc:
            handle, self._handle = self._handle, None
            if handle is not None:
                with contextlib.suppress(OSError):
                    handle.close()
            raise TraceWriteError(f"cannot write the trace ({exc.strerror or exc})",
                                  source=str(self.path), field="--trace") from None

    def _write(self, record: dict[str, Any]) -> None:
        assert self._handle is not None, "trace already closed"
        with self._reporting():
            self._handle.write(json.dumps(record, separators=(",", ":"), allow_nan=False)
                               + "\n")

    def write_state(self, t: float, base: Sequence[float], q: Sequence[float],
                    w: Sequence[float], held: dict[str, str],
                    objects: dict[str, Sequence[float]],
                    action: tuple[str, str | None] | None,
                    parallel: Sequence[str] | None = None) -> None:
        """One state; `parallel`: what moved at once into it ("base" and joint names)."""
        record = {
            "t": round(t, DIGITS), "base": [round(v, DIGITS) for v in base],
            "q": [round(v, DIGITS) for v in q], "w": [round(v, DIGITS) for v in w],
            "held": dict(held),
            "objects": {n: [round(v, DIGITS) for v in pose] for n, pose in objects.items()},
            "action": None if action is None else {"name": action[0], "object": action[1]}}
        if parallel:
            record["parallel"] = list(parallel)
        self._write(record)
        self.states += 1
        self.last_t = t
        self._last = record

    def close(self, complete: bool = True) -> None:
        """Close the file; `complete`: what was to be traced ran to its end, marked by the
        last state written once more with `"end": true` (not after an interruption or a
        crash: the trace then reads as cut short, which it is)."""
        if self._handle is not None:
            if complete and self._last is not None:
                still = {k: v for k, v in self._last.items() if k != "parallel"}
                self._write({**still, "end": True})
            with self._reporting():
                self._handle.close()
            self._handle = None


@dataclass(frozen=True)
class Trace:
    header: dict[str, Any]
    states: list[dict[str, Any]]

    @property
    def cut_short(self) -> bool:
        """Its header promises an end mark, and its last state is not one."""
        return bool(self.header.get(END_MARKED)) and not self.states[-1].get("end")

    @property
    def duration_s(self) -> float:
        return float(self.states[-1]["t"]) if self.states else 0.0


def _numbers(value: Any, n: int | None) -> bool:
    return (isinstance(value, list) and (n is None or len(value) == n)
            and all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                    for v in value))


def read_trace(path: str | Path) -> Trace:
    """Read and validate a trace; a problem raises TraceError naming the line."""
    path = Path(path)
    src = str(path)
    checked_file(path, "trace", TraceError)
    try:
        handle = path.open(encoding="utf-8")
    except OSError as exc:
        raise TraceError(f"cannot read trace ({exc.strerror})", source=src) from None
    header: dict[str, Any] | None = None
    states: list[dict[str, Any]] = []
    last_t = -math.inf
    with handle:
        try:
            for number, line in enumerate(handle, start=1):
                where = f"line {number}"

                def fail(message: str, where: str = where) -> TraceError:
                    return TraceError(message, source=src, field=where)

                if not line.strip():
                    raise fail("empty line; expected one JSON object per line")
                try:
                    record = parse_json(line)
                except JSONInputError as exc:
                    raise fail(str(exc)) from None
                if not isinstance(record, dict):
                    raise fail("expected a JSON object")
                if header is None:
                    header = _check_header(record, fail)
                    continue
                _check_state(record, header, fail)
                if states and states[-1].get("end"):
                    raise fail("a state after the trace's end (the state marked \"end\": "
                               "true); expected the end last")
                missing = [n for n in states[0]["objects"] if n not in record["objects"]] \
                    if states else []
                if missing:  # (one the first lacks is judged against the setup's items)
                    raise fail(f"objects: {', '.join(missing)} missing (every state lists "
                               f"the objects of the first: "
                               f"{', '.join(states[0]['objects'])})")
                if record["t"] < last_t:
                    raise fail(f"t = {record['t']} goes back in time (previous {last_t}); "
                               "expected non-decreasing robot time")
                last_t = record["t"]
                states.append(record)
        except UnicodeDecodeError:
            raise TraceError("not UTF-8 text; expected JSON Lines", source=src) from None
    if header is None:
        raise TraceError(f"empty file; expected a {TRACE_FORMAT} header line", source=src)
    if not states:  # (a trace is written with the robot's first state: this one was cut)
        raise TraceError("no states after the header; expected at least the robot's state "
                         "at t = 0 (a trace cut short?)", source=src, field="line 2")
    return Trace(header, states)


def _check_header(record: dict[str, Any], fail) -> dict[str, Any]:
    if record.get("format") not in READ_FORMATS:
        raise fail(f"expected a header with \"format\": \"{TRACE_FORMAT}\" (or "
                   f"\"{READ_FORMATS[0]}\"), got {json.dumps(record.get('format'))}")
    missing = [k for k in HEADER_KEYS if k not in record]
    if missing:
        raise fail(f"header misses {', '.join(missing)}")
    if not isinstance(record["setup"], str) or not record["setup"]:
        raise fail("header field setup: expected a setup name or path")
    for key in ("joints", "world_joints"):
        value = record[key]
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise fail(f"header field {key}: expected a list of joint names")
        if len(set(value)) != len(value):
            twice = next(v for v in value if value.count(v) > 1)
            raise fail(f"header field {key}: {twice!r} is listed twice")
    _check_header_2(record, fail)
    return record


def _limit(value: Any) -> bool:
    """A joint limit entry's number: finite, or null (none: a continuous joint)."""
    return value is None or (isinstance(value, int | float) and not isinstance(value, bool)
                             and math.isfinite(value))


def _check_header_2(record: dict[str, Any], fail) -> None:
    """What /2 adds, where given: the robot's joint limits and the base's limits."""
    robot = record.get("robot")
    if robot is not None:
        limits = robot.get("joint_limits", {}) if isinstance(robot, dict) else None
        if not isinstance(limits, dict) or not all(
                isinstance(v, list) and 2 <= len(v) <= 3 and all(_limit(x) for x in v)
                for v in limits.values()):
            raise fail("header field robot: expected {\"urdf\": ..., \"joint_limits\": "
                       "{name: [lower, upper, velocity]}} (numbers, or null for none)")
    if END_MARKED in record and not isinstance(record[END_MARKED], bool):
        raise fail(f"header field {END_MARKED}: expected true or false, got "
                   f"{json.dumps(record[END_MARKED])[:40]}")
    digest = record.get("setup_hash")
    if digest is not None and not (isinstance(digest, str) and 0 < len(digest) <= 64):
        raise fail("header field setup_hash: expected the setup's content hash (text)")
    base = record.get("base_limits")
    if base is not None:
        keys = ("speed_m_s", "turn_rad_s", "accel_m_s2", "turn_accel_rad_s2")
        if not isinstance(base, dict) or not all(
                k in keys and isinstance(v, int | float) and not isinstance(v, bool)
                and math.isfinite(v) and v > 0 for k, v in base.items()):
            raise fail(f"header field base_limits: expected {{name: number > 0}} with names "
                       f"among {', '.join(keys)}")


def _check_state(record: dict[str, Any], header: dict[str, Any], fail) -> None:
    missing = [k for k in STATE_KEYS if k not in record]
    if missing:
        raise fail(f"state misses {', '.join(missing)}; expected {', '.join(STATE_KEYS)}")
    t = record["t"]
    if not (isinstance(t, int | float) and not isinstance(t, bool) and math.isfinite(t)
            and t >= 0):
        raise fail(f"t: expected a time >= 0 in seconds, got {json.dumps(t)}")
    if not _numbers(record["base"], 3):
        raise fail("base: expected [x, y, yaw]")
    if not _numbers(record["q"], len(header["joints"])):
        raise fail(f"q: expected {len(header['joints'])} numbers (the header's joints)")
    if not _numbers(record["w"], len(header["world_joints"])):
        raise fail(f"w: expected {len(header['world_joints'])} numbers (the header's "
                   "world_joints)")
    objects = record["objects"]
    if not isinstance(objects, dict) or not all(_numbers(v, 7) for v in objects.values()):
        raise fail("objects: expected {name: [x, y, z, qx, qy, qz, qw]}")
    held = record["held"]
    if not isinstance(held, dict) or not all(v in HELD_BY for v in held.values()):
        raise fail(f"held: expected {{object: arm}} with arm {' or '.join(HELD_BY)}, got "
                   f"{json.dumps(held)[:60]}")
    unknown = [name for name in held if name not in objects]
    if unknown:
        raise fail(f"held: {unknown[0]!r} is not one of the state's objects")
    if "end" in record and record["end"] is not True:
        raise fail(f"end: expected true (the trace's last state) or no end, got "
                   f"{json.dumps(record['end'])[:40]}")
    action = record["action"]
    if action is not None and not (
            isinstance(action, dict) and isinstance(action.get("name"), str)
            and (action.get("object") is None or isinstance(action.get("object"), str))):
        raise fail("action: expected null or {\"name\": text, \"object\": text or null}")


def trace_setup(trace: Trace) -> Any:
    """The setup a trace was written in, loaded as its header names it; TraceError if it
    cannot be loaded or has changed since (its content hash, where the header has one:
    checking a trace against another scene than the one it ran in would find what was
    never there, or miss what was)."""
    from cramlite.errors import UserInputError
    from cramlite.world.setup import load_setup

    try:
        setup = load_setup(trace.header["setup"])
    except UserInputError as exc:
        raise TraceError(f"header field setup: {exc}", field="line 1") from None
    recorded = trace.header.get("setup_hash")
    if recorded and setup.content_hash != recorded:
        raise TraceError(f"the setup {trace.header['setup']!r} has changed since this trace was "
                         f"written (content hash {recorded}, now {setup.content_hash}); "
                         "expected the setup files as they were", field="line 1")
    return setup

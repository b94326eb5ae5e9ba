"""Setup files: a world, the robot's start pose, the items and where they go.

A setup is YAML (see worlds/setups/v1.yaml, commented); this module parses and
validates it without touching PyBullet, so that every mistake is reported with the
file, the field and what was expected: unknown keys, numbers that are not finite or
ordinary-sized, names that could not be part of a file name, item URDFs that are not
well-formed or have non-positive sizes. Geometry checks (an item inside another body or
off its surface, a target in the air, two targets on one spot, the robot outside the
kitchen or inside furniture) happen when a `World` loads the setup.
"""

from __future__ import annotations

import hashlib
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from cramlite.errors import SetupError
from cramlite.resources import worlds_dir
from cramlite.world.item_types import item_type_file
from cramlite.world.strict_yaml import describe_yaml_error, load_strict
from cramlite.world.urdf_check import urdf_problem

#: Relational-dependency categories of the OPM (SPEC section 1); "none" means k = 1.
CATEGORIES = ("strong", "mid", "food", "none")
SETUP_FORMAT = 1

ITEM_KEYS = {"name", "type", "pose", "surface", "in", "contained", "category", "target",
             "aliases"}
TOP_KEYS = {"format", "name", "description", "world", "robot", "items", "baseline_order"}
ROBOT_KEYS = {"start"}
#: Setup and item names end up in file names and in space-separated CSV columns.
NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.+-]{0,63}")
NAME_RULE = ("1-64 letters, digits, '_', '.', '+' or '-', starting with a letter or digit "
             "(names become file names)")
MAX_SETUP_BYTES = 1024 * 1024
MAX_ITEMS = 100
#: Poses are metres in a room-sized world, yaw in radians.
MAX_ABS_POSITION_M = 1000.0
MAX_ABS_YAW = 2 * math.pi + 1e-6


def builtin_setup_names() -> list[str]:
    return sorted(p.stem for p in (worlds_dir() / "setups").glob("*.yaml"))


@dataclass(frozen=True)
class Pose:
    """A pose on a surface: position (z = bottom face of the item) and yaw in radians."""

    x: float
    y: float
    z: float
    yaw: float = 0.0

    @property
    def xyz(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.z)


@dataclass(frozen=True)
class ItemSpec:
    name: str
    type: str
    urdf: Path
    pose: Pose
    surface: str  #: the link it stands on (for an item in a container: the container's)
    target: Pose
    contained: bool = False
    category: str = "none"
    #: Other names of the item (a learned strategy maps `breakfast-cereal` to `cereal`).
    aliases: tuple[str, ...] = ()
    #: The closed container (drawer, cupboard) it is stored in, if any (`in:` in the file).
    container: str | None = None


@dataclass(frozen=True)
class RobotStart:
    x: float
    y: float
    yaw: float


@dataclass(frozen=True)
class Setup:
    """A validated setup file."""

    name: str
    source: Path
    world_urdf: Path
    robot_start: RobotStart
    items: tuple[ItemSpec, ...]
    baseline_order: tuple[str, ...]
    description: str = ""
    raw: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)
    #: SHA-256 (hex, 16 characters) of the setup file and every URDF it uses: two setups
    #: with the same hash give the same trials.
    content_hash: str = ""

    def item(self, name: str) -> ItemSpec:
        for spec in self.items:
            if spec.name == name:
                return spec
        raise KeyError(name)


def resolve_setup_path(setup: str | Path) -> Path:
    """`v1`..`v5` (or any shipped setup name) or a path to a YAML file. A bare name is a
    shipped setup's first; anything written as a path (`./v1`, `dir/v1`) is that file."""
    text = str(setup)
    if isinstance(setup, str) and text and "/" not in text and "\\" not in text:
        shipped = worlds_dir() / "setups" / f"{text}.yaml"
        if shipped.is_file():
            return shipped
    path = Path(text)
    if path.exists():
        return path
    raise SetupError(
        f"no such setup file; expected a path or one of {', '.join(builtin_setup_names())}",
        source=text,
    )


def load_setup(setup: str | Path) -> Setup:
    """Read and validate a setup file (by shipped name or path)."""
    path = resolve_setup_path(setup)
    src = str(path)
    try:
        if not path.is_file():
            raise SetupError("not a file; expected a setup YAML file", source=src)
        if path.stat().st_size > MAX_SETUP_BYTES:
            raise SetupError(f"larger than {MAX_SETUP_BYTES} bytes; expected a setup file",
                             source=src)
        content = path.read_bytes()
        data = load_strict(content.decode("utf-8"))
    except yaml.YAMLError as exc:
        message, where = describe_yaml_error(exc, expected="a YAML mapping")
        raise SetupError(message, source=src, field=where) from None
    except UnicodeDecodeError:
        raise SetupError("not UTF-8 text; expected a setup YAML file", source=src) from None
    except OSError as exc:
        raise SetupError(f"cannot read file ({exc.strerror or exc.__class__.__name__})",
                         source=src) from None
    except (ValueError, RecursionError) as exc:  # e.g. an integer of 5,000 digits
        raise SetupError(f"unusable YAML ({str(exc) or type(exc).__name__})",
                         source=src) from None
    setup = parse_setup(data, path)
    digest = hashlib.sha256(content)
    for urdf in (setup.world_urdf, *(item.urdf for item in setup.items)):
        digest.update(urdf.read_bytes())
        sidecar = item_type_file(urdf)  # (an item's type file: upright, grasps)
        if urdf != setup.world_urdf and sidecar.is_file():
            digest.update(sidecar.read_bytes())
    return _replace(setup, content_hash=digest.hexdigest()[:16])


def _replace(setup: Setup, **changes: Any) -> Setup:
    from dataclasses import replace

    return replace(setup, **changes)


def parse_setup(data: Any, path: Path) -> Setup:
    src = str(path)

    def fail(fld: str, msg: str) -> SetupError:
        return SetupError(msg, source=src, field=fld)

    if not isinstance(data, dict):
        raise fail("(top level)", f"expected a mapping with keys {sorted(TOP_KEYS)}, "
                                  f"got {type(data).__name__}")
    unknown = set(data) - TOP_KEYS
    if unknown:
        raise fail(sorted(unknown)[0], f"unknown key; expected one of {sorted(TOP_KEYS)}")
    fmt = data.get("format", SETUP_FORMAT)
    if type(fmt) is not type(SETUP_FORMAT) or fmt != SETUP_FORMAT:  # (true == 1)
        raise fail("format", f"expected {SETUP_FORMAT}, got {fmt!r}")
    name = data.get("name", path.stem)
    if not isinstance(name, str) or not NAME_PATTERN.fullmatch(name):
        raise fail("name", f"expected {NAME_RULE}, got {_short(name)}")

    world = data.get("world")
    if not isinstance(world, str) or not world:
        raise fail("world", "expected the name of a world in worlds/ (e.g. kitchen) or a path "
                            "to a URDF")
    world_urdf = _resolve_urdf(world, path, worlds_dir())
    if world_urdf is None:
        raise fail("world", f"expected worlds/{world}.urdf or a URDF path; found neither")
    problem = urdf_problem(world_urdf)
    if problem:
        raise fail("world", f"{world_urdf}: {problem}")

    robot = data.get("robot")
    if not isinstance(robot, dict) or "start" not in robot:
        raise fail("robot", "expected a mapping with 'start: [x, y, yaw]'")
    unknown = set(robot) - ROBOT_KEYS
    if unknown:
        raise fail(f"robot.{sorted(map(str, unknown))[0]}",
                   f"unknown key; expected only {sorted(ROBOT_KEYS)}")
    start = _numbers(robot["start"], 3, "robot.start", "[x, y, yaw]", fail)
    robot_start = RobotStart(*start)

    raw_items = data.get("items")
    if not isinstance(raw_items, list) or not raw_items:
        raise fail("items", "expected a non-empty list of items")
    if len(raw_items) > MAX_ITEMS:
        raise fail("items", f"{len(raw_items)} items; expected at most {MAX_ITEMS}")
    items = tuple(_parse_item(raw, i, path, fail) for i, raw in enumerate(raw_items))
    names = [it.name for it in items]
    for i, nm in enumerate(names):
        if nm in names[:i]:
            raise fail(f"items[{i}].name", f"duplicate item name {nm!r}; names must be unique")

    order = data.get("baseline_order", names)
    if not isinstance(order, list) or sorted(map(str, order)) != sorted(names):
        raise fail("baseline_order", f"expected a permutation of the item names {names}, "
                                     f"got {order!r}")
    return Setup(name=name, source=path, world_urdf=world_urdf, robot_start=robot_start,
                 items=items, baseline_order=tuple(map(str, order)),
                 description=str(data.get("description", "")), raw=data)


def _parse_item(raw: Any, i: int, path: Path, fail) -> ItemSpec:
    where = f"items[{i}]"
    if not isinstance(raw, dict):
        raise fail(where, f"expected a mapping with keys {sorted(ITEM_KEYS)}")
    unknown = set(raw) - ITEM_KEYS
    if unknown:
        raise fail(f"{where}.{sorted(unknown)[0]}", f"unknown key; expected one of "
                                                    f"{sorted(ITEM_KEYS)}")
    for key in ("name", "pose", "target"):
        if key not in raw:
            raise fail(f"{where}.{key}", "missing; every item needs name, pose, target and "
                                         "surface (or in: a container)")
    if ("surface" in raw) == ("in" in raw):
        raise fail(f"{where}.surface", "expected either 'surface: <link it stands on>' or "
                                       "'in: <container>', not both or neither")
    name = raw["name"]
    if not isinstance(name, str) or not NAME_PATTERN.fullmatch(name):
        raise fail(f"{where}.name", f"expected {NAME_RULE}, got {_short(name)}")
    item_type = raw.get("type", name)
    if not isinstance(item_type, str) or not item_type:
        raise fail(f"{where}.type", f"expected a string, got {_short(item_type)}")
    urdf = _resolve_urdf(item_type, path, worlds_dir() / "items")
    if urdf is None:
        known = sorted(p.stem for p in (worlds_dir() / "items").glob("*.urdf"))
        raise fail(f"{where}.type", f"unknown item type {_short(item_type)}; expected one of "
                                    f"{known} or a path to a URDF")
    problem = urdf_problem(urdf)
    if problem:
        raise fail(f"{where}.type", f"{urdf}: {problem}")
    pose = Pose(*_numbers(raw["pose"], 4, f"{where}.pose", "[x, y, z, yaw]", fail))
    target = Pose(*_numbers(raw["target"], 4, f"{where}.target", "[x, y, z, yaw]", fail))
    container = raw.get("in")
    if container is not None and (not isinstance(container, str) or not container):
        raise fail(f"{where}.in", f"expected the name of a container, got {container!r}")
    surface = raw.get("surface", container)
    if not isinstance(surface, str) or not surface:
        raise fail(f"{where}.surface", f"expected the name of a world link, got {surface!r}")
    contained = raw.get("contained", container is not None)
    if not isinstance(contained, bool):
        raise fail(f"{where}.contained", f"expected true or false, got {contained!r}")
    if contained != (container is not None):
        raise fail(f"{where}.contained", "follows from 'in:' (items in a container are "
                                         f"contained, the others not); expected "
                                         f"{str(container is not None).lower()} or no key")
    category = raw.get("category", "none")
    if category is None:
        category = "none"
    if category not in CATEGORIES:
        raise fail(f"{where}.category", f"unknown category {category!r}; expected one of "
                                        f"{', '.join(CATEGORIES)}")
    aliases = raw.get("aliases") or []
    if not isinstance(aliases, list) or not all(isinstance(a, str) and a for a in aliases):
        raise fail(f"{where}.aliases", f"expected a list of names, got {aliases!r}")
    return ItemSpec(name=name, type=item_type, urdf=urdf, pose=pose, surface=surface,
                    target=target, contained=contained, category=category,
                    aliases=tuple(aliases), container=container)


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _numbers(value: Any, n: int, fld: str, shape: str, fail) -> tuple[float, ...]:
    """n finite numbers of ordinary size: positions within +-MAX_ABS_POSITION_M, a yaw
    (the last of a pose) within +-2 pi."""
    if not isinstance(value, list | tuple):
        raise fail(fld, f"expected {n} numbers {shape}, got {_short(value)}")
    if len(value) != n:
        raise fail(fld, f"expected {n} numbers {shape}, got {len(value)}")
    out = []
    for i, v in enumerate(value):
        limit = MAX_ABS_YAW if i == n - 1 and shape.endswith("yaw]") else MAX_ABS_POSITION_M
        ok = not isinstance(v, bool) and isinstance(v, int | float) and abs(v) <= limit
        if not ok:  # also NaN (abs(nan) <= limit is False) and integers of any size
            unit = "radians within +-2 pi" if limit == MAX_ABS_YAW else \
                f"metres within +-{MAX_ABS_POSITION_M:g}"
            shown = f"an integer with {len(str(abs(v)))} digits" if isinstance(v, int) \
                and not isinstance(v, bool) and abs(v) > 10**15 else _short(v)
            names = shape.strip("[]").split(", ")
            what = names[i] if len(names) == n else f"value {i}"
            if isinstance(v, bool) or not isinstance(v, int | float):
                problem = f"must be a number ({unit})"
            elif v != v or v in (float("inf"), float("-inf")):
                problem = f"must be finite ({unit})"
            else:
                problem = f"must be within {unit.split(' within ')[1]} ({unit.split()[0]})"
            raise fail(f"{fld}[{i}]", f"expected {n} numbers {shape}; {what} {problem}, "
                                      f"got {shown}")
        out.append(float(v))
    return tuple(out)


def _resolve_urdf(name: str, setup_path: Path, folder: Path) -> Path | None:
    for candidate in (folder / f"{name}.urdf", setup_path.parent / name, Path(name)):
        if candidate.suffix == ".urdf" and candidate.is_file():
            return candidate.resolve()
    return None

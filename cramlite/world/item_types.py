"""Item types: what an item's URDF cannot say, in a YAML file beside it (`cup.urdf` ->
`cup.item.yaml`; ".item" keeps it apart from a setup file beside it): whether it must be
carried upright (and how far it may tilt), which turns about its vertical axis leave it
looking the same (what "at its target yaw" means), and
which grasps suit it. Every key is optional; an item without the file is not upright,
has the symmetry its shape has, and may be grasped any way that fits the gripper.

    # cup: open at the top; tipping it spills what is in it
    upright: true
    upright_tolerance_deg: 15
    yaw_symmetry: any          # any | 180 | 90 | 360 (none): degrees
    grasps: [front, top]       # front | top | rim
    reason: open at the top; tipping it spills
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path

import yaml

from cramlite.errors import SetupError
from cramlite.world.strict_yaml import describe_yaml_error, load_strict

KEYS = {"upright", "upright_tolerance_deg", "yaw_symmetry", "grasps", "reason"}
GRASP_KINDS = ("front", "top", "rim")
SYMMETRIES = {"any": 0.0, "90": 90.0, "180": 180.0, "360": 360.0, "none": 360.0}
DEFAULT_TILT_DEG = 15.0
DEFAULT_YAW_TOLERANCE_DEG = 10.0


@dataclass(frozen=True)
class ItemType:
    """How an item type is handled (see the module's doc)."""

    upright: bool = False
    upright_tolerance_deg: float = DEFAULT_TILT_DEG
    #: Degrees of a turn about +z that leaves it the same (0: any turn; 360: none). None:
    #: what its shape has (see `cramlite.scene.models.ItemModel`).
    yaw_symmetry_deg: float | None = None
    grasps: tuple[str, ...] = GRASP_KINDS
    reason: str = ""
    source: Path | None = None

    def yaw_error(self, yaw: float, target: float, symmetry_deg: float) -> float:
        """How far (radians, >= 0) a yaw is from the target's, up to the symmetry."""
        if symmetry_deg <= 0:
            return 0.0
        period = math.radians(symmetry_deg)
        return abs(math.remainder(yaw - target, period))


def item_type_file(urdf: Path) -> Path:
    return Path(urdf).with_suffix(".item.yaml")


@functools.cache
def _load(path: str, stamp: float) -> ItemType:
    file = Path(path)
    if not file.is_file():
        return ItemType()
    try:
        raw = load_strict(file.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        message, where = describe_yaml_error(exc)
        raise SetupError(message, source=str(file), field=where) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SetupError(f"cannot read it: {exc}", source=str(file)) from None
    except (ValueError, RecursionError) as exc:  # e.g. an integer of 5,000 digits
        raise SetupError(f"unusable YAML ({str(exc) or type(exc).__name__})",
                         source=str(file)) from None
    if raw is None:
        return ItemType(source=file)
    if not isinstance(raw, dict):
        raise SetupError(f"expected a mapping with keys {sorted(KEYS)}", source=str(file))
    unknown = set(raw) - KEYS
    if unknown:
        raise SetupError(f"unknown key {sorted(unknown)[0]!r}; expected {sorted(KEYS)}",
                         source=str(file), field=sorted(unknown)[0])
    upright = raw.get("upright", False)
    if not isinstance(upright, bool):
        raise SetupError(f"expected true or false, got {upright!r}", source=str(file),
                         field="upright")
    tilt = raw.get("upright_tolerance_deg", DEFAULT_TILT_DEG)
    if isinstance(tilt, bool) or not isinstance(tilt, int | float) or not 0 < tilt < 90:
        raise SetupError(f"expected degrees between 0 and 90, got {tilt!r}",
                         source=str(file), field="upright_tolerance_deg")
    symmetry = raw.get("yaw_symmetry")
    if symmetry is not None and str(symmetry) not in SYMMETRIES:
        raise SetupError(f"expected one of {', '.join(SYMMETRIES)}, got {symmetry!r}",
                         source=str(file), field="yaw_symmetry")
    grasps = raw.get("grasps", list(GRASP_KINDS))
    if not isinstance(grasps, list) or not grasps or \
            any(g not in GRASP_KINDS for g in grasps):
        raise SetupError(f"expected a list of {', '.join(GRASP_KINDS)}, got {grasps!r}",
                         source=str(file), field="grasps")
    reason = raw.get("reason", "")
    if not isinstance(reason, str):
        raise SetupError(f"expected text, got {reason!r}", source=str(file), field="reason")
    return ItemType(upright, float(tilt),
                    None if symmetry is None else SYMMETRIES[str(symmetry)],
                    tuple(grasps), reason, file)


def item_type(urdf: Path) -> ItemType:
    """The item type of an item URDF (its YAML file beside it, if there is one)."""
    path = item_type_file(urdf)
    stamp = path.stat().st_mtime if path.is_file() else 0.0
    return _load(str(path.resolve()), stamp)

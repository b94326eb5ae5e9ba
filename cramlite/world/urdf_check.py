"""Checks of a user's URDF (a world or an item) before Pinocchio, coal or a simulator
read it: why it cannot be loaded, in one line, or None.

The C++ parsers behind them (urdfdom, assimp) print to the process's stderr, crash on a
joint cycle (a segmentation fault) and accept a box of 1e300 m, a NaN mass or a mesh at
`/etc/passwd`; so everything they would read is checked here first: UTF-8 XML without
a DOCTYPE (no entities), a tree of links and joints (one root, one parent per link, no
cycle, at most MAX_LINKS links), every number finite and within a physical range, and
meshes that are files of a mesh format inside the URDF's own folder.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path

#: The largest URDF read (bytes).
MAX_URDF_BYTES = 4 * 1024 * 1024
#: The most links a URDF may have (the PR2 has 95; the kitchen 31).
MAX_LINKS = 1000
#: The largest size of a shape, a mesh scale or an origin's offset (m).
MAX_LENGTH_M = 100.0
#: The largest mass of a link (kg) and inertia entry (kg m^2).
MAX_MASS_KG = 1.0e5
MAX_INERTIA = 1.0e6
#: The largest joint limit: position (m or rad), velocity, effort.
MAX_LIMIT = 1.0e6
#: Mesh formats the loaders read, and the largest mesh file (bytes).
MESH_SUFFIXES = (".stl", ".obj", ".dae", ".ply")
MAX_MESH_BYTES = 64 * 1024 * 1024
JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


class URDFProblem(ValueError):
    """Why a URDF cannot be loaded."""


def urdf_problem(path: Path) -> str | None:
    """Why the URDF at `path` could not be loaded as an item or a world, else None."""
    try:
        check_urdf(path)
    except URDFProblem as exc:
        return str(exc)
    return None


def check_urdf(path: Path) -> None:
    """Raise URDFProblem saying what is wrong with the URDF at `path`."""
    root = _parse(path)
    if root.tag != "robot" or root.find("link") is None:
        raise URDFProblem("expected a URDF: a <robot> element with at least one <link>")
    links = root.findall("link")
    if len(links) > MAX_LINKS:
        raise URDFProblem(f"{len(links)} links; at most {MAX_LINKS} are read")
    names = [link.get("name") or "" for link in links]
    _unique(names, "link")
    for link in links:
        _check_link(link, path)
    _check_tree(root, set(names))


def _parse(path: Path) -> ET.Element:
    try:
        if not path.is_file():
            raise URDFProblem("not a regular file; expected a URDF")
        if path.stat().st_size > MAX_URDF_BYTES:
            raise URDFProblem(f"larger than {MAX_URDF_BYTES} bytes")
        data = path.read_bytes()
    except OSError as exc:
        raise URDFProblem(f"cannot read it ({exc.strerror or type(exc).__name__})") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise URDFProblem("not UTF-8 text; expected a URDF in UTF-8") from None
    if "<!DOCTYPE" in text or "<!ENTITY" in text:
        raise URDFProblem("has a DOCTYPE or ENTITY declaration; a URDF needs neither")
    try:
        return ET.fromstring(text)
    except ET.ParseError as exc:
        raise URDFProblem(f"not well-formed XML ({exc}); expected a URDF") from None


def _unique(names: list[str], kind: str) -> None:
    seen: set[str] = set()
    for name in names:
        if not name:
            raise URDFProblem(f"a <{kind}> without a name")
        if name in seen:
            raise URDFProblem(f"two {kind}s named {name!r}")
        seen.add(name)


def _numbers(text: str | None, n: int, label: str, low: float, high: float,
             low_open: bool = False) -> list[float]:
    """`n` finite numbers in [low, high] ((low, high] with `low_open`) from an attribute."""
    try:
        values = [float(v) for v in (text or "").split()]
    except ValueError:
        values = []
    if len(values) != n or not all(
            math.isfinite(v) and (v > low if low_open else v >= low) and v <= high
            for v in values):
        bound = f"> {low:g}" if low_open else f">= {low:g}"
        raise URDFProblem(f"{label} {text!r}; expected {n} number{'s' * (n > 1)} {bound} "
                          f"and <= {high:g}")
    return values


def _origins(element: ET.Element, label: str) -> None:
    for origin in element.iter("origin"):
        for attr in ("xyz", "rpy"):
            if origin.get(attr) is not None:
                limit = MAX_LENGTH_M if attr == "xyz" else 1.0e3
                _numbers(origin.get(attr), 3, f"{label}: origin {attr}", -limit, limit)


def _check_link(link: ET.Element, path: Path) -> None:
    label = f"link {link.get('name')!r}"
    for geometry in link.iter("geometry"):
        if len(geometry) != 1:  # (urdfdom prints its complaint from C++, then skips it)
            raise URDFProblem(f"{label}: a <geometry> with {len(geometry)} shapes; expected "
                              "one box, cylinder, sphere or mesh")
        for shape in geometry:
            _check_shape(shape, label, path)
    _origins(link, label)
    for mass in link.iter("mass"):
        _numbers(mass.get("value"), 1, f"{label}: mass", 0.0, MAX_MASS_KG)
    for inertia in link.iter("inertia"):
        for key in INERTIA_KEYS:
            if inertia.get(key) is not None:
                _numbers(inertia.get(key), 1, f"{label}: inertia {key}", -MAX_INERTIA,
                         MAX_INERTIA)


def _check_shape(shape: ET.Element, label: str, path: Path) -> None:
    size = (0.0, MAX_LENGTH_M)
    if shape.tag == "box":
        _numbers(shape.get("size"), 3, f"{label}: box size", *size, low_open=True)
    elif shape.tag == "cylinder":
        _numbers(shape.get("radius"), 1, f"{label}: cylinder radius", *size, low_open=True)
        _numbers(shape.get("length"), 1, f"{label}: cylinder length", *size, low_open=True)
    elif shape.tag == "sphere":
        _numbers(shape.get("radius"), 1, f"{label}: sphere radius", *size, low_open=True)
    elif shape.tag == "mesh":
        if shape.get("scale") is not None:
            _numbers(shape.get("scale"), 3, f"{label}: mesh scale", *size, low_open=True)
        _mesh_file(shape.get("filename") or "", label, path)
    else:
        raise URDFProblem(f"{label}: geometry <{shape.tag}>; expected box, cylinder, sphere "
                          "or mesh")


def _mesh_file(filename: str, label: str, path: Path) -> None:
    """A mesh is a file of a mesh format inside the URDF's folder (or below it)."""
    folder = path.resolve().parent
    relative = Path(filename)
    if "://" in filename or relative.is_absolute() or ".." in relative.parts or not filename:
        raise URDFProblem(f"{label}: mesh {filename!r}; expected a file name relative to the "
                          "URDF's folder (no package://, no absolute path, no ..)")
    target = (folder / relative).resolve()
    if not target.is_relative_to(folder):
        raise URDFProblem(f"{label}: mesh {filename!r} leads outside the URDF's folder")
    if target.suffix.lower() not in MESH_SUFFIXES:
        raise URDFProblem(f"{label}: mesh {filename!r}; expected a {', '.join(MESH_SUFFIXES)} "
                          "file")
    if not target.is_file():
        raise URDFProblem(f"{label}: mesh file {filename!r} not found")
    if target.stat().st_size > MAX_MESH_BYTES:
        raise URDFProblem(f"{label}: mesh file {filename!r} is larger than {MAX_MESH_BYTES} "
                          "bytes")


def _check_tree(root: ET.Element, links: set[str]) -> None:
    """Joints connect existing links into one tree: one root, one parent per link."""
    joints = root.findall("joint")
    _unique([j.get("name") or "" for j in joints], "joint")
    parent_of: dict[str, str] = {}
    children: dict[str, list[str]] = {}
    for joint in joints:
        label = f"joint {joint.get('name')!r}"
        kind = joint.get("type")
        if kind not in JOINT_TYPES:
            raise URDFProblem(f"{label}: type {kind!r}; expected one of {', '.join(JOINT_TYPES)}")
        parent, child = _link_ref(joint, "parent", label), _link_ref(joint, "child", label)
        for name in (parent, child):
            if name not in links:
                raise URDFProblem(f"{label}: no link {name!r}")
        if child in parent_of:
            raise URDFProblem(f"{label}: link {child!r} has two parents ({parent_of[child]!r} "
                              f"and {parent!r})")
        parent_of[child] = parent
        children.setdefault(parent, []).append(child)
        _origins(joint, label)
        _check_joint_numbers(joint, label)
    roots = sorted(links - set(parent_of))
    if len(roots) != 1:
        raise URDFProblem("the links form no tree (a joint cycle: every link has a parent)"
                          if not roots else
                          f"{len(roots)} root links ({', '.join(roots[:3])}, ...); expected one "
                          "(every other link the child of a joint)")
    reached = set(_reachable(roots[0], children))
    if reached != links:
        cut = sorted(links - reached)[0]
        raise URDFProblem(f"link {cut!r} is on a joint cycle (not reached from the root "
                          f"{roots[0]!r})")


def _link_ref(joint: ET.Element, tag: str, label: str) -> str:
    element = joint.find(tag)
    name = element.get("link") if element is not None else None
    if not name:
        raise URDFProblem(f"{label}: expected <{tag} link=\"...\"/>")
    return name


def _check_joint_numbers(joint: ET.Element, label: str) -> None:
    axis = joint.find("axis")
    if axis is not None:
        values = _numbers(axis.get("xyz"), 3, f"{label}: axis", -1.0e3, 1.0e3)
        if not any(values):
            raise URDFProblem(f"{label}: axis {axis.get('xyz')!r}; expected a non-zero "
                              "direction")
    limit = joint.find("limit")
    if limit is not None:
        for key in ("lower", "upper", "effort", "velocity"):
            if limit.get(key) is not None:
                _numbers(limit.get(key), 1, f"{label}: limit {key}", -MAX_LIMIT, MAX_LIMIT)
    for mimic in joint.iter("mimic"):
        for key in ("multiplier", "offset"):
            if mimic.get(key) is not None:
                _numbers(mimic.get(key), 1, f"{label}: mimic {key}", -MAX_LIMIT, MAX_LIMIT)


def _reachable(start: str, children: dict[str, list[str]]) -> Iterator[str]:
    stack = [start]
    seen: set[str] = set()
    while stack:  # (not recursive: a chain of MAX_LINKS links is fine)
        link = stack.pop()
        if link in seen:
            continue
        seen.add(link)
        yield link
        stack.extend(children.get(link, ()))


__all__ = ["MAX_LINKS", "MAX_URDF_BYTES", "URDFProblem", "check_urdf", "urdf_problem"]

"""Writes the kitchen and item URDFs of worlds/ from the numbers below.

Run `python worlds/build_worlds.py` after changing a number; the URDFs are committed so
that cramlite needs no build step. Everything is a primitive (box or cylinder) we own.
Layout numbers follow shared/SPEC.md section 3 (PyCRAM's kitchen, lengthened so the
four counter spots fit).
"""

from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).resolve().parent

# name: (x_min, x_max, y_min, y_max, z_min, z_max, rgba)
KITCHEN_BOXES: dict[str, tuple[float, float, float, float, float, float, str]] = {
    "floor": (-2.5, 2.5, -3.05, 3.55, -0.02, 0.0, "0.80 0.78 0.74 1"),
    "wall_back": (2.05, 2.15, -3.05, 3.55, 0.0, 2.0, "0.93 0.93 0.90 1"),
    "wall_left": (-2.6, -2.5, -3.05, 3.55, 0.0, 2.0, "0.93 0.93 0.90 1"),
    "wall_south": (-2.6, 2.15, -3.15, -3.05, 0.0, 2.0, "0.93 0.93 0.90 1"),
    "wall_north": (-2.6, 2.15, 3.55, 3.65, 0.0, 2.0, "0.93 0.93 0.90 1"),
    # Sink-area counter: front edge x = 1.25, top 0.85 m (SPEC 3), with two drawers under
    # its top at its south end (the cavities between the boxes below).
    "counter": (1.25, 1.85, -0.95, 1.35, 0.80, 0.85, "0.55 0.42 0.30 1"),
    "counter_base": (1.25, 1.85, -0.95, 1.35, 0.0, 0.58, "0.50 0.38 0.27 1"),
    "counter_body": (1.25, 1.85, -0.05, 1.35, 0.58, 0.80, "0.50 0.38 0.27 1"),
    "counter_end": (1.25, 1.85, -0.95, -0.91, 0.58, 0.80, "0.50 0.38 0.27 1"),
    "counter_divider": (1.25, 1.85, -0.49, -0.47, 0.58, 0.80, "0.50 0.38 0.27 1"),
    "counter_back": (1.83, 1.85, -0.91, -0.05, 0.58, 0.80, "0.50 0.38 0.27 1"),
    # Kitchen island: near edge x = -0.67, top 0.86 m (SPEC 3, PyCRAM's island).
    "island": (-1.47, -0.67, 0.49, 2.94, 0.0, 0.86, "0.62 0.50 0.38 1"),
    "fridge": (1.25, 1.95, -2.0, -1.25, 0.0, 1.8, "0.85 0.87 0.90 1"),
    # A cupboard beside the counter: a shelf at 1 m, about the PR2's shoulder height (its
    # floor, the "cupboard" link), behind a door hinged on its left that opens wide, to
    # 130 degrees, out of the way (in stages: the PR2 cannot follow the whole arc from one
    # place).
    "cupboard": (1.25, 1.85, 1.45, 2.05, 0.0, 1.0, "0.42 0.45 0.50 1"),
    "cupboard_top": (1.25, 1.85, 1.45, 2.05, 1.63, 1.65, "0.42 0.45 0.50 1"),
    "cupboard_back": (1.83, 1.85, 1.47, 2.03, 1.0, 1.63, "0.42 0.45 0.50 1"),
    "cupboard_left": (1.25, 1.85, 2.03, 2.05, 1.0, 1.63, "0.42 0.45 0.50 1"),
    "cupboard_right": (1.25, 1.85, 1.45, 1.47, 1.0, 1.63, "0.42 0.45 0.50 1"),
    # An open-top bin on the far end of the island: items in it are "contained" (OPM c).
    "bin": (-1.15, -0.80, 2.25, 2.70, 0.86, 0.87, "0.35 0.55 0.45 1"),
    "bin_wall_near": (-0.81, -0.80, 2.25, 2.70, 0.87, 0.93, "0.35 0.55 0.45 1"),
    "bin_wall_far": (-1.15, -1.14, 2.25, 2.70, 0.87, 0.93, "0.35 0.55 0.45 1"),
    "bin_wall_south": (-1.14, -0.81, 2.25, 2.26, 0.87, 0.93, "0.35 0.55 0.45 1"),
    "bin_wall_north": (-1.14, -0.81, 2.69, 2.70, 0.87, 0.93, "0.35 0.55 0.45 1"),
}
# Articulated storage: each a link on a joint (in the link's own frame, boxes as
# (x_min, x_max, y_min, y_max, z_min, z_max)), a handle link fixed to it, and where items
# rest inside. Drawers slide out toward -x; the door turns about its left edge.
DRAWER_BOXES = {  # frame: the closed drawer's front, bottom, middle
    "bottom": (0.02, 0.56, -0.19, 0.19, 0.0, 0.02),
    "front": (0.0, 0.02, -0.20, 0.20, 0.0, 0.21),
    "back": (0.54, 0.56, -0.19, 0.19, 0.02, 0.14),
    "left": (0.02, 0.54, 0.17, 0.19, 0.02, 0.14),
    "right": (0.02, 0.54, -0.19, -0.17, 0.02, 0.14),
}
DRAWER_HANDLE = {"bar": (-0.05, -0.03, -0.08, 0.08, 0.15, 0.17),
                 "post_l": (-0.03, 0.0, 0.06, 0.07, 0.15, 0.17),
                 "post_r": (-0.03, 0.0, -0.07, -0.06, 0.15, 0.17)}
DOOR_BOXES = {"panel": (-0.02, 0.0, -0.57, -0.005, 0.0, 0.63)}  # frame: the hinge, bottom
DOOR_HANDLE = {"bar": (-0.06, -0.04, -0.53, -0.51, 0.12, 0.30),
               "post_t": (-0.04, -0.02, -0.53, -0.51, 0.28, 0.30),
               "post_b": (-0.04, -0.02, -0.53, -0.51, 0.12, 0.14)}
#: name: (kind, joint origin xyz, axis, upper limit, rgba)
ARTICULATED = {
    "drawer_1": ("drawer", (1.25, -0.70, 0.58), (-1, 0, 0), 0.35, "0.62 0.48 0.34 1"),
    "drawer_2": ("drawer", (1.25, -0.27, 0.58), (-1, 0, 0), 0.35, "0.62 0.48 0.34 1"),
    "cupboard_door": ("door", (1.25, 2.045, 1.0), (0, 0, -1), 2.3, "0.48 0.52 0.58 1"),
}
#: Containers, as the setup files name them: the moving part, its joint and handle, where
#: items rest (link, box in its frame, z = the bottom items stand on), how the handle is
#: grasped (tool roll about the approach), and the joint value when open (closed = 0).
CONTAINERS = {
    "drawer_1": {"kind": "drawer", "link": "drawer_1", "joint": "drawer_1_joint",
                 "handle": "drawer_1_handle", "grasp": [-0.04, 0.0, 0.16], "roll": 1.5708,
                 "inside": {"link": "drawer_1", "min": [0.03, -0.165, 0.02],
                            "max": [0.33, 0.165, 0.20]},
                 "open": 0.35},
    "drawer_2": {"kind": "drawer", "link": "drawer_2", "joint": "drawer_2_joint",
                 "handle": "drawer_2_handle", "grasp": [-0.04, 0.0, 0.16], "roll": 1.5708,
                 "inside": {"link": "drawer_2", "min": [0.03, -0.165, 0.02],
                            "max": [0.33, 0.165, 0.20]},
                 "open": 0.35},
    "cupboard": {"kind": "cupboard", "link": "cupboard_door", "joint": "cupboard_door_joint",
                 "handle": "cupboard_door_handle", "grasp": [-0.05, -0.52, 0.21], "roll": 0.0,
                 "inside": {"link": "cupboard", "min": [1.28, 1.48, 1.0],
                            "max": [1.60, 2.02, 1.6]},
                 "open": 2.3},
}

# Visual-only decoration (no collision): the sink basin on the counter.
KITCHEN_VISUALS = {"sink": (1.45, 1.75, 1.0, 1.3, 0.85, 0.853, "0.45 0.50 0.55 1")}

# Items: origin at the centre of the bottom face. Sizes in metres, masses in kg.
# (shape, size, mass, rgba); box size = (x, y, z), cylinder size = (radius, height).
ITEMS: dict[str, tuple[str, tuple[float, ...], float, str]] = {
    "spoon": ("box", (0.16, 0.03, 0.015), 0.03, "0.75 0.75 0.78 1"),
    "breakfast-cereal": ("box", (0.07, 0.19, 0.29), 0.45, "0.90 0.70 0.15 1"),
    "milk": ("box", (0.075, 0.075, 0.20), 1.05, "0.95 0.95 0.98 1"),
    "cup": ("cylinder", (0.04, 0.095), 0.25, "0.20 0.45 0.80 1"),
    "bowl": ("bowl", (0.08, 0.065), 0.35, "0.85 0.30 0.25 1"),
}
#: The bowl is hollow (a person or a PR2 holds it by its rim): a base and a ring of wall
#: segments, all boxes and a cylinder.
BOWL_WALL_M = 0.006
BOWL_BASE_M = 0.008
BOWL_SEGMENTS = 16


def _box_link(name: str, box: tuple[float, float, float, float, float, float, str],
              collision: bool = True) -> str:
    x0, x1, y0, y1, z0, z1, rgba = box
    cx, cy, cz = (x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2
    size = f"{x1 - x0:.4f} {y1 - y0:.4f} {z1 - z0:.4f}"
    origin = f'<origin xyz="{cx:.4f} {cy:.4f} {cz:.4f}"/>'
    geometry = f"<geometry><box size=\"{size}\"/></geometry>"
    coll = f"<collision>{origin}{geometry}</collision>" if collision else ""
    return (
        f'  <link name="{name}">\n'
        f'    <visual>{origin}{geometry}<material name="{name}_mat"><color rgba="{rgba}"/>'
        f"</material></visual>\n    {coll}\n"
        '    <inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>'
        "</inertial>\n  </link>\n"
    )


def _boxes_link(name: str, boxes: dict[str, tuple[float, ...]], rgba: str) -> str:
    """A link made of several boxes given in its own frame (visual and collision)."""
    shapes = []
    for box in boxes.values():
        x0, x1, y0, y1, z0, z1 = box
        origin = f'<origin xyz="{(x0 + x1) / 2:.4f} {(y0 + y1) / 2:.4f} {(z0 + z1) / 2:.4f}"/>'
        geometry = f'<geometry><box size="{x1 - x0:.4f} {y1 - y0:.4f} {z1 - z0:.4f}"/></geometry>'
        shapes.append(f"    <visual>{origin}{geometry}<material name=\"{name}_mat\">"
                      f"<color rgba=\"{rgba}\"/></material></visual>\n"
                      f"    <collision>{origin}{geometry}</collision>\n")
    return (f'  <link name="{name}">\n{"".join(shapes)}'
            '    <inertial><mass value="0.5"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" '
            'iyz="0" izz="0.01"/></inertial>\n  </link>\n')


def articulated_urdf() -> str:
    parts = []
    for name, (kind, origin, axis, upper, rgba) in ARTICULATED.items():
        boxes, handle = (DRAWER_BOXES, DRAWER_HANDLE) if kind == "drawer" else \
            (DOOR_BOXES, DOOR_HANDLE)
        parts.append(_boxes_link(name, boxes, rgba))
        parts.append(_boxes_link(f"{name}_handle", handle, "0.75 0.75 0.78 1"))
        joint_type = "prismatic" if kind == "drawer" else "revolute"
        parent = "floor"
        x, y, z = origin
        parts.append(
            f'  <joint name="{name}_joint" type="{joint_type}"><parent link="{parent}"/>'
            f'<child link="{name}"/><origin xyz="{x} {y} {z}"/>'
            f'<axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>'
            f'<limit lower="0" upper="{upper}" effort="100" velocity="0.5"/></joint>\n')
        parts.append(f'  <joint name="{name}_to_handle" type="fixed"><parent link="{name}"/>'
                     f'<child link="{name}_handle"/></joint>\n')
    return "".join(parts)


def containers_yaml() -> str:
    import json

    lines = ["# generated by worlds/build_worlds.py: the kitchen's containers (see README)",
             "containers:"]
    for name, spec in CONTAINERS.items():
        lines.append(f"  {name}: {json.dumps(spec)}")
    return "\n".join(lines) + "\n"


def kitchen_urdf() -> str:
    parts = ['<?xml version="1.0"?>\n<!-- generated by worlds/build_worlds.py -->\n'
             '<robot name="kitchen">\n']
    parts.append(_box_link("floor", KITCHEN_BOXES["floor"]))
    children = {k: v for k, v in KITCHEN_BOXES.items() if k != "floor"}
    for name, box in children.items():
        parts.append(_box_link(name, box))
    for name, box in KITCHEN_VISUALS.items():
        parts.append(_box_link(name, box, collision=False))
    for name in [*children, *KITCHEN_VISUALS]:
        parts.append(f'  <joint name="floor_to_{name}" type="fixed"><parent link="floor"/>'
                     f'<child link="{name}"/></joint>\n')
    parts.append(articulated_urdf())
    parts.append("</robot>\n")
    return "".join(parts)


def bowl_urdf(name: str) -> str:
    """A hollow bowl: a base disc and BOWL_SEGMENTS wall boxes around it."""
    import math

    _, (radius, height), mass, rgba = ITEMS[name]
    material = f'<material name="{name}_mat"><color rgba="{rgba}"/></material>'
    shapes = []
    base = f'<cylinder radius="{radius}" length="{BOWL_BASE_M}"/>'
    origin = f'<origin xyz="0 0 {BOWL_BASE_M / 2:.4f}"/>'
    shapes.append((origin, base))
    chord = 2 * radius * math.tan(math.pi / BOWL_SEGMENTS)  # (the segments' outer corners
    # touch the circle: a ring without gaps)
    wall = height - BOWL_BASE_M
    for k in range(BOWL_SEGMENTS):
        angle = 2 * math.pi * k / BOWL_SEGMENTS
        r = radius - BOWL_WALL_M / 2
        origin = (f'<origin xyz="{r * math.cos(angle):.5f} {r * math.sin(angle):.5f} '
                  f'{BOWL_BASE_M + wall / 2:.4f}" rpy="0 0 {angle:.5f}"/>')
        shapes.append((origin, f'<box size="{BOWL_WALL_M} {chord:.5f} {wall:.4f}"/>'))
    body = "".join(f"    <visual>{o}<geometry>{g}</geometry>{material}</visual>\n"
                   f"    <collision>{o}<geometry>{g}</geometry></collision>\n"
                   for o, g in shapes)
    inertia = mass * radius ** 2 / 2
    return (
        '<?xml version="1.0"?>\n<!-- generated by worlds/build_worlds.py -->\n'
        f'<robot name="{name}">\n  <link name="{name}">\n{body}'
        f'    <inertial><origin xyz="0 0 {height / 3:.4f}"/><mass value="{mass}"/>'
        f'<inertia ixx="{inertia / 2:.6g}" ixy="0" ixz="0" iyy="{inertia / 2:.6g}" iyz="0" '
        f'izz="{inertia:.6g}"/></inertial>\n  </link>\n</robot>\n'
    )


def item_urdf(name: str) -> str:
    shape, size, mass, rgba = ITEMS[name]
    if shape == "bowl":
        return bowl_urdf(name)
    if shape == "box":
        sx, sy, sz = size
        geometry = f'<box size="{sx} {sy} {sz}"/>'
        ixx = mass * (sy**2 + sz**2) / 12
        iyy = mass * (sx**2 + sz**2) / 12
        izz = mass * (sx**2 + sy**2) / 12
        height = sz
    else:
        radius, height = size
        geometry = f'<cylinder radius="{radius}" length="{height}"/>'
        ixx = iyy = mass * (3 * radius**2 + height**2) / 12
        izz = mass * radius**2 / 2
    origin = f'<origin xyz="0 0 {height / 2:.4f}"/>'
    return (
        '<?xml version="1.0"?>\n<!-- generated by worlds/build_worlds.py -->\n'
        f'<robot name="{name}">\n  <link name="{name}">\n'
        f'    <visual>{origin}<geometry>{geometry}</geometry>'
        f'<material name="{name}_mat"><color rgba="{rgba}"/></material></visual>\n'
        f"    <collision>{origin}<geometry>{geometry}</geometry></collision>\n"
        f'    <inertial>{origin}<mass value="{mass}"/>'
        f'<inertia ixx="{ixx:.6g}" ixy="0" ixz="0" iyy="{iyy:.6g}" iyz="0" izz="{izz:.6g}"/>'
        "</inertial>\n  </link>\n</robot>\n"
    )


def main() -> None:
    (HERE / "kitchen.urdf").write_text(kitchen_urdf())
    (HERE / "kitchen.containers.yaml").write_text(containers_yaml())
    for name in ITEMS:
        (HERE / "items" / f"{name}.urdf").write_text(item_urdf(name))


if __name__ == "__main__":
    main()

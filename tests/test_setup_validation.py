"""Every bad setup ends with exit code 2 and one line naming file, field and expectation."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import ROOT, run_cli


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    return path


def _assert_user_error(result, *fragments: str) -> None:
    print(result.stderr)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "Traceback" not in result.stderr
    for fragment in fragments:
        assert fragment in lines[0]


def test_missing_file(tmp_path: Path) -> None:
    missing = tmp_path / "nope.yaml"
    _assert_user_error(run_cli("show", str(missing)), str(missing), "v1")


def test_malformed_yaml(tmp_path: Path) -> None:
    path = _write(tmp_path, "name: x\nitems: [\n  - a: b\n")
    _assert_user_error(run_cli("show", str(path)), str(path), "line", "YAML")


def test_a_key_given_twice_is_refused(tmp_path: Path, setup_text: str) -> None:
    # (YAML would keep the last one: this setup would silently be named "twice")
    path = _write(tmp_path, setup_text.replace("\nitems:", "\nname: twice\nitems:", 1))
    _assert_user_error(run_cli("show", str(path)), str(path), "line", "'name' appears twice")


@pytest.mark.parametrize(("old", "new"), [
    ("description: ", "description: &a "), ("aliases: [cereal]", "aliases: &c [cereal]"),
    ("category: mid", "category: &k mid"), ("baseline_order: [", "baseline_order: &o ["),
    ("name: v1", "name: &n v1"), ("start: [", "start: &s ["),
    ("pose: [1.45, 0.35, 0.85, 0.0]", "pose: &p [1.45, 0.35, 0.85, 0.0]"),
])
def test_yaml_anchors_and_aliases_are_refused_in_one_line(tmp_path: Path, setup_text: str,
                                                          old: str, new: str) -> None:
    """(A 3 KB file of nested aliases expands to gigabytes when printed.)"""
    assert old in setup_text
    path = _write(tmp_path, setup_text.replace(old, new, 1))
    _assert_user_error(run_cli("show", str(path)), str(path), "line", "anchors and aliases")


def test_an_item_type_file_with_an_alias_is_refused(tmp_path: Path, setup_text: str) -> None:
    import shutil

    from tests.conftest import ROOT

    items = ROOT / "worlds" / "items"
    shutil.copy(items / "cup.urdf", tmp_path / "mug.urdf")
    (tmp_path / "mug.item.yaml").write_text("upright: &u true\ngrasps: [front]\n")
    text = setup_text.replace("type: cup ", f"type: {tmp_path / 'mug.urdf'} ")
    path = _write(tmp_path, text)
    done = run_cli("show", str(path))
    _assert_user_error(done, str(tmp_path / "mug.item.yaml"), "anchors and aliases")


def test_unknown_category(tmp_path: Path, setup_text: str) -> None:
    path = _write(tmp_path, setup_text.replace("category: mid", "category: utensil"))
    _assert_user_error(run_cli("show", str(path)), str(path), "items[4].category",
                       "'utensil'", "strong, mid, food, none")


def test_pose_with_wrong_number_of_values(tmp_path: Path, setup_text: str) -> None:
    path = _write(tmp_path, setup_text.replace("pose: [1.45, 0.35, 0.85, 0.0]",
                                               "pose: [1.45, 0.35, 0.85]"))
    _assert_user_error(run_cli("show", str(path)), str(path), "items[0].pose",
                       "expected 4 numbers [x, y, z, yaw], got 3")


def test_item_inside_another_body(tmp_path: Path, setup_text: str) -> None:
    # the spoon moved onto the milk's spot
    path = _write(tmp_path, setup_text.replace("pose: [1.45, 0.35, 0.85, 0.0]",
                                               "pose: [1.45, -0.15, 0.85, 0.0]"))
    _assert_user_error(run_cli("show", str(path)), str(path), "items[", ".pose", "inside",
                       "free spot")


def test_item_off_its_surface(tmp_path: Path, setup_text: str) -> None:
    path = _write(tmp_path, setup_text.replace("pose: [1.45, 0.35, 0.85, 0.0]",
                                               "pose: [0.2, 0.35, 0.85, 0.0]"))
    _assert_user_error(run_cli("show", str(path)), "items[0].pose", "not on 'counter'")


@pytest.mark.parametrize(("old", "new", "field"), [
    ("baseline_order: [breakfast-cereal, cup, bowl, spoon, milk]",
     "baseline_order: [cup, bowl, spoon, milk]", "baseline_order"),
    ("world: kitchen", "world: moonbase", "world"),
    ("type: cup ", "type: teapot ", "items[3].type"),
    ("start: [-0.5, -1.8, 1.5708]", "start: [-0.5, oops, 1.5708]", "robot.start"),
    ("surface: island", "surface: shelf", "items[1].surface"),
])
def test_other_bad_fields(tmp_path: Path, setup_text: str, old: str, new: str,
                          field: str) -> None:
    assert old in setup_text
    path = _write(tmp_path, setup_text.replace(old, new))
    _assert_user_error(run_cli("show", str(path)), str(path), field)


def test_shipped_setups_validate_and_a_copy_works(tmp_path: Path, setup_text: str) -> None:
    path = _write(tmp_path, setup_text.replace("name: v1", "name: mine"))
    out = tmp_path / "mine.png"
    result = run_cli("show", str(path), "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert out.stat().st_size > 10_000


# -- hardening: every impossible scene is refused when the setup loads ---------------------
NEGATIVE_BOX = (ROOT_ITEMS := Path(__file__).resolve().parents[1] / "worlds" / "items") \
    and (ROOT_ITEMS / "milk.urdf").read_text().replace('size="0.075 0.075 0.2"',
                                                      'size="-0.075 0.075 0.2"')

MILK = (ROOT_ITEMS / "milk.urdf").read_text()


def _mesh(filename: str) -> str:
    return (f"<robot name='x'><link name='a'><collision><geometry><mesh filename='{filename}'/>"
            "</geometry></collision></link></robot>")


def _links(n: int, origin: str = "", cycle: bool = False) -> str:
    """A chain of n box links joined by fixed joints (the last joined back to the first
    with `cycle`)."""
    box = "<collision><geometry><box size='0.05 0.05 0.05'/></geometry></collision>"
    links = "".join(f"<link name='l{i}'>{box}</link>" for i in range(n))
    pairs = [(i - 1, i) for i in range(1, n)] + ([(n - 1, 0)] if cycle else [])
    joints = "".join(f"<joint name='j{c}' type='fixed'><parent link='l{p}'/>"
                     f"<child link='l{c}'/>{origin}</joint>" for p, c in pairs)
    return f"<robot name='chain'>{links}{joints}</robot>"


SPOON_POSE = "pose: [1.45, 0.35, 0.85, 0.0]"
SPOON_TARGET = "target: [-0.85, 1.0, 0.86, 0.0]"
CUP_TARGET = "target: [-1.0, 1.1, 0.86, 0.0]"
START = "start: [-0.5, -1.8, 1.5708]"


@pytest.mark.parametrize(("old", "new", "fragments"), [
    # targets: off the island, in the air, under the floor, two on one spot, in furniture
    (SPOON_TARGET, "target: [-0.3, 1.0, 0.86, 0.0]", ("items[0].target", "rests on no surface")),
    (SPOON_TARGET, "target: [-0.85, 1.0, 1.5, 0.0]", ("items[0].target", "in the air")),
    (SPOON_TARGET, "target: [-0.85, 1.0, -0.5, 0.0]", ("items[0].target", "below the floor")),
    (SPOON_TARGET, "target: [-0.85, 1.0, 0.0, 0.0]", ("items[0].target", "rests on no surface")),
    (CUP_TARGET, SPOON_TARGET, ("items[3].target", "overlaps the target of 'spoon'")),
    (CUP_TARGET, "target: [-0.85, 2.47, 0.86, 0.0]", ("items[3].target", "inside the furniture")),
    # the robot: outside the kitchen, inside furniture, on an item, unknown keys
    (START, "start: [10.0, 0.0, 0.0]", ("robot.start", "not on the floor of the kitchen")),
    (START, "start: [-2.4, 0.0, 0.0]", ("robot.start", "not on the floor")),
    (START, "start: [1.55, 0.2, 0.0]", ("robot.start", "inside 'counter_base'")),
    (START, "start: [1.9, -0.5, 0.0]", ("robot.start", "inside 'counter_base'")),  # (deepest)
    (START, START + "\n  speed: 2", ("robot.speed", "unknown key; expected only ['start']")),
    # numbers: 400 digits, NaN, infinity, a yaw of many turns
    (SPOON_POSE, "pose: [" + "1" * 400 + ", 0.35, 0.85, 0.0]",
     ("items[0].pose", "integer with 400 digits")),
    (SPOON_POSE, "pose: [1.45, .nan, 0.85, 0.0]", ("items[0].pose[1]", "y must be finite")),
    (SPOON_POSE, "pose: [1.45, 0.35, .inf, 0.0]", ("items[0].pose[2]", "z must be finite")),
    (SPOON_POSE, "pose: [1.45, '0.4.5', 0.85, 0.0]",
     ("items[0].pose[1]", "y must be a number", "got '0.4.5'")),
    (SPOON_POSE, "pose: [1.45, 0.35, 0.85, 100.0]", ("items[0].pose", "within +-2 pi")),
    (START, "start: [-0.5, -1.8, 1.0e+300]", ("robot.start", "within +-2 pi")),
    (SPOON_POSE, "pose: [" + "7" * 5000 + ", 0.35, 0.85, 0.0]", ("unusable YAML",)),
    # names end up in file names and CSV columns
    ("name: v1", "name: ../../etc/v1", ("name", "'../../etc/v1'", "file names")),
    ("name: v1", "name: 'a\\\\b'", ("name", "file names")),
    ("name: v1", "name: ''", ("name", "file names")),
    ("  - name: spoon", "  - name: soup spoon", ("items[0].name", "'soup spoon'")),
    # YAML 1.1: `yes:` is a boolean key, `true` equals 1
    ("name: v1", "name: v1\nyes: 1", ("line", "the key 'yes' is read as bool True")),
    ("name: v1", "name: v1\n2: 1", ("line", "the key '2' is read as int 2")),
    ("format: 1", "format: true", ("format", "expected 1, got True")),
])
def test_impossible_setups_are_refused_at_load(tmp_path: Path, setup_text: str, old: str,
                                               new: str, fragments: tuple[str, ...]) -> None:
    assert old in setup_text
    path = _write(tmp_path, setup_text.replace(old, new, 1))
    _assert_user_error(run_cli("show", str(path), "--out", str(tmp_path / "x.png")),
                       str(path), *fragments)
    assert not (tmp_path / "x.png").exists()


def test_a_target_needs_something_under_it_wherever_its_item_starts(tmp_path: Path) -> None:
    c1 = (ROOT / "worlds" / "setups" / "c1.yaml").read_text()
    spoon_target = "target: [-0.85, 1.0, 0.86, 0.0]"  # (the spoon starts in drawer_1)
    assert spoon_target in c1
    for target, why in (("[-0.85, 1.0, 1.5, 0.0]", "in the air"),
                        ("[5.0, 5.0, 0.86, 0.0]", "rests on no surface")):
        path = _write(tmp_path, c1.replace(spoon_target, f"target: {target}", 1))
        _assert_user_error(run_cli("show", str(path), "--out", str(tmp_path / "x.png")),
                           str(path), "items[0].target", why)
    # a target on a drawer's bottom (given as it is closed) has something under it
    into_drawer = c1.replace(spoon_target, "target: [1.45, -0.62, 0.6, 0.0]", 1)
    done = run_cli("show", str(_write(tmp_path, into_drawer)), "--out",
                   str(tmp_path / "y.png"))
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize(("urdf", "fragments"), [
    ("garbage, not XML", ("items[0].type", "not well-formed XML")),
    ("<robot name='x'/>", ("items[0].type", "at least one <link>")),
    ("<html><link/></html>", ("items[0].type", "expected a URDF")),
    (NEGATIVE_BOX, ("items[0].type", "box size '-0.075 0.075 0.2'", "3 numbers > 0")),
    (NEGATIVE_BOX.replace('size="-0.075 0.075 0.2"', 'size="0.075 nan 0.2"'),
     ("items[0].type", "box size")),
    (NEGATIVE_BOX.replace('size="-0.075 0.075 0.2"', 'size="0.075 0.075 0.2"').replace(
        'value="1.05"', 'value="-1"'), ("items[0].type", "mass '-1'")),
    ("<robot name='x'><link name='a'><visual><geometry><mesh filename='nowhere.obj'/>"
     "</geometry></visual></link></robot>", ("items[0].type", "mesh file 'nowhere.obj'")),
    ("<robot name='x'><link name='a'><collision><geometry><cylinder radius='0' length='1'/>"
     "</geometry></collision></link></robot>", ("items[0].type", "cylinder radius '0'")),
    # what the C++ parsers print, crash on or accept (#29 findings 6-7)
    (MILK.replace('size="0.075 0.075 0.2"', 'size="1e300 0.075 0.2"'),
     ("items[0].type", "box size '1e300 0.075 0.2'", "<= 100")),
    (MILK.replace('value="1.05"', 'value="1e308"'), ("items[0].type", "mass '1e308'")),
    (_mesh("package://pr2_description/meshes/x.stl"), ("no package://",)),
    (_mesh("/etc/passwd"), ("mesh '/etc/passwd'", "no absolute path")),
    (_mesh("../../x.stl"), ("no ..",)),
    (_mesh("odd.urdf"), ("expected a .stl, .obj, .dae, .ply file",)),
    (_mesh("odd.stl' scale='-1 nan 0"), ("mesh scale '-1 nan 0'",)),
    (_links(3, "<origin xyz='0 nan 0'/>"), ("joint 'j1': origin xyz '0 nan 0'",)),
    (_links(3, cycle=True), ("joint cycle",)),
    (_links(1001), ("1001 links; at most 1000",)),
    (_links(3).replace("<joint name='j2'", "<joint name='j1'"), ("two joints named 'j1'",)),
    (_links(3).replace("<parent link='l1'/>", "<parent link='nope'/>"), ("no link 'nope'",)),
    (_links(3).replace("<joint name='j2' type='fixed'>", "<joint name='j2' type='hinge'>"),
     ("type 'hinge'",)),
    ("<!DOCTYPE r [<!ENTITY a 'aaaa'>]><robot name='x'><link name='&a;'/></robot>",
     ("DOCTYPE",)),
    # urdfdom printed eight lines of its own, from C++, before the one of cramlite's
    (MILK.replace('<box size="0.075 0.075 0.2"/>', "", 1), ("a <geometry> with 0 shapes",)),
    (MILK.replace('<box size="0.075 0.075 0.2"/>', '<box size="0.075 0.075 0.2"/>'
                  '<sphere radius="0.1"/>', 1), ("a <geometry> with 2 shapes",)),
])
def test_item_urdfs_that_cannot_be_loaded_are_refused(tmp_path: Path, setup_text: str,
                                                      urdf: str,
                                                      fragments: tuple[str, ...]) -> None:
    (tmp_path / "odd.urdf").write_text(urdf)
    path = _write(tmp_path, setup_text.replace("type: spoon ", "type: odd.urdf ", 1))
    _assert_user_error(run_cli("show", str(path)), str(path), *fragments)


def test_a_utf16_urdf_and_a_mesh_outside_the_folder_are_refused(tmp_path: Path,
                                                                 setup_text: str) -> None:
    (tmp_path / "odd.urdf").write_bytes(MILK.encode("utf-16"))
    path = _write(tmp_path, setup_text.replace("type: spoon ", "type: odd.urdf ", 1))
    _assert_user_error(run_cli("show", str(path)), str(path), "items[0].type", "not UTF-8")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "link.stl").symlink_to("/etc/passwd")
    (tmp_path / "odd.urdf").write_text(_mesh("sub/link.stl"))
    _assert_user_error(run_cli("show", str(path)), str(path), "leads outside the URDF's folder")
    (tmp_path / "garbage.obj").write_text("not a mesh\n")  # (coal's loader: 5 lines)
    (tmp_path / "odd.urdf").write_text(_mesh("garbage.obj"))
    _assert_user_error(run_cli("show", str(path)), str(path), "garbage.obj", "Hint")
    assert "assimp.cpp" not in run_cli("show", str(path)).stderr


def test_a_chain_of_1000_links_loads(tmp_path: Path, setup_text: str) -> None:
    from cramlite.world.urdf_check import urdf_problem

    (tmp_path / "chain.urdf").write_text(_links(1000))
    assert urdf_problem(tmp_path / "chain.urdf") is None


def test_other_unreadable_setup_files(tmp_path: Path) -> None:
    folder = tmp_path / "folder.yaml"
    folder.mkdir()
    _assert_user_error(run_cli("show", str(folder)), str(folder), "not a file")
    latin = tmp_path / "latin.yaml"
    latin.write_bytes("name: caf\xe9\n".encode("latin-1"))
    _assert_user_error(run_cli("show", str(latin)), str(latin), "not UTF-8")


def test_run_and_bench_refuse_a_bad_setup_before_any_trial(tmp_path: Path,
                                                           setup_text: str) -> None:
    path = _write(tmp_path, setup_text.replace(CUP_TARGET, SPOON_TARGET).replace("name: v1",
                                                                                "name: bad"))
    _assert_user_error(run_cli("run", str(path)), "items[3].target")
    out = tmp_path / "results"
    bench = run_cli("bench", "--setups", f"v1,{path}", "--out", str(out), "--no-plots")
    _assert_user_error(bench, str(path), "items[3].target", "overlaps")
    assert not (out / "trials.csv").exists()


def test_a_setup_hash_covers_the_file_and_its_urdfs(tmp_path: Path, setup_text: str) -> None:
    from cramlite.world.setup import load_setup

    items = Path(__file__).resolve().parents[1] / "worlds" / "items"
    (tmp_path / "cup.urdf").write_text((items / "cup.urdf").read_text())
    same = _write(tmp_path, setup_text)
    assert load_setup(same).content_hash == load_setup("v1").content_hash
    moved = load_setup(_write(tmp_path, setup_text.replace(START, "start: [-0.4, -1.8, 1.5708]")))
    assert moved.content_hash != load_setup("v1").content_hash
    own_cup = load_setup(_write(tmp_path, setup_text.replace("type: cup ", "type: cup.urdf ")))
    (tmp_path / "cup.urdf").write_text((items / "cup.urdf").read_text() + "<!-- edited -->")
    edited = load_setup(_write(tmp_path, setup_text.replace("type: cup ", "type: cup.urdf ")))
    assert edited.content_hash != own_cup.content_hash


@pytest.mark.parametrize(("change", "fragments"), [
    (lambda t: t.replace("  drawer_2:", "  drawer_1:", 1), ("line 4", "'drawer_1' appears twice")),
    (lambda t: t.replace("containers:", "containers: &all", 1), ("line 2", "anchors and aliases")),
    (lambda t: t.replace("  cupboard: {", "  cupboard: {{", 1), ("line", "malformed YAML")),
    (lambda t: t.replace('"open": 0.35}', '"open": 5.0}', 1),
     ("containers.drawer_1.open", "open 5 is outside its joint's limits; expected a value "
      "from 0 to 0.35")),
])
def test_a_containers_file_is_read_by_the_setups_rules_and_refused_in_one_line(
        tmp_path: Path, setup_text: str, change, fragments) -> None:
    """(A world's containers file: a repeated container would silently replace another.)"""
    import shutil

    from tests.conftest import ROOT

    shutil.copy(ROOT / "worlds" / "kitchen.urdf", tmp_path / "kitchen.urdf")
    containers = (ROOT / "worlds" / "kitchen.containers.yaml").read_text()
    (tmp_path / "kitchen.containers.yaml").write_text(change(containers))
    path = _write(tmp_path, setup_text.replace("world: kitchen ", "world: kitchen.urdf ", 1))
    _assert_user_error(run_cli("show", str(path)), str(tmp_path / "kitchen.containers.yaml"),
                       *fragments)


def test_a_setup_written_as_a_path_is_that_file_even_with_a_shipped_name(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`./v1` and `dir/v1` name a file; only the bare name `v1` is the shipped setup."""
    from cramlite.errors import SetupError
    from cramlite.world.setup import resolve_setup_path, worlds_dir

    shipped = worlds_dir() / "setups" / "v1.yaml"
    (tmp_path / "v1").write_text(shipped.read_text())
    monkeypatch.chdir(tmp_path.parent)
    assert resolve_setup_path("v1") == shipped
    assert resolve_setup_path(f"{tmp_path.name}/v1").resolve() == (tmp_path / "v1").resolve()
    monkeypatch.chdir(tmp_path)
    assert resolve_setup_path("./v1").resolve() == (tmp_path / "v1").resolve()
    assert resolve_setup_path(str(tmp_path / "v1")) == tmp_path / "v1"
    with pytest.raises(SetupError):  # (a shipped name, as a path, is no shipped setup)
        resolve_setup_path("./v2")


def test_an_item_without_collision_geometry_is_named_once(tmp_path: Path,
                                                         setup_text: str) -> None:
    visual_only = ("<robot name='x'><link name='a'><visual><geometry><box size='0.1 0.1 0.1'/>"
                   "</geometry></visual></link></robot>")
    (tmp_path / "odd.urdf").write_text(visual_only)
    path = _write(tmp_path, setup_text.replace("type: spoon ", "type: odd.urdf ", 1))
    done = run_cli("show", str(path))
    _assert_user_error(done, str(path), "the item has no collision geometry")
    assert done.stderr.count("odd.urdf") == 1, done.stderr


def test_a_world_without_a_containers_file_names_the_file_looked_for(tmp_path: Path) -> None:
    """(It said "expected one of none (this world has none)": which file was missing?)"""
    import shutil

    shutil.copy(ROOT / "worlds" / "kitchen.urdf", tmp_path / "kitchen.urdf")
    c1 = (ROOT / "worlds" / "setups" / "c1.yaml").read_text()
    assert "world: kitchen\n" in c1
    path = _write(tmp_path, c1.replace("world: kitchen\n", "world: kitchen.urdf\n", 1))
    _assert_user_error(run_cli("show", str(path)), str(path), "items[0].in",
                       "unknown container 'drawer_1'",
                       f"no {tmp_path / 'kitchen.containers.yaml'} beside its URDF")
    # a file that lists other containers is named too
    (tmp_path / "kitchen.containers.yaml").write_text(
        (ROOT / "worlds" / "kitchen.containers.yaml").read_text())
    oven = _write(tmp_path, c1.replace("world: kitchen\n", "world: kitchen.urdf\n", 1)
                  .replace("in: drawer_1\n", "in: oven\n", 1))
    _assert_user_error(run_cli("show", str(oven)), "items[0].in", "unknown container 'oven'",
                       "drawer_1, drawer_2, cupboard",
                       f"(from {tmp_path / 'kitchen.containers.yaml'})")


@pytest.mark.parametrize(("item", "target", "fragments"), [
    # 20 cm tall, the drawer 18 cm inside (the run failed later, at the drawer)
    ("milk", "[1.4, -0.7, 0.6, 0.0]", ("items[2].target", "target of 'milk'",
                                       "does not fit in 'drawer_1'", "at most 0.18 m tall")),
    # through the drawer's back: its bounds 2 cm beyond the inside
    ("cup", "[1.56, -0.7, 0.6, 0.0]", ("items[3].target", "target of 'cup'",
                                       "does not fit in 'drawer_1'", "inside 0.30 x 0.33 m")),
    ("cup", "[1.4, -0.7, 0.6, 0.0]", ()),  # (in the middle of the drawer: it fits)
])
def test_a_target_in_a_container_is_refused_where_the_item_does_not_fit(
        tmp_path: Path, setup_text: str, item: str, target: str,
        fragments: tuple[str, ...]) -> None:
    """The same check as an item `in:` a container at the start."""
    old = {"milk": "target: [-0.85, 1.6, 0.86, 0.0]", "cup": CUP_TARGET}[item]
    assert setup_text.count(old) == 1
    path = _write(tmp_path, setup_text.replace(old, f"target: {target}"))
    done = run_cli("show", str(path), "--out", str(tmp_path / "x.png"))
    if fragments:
        _assert_user_error(done, str(path), *fragments)
    else:
        assert done.returncode == 0, done.stderr


BOWL_POSE = "pose: [1.45, -0.65, 0.85, 0.0]"
BOWL_TARGET = "target: [-0.85, 1.24, 0.86, 0.0]"


@pytest.mark.parametrize(("old", "new", "fragments"), [
    # its middle at the counter's front edge (x = 1.25: on PyBullet the bowl fell off)
    (BOWL_POSE, "pose: [1.25, -0.65, 0.85, 0.0]",
     ("items[4].pose", "item 'bowl'", "not on 'counter'", "0.000 m inside its edge",
      "expected x in [1.27, 1.83], y in [-0.93, 1.33], z = 0.85")),
    (BOWL_POSE, "pose: [1.26, -0.65, 0.85, 0.0]", ("items[4].pose", "0.010 m inside")),
    # half of it over the island's near edge (x = -0.67), or 3 cm inside it: the robot
    # may put it 3 cm from its target
    (BOWL_TARGET, "target: [-0.67, 1.24, 0.86, 0.0]",
     ("items[4].target", "target of 'bowl'", "at the edge of 'island'",
      "expected x in [-1.42, -0.72], y in [0.54, 2.89]")),
    (BOWL_TARGET, "target: [-0.7, 1.24, 0.86, 0.0]",
     ("items[4].target", "at the edge of 'island'", "0.030 m inside its edge")),
    # overhanging the edge with its centre well inside: it stands
    (BOWL_POSE, "pose: [1.28, -0.65, 0.85, 0.0]", ()),
    (BOWL_TARGET, "target: [-0.72, 1.24, 0.86, 0.0]", ()),
])
def test_an_item_stands_with_its_centre_of_mass_inside_its_surface(
        tmp_path: Path, setup_text: str, old: str, new: str,
        fragments: tuple[str, ...]) -> None:
    assert setup_text.count(old) == 1
    path = _write(tmp_path, setup_text.replace(old, new))
    done = run_cli("show", str(path), "--out", str(tmp_path / "x.png"))
    if fragments:
        _assert_user_error(done, str(path), *fragments)
    else:
        assert done.returncode == 0, done.stderr


def test_the_support_check_takes_the_centre_of_mass_and_the_yaw(tmp_path: Path,
                                                                 setup_text: str) -> None:
    """A carton whose mass is 3 cm to its +x side: at 2.5 cm from the counter's edge it
    stands with that side inward, not turned the other way."""
    import shutil

    (tmp_path / "carton.urdf").write_text(
        MILK.replace('<inertial><origin xyz="0 0 0.1000"/>',
                     '<inertial><origin xyz="0.03 0 0.1000"/>'))
    shutil.copy(ROOT_ITEMS / "milk.item.yaml", tmp_path / "carton.item.yaml")
    milk_pose = "type: milk          # worlds/items/milk.urdf\n    pose: [1.45, -0.15, 0.85, 0.0]"
    assert milk_pose in setup_text

    def at(yaw: float):
        text = setup_text.replace(milk_pose, "type: carton.urdf\n    pose: "
                                             f"[1.275, -0.15, 0.85, {yaw}]")
        return run_cli("show", str(_write(tmp_path, text)), "--out", str(tmp_path / "x.png"))

    done = at(0.0)
    assert done.returncode == 0, done.stderr
    _assert_user_error(at(3.1416), "items[2].pose", "item 'milk'", "0.005 m beyond its edge",
                       "expected x in [1.30, 1.86]")


def test_the_robot_starts_free_with_its_arms_as_a_trial_begins(tmp_path: Path,
                                                               setup_text: str) -> None:
    """A trial begins with every joint at zero (the arms stretched out forward; the plan
    parks them first): facing the counter from 0.3 m, the parked robot is free and the
    fingertips are 1.8 cm inside the counter (what `replay --check` found at t = 0)."""
    path = _write(tmp_path, setup_text.replace(START, "start: [0.3, 0.0, 0.0]"))
    _assert_user_error(run_cli("show", str(path), "--out", str(tmp_path / "x.png")),
                       str(path), "robot.start", "starts inside 'counter_body'",
                       "overlap 1.8 cm: its l_gripper_l_finger_tip_link",
                       "as a trial begins, stretched out")
    back = _write(tmp_path, setup_text.replace(START, "start: [0.25, 0.0, 0.0]"))
    done = run_cli("show", str(back), "--out", str(tmp_path / "x.png"))
    assert done.returncode == 0, done.stderr


def test_the_robot_start_check_takes_every_link_and_both_arm_poses() -> None:
    """On the planning scene itself: the robot's shapes at its start are every link's,
    parked and as a trial begins, and the grippers are where Pinocchio places them."""
    from cramlite.scene.scene import PlanningScene
    from cramlite.scene.validate import _robot_poses
    from cramlite.world.setup import load_setup

    scene = PlanningScene(load_setup("v1"))
    poses = dict(_robot_poses(scene))
    assert len(poses) == 2
    for placed in poses.values():
        assert {shape.link for shape, _ in placed} == set(scene.robot.shapes_by_link)
    stretched = next(placed for how, placed in poses.items() if "stretched" in how)
    tip = next(p for s, p in stretched if s.link == "l_gripper_l_finger_tip_link")
    start = scene.setup.robot_start  # (facing +y: the arms reach along it)
    assert tip[1, 3] - start.y > 0.8

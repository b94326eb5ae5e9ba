"""Generated hostile input (hypothesis, derandomized so a run is repeatable, bounded in
examples): whatever a setup, an ordering request, a trace, a data CSV, a trials.csv or a
URDF holds, reading it either works or raises the one error type the command line prints
as one line (exit 2); nothing else may escape (#29)."""

from __future__ import annotations

import copy
import csv
import io
import json
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cramlite.errors import UserInputError
from cramlite.resources import worlds_dir

FUZZ = settings(max_examples=60, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow,
                                       HealthCheck.function_scoped_fixture])

#: Values of every JSON/YAML kind, including the awkward ones (NaN, huge, deep, empty).
SCALARS = st.one_of(
    st.none(), st.booleans(), st.integers(min_value=-(10**30), max_value=10**30),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=20),
    st.sampled_from(["", "..", "/etc/passwd", "package://x/y.stl", "drawer_1", "counter",
                     "\x00", "²", "1e400", "nan", "-0", "kitchen", "cup", "v1"]))
VALUES = st.recursive(SCALARS, lambda inner: st.one_of(
    st.lists(inner, max_size=5), st.dictionaries(st.text(max_size=8), inner, max_size=5)),
    max_leaves=20)


def _mutated(document: Any, data: st.DataObject, edits: int = 3) -> Any:
    """`document` with a few values (anywhere in it) replaced, keys added or removed."""
    document = copy.deepcopy(document)
    for _ in range(data.draw(st.integers(1, edits))):
        paths = list(_paths(document))
        path = data.draw(st.sampled_from(paths))
        parent, key = _at(document, path)
        action = data.draw(st.sampled_from(["replace", "delete", "add"]))
        if action == "replace" or parent is None:
            if parent is None:
                document = data.draw(VALUES)
            else:
                parent[key] = data.draw(VALUES)
        elif action == "delete":
            del parent[key]
        elif isinstance(parent, dict):
            parent[data.draw(st.text(max_size=8))] = data.draw(VALUES)
        else:
            parent.append(data.draw(VALUES))
    return document


def _paths(node: Any, path: tuple = ()) -> list[tuple]:
    out = [path]
    if isinstance(node, dict):  # (and four keys of a long mapping, e.g. joint limits)
        for key, value in list(node.items())[:4 if len(node) > 12 else None]:
            out += _paths(value, (*path, key))
    elif isinstance(node, list):  # (two elements of a list: long lists of numbers would
        for i, value in enumerate(node[:2]):  # otherwise take nearly every draw)
            out += _paths(value, (*path, i))
    return out


def _at(document: Any, path: tuple) -> tuple[Any, Any]:
    if not path:
        return None, None
    node = document
    for key in path[:-1]:
        node = node[key]
    return node, path[-1]


def _one_line(exc: BaseException) -> None:
    assert isinstance(exc, UserInputError), f"{type(exc).__name__}: {exc}"
    assert str(exc).strip(), "an empty message"


# -- setups --------------------------------------------------------------------------------
V1 = yaml.safe_load((worlds_dir() / "setups" / "v1.yaml").read_text())


@FUZZ
@given(data=st.data())
def test_a_mutated_setup_loads_or_is_one_user_error(tmp_path_factory, data) -> None:
    from cramlite.world.setup import load_setup

    path = tmp_path_factory.mktemp("fuzz") / "setup.yaml"
    try:
        text = yaml.safe_dump(_mutated(V1, data), allow_unicode=True)
    except (yaml.YAMLError, ValueError):
        return  # (not representable as YAML: nothing a user could write)
    path.write_text(text, encoding="utf-8")
    try:
        load_setup(path)
    except Exception as exc:  # noqa: BLE001 - the point: which kind escapes
        _one_line(exc)


# -- ordering requests ---------------------------------------------------------------------
REQUEST = {"id": 7, "robot": [0.0, 0.0, 0.0], "strategy": "opm",
           "params": {"mid_k": 0.5}, "full_order": True,
           "items": [{"name": "cup", "position": [1.0, 0.5, 0.8], "category": "strong"},
                     {"name": "bowl", "position": [1.2, -0.5, 0.8], "contained": True}]}


@FUZZ
@given(data=st.data())
def test_a_mutated_request_is_answered_or_is_one_request_error(data) -> None:
    from cramlite.strategies.service import answer_text

    try:
        text = json.dumps(_mutated(REQUEST, data))
    except ValueError:
        return
    try:
        reply = answer_text(text)
    except Exception as exc:  # noqa: BLE001
        _one_line(exc)
    else:
        assert "next" in reply


# -- traces --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def trace_lines(tmp_path_factory) -> list[dict[str, Any]]:
    from cramlite.trial import TrialRunner

    path = tmp_path_factory.mktemp("trace") / "v1.jsonl"
    with TrialRunner("v1", backend="kinematic") as runner:
        runner.run("opm", seed=0, trace=path)
    lines = [json.loads(x) for x in path.read_text().splitlines()]
    return [lines[0], *lines[1::40]]  # (the header and a few states: quick to check)


@FUZZ
@given(data=st.data())
def test_a_mutated_trace_reads_and_checks_or_is_one_trace_error(trace_lines, tmp_path_factory,
                                                                 data) -> None:
    from cramlite.trace import read_trace
    from cramlite.trace.physics import physics_findings

    lines = copy.deepcopy(trace_lines)
    for _ in range(data.draw(st.integers(1, 2))):  # (a line: the header or a state)
        k = data.draw(st.integers(0, len(lines) - 1))
        lines[k] = _mutated(lines[k], data, edits=2)
    path = tmp_path_factory.mktemp("fuzz") / "t.jsonl"
    try:
        body = "".join(json.dumps(x, allow_nan=True) + "\n" for x in
                       (lines if isinstance(lines, list) else [lines]))
    except (ValueError, TypeError):
        return
    path.write_text(body)
    try:
        physics_findings(read_trace(path))
    except Exception as exc:  # noqa: BLE001
        _one_line(exc)


# -- data CSVs and trials.csv --------------------------------------------------------------
DATA_HEADER = ["ID", "sequence", "coordinates", "start_coordinates", "strong_k", "mid_k",
               "food_k", "containment", "error"]
DATA_ROW = ["s13-d21", "cutting_board,knife,plate", "cutting_board: (1,2,2);knife: (1,2,2);"
            "plate: (3,1,3)", "[2,2,2],[2,2,2],[1,1,2]", "cutting_board", "0", "plate",
            "knife", "0.7"]
CELLS = st.one_of(st.text(max_size=40), st.sampled_from(
    ["", "nan", "inf", "[1,2", "a: (1,2);b: (nan,1,1)", "x: (1,2,3);x: (1,2,3)", "\x00",
     "[[[[[[", "1e400", ",,,", "a: (" + "9" * 500 + ",1,1)"]))


@FUZZ
@given(cells=st.lists(st.tuples(st.integers(0, len(DATA_ROW) - 1), CELLS), max_size=4))
def test_a_mutated_data_row_loads_or_is_one_data_error(tmp_path_factory, cells) -> None:
    from cramlite.evaluation.data import load_episodes

    row = list(DATA_ROW)
    for index, value in cells:
        row[index] = value
    path = tmp_path_factory.mktemp("fuzz") / "data.csv"
    buffer = io.StringIO()
    csv.writer(buffer).writerows([DATA_HEADER, row])
    path.write_text(buffer.getvalue())
    try:
        load_episodes(path)
    except Exception as exc:  # noqa: BLE001
        _one_line(exc)


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> Path:
    from tests.conftest import run_cli

    out = tmp_path_factory.mktemp("results") / "out"
    assert run_cli("bench", "--setups", "v1", "--strategies", "opm", "--trials", "1",
                   "--backend", "kinematic", "--no-plots", "--out", str(out)).returncode == 0
    return out


@FUZZ
@given(data=st.data())
def test_a_mutated_trials_row_is_read_or_is_one_error(results, tmp_path_factory,
                                                      data) -> None:
    from cramlite.bench.store import TrialStore
    from cramlite.report.folder import read_folder

    (row,) = csv.DictReader((results / "trials.csv").open(newline=""))
    for _ in range(data.draw(st.integers(1, 3))):
        row[data.draw(st.sampled_from(list(row)))] = data.draw(CELLS)
    out = tmp_path_factory.mktemp("fuzz")
    (out / "metadata.json").write_bytes((results / "metadata.json").read_bytes())
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(row))
    writer.writeheader()
    writer.writerow(row)
    (out / "trials.csv").write_text(buffer.getvalue())
    for read in (lambda: TrialStore(out).rows(), lambda: read_folder(out)):
        try:
            read()
        except Exception as exc:  # noqa: BLE001
            _one_line(exc)


# -- URDFs ---------------------------------------------------------------------------------
TAGS = st.sampled_from(["robot", "link", "joint", "visual", "collision", "geometry", "box",
                        "mesh", "cylinder", "sphere", "origin", "inertial", "mass", "parent",
                        "child", "axis", "limit", "mimic"])
ATTRS = st.dictionaries(st.sampled_from(["name", "type", "size", "radius", "length", "xyz",
                                         "rpy", "value", "link", "filename", "scale", "lower",
                                         "upper", "velocity", "ixx"]),
                        CELLS, max_size=3)


def _xml(tag: str, attrs: dict[str, str], children: list[str]) -> str:
    from xml.sax.saxutils import quoteattr

    text = " ".join(f"{k}={quoteattr(''.join(c for c in v if c >= ' '))}"
                    for k, v in attrs.items())
    return f"<{tag} {text}>{''.join(children)}</{tag}>"


ELEMENTS = st.recursive(st.builds(_xml, TAGS, ATTRS, st.just([])),
                        lambda inner: st.builds(_xml, TAGS, ATTRS, st.lists(inner, max_size=4)),
                        max_leaves=15)


@FUZZ
@given(body=st.lists(ELEMENTS, max_size=6))
def test_a_generated_urdf_is_accepted_or_refused_in_one_line(tmp_path_factory, body) -> None:
    from cramlite.world.urdf_check import urdf_problem

    path = tmp_path_factory.mktemp("fuzz") / "x.urdf"
    path.write_text(f"<robot name='x'>{''.join(body)}</robot>")
    problem = urdf_problem(path)
    assert problem is None or (problem.strip() and "\n" not in problem)

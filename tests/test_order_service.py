"""`cramlite order`: the OPM as a JSON service, and every malformed request."""

from __future__ import annotations

import json

import pytest

from cramlite.strategies.service import RequestError, answer
from tests.conftest import run_cli

GOOD = {"robot": [-0.5, -1.8, 0.0], "items": [
    {"name": "bowl", "position": [1.45, -0.65, 0.85], "category": "mid"},
    {"name": "cup", "position": [1.45, 0.85, 0.85]},
    {"name": "milk", "position": [1.45, -0.15, 0.85], "c": 1.0},
    {"name": "cereal", "position": [-0.85, 1.75, 0.86], "k": 1.0, "contained": False}],
    "strategy": "opm", "params": {"mid_k": 0.3}, "dims": "xy", "form": "power", "seed": 0}


def test_reply_by_hand() -> None:
    reply = answer(GOOD)
    assert reply["next"] == "bowl"
    # bowl: d = sqrt(1.95^2 + 1.15^2), k = 0.3 -> d^0.3 = (d^2)^0.15
    assert reply["costs"]["bowl"] == pytest.approx((1.95**2 + 1.15**2) ** 0.15)
    assert reply["costs"]["cup"] == pytest.approx((1.95**2 + 2.65**2) ** 0.5)
    # agent moves to each chosen item: bowl -> milk (0.5 m) -> cup (1.0 m) -> cereal
    assert reply["order"] == ["bowl", "milk", "cup", "cereal"]
    with_then = answer({**GOOD, "then_at": [-0.3, 1.5, 0.0]})
    assert with_then["order"] == ["bowl", "cereal", "cup", "milk"]


def test_cli_reads_file_and_stdin(tmp_path) -> None:
    path = tmp_path / "req.json"
    path.write_text(json.dumps(GOOD))
    from_file = run_cli("order", str(path))
    from_stdin = run_cli("order", "-", stdin=json.dumps(GOOD))
    assert from_file.returncode == from_stdin.returncode == 0
    assert json.loads(from_file.stdout) == json.loads(from_stdin.stdout) == answer(GOOD)


def _bad(**changes):
    req = json.loads(json.dumps(GOOD))
    for key, value in changes.items():
        if value is _DROP:
            req.pop(key)
        else:
            req[key] = value
    return req


_DROP = object()


def _item(i: int, **changes):
    items = json.loads(json.dumps(GOOD["items"]))
    for key, value in changes.items():
        if value is _DROP:
            items[i].pop(key)
        else:
            items[i][key] = value
    return items


@pytest.mark.parametrize(("request_", "field"), [
    ([1, 2], "(request)"),
    (_bad(robot=_DROP), "robot"),
    (_bad(robot=[0, 0]), "robot"),
    (_bad(robot=[0, "a", 0]), "robot"),
    (_bad(items=[]), "items"),
    (_bad(items="bowl"), "items"),
    (_bad(items=[5]), "items[0]"),
    (_bad(items=_item(1, name=_DROP)), "items[1].name"),
    (_bad(items=_item(1, name="bowl")), "items[1].name"),
    (_bad(items=_item(2, position=_DROP)), "items[2].position"),
    (_bad(items=_item(2, position=[1, 2, 3, 4])), "items[2].position"),
    (_bad(items=_item(0, category="utensil")), "items[0].category"),
    (_bad(items=_item(0, k="low")), "items[0].k"),
    (_bad(items=_item(0, c=None, contained="yes")), "items[0].contained"),
    (_bad(items=_item(0, c=True)), "items[0].c"),
    (_bad(items=_item(0, colour="red")), "items[0].colour"),
    (_bad(strategy="greedy"), "strategy"),
    (_bad(strategy=3), "strategy"),
    (_bad(params={"strong": 0.2}), "params.strong"),
    (_bad(params={"mid_k": "x"}), "params.mid_k"),
    (_bad(params=[0.2]), "params"),
    (_bad(dims="xyzw"), "dims"),
    (_bad(form="exp"), "form"),
    (_bad(seed=-1), "seed"),
    (_bad(seed=1.5), "seed"),
    (_bad(then_at=[0, 0]), "then_at"),
    (_bad(extra=1), "extra"),
])
def test_malformed_requests_name_the_field(request_, field: str) -> None:
    with pytest.raises(RequestError) as info:
        answer(request_)
    print(info.value)
    assert info.value.field == field


def test_cli_malformed_request_exits_2_with_one_line() -> None:
    result = run_cli("order", "-", stdin=json.dumps(_bad(dims="xyzw")))
    assert result.returncode == 2
    assert result.stdout == ""
    line = result.stderr.strip()
    assert len(line.splitlines()) == 1 and "dims" in line and "xyz" in line
    broken = run_cli("order", "-", stdin="{not json")
    assert broken.returncode == 2 and "not valid JSON" in broken.stderr
    missing = run_cli("order", "/no/such.json")
    assert missing.returncode == 2 and "/no/such.json" in missing.stderr
    assert "Traceback" not in broken.stderr + missing.stderr

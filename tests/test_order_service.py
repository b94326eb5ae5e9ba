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
    (_bad(strategy="baseline", params={"c": 2.0}), "params"),  # (it would ignore them)
    (_bad(strategy="nearest", params={"mid_k": 0.3}), "params"),
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


# -- hardening: every odd request is a clean error naming its field -----------------------
def _strict(text: str):
    """Parse as strict JSON: NaN and Infinity are not JSON."""
    def refuse(constant: str):
        raise ValueError(f"non-standard JSON constant {constant}")
    return json.loads(text, parse_constant=refuse)


def _deep(depth: int) -> str:
    return '{"robot": [0, 0, 0], "items": ' + "[" * depth + "]" * depth + "}"


@pytest.mark.parametrize(("text", "field", "fragment"), [
    (json.dumps(_bad(dims=["x", "y"])), "dims", "expected one of"),
    (json.dumps(_bad(form=["power"])), "form", "expected one of"),
    (json.dumps(_bad(items=_item(0, category=["mid"]))), "items[0].category", "expected one of"),
    (json.dumps(_bad(items=_item(0, k=1e308))), "items[0].k", "in [0, 10]"),
    (json.dumps(_bad(items=_item(0, k=-0.5))), "items[0].k", "in [0, 10]"),
    (json.dumps(_bad(items=_item(0, c=-1))), "items[0].c", "in (0, 1000]"),
    (json.dumps(_bad(items=_item(0, c=0))), "items[0].c", "in (0, 1000]"),
    (json.dumps(_bad(items=_item(0, k=10**400))), "items[0].k", "401 digits"),
    (json.dumps(_bad(robot=[10**400, 0, 0])), "robot", "401 digits"),
    (json.dumps(_bad(robot=[1e300, 0, 0])), "robot", "within +-1e+06 m"),
    (json.dumps(_bad(then_at=[0, -1e7, 0])), "then_at", "within"),
    (json.dumps(_bad(seed=10**30)), "seed", "[0, 2^64 - 1]"),
    (json.dumps(_bad(params={"c": -1})), "params.c", "in (0, 1000]"),
    (json.dumps(_bad(params={"strong_k": -0.1})), "params.strong_k", "in [0, 10]"),
    (json.dumps(_bad(params={"food_k": 1e308})), "params.food_k", "in [0, 10]"),
    (json.dumps(_bad(weights=[1, -1, 0])), "weights", "[0, 1000]"),
    (json.dumps(_bad(weights=[0, 0, 0])), "weights", "not all 0"),
    (json.dumps(_bad(weights="spam")), "weights", "span"),
    (json.dumps(_bad(full_order="yes")), "full_order", "true or false"),
    (json.dumps(_bad(id=[1])), "id", "string"),
    (json.dumps(_bad(strategy="pathlib:Path")), "strategy", "not a registered strategy"),
    (json.dumps(_bad(strategy="os:system")), "strategy", "not a registered strategy"),
    (json.dumps(_bad(items=_item(0, name="x" * 300))), "items[0].name", "at most 256"),
    ('{"robot": [0, 0, 0], "params": {"mid_k": NaN}, "items": [{"name": "a", '
     '"position": [1, 0, 0]}]}', "params.mid_k", "finite"),
    ('{"robot": [0, 0, Infinity], "items": [{"name": "a", "position": [1, 0, 0]}]}',
     "robot", "within"),
    ('{"robot": [0, 0, 0], "items": [{"name": "a", "position": [NaN, 0, 0]}]}',
     "items[0].position", "within"),
    ('{"robot": [0, 0, 0], "seed": ' + "9" * 5000 + ', "items": []}', None,
     "not a usable request"),
    (_deep(100_000), None, "nested too deeply"),
    (b'\xff\xfe{"robot": [0, 0, 0]}', None, "not UTF-8 text"),
])
def test_odd_requests_are_refused_naming_the_field(text: str | bytes, field: str | None,
                                                   fragment: str) -> None:
    from cramlite.strategies.service import answer_text

    with pytest.raises(RequestError) as info:
        answer_text(text, "<stdin>")
    print(info.value)
    assert info.value.field == field
    assert fragment in str(info.value)


@pytest.mark.parametrize(("params", "fragment"), [
    ("c=-1", "c: expected a finite number in (0, 1000]"),
    ("mid_k=nan", "mid_k: expected a finite number in [0, 10]"),
    ("strong_k=1e308", "strong_k: expected a finite number in [0, 10]"),
])
def test_negative_or_nan_params_on_the_command_line_exit_2(params: str, fragment: str) -> None:
    result = run_cli("run", "v1", "--params", params)
    print(result.stderr)
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert result.stderr.strip() == f"cramlite run: error: --params: {fragment}, got " \
        f"{float(params.split('=')[1])!r}"


def test_replies_are_strict_json_even_far_away() -> None:
    far = {"robot": [1e6, -1e6, 1e6], "params": {"c": 1000, "mid_k": 10},
           "items": [{"name": "a", "position": [-1e6, 1e6, -1e6], "k": 10, "c": 1000},
                     {"name": "b", "position": [-1e6, 1e6, 0], "category": "mid",
                      "contained": True}],
           "form": "power", "dims": "xyz"}
    result = run_cli("order", "-", stdin=json.dumps(far))
    assert result.returncode == 0, result.stderr
    reply = _strict(result.stdout)
    assert reply["next"] == "b" and all(v < 1e70 for v in reply["costs"].values())


def test_a_query_is_linear_and_the_full_order_has_a_documented_limit() -> None:
    from cramlite.strategies.service import MAX_ITEMS, MAX_ORDER_ITEMS

    items = [{"name": f"i{n}", "position": [n % 997 / 10, n // 997 / 10, 0]}
             for n in range(MAX_ITEMS)]
    request = {"robot": [50, 5, 0], "items": items, "full_order": False}
    reply = answer(request)
    assert set(reply) == {"next", "costs"} and len(reply["costs"]) == MAX_ITEMS
    assert reply["next"] == min(reply["costs"], key=reply["costs"].get)
    with pytest.raises(RequestError, match="full_order"):
        answer({**request, "full_order": True, "items": items[:MAX_ORDER_ITEMS + 1]})
    assert len(answer({**request, "full_order": True,
                       "items": items[:MAX_ORDER_ITEMS]})["order"]) == MAX_ORDER_ITEMS
    with pytest.raises(RequestError, match=f"at most {MAX_ITEMS}"):
        answer({**request, "items": items + [{"name": "x", "position": [0, 0, 0]}]})


def test_the_reply_echoes_the_id() -> None:
    assert answer({**GOOD, "id": "r-17"})["id"] == "r-17"
    assert answer({**GOOD, "id": 17})["id"] == 17
    assert "id" not in answer(GOOD)


# -- the service: one request per line, one reply per line ---------------------------------
def _serve(*extra: str):
    import subprocess
    import sys

    from tests.conftest import ROOT

    return subprocess.Popen([sys.executable, "-m", "cramlite", "order", "--serve", *extra],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, bufsize=1, cwd=ROOT)


def test_serve_answers_line_by_line_and_survives_bad_lines() -> None:
    service = _serve()
    try:
        def ask(line: str) -> dict:
            service.stdin.write(line + "\n")
            service.stdin.flush()
            reply = service.stdout.readline()  # blocks until the reply is flushed
            print(line[:60], "->", reply.strip()[:120])
            return _strict(reply)

        assert ask(json.dumps({**GOOD, "id": 1})) == {"id": 1, **answer(GOOD)}
        error = ask("{not json")
        assert error["field"] == "(request)" and "not valid JSON" in error["error"]
        error = ask(json.dumps({**_bad(dims=["x"]), "id": "two"}))
        assert error == {"id": "two", "field": "dims",
                         "error": "dims: expected one of x, y, z, xy, xz, yz, xyz, got a "
                                  "list of 1 value(s)"}
        assert ask("")["field"] == "(request)"
        assert ask(json.dumps(_bad(robot=[1e300, 0, 0])))["field"] == "robot"
        assert ask(_deep(100_000))["error"].endswith("nested too deeply)")
        assert ask(json.dumps({**GOOD, "id": 3}))["next"] == "bowl"  # still serving
        service.stdin.close()
        assert service.wait(timeout=30) == 0
        assert service.stdout.read() == "" and service.stderr.read() == ""
    finally:
        service.kill()


def test_serve_uses_the_command_line_strategy_and_refuses_a_file() -> None:
    service = _serve("--strategy", "nearest")
    out, err = service.communicate(json.dumps({**GOOD, "strategy": None}) + "\n", timeout=60)
    assert _strict(out)["costs"]["bowl"] == pytest.approx((1.95**2 + 1.15**2) ** 0.5)
    with_file = run_cli("order", "--serve", "request.json")
    assert with_file.returncode == 2 and "--serve" in with_file.stderr
    unknown = run_cli("order", "--serve", "--strategy", "greedy", stdin="")
    assert unknown.returncode == 2 and "greedy" in unknown.stderr


def test_closed_output_pipe_ends_quietly(tmp_path) -> None:
    import subprocess
    import sys

    from tests.conftest import ROOT

    big = {"robot": [0, 0, 0], "full_order": False,
           "items": [{"name": f"item-{n}", "position": [n, 0, 0]} for n in range(50_000)]}
    (tmp_path / "big.json").write_text(json.dumps(big))
    shell = subprocess.run(
        f"'{sys.executable}' -m cramlite order '{tmp_path / 'big.json'}' 2>'{tmp_path}/err' "
        "| head -c 10", shell=True, capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert shell.stdout == '{"next": "'
    assert (tmp_path / "err").read_text() == ""
    for args, stdin in ((["order", "-"], json.dumps(GOOD)),
                        (["order", "--serve"], (json.dumps(GOOD) + "\n") * 2000)):
        proc = subprocess.Popen([sys.executable, "-m", "cramlite", *args], cwd=ROOT,
                                stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        proc.stdout.close()  # the reader went away before the first reply
        _, err = proc.communicate(stdin, timeout=120)
        print(args, proc.returncode, err)
        assert err == "" and proc.returncode == 141

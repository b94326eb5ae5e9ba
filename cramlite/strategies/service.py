"""The ordering service without ROS: a JSON request in, a JSON reply out.

Request (see `cramlite order --help`):
    {"robot": [x, y, z], "items": [{"name": ..., "position": [x, y, z],
      "k": 0.3 | "category": "mid", "c": 1.7 | "contained": true}, ...],
     "strategy": "opm", "params": {...}, "dims": "xy", "form": "power", "seed": 0,
     "then_at": [x, y, z]}
Reply: {"next": NAME, "costs": {NAME: cost}, "order": [NAME, ...]} where `order` repeats
the query, the agent moving to `then_at` after each item if given, else to the item.
"""

from __future__ import annotations

import json
import math
from typing import Any

from cramlite.errors import UserInputError
from cramlite.strategies.base import StrategyError
from cramlite.strategies.candidates import CATEGORIES, Candidate, OPMParams
from cramlite.strategies.cost import DIMS, FORMS
from cramlite.strategies.registry import make_strategy

REQUEST_KEYS = {"robot", "items", "strategy", "params", "dims", "form", "seed", "then_at",
                "weights"}
ITEM_KEYS = {"name", "position", "k", "category", "c", "contained", "then_at"}


class RequestError(UserInputError):
    """A malformed ordering request."""


def _fail(field: str, message: str) -> RequestError:
    return RequestError(message, field=field)


def _point(value: Any, field: str) -> tuple[float, float, float]:
    if (not isinstance(value, list) or len(value) != 3
            or not all(_is_number(v) for v in value)):
        raise _fail(field, f"expected [x, y, z] (3 finite numbers), got {json.dumps(value)}")
    return (float(value[0]), float(value[1]), float(value[2]))


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def parse_request(request: Any) -> dict[str, Any]:
    """Validate a decoded request; every problem names its field."""
    if not isinstance(request, dict):
        raise _fail("(request)", "expected a JSON object with 'robot' and 'items'")
    unknown = sorted(set(request) - REQUEST_KEYS)
    if unknown:
        raise _fail(unknown[0], f"unknown field; expected some of {sorted(REQUEST_KEYS)}")
    if "robot" not in request:
        raise _fail("robot", "missing; expected [x, y, z]")
    robot = _point(request["robot"], "robot")
    then_at = _point(request["then_at"], "then_at") if request.get("then_at") is not None \
        else None
    items = request.get("items")
    if not isinstance(items, list) or not items:
        raise _fail("items", "expected a non-empty list of items")
    candidates, names = [], set()
    for i, item in enumerate(items):
        where = f"items[{i}]"
        if not isinstance(item, dict):
            raise _fail(where, "expected an object with 'name' and 'position'")
        extra = sorted(set(item) - ITEM_KEYS)
        if extra:
            raise _fail(f"{where}.{extra[0]}", f"unknown field; expected some of "
                                               f"{sorted(ITEM_KEYS)}")
        name = item.get("name")
        if not isinstance(name, str) or not name:
            raise _fail(f"{where}.name", f"expected a non-empty string, got {json.dumps(name)}")
        if name in names:
            raise _fail(f"{where}.name", f"duplicate item name {name!r}; names must be unique")
        names.add(name)
        if "position" not in item:
            raise _fail(f"{where}.position", "missing; expected [x, y, z]")
        position = _point(item["position"], f"{where}.position")
        k = item.get("k")
        if k is not None and not _is_number(k):
            raise _fail(f"{where}.k", f"expected a number, got {json.dumps(k)}")
        category = item.get("category", "none")
        if category not in CATEGORIES:
            raise _fail(f"{where}.category", f"expected one of {', '.join(CATEGORIES)}, "
                                             f"got {json.dumps(category)}")
        c = item.get("c")
        if c is not None and not _is_number(c):
            raise _fail(f"{where}.c", f"expected a number, got {json.dumps(c)}")
        contained = item.get("contained", False)
        if not isinstance(contained, bool):
            raise _fail(f"{where}.contained", f"expected true or false, got "
                                              f"{json.dumps(contained)}")
        item_then = (_point(item["then_at"], f"{where}.then_at")
                     if item.get("then_at") is not None else then_at)
        candidates.append(Candidate(name=name, position=position, category=category,
                                    contained=contained, k=k, c=c, then_at=item_then))
    strategy = request.get("strategy", "opm")
    if not isinstance(strategy, str):
        raise _fail("strategy", f"expected a strategy name, got {json.dumps(strategy)}")
    params = request.get("params") or {}
    if not isinstance(params, dict):
        raise _fail("params", f"expected an object like {{\"mid_k\": 0.3}}, got "
                              f"{json.dumps(params)}")
    for key, value in params.items():
        if key not in OPMParams.names():
            raise _fail(f"params.{key}", f"unknown parameter; expected some of "
                                         f"{', '.join(OPMParams.names())}")
        if not _is_number(value):
            raise _fail(f"params.{key}", f"expected a number, got {json.dumps(value)}")
    dims = request.get("dims", "xy")
    if dims not in DIMS:
        raise _fail("dims", f"expected one of {', '.join(DIMS)}, got {json.dumps(dims)}")
    form = request.get("form", "power")
    if form not in FORMS:
        raise _fail("form", f"expected one of {', '.join(FORMS)}, got {json.dumps(form)}")
    weights = request.get("weights")
    if weights is not None and weights != "span":
        weights = _point(weights, "weights")
    seed = request.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise _fail("seed", f"expected a non-negative integer, got {json.dumps(seed)}")
    return {"robot": robot, "candidates": candidates, "strategy": strategy, "params": params,
            "dims": dims, "form": form, "weights": weights, "seed": seed, "then_at": then_at}


def answer(request: Any) -> dict[str, Any]:
    """The reply to an ordering request."""
    req = parse_request(request)
    try:
        strategy = make_strategy(req["strategy"], params=req["params"], dims=req["dims"],
                                 form=req["form"], axis_weights=req["weights"], rng=req["seed"])
    except StrategyError as exc:
        raise _fail("strategy" if "strategy" in str(exc) else "params", str(exc)) from None
    candidates, agent = list(req["candidates"]), req["robot"]
    strategy.reset(candidates, agent)
    values = strategy.costs(candidates, agent)
    costs = {} if values is None else {c.name: v for c, v in zip(candidates, values,
                                                                 strict=True)}
    order, remaining = [], list(candidates)
    try:
        while remaining:
            chosen = strategy.choose(remaining, agent)
            order.append(chosen.name)
            remaining.remove(chosen)
            agent = req["then_at"] if req["then_at"] is not None else chosen.position
    except StrategyError as exc:
        raise _fail("items", str(exc)) from None
    return {"next": order[0], "costs": costs, "order": order}


def answer_text(text: str, source: str = "request") -> dict[str, Any]:
    try:
        request = json.loads(text)
    except json.JSONDecodeError as exc:
        raise RequestError(f"not valid JSON ({exc.msg} at line {exc.lineno} column "
                           f"{exc.colno})", source=source) from None
    try:
        return answer(request)
    except RequestError as exc:
        exc.source = source
        raise RequestError(exc.detail, source=source, field=exc.field) from None

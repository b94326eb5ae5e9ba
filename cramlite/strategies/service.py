"""The ordering service without ROS: a JSON request in, a JSON reply out.

Request (see `cramlite order --help`):
    {"robot": [x, y, z], "items": [{"name": ..., "position": [x, y, z],
      "k": 0.3 | "category": "mid", "c": 1.7 | "contained": true}, ...],
     "strategy": "opm", "params": {...}, "dims": "xy", "form": "power", "seed": 0,
     "then_at": [x, y, z], "weights": [wx, wy, wz] | "span", "full_order": true,
     "capacity": 2, "id": ...}
Reply: {"next": NAME, "costs": {NAME: cost}, "order": [NAME, ...]} where `order` repeats
the query, the agent moving to `then_at` after each item if given, else to the item
(`"full_order": false` leaves it out). With "capacity": N the reply adds "batch": the
items to carry together next, in fetch order (the strategy's `choose_batch`; "next" is
as without it). A request's `id` is echoed in its reply.

Limits, so that every request is answered quickly and every reply is strict JSON:
coordinates within +-MAX_COORDINATE_M, k in K_RANGE, c in C_RANGE, weights in
[0, MAX_WEIGHT]; at most MAX_ITEMS items, of which a full order covers at most
MAX_ORDER_ITEMS (each step of it is a query over the remaining items, so it costs
O(n^2)); the next item and the costs alone take time linear in the number of items.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from typing import IO, Any

from cramlite.errors import UserInputError
from cramlite.strategies.base import (
    MAX_COORDINATE_M,
    StrategyError,
    checked_batch,
    checked_choice,
    parameter_problem,
    strategy_label,
)
from cramlite.strategies.candidates import CATEGORIES, Candidate, OPMParams
from cramlite.strategies.cost import DIMS, FORMS
from cramlite.strategies.registry import ignores_params, make_strategy

REQUEST_KEYS = {"robot", "items", "strategy", "params", "dims", "form", "seed", "then_at",
                "weights", "full_order", "id", "capacity"}
ITEM_KEYS = {"name", "position", "k", "category", "c", "contained", "then_at"}
#: Most items one request may hold, and most for which the full order is computed.
MAX_ITEMS = 100_000
MAX_ORDER_ITEMS = 200
#: Longest request line `--serve` reads (larger lines get an error reply).
MAX_REQUEST_BYTES = 32 * 1024 * 1024
MAX_NAME_CHARS = 256
MAX_WEIGHT = 1000.0
MAX_SEED = 2**64 - 1
#: Most items one batch request may ask to carry together.
MAX_CAPACITY = 16


class RequestError(UserInputError):
    """A malformed ordering request."""


def _fail(field: str, message: str) -> RequestError:
    return RequestError(message, field=field)


def _show(value: Any) -> str:
    """A short rendering of a (possibly huge or deeply nested) JSON value for messages."""
    if isinstance(value, dict):
        return f"an object with {len(value)} field(s)"
    if isinstance(value, list):
        return f"a list of {len(value)} value(s)"
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**15:
        return f"an integer with {len(str(abs(value)))} digits"
    text = json.dumps(value) if not isinstance(value, float) or math.isfinite(value) \
        else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def _coordinate(v: Any) -> bool:
    """A finite number within +-MAX_COORDINATE_M (ints compared exactly, however big)."""
    if not _is_number(v):
        return False
    return abs(v) <= MAX_COORDINATE_M if isinstance(v, int) else \
        (math.isfinite(v) and abs(v) <= MAX_COORDINATE_M)


def _point(value: Any, field: str) -> tuple[float, float, float]:
    if isinstance(value, list) and len(value) == 3 and all(map(_coordinate, value)):
        return (float(value[0]), float(value[1]), float(value[2]))
    shown = ("[" + ", ".join(map(_show, value)) + "]" if isinstance(value, list)
             and len(value) <= 4 else _show(value))
    raise _fail(field, f"expected [x, y, z] (3 numbers within +-{MAX_COORDINATE_M:g} m), "
                       f"got {shown}")


def _param(value: Any, field: str, kind: str) -> float:
    problem = parameter_problem(kind, value)
    if problem:
        raise _fail(field, problem)
    return float(value)


def _weights(value: Any) -> tuple[float, float, float] | str | None:
    if value is None or value == "span":
        return value
    ok = (isinstance(value, list) and len(value) == 3
          and all(_is_number(w) and (isinstance(w, int) or math.isfinite(w))
                  and 0 <= w <= MAX_WEIGHT for w in value)
          and any(w > 0 for w in value))
    if not ok:
        raise _fail("weights", f"expected \"span\" or [wx, wy, wz]: 3 numbers in "
                               f"[0, {MAX_WEIGHT:g}], not all 0; got {_show(value)}")
    return (float(value[0]), float(value[1]), float(value[2]))


def _item(item: Any, where: str, then_at: tuple[float, float, float] | None) -> Candidate:
    if not isinstance(item, dict):
        raise _fail(where, f"expected an object with 'name' and 'position', got {_show(item)}")
    extra = sorted(set(item) - ITEM_KEYS)
    if extra:
        raise _fail(f"{where}.{extra[0]}", f"unknown field; expected some of "
                                           f"{sorted(ITEM_KEYS)}")
    name = item.get("name")
    if not isinstance(name, str) or not name or len(name) > MAX_NAME_CHARS:
        raise _fail(f"{where}.name", f"expected a non-empty string of at most "
                                     f"{MAX_NAME_CHARS} characters, got {_show(name)}")
    if "position" not in item:
        raise _fail(f"{where}.position", "missing; expected [x, y, z]")
    position = _point(item["position"], f"{where}.position")
    k = item.get("k")
    if k is not None:
        k = _param(k, f"{where}.k", "k")
    category = item.get("category", "none")
    if not isinstance(category, str) or category not in CATEGORIES:
        raise _fail(f"{where}.category", f"expected one of {', '.join(CATEGORIES)}, "
                                         f"got {_show(category)}")
    c = item.get("c")
    if c is not None:
        c = _param(c, f"{where}.c", "c")
    contained = item.get("contained", False)
    if not isinstance(contained, bool):
        raise _fail(f"{where}.contained", f"expected true or false, got {_show(contained)}")
    item_then = (_point(item["then_at"], f"{where}.then_at")
                 if item.get("then_at") is not None else then_at)
    return Candidate(name=name, position=position, category=category, contained=contained,
                     k=k, c=c, then_at=item_then)


def request_id(request: Any) -> Any:
    """The request's `id` if it has a usable one (echoed in replies, errors included)."""
    if not isinstance(request, dict):
        return None
    rid = request.get("id")
    if isinstance(rid, str) and len(rid) <= MAX_NAME_CHARS:
        return rid
    if isinstance(rid, int) and not isinstance(rid, bool) and abs(rid) <= MAX_SEED:
        return rid
    return None


def parse_request(request: Any) -> dict[str, Any]:
    """Validate a decoded request; every problem names its field."""
    if not isinstance(request, dict):
        raise _fail("(request)", f"expected a JSON object with 'robot' and 'items', got "
                                 f"{_show(request)}")
    unknown = sorted(set(request) - REQUEST_KEYS)
    if unknown:
        raise _fail(unknown[0], f"unknown field; expected some of {sorted(REQUEST_KEYS)}")
    if "id" in request and request["id"] is not None and request_id(request) is None:
        raise _fail("id", f"expected a string of at most {MAX_NAME_CHARS} characters or an "
                          f"integer, got {_show(request['id'])}")
    if "robot" not in request:
        raise _fail("robot", "missing; expected [x, y, z]")
    robot = _point(request["robot"], "robot")
    then_at = _point(request["then_at"], "then_at") if request.get("then_at") is not None \
        else None
    full_order = request.get("full_order", True)
    if not isinstance(full_order, bool):
        raise _fail("full_order", f"expected true or false, got {_show(full_order)}")
    items = request.get("items")
    if not isinstance(items, list) or not items:
        raise _fail("items", f"expected a non-empty list of items, got {_show(items)}")
    if len(items) > MAX_ITEMS:
        raise _fail("items", f"{len(items)} items; expected at most {MAX_ITEMS}")
    if full_order and len(items) > MAX_ORDER_ITEMS:
        raise _fail("items", f"{len(items)} items; a full order is computed for at most "
                             f"{MAX_ORDER_ITEMS} (each step repeats the query); send "
                             "\"full_order\": false for the next item and the costs alone "
                             f"(linear time, up to {MAX_ITEMS} items)")
    candidates, names = [], set()
    for i, item in enumerate(items):
        candidate = _item(item, f"items[{i}]", then_at)
        if candidate.name in names:
            raise _fail(f"items[{i}].name", f"duplicate item name {candidate.name!r}; names "
                                            "must be unique")
        names.add(candidate.name)
        candidates.append(candidate)
    strategy = request.get("strategy")
    if strategy is not None and (not isinstance(strategy, str) or not strategy):
        raise _fail("strategy", f"expected a strategy name, got {_show(strategy)}")
    params = request.get("params") or {}
    if not isinstance(params, dict):
        raise _fail("params", f"expected an object like {{\"mid_k\": 0.3}}, got "
                              f"{_show(params)}")
    checked = {}
    for key, value in params.items():
        if key not in OPMParams.names():
            raise _fail(f"params.{key}", f"unknown parameter; expected some of "
                                         f"{', '.join(OPMParams.names())}")
        checked[key] = _param(value, f"params.{key}", key)
    dims = request.get("dims", "xy")
    if not isinstance(dims, str) or dims not in DIMS:
        raise _fail("dims", f"expected one of {', '.join(DIMS)}, got {_show(dims)}")
    form = request.get("form", "power")
    if not isinstance(form, str) or form not in FORMS:
        raise _fail("form", f"expected one of {', '.join(FORMS)}, got {_show(form)}")
    weights = _weights(request.get("weights"))
    seed = request.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed <= MAX_SEED:
        raise _fail("seed", f"expected an integer in [0, 2^64 - 1], got {_show(seed)}")
    capacity = request.get("capacity")
    if capacity is not None and (not isinstance(capacity, int) or isinstance(capacity, bool)
                                 or not 1 <= capacity <= MAX_CAPACITY):
        raise _fail("capacity", f"expected an integer in [1, {MAX_CAPACITY}] (items carried "
                                f"together, e.g. 2: one per hand), got {_show(capacity)}")
    return {"robot": robot, "candidates": candidates, "strategy": strategy, "params": checked,
            "dims": dims, "form": form, "weights": weights, "seed": seed, "then_at": then_at,
            "full_order": full_order, "id": request_id(request), "capacity": capacity}


def answer(request: Any, default_strategy: str = "opm") -> dict[str, Any]:
    """The reply to an ordering request. A request may name only registered strategies;
    `default_strategy` (given on the command line) is used when it names none, and may be
    any strategy the command line accepts."""
    req = parse_request(request)
    name = req["strategy"] or default_strategy

    def made() -> Any:
        try:
            # (a request that names a strategy and gives it parameters it would ignore; one
            # that names none gets the server's, whatever parameters its client sends)
            if req["params"] and req["strategy"] and ignores_params(
                    name, registered_only=name != default_strategy):
                raise _fail("params", f"strategy {name!r} takes no parameters (these are the "
                                      "OPM's: e.g. \"strategy\": \"opm\")")
            return make_strategy(name, registered_only=name != default_strategy,
                                 params=req["params"], dims=req["dims"], form=req["form"],
                                 axis_weights=req["weights"], rng=req["seed"])
        except StrategyError as exc:
            raise _fail("strategy", str(exc)) from None

    strategy = made()
    candidates, agent = req["candidates"], req["robot"]
    reply: dict[str, Any] = {} if req["id"] is None else {"id": req["id"]}
    try:
        if req["capacity"] is not None:  # (its own instance: "next" stays as without it)
            batcher = made()
            batcher.reset(candidates, agent)
            reply["batch"] = [c.name for c in checked_batch(batcher, candidates, agent,
                                                              req["capacity"])]
        strategy.reset(candidates, agent)
        values = strategy.costs(candidates, agent)
        if not req["full_order"]:
            reply["next"] = checked_choice(strategy, candidates, agent).name
            reply["costs"] = _costs(candidates, values)
            return reply
        order, remaining = [], list(candidates)
        while remaining:
            chosen = checked_choice(strategy, remaining, agent)
            order.append(chosen.name)
            remaining.remove(chosen)
            agent = req["then_at"] if req["then_at"] is not None else chosen.position
    except StrategyError as exc:
        raise _fail("strategy", str(exc)) from None
    except Exception as exc:  # a plugin's reset or costs failed
        raise _fail("strategy", f"strategy {strategy_label(strategy)} raised "
                                f"{type(exc).__name__}: {exc}") from None
    reply.update(next=order[0], costs=_costs(candidates, values), order=order)
    return reply


def _costs(candidates: list[Candidate], values: list[float] | None) -> dict[str, float]:
    if values is None:
        return {}
    costs = {c.name: float(v) for c, v in zip(candidates, values, strict=True)}
    bad = next((n for n, v in costs.items() if not math.isfinite(v)), None)
    if bad is not None:  # the limits should prevent it; a reply is strict JSON regardless
        raise _fail("items", f"the cost of {bad!r} is not a finite number")
    return costs


def decode(text: str | bytes, source: str = "request") -> Any:
    """JSON text to a value; anything that is not valid JSON is a RequestError."""
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise RequestError(f"not UTF-8 text (byte {exc.start}); expected a JSON object",
                               source=source) from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise RequestError(f"not valid JSON ({exc.msg} at line {exc.lineno} column "
                           f"{exc.colno})", source=source) from None
    except RecursionError:
        raise RequestError("not a usable request (nested too deeply)", source=source) from None
    except ValueError as exc:  # e.g. an integer of 5,000 digits
        raise RequestError(f"not a usable request ({exc})", source=source) from None


def encode(reply: dict[str, Any]) -> str:
    """Strict JSON (never NaN or Infinity), one line."""
    return json.dumps(reply, allow_nan=False, separators=(", ", ": "))


def answer_text(text: str | bytes, source: str = "request",
                default_strategy: str = "opm") -> dict[str, Any]:
    request = decode(text, source)
    try:
        return answer(request, default_strategy)
    except RequestError as exc:
        raise RequestError(exc.detail, source=source, field=exc.field) from None


def error_reply(exc: RequestError, rid: Any = None) -> dict[str, Any]:
    reply: dict[str, Any] = {} if rid is None else {"id": rid}
    reply.update(error=str(exc), field=exc.field)
    return reply


def serve(lines_in: IO[bytes], out: IO[str], default_strategy: str = "opm",
          on_internal_error: Callable[[BaseException], None] | None = None) -> int:
    """Answer one request per line until end of input; each reply is one line, flushed.
    A bad line gets an error reply naming the field, and the service goes on. Returns the
    number of requests answered."""
    count = 0
    while True:
        line = lines_in.readline(MAX_REQUEST_BYTES + 1)
        if not line:
            return count
        count += 1
        if len(line) > MAX_REQUEST_BYTES and not line.endswith(b"\n"):
            while True:  # skip the rest of the oversized line
                rest = lines_in.readline(MAX_REQUEST_BYTES)
                if not rest or rest.endswith(b"\n"):
                    break
            reply = error_reply(RequestError(f"longer than {MAX_REQUEST_BYTES} bytes",
                                             field="(request)"))
        else:
            reply = _answer_line(line, default_strategy, on_internal_error)
        out.write(encode(reply) + "\n")
        out.flush()


def _answer_line(line: bytes, default_strategy: str,
                 on_internal_error: Callable[[BaseException], None] | None) -> dict[str, Any]:
    request: Any = None
    try:
        if not line.strip():
            raise RequestError("empty line; expected a JSON object", field="(request)")
        request = decode(line)
        return answer(request, default_strategy)
    except RequestError as exc:
        if exc.field is None:
            exc = RequestError(exc.detail, field="(request)")
        return error_reply(exc, request_id(request))
    except Exception as exc:  # a bug must not take the service down for later requests
        if on_internal_error is not None:
            on_internal_error(exc)
        return {"error": f"internal error: {type(exc).__name__}: {exc}", "field": None}

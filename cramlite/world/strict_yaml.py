"""YAML as cramlite reads its own files (setups, item types): the safe loader, a key given
twice in one mapping refused (the last would silently win), keys that are not text
refused (`yes:` is a boolean key in YAML 1.1), and anchors and aliases
refused (`&a`, `*a`, and so `<<:` merge keys): a 3 KB file of nested aliases expands to
gigabytes when printed or walked, and no setup needs them."""

from __future__ import annotations

import re
from typing import Any

import yaml

ALIASES_REFUSED = ("anchors and aliases (&name, *name, and so <<: merge keys) are not "
                   "supported; write the value out")


class StrictLoader(yaml.SafeLoader):
    """The safe loader without anchors, aliases or repeated keys."""

    def fetch_alias(self) -> None:
        raise yaml.scanner.ScannerError(None, None, ALIASES_REFUSED, self.get_mark())

    def fetch_anchor(self) -> None:
        raise yaml.scanner.ScannerError(None, None, ALIASES_REFUSED, self.get_mark())


def _mapping_without_duplicates(loader: StrictLoader, node: yaml.MappingNode,
                                deep: bool = False) -> dict:
    seen = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=True)
        if not isinstance(key, str):  # (YAML 1.1 reads `yes:`, `on:` and `1:` as others)
            raise yaml.constructor.ConstructorError(
                None, None, f"the key {key_node.value!r} is read as {type(key).__name__} "
                f"{key!r}; expected a text key (quote it: \"{key_node.value}\":)",
                key_node.start_mark)
        if key in seen:
            raise yaml.constructor.ConstructorError(
                None, None, f"the key {key!r} appears twice", key_node.start_mark)
        seen.add(key)
    return loader.construct_mapping(node, deep=deep)


class _StrictCLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):  # type: ignore[misc]
    """The same rules on libyaml's parser (PyYAML's wheels ship it): seven times faster
    than the pure-Python one (a setup and its item types: ~40 ms a process). Its scanner
    is C: text with an anchor or alias (`_has_anchors`) is left to `StrictLoader`, which
    refuses it, before libyaml could expand it."""


for _loader in (StrictLoader, _StrictCLoader):
    _loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG,
                            _mapping_without_duplicates)

#: Where libyaml reads text that the pure-Python parser refuses or reads otherwise (found
#: by a differential fuzzer): tabs, byte-order marks, lone surrogates, tags (`!`), `?` in
#: flow scalars, a comment right after a block scalar's header. Text with any of them is
#: read by `StrictLoader` alone, as is text with `_FLOW_OPENERS` brackets or more (libyaml
#: reads flow collections nested ~500 deep that Python's recursion limit refuses).
_LIBYAML_DIFFERS = re.compile(r"[\t\ufeff\ud800-\udfff!?]|[|>][-+0-9]*#")
_FLOW_OPENERS = 256


def load_strict(text: str) -> Any:
    """Parse YAML text by `StrictLoader`'s rules (raises yaml.YAMLError): on libyaml's
    parser where PyYAML has it and the text has nothing libyaml reads otherwise; text
    that it refuses is parsed again by `StrictLoader`, whose messages say more (e.g.
    which character cannot start a token). A value no constructor can make (`!!timestamp
    x`) is a YAML error too."""
    try:
        if (getattr(yaml, "__with_libyaml__", False) and not _LIBYAML_DIFFERS.search(text)
                and text.count("[") + text.count("{") < _FLOW_OPENERS):
            try:
                if not _has_anchors(text):
                    return yaml.load(text, Loader=_StrictCLoader)
            except yaml.YAMLError:
                pass
        return yaml.load(text, Loader=StrictLoader)
    except (AttributeError, IndexError, KeyError, TypeError) as exc:  # (PyYAML's own)
        raise yaml.constructor.ConstructorError(
            None, None, f"a value cannot be read ({type(exc).__name__}: {exc})") from None


def _has_anchors(text: str) -> bool:
    """Has the text an anchor or alias? (Read as libyaml's events, which expand nothing;
    no anchor or alias is written without `&` or `*`.)"""
    return ("&" in text or "*" in text) and any(
        getattr(event, "anchor", None) is not None  # (an alias names its anchor)
        for event in yaml.parse(text, Loader=_StrictCLoader))


def describe_yaml_error(exc: yaml.YAMLError, expected: str = "",
                        ) -> tuple[str, str | None]:
    """A YAML error as (what is wrong, where: "line N", or None), for a one-line error;
    `expected` (what the file should be) follows a malformed file's problem."""
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or "could not parse"
    message = f"YAML {problem}" if problem == ALIASES_REFUSED else \
        f"malformed YAML ({problem}){'; expected ' + expected if expected else ''}"
    return message, (f"line {mark.line + 1}" if mark is not None else None)

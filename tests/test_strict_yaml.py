"""cramlite's YAML rules on both parsers: libyaml's (fast, used where PyYAML has it) and
the pure-Python one (where it has not, and for the messages of refused text)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from cramlite.world.strict_yaml import ALIASES_REFUSED, StrictLoader, load_strict
from tests.conftest import ROOT


def _python(text: str):
    return yaml.load(text, Loader=StrictLoader)


@pytest.mark.parametrize("path", sorted((ROOT / "worlds").rglob("*.yaml")), ids=str)
def test_every_shipped_yaml_file_reads_the_same_on_both_parsers(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    assert load_strict(text) == _python(text)


@pytest.mark.parametrize("text", [
    "a: &x 1\nb: *x\n", "a: *x\n", "a: [1, *x]\n", "a: &x\n  b: 1\nc:\n  <<: *x\n",
    "- &a [1, 2]\n- *a\n",
    # an alias bomb (3 KB that expands to gigabytes): refused before anything expands
    "a: &a [x, x, x, x, x, x, x, x, x]\n" +
    "".join(f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 9)}]\n"
            for i in range(8)),
])
def test_anchors_and_aliases_are_refused_where_they_stand(text: str) -> None:
    with pytest.raises(yaml.YAMLError) as fast:
        load_strict(text)
    with pytest.raises(yaml.YAMLError) as slow:
        _python(text)
    assert fast.value.problem == slow.value.problem == ALIASES_REFUSED
    assert fast.value.problem_mark.line == slow.value.problem_mark.line


@pytest.mark.parametrize("text", [
    "a: 1\na: 2\n", "{a: 1, a: 2}\n", "yes: 1\n", "a: 1\n  b: 2\n", "a:\n\t- 1\n",
    "a: [1, 2\nb: 3\n", "- a\nb: 1\n", "a: '\n",
])
def test_refused_text_is_refused_in_the_same_words_on_both_parsers(text: str) -> None:
    """(libyaml's own messages say less: "found character that cannot start any token"
    without the tab it found.)"""
    with pytest.raises(yaml.YAMLError) as fast:
        load_strict(text)
    with pytest.raises(yaml.YAMLError) as slow:
        _python(text)
    assert str(fast.value) == str(slow.value)


def test_libyaml_parses_what_is_read(monkeypatch: pytest.MonkeyPatch) -> None:
    """The fast parser is the one used where PyYAML has it (its wheels do)."""
    if not getattr(yaml, "__with_libyaml__", False):
        pytest.skip("this PyYAML was built without libyaml")
    from cramlite.world import strict_yaml

    calls = []
    original = strict_yaml._StrictCLoader.__init__

    def counting(self, stream):
        calls.append(stream)
        original(self, stream)

    monkeypatch.setattr(strict_yaml._StrictCLoader, "__init__", counting)
    assert load_strict("name: v1\nitems: [1, 2]\n") == {"name": "v1", "items": [1, 2]}
    assert calls


@pytest.mark.parametrize("text", [
    "a: 1\t# a tab before a comment\n", "a: 1\t\n", "a:\t1\n", "a: [1,\t2]\n", "a: x\ty\n",
    "grasps: [front, t?op]\n", "{a: b?}\n", "a: !\n", "! : 1\n", "\ufeff\ufeffa: 1\n",
    "a:\n\ufeff  b\n", "a: >#\n", "a: |#c\n", "a: \ud800\n",
    "a: " + "[" * 600 + "]" * 600 + "\n",
])
def test_text_libyaml_reads_otherwise_is_read_as_the_pure_python_parser_reads_it(
        text: str) -> None:
    """(Found by a differential fuzzer: libyaml is more lenient with tabs, `?` in flow
    scalars, bare tags, byte-order marks and comments after a block scalar's header, and
    nests flow collections deeper.)"""
    def outcome(load):
        try:
            return "ok", load(text)
        except (yaml.YAMLError, ValueError, RecursionError) as exc:
            return "error", type(exc).__name__, str(exc)

    assert outcome(load_strict) == outcome(_python)


@pytest.mark.parametrize("text", ["a: !!timestamp x\n", "a: !!int\n"])
def test_a_value_no_constructor_can_make_is_a_yaml_error(text: str) -> None:
    """(PyYAML's constructors raise AttributeError or IndexError there: a traceback.)"""
    with pytest.raises(yaml.YAMLError, match="a value cannot be read"):
        load_strict(text)

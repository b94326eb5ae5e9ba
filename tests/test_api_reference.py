"""docs/api.md is generated from the public API (python -m cramlite.api_reference): it
says what the code's signatures and docstrings say, and covers the designators, the plan
language, strategies, plans and backends."""

from __future__ import annotations

from cramlite.api_reference import SECTIONS, reference
from tests.conftest import ROOT


def test_the_api_reference_is_what_the_code_says() -> None:
    text = (ROOT / "docs" / "api.md").read_text()
    assert text == reference(), ("docs/api.md is stale: python -m cramlite.api_reference "
                                 "> docs/api.md")
    for name in ("TransportAction", "DetectAction", "Parallel", "Strategy", "ProcessModules",
                 "PlanReport", "simulated_robot"):
        assert f"### `{name}`" in text
    assert "0x" not in text  # (no object addresses: the same on every machine)


def test_every_name_of_the_reference_is_importable_from_cramlite_or_its_module() -> None:
    import importlib

    import cramlite

    for _, names in SECTIONS:
        for module, name in names:
            assert getattr(importlib.import_module(module), name) is not None
    exported = set(cramlite.__all__)
    missing = [n for _, names in SECTIONS for m, n in names
               if m.startswith("cramlite.designators") and m.count(".") == 1
               and n.endswith("Action") and n not in exported]
    assert missing == [], missing

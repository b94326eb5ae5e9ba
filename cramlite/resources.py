"""Where the shipped files are: worlds, items, setups and human sequences.

They are package data (`cramlite.worlds`, `cramlite.data`, mapped from the top-level
`worlds/` and `data/` folders by pyproject.toml), found with importlib.resources, so a
wheel, an sdist and an editable checkout behave the same and nothing depends on the
current directory.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

#: Shipped human-sequence files, by the short name a user may give instead of a path.
SHIPPED_DATA = {"table-setting": "human_sequences/table_setting_sequences.csv",
                "cooking": "human_sequences/cooking_sequences.csv",
                "clearing-up": "human_sequences/clearing_up_sequences.csv",
                "all": "human_sequences/all_sequences.csv"}


def _package_dir(package: str) -> Path:
    return Path(str(resources.files(package)))


def worlds_dir() -> Path:
    """The folder holding the kitchen URDF, `items/` and `setups/`."""
    return _package_dir("cramlite.worlds")


def data_dir() -> Path:
    """The folder holding the shipped human sequences."""
    return _package_dir("cramlite.data")


def shipped_data_path(name: str) -> Path | None:
    """The file of a shipped data set by its short name (e.g. `table-setting`), or None."""
    relative = SHIPPED_DATA.get(name)
    return None if relative is None else data_dir() / relative


def resolve_data_path(text: str | Path) -> Path:
    """A path as given if it exists, else a shipped data set's file by name, else the
    path as given (the loader then reports it as missing)."""
    path = Path(text)
    if path.exists():
        return path
    return shipped_data_path(str(text)) or path

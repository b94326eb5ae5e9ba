"""File names made from user data (setup, plan, strategy and model names), made safe.

A strategy may be named `learned:../../nn.model` and a setup cell of a trials.csv may hold
anything: such text never becomes a path as it is. `safe_stem` keeps a readable slug of
it (letters, digits, `_ . + -`; at most 60 characters) and adds a short hash of the full
text, so two names that slug alike (`learned:a/nn.model`, `learned:b/nn.model`) never
share a file; `inside` builds the path and refuses one that would leave its folder.
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

from cramlite.errors import UserInputError

#: Characters kept in a slug; every run of others becomes one "_".
_UNSAFE = re.compile(r"[^A-Za-z0-9_.+-]+")
MAX_SLUG = 60
HASH_CHARACTERS = 8


def safe_stem(*parts: object) -> str:
    """A file-name stem for the parts (joined by "-"): a slug and a hash of the parts."""
    texts = [str(part) for part in parts]
    slug = _UNSAFE.sub("_", "-".join(texts)).strip("._-")[:MAX_SLUG].rstrip("._-") or "x"
    digest = hashlib.sha256("\x1f".join(texts).encode("utf-8", "surrogatepass")).hexdigest()
    return f"{slug}-{digest[:HASH_CHARACTERS]}"


def inside(folder: str | Path, name: str) -> Path:
    """`folder / name`, refused (UserInputError) unless it stays inside `folder`."""
    root = Path(folder)
    path = root / name
    if not path.resolve().is_relative_to(root.resolve()) or path.resolve() == root.resolve():
        raise UserInputError(f"the file name {name!r} would leave its folder; expected a "
                             "plain file name", source=str(root))
    return path


def trial_stem(setup: object, plan: object, strategy: object, trial: object,
               backend: object = "") -> str:
    """The stem of a trial's files (its trace, its timeline and replay in the report); the
    backend is part of it where a bench ran on several."""
    return safe_stem(setup, plan, strategy, trial, *([backend] if backend else []))

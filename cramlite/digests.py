"""Short content hashes of files (16 hex digits of SHA-256): what identifies a URDF, a plan
file or a model in caches, traces and the resume key. No heavy imports: the strategy
registry uses it."""

from __future__ import annotations

import hashlib
from pathlib import Path


def file_digest(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]

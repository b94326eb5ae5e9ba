"""Loading a user's code named on the command line: `package.module:name` or
`path/to/file.py:name`.

A file is loaded by its path under a module name of its own (so two files called
`plan.py` never collide), and its folder is put at the *end* of `sys.path` (its sibling
modules import; a `json.py` beside it never shadows the standard library). A module name
that Python cannot find is looked for in the current folder the same way, so
`--strategy farthest:FarthestFirst` works from the folder holding `farthest.py`, as users
expect, without PYTHONPATH. A spawned or Dask worker resolves the same text again.
"""

from __future__ import annotations

import atexit
import functools
import hashlib
import importlib
import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

from cramlite.digests import file_digest
from cramlite.errors import UserInputError


@functools.cache
def user_code() -> None:
    """Called where a user's code is loaded (a file, a module, an entry point): from then
    on, the files still open at exit are flushed (`flush_open_files`), once. The console
    script skips the interpreter's teardown, which would flush them; cramlite closes its
    own, so a run of the shipped plans and strategies is spared the scan (15 ms)."""
    atexit.register(flush_open_files)


def flush_open_files() -> None:
    """Flush every writable file object still open, as the teardown would (closing it)."""
    import gc
    import io

    standard = {id(sys.stdout), id(sys.stderr), id(sys.__stdout__), id(sys.__stderr__)}
    for obj in gc.get_objects():
        if isinstance(obj, io.IOBase) and id(obj) not in standard:
            try:
                if not obj.closed and obj.writable():
                    obj.flush()
            except (OSError, ValueError, AttributeError):
                pass  # (its data would be lost by the teardown too)


def is_code_reference(text: str) -> bool:
    """Does the text name code (`module:name` or `file.py:name`)?"""
    module, sep, attr = text.rpartition(":")
    return bool(sep and module and attr)


def names_file(text: str) -> bool:
    """Does a code reference name a file (rather than an importable module)?"""
    module = text.rpartition(":")[0]
    return module.endswith(".py") or "/" in module or "\\" in module


def code_file(text: str) -> Path | None:
    """The file a reference names (resolved), or None for a module name."""
    if not names_file(text):
        return None
    return Path(text.rpartition(":")[0]).expanduser().resolve()


def file_hash(text: str) -> str:
    """A short hash of the content of the file a reference names, or of the module's
    source file for `module:name` ("" if there is none to read): a changed plan or
    strategy is a new one, whichever way it is named."""
    path = code_file(text) if names_file(text) else _module_file(text)
    return file_digest(path) if path is not None and path.is_file() else ""


def _module_file(text: str) -> Path | None:
    """The source file of the module a `module:name` reference names (looked for in the
    current folder as `_import` does, if Python cannot find it), or None."""
    local = absolute_reference(text, Path.cwd())
    if names_file(local):
        return code_file(local)
    try:
        spec = importlib.util.find_spec(text.rpartition(":")[0])
    except (ImportError, ValueError):
        return None
    origin = getattr(spec, "origin", None)
    return Path(origin) if origin and origin.endswith(".py") else None


def absolute_reference(text: str, folder: str | Path) -> str:
    """The reference as a process started elsewhere (a Dask worker) loads it: a relative
    file made absolute against `folder`, a module found only in `folder` as its file."""
    if text.startswith("learned:"):
        model = Path(text[len("learned:"):]).expanduser()
        return text if model.is_absolute() else f"learned:{Path(folder) / model}"
    if not is_code_reference(text):
        return text
    module, _, attr = text.rpartition(":")
    if names_file(text):
        path = Path(module).expanduser()
        return text if path.is_absolute() else f"{Path(folder) / path}:{attr}"
    top = module.split(".")[0]
    if importlib.util.find_spec(top) is None:
        base = Path(folder)
        candidate = base / (module.replace(".", "/") + ".py")
        if candidate.is_file():
            return f"{candidate}:{attr}"
        package = base / module.replace(".", "/") / "__init__.py"
        if package.is_file():
            return f"{package}:{attr}"
    return text


def trial_code_hash(plan: str, strategy: str) -> str:
    """What the resume key holds of the code a trial runs beyond its names: the hashes of
    a plan file, a strategy file and a learned strategy's model file ("" if none)."""
    parts = [file_hash(plan) if is_code_reference(plan) else ""]
    if strategy.startswith("learned:"):
        model = Path(strategy[len("learned:"):]).expanduser()
        parts.append(_content_hash(model))
    elif is_code_reference(strategy):
        parts.append(file_hash(strategy))
    parts = [p for p in parts if p]
    if not parts:
        return ""
    return parts[0] if len(parts) == 1 else \
        hashlib.sha256("+".join(parts).encode()).hexdigest()[:16]


def _content_hash(path: Path) -> str:
    """A file's content hash, or a folder's (its files' names and contents)."""
    if path.is_file():
        return file_digest(path)
    if not path.is_dir():
        return ""
    digest = hashlib.sha256()
    for item in sorted(p for p in path.rglob("*") if p.is_file()):
        digest.update(str(item.relative_to(path)).encode() + b"\0" + item.read_bytes())
    return digest.hexdigest()[:16]


def load_reference(text: str, what: str, field: str) -> Any:
    """The object `module:name` or `file.py:name` names; UserInputError (naming `field`)
    if it cannot be loaded, with the reason (what the user's module raised, too)."""
    if not is_code_reference(text):
        raise UserInputError(f"expected {what} as package.module:name or path/to/file.py:name, "
                             f"got {text!r}", field=field)
    module_text, _, attr = text.rpartition(":")
    try:
        user_code()
        module = _load_file(code_file(text), field) if names_file(text) else \
            _import(module_text)
    except UserInputError:
        raise
    except Exception as exc:  # what the user's module raises on import
        raise UserInputError(f"cannot load {what} {text!r}: {type(exc).__name__}: {exc}",
                             field=field) from None
    try:
        value = module
        for part in attr.split("."):
            value = getattr(value, part)
    except AttributeError:
        public = sorted(n for n in vars(module) if not n.startswith("_"))
        own = [n for n in public  # (what the module defines before what it imports)
               if getattr(getattr(module, n), "__module__", None) == module.__name__]
        public = own + [n for n in public if n not in own]
        # (a file by its path: the module name it is loaded under is cramlite's own)
        where = str(code_file(text)) if names_file(text) else module.__name__
        raise UserInputError(f"cannot load {what} {text!r}: {where} has no "
                             f"{attr!r}; it has {', '.join(public[:12]) or 'nothing public'}",
                             field=field) from None
    return value


def _load_file(path: Path | None, field: str) -> ModuleType:
    assert path is not None
    if not path.is_file():
        raise UserInputError(f"no such file: {path}", field=field)
    digest = hashlib.sha256(str(path).encode()).hexdigest()[:10]
    stem = "".join(c if c.isalnum() else "_" for c in path.stem)
    name = f"_cramlite_user_{stem}_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    _append_to_path(path.parent)
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise UserInputError(f"cannot load {path} as Python code", field=field)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # (dataclasses and pickle look their module up)
    try:
        spec.loader.exec_module(module)
    except BaseException:
        sys.modules.pop(name, None)
        raise
    return module


def _import(name: str) -> ModuleType:
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as exc:
        top = name.split(".")[0]
        here = Path.cwd()
        if exc.name != top or not ((here / f"{top}.py").is_file() or
                                   (here / top / "__init__.py").is_file()):
            raise
        _append_to_path(here)  # (after the standard library and the installed packages)
        return importlib.import_module(name)


def _append_to_path(folder: Path) -> None:
    text = str(folder)
    if text not in sys.path:
        sys.path.append(text)

"""A cramlite plugin package: the farthest-first strategy and the fetch-two plan of
`examples/`, registered by name through entry points (see its pyproject.toml)."""

from cramlite_farthest.plan import fetch_two
from cramlite_farthest.strategy import FarthestFirst

__all__ = ["FarthestFirst", "fetch_two"]

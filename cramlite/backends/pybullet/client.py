"""The pybullet module, imported with its C-level start-up banner silenced.

Import `p` from here instead of `import pybullet`, so that `--json` output stays clean.
"""

from cramlite.backends.pybullet.quiet import c_output_silenced

with c_output_silenced(stderr=True):
    import pybullet as p

__all__ = ["p"]

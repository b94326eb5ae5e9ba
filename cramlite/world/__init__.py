"""Setup files, the kitchen's containers, the PR2's constants and top-down maps: what a
setup is, without any simulator (the backends load it; the planning scene models it)."""

from cramlite.world.setup import ItemSpec, Pose, Setup, load_setup

__all__ = ["ItemSpec", "Pose", "Setup", "load_setup"]

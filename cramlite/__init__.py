"""cramlite: a lightweight, ROS-free robot plan executive in the style of PyCRAM."""

__version__ = "0.1.0"

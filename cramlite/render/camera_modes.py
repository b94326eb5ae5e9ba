"""The names of a replay camera's modes (here, without numpy: the command line lists them
in --help before anything heavy is imported)."""

#: fixed: the kitchen from above its south end; top: straight down on the whole kitchen;
#: follow: behind and above the robot, looking where it faces.
CAMERA_MODES = ("fixed", "top", "follow")

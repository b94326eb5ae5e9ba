"""Names the command line offers for evaluation, without importing numpy (fast startup)."""

METRICS = ("ape", "expected-ape", "edit", "edit-unrestricted")
PROTOCOLS = ("heldout", "thesis", "reference")
DIM_NAMES = ("x", "y", "z", "xy", "xz", "yz", "xyz")
#: The softmax temperature `simulate` draws with unless told otherwise (costs are metres
#: raised to k, times c: at 0.05 an item 5 cm costlier than the best is taken e times less
#: often).
DEFAULT_TEMPERATURE = 0.05

"""Names the command line offers for evaluation, without importing numpy (fast startup)."""

METRICS = ("ape", "expected-ape", "edit", "edit-unrestricted")
PROTOCOLS = ("heldout", "thesis", "reference")
DIM_NAMES = ("x", "y", "z", "xy", "xz", "yz", "xyz")

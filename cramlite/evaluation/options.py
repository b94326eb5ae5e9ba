"""Names the command line offers for evaluation, without importing numpy (fast startup)."""

METRICS = ("ape", "expected-ape", "edit", "edit-unrestricted")
#: `fit` also maximises the likelihood of the observed choices under a softmax choice rule
#: (the rule `simulate` draws with), for strategies with a cost per item.
FIT_METRICS = (*METRICS, "likelihood")
PROTOCOLS = ("heldout", "thesis", "reference")
DIM_NAMES = ("x", "y", "z", "xy", "xz", "yz", "xyz")
#: The softmax temperature `simulate` draws with unless told otherwise (costs are metres
#: raised to k, times c: at 0.05 an item 5 cm costlier than the best is taken e times less
#: often).
DEFAULT_TEMPERATURE = 0.05

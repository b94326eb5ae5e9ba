"""The thesis's published APE means (thesis protocol), for showing ours beside them."""

from __future__ import annotations

#: APE means, thesis protocol, by shipped data set and model (thesis 3.3.4-3.3.6).
PUBLISHED_APE = {
    "table-setting": {"opm": 4.04, "rnn": 4.70, "nn": 2.48, "cpt": 6.09},
    "cooking": {"opm": 2.78, "rnn": 3.42, "nn": 4.96},
    "clearing-up": {"opm": 3.82, "rnn": 6.59, "nn": 7.41},
    "all": {"opm": 3.56, "rnn": 4.32, "nn": 3.67},
}


def model_label(strategy: str) -> str | None:
    """`opm`, or the kind of a `learned:MODEL` (rnn, nn, cpt); None for others."""
    if strategy == "opm":
        return "opm"
    if strategy.startswith("learned:"):
        from cramlite.learning.modelfile import load_model

        return load_model(strategy[len("learned:"):]).kind
    return None


def published_ape(data: str, strategy: str, metric: str, protocol: str) -> float | None:
    """The published figure for this strategy on a shipped data set named `data`, where
    it is comparable (APE under the thesis protocol, the OPM at the source's parameters)."""
    if metric != "ape" or protocol != "thesis" or data not in PUBLISHED_APE:
        return None
    label = model_label(strategy)
    return None if label is None else PUBLISHED_APE[data].get(label)

"""What sticks out of the base (a parked arm, a carried item) sweeps past the items that
stand in the kitchen, not through them: the base's 2D maps hold the furniture only, so the
items standing that rise to an outline's height are looked at too (their boxes), and the
exact check decides where an outline meets one."""

from __future__ import annotations

from pathlib import Path

from cramlite.trace import read_trace
from cramlite.trace.check import penetrations
from cramlite.trial import TrialRunner

SETUP = Path(__file__).parent / "data" / "setups" / "arm_over_a_standing_box.yaml"


def test_a_parked_arm_turned_over_the_island_misses_the_box_standing_there(tmp_path) -> None:
    """A random setup where, driving on with the left arm parking, the base turned the
    right arm through the cereal box on the island (3.5 cm deep): the arm was over the
    island, which the map for its height counts as free."""
    trace = tmp_path / "sweep.jsonl"
    with TrialRunner(SETUP, backend="kinematic") as runner:
        result = runner.run("baseline", seed=2432121711, trace=trace)
    assert result.success, result.failures
    found = penetrations(read_trace(trace), tolerance_m=0.01)
    assert found == [], [f.describe() for f in found]

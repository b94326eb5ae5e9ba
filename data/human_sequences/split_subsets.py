"""Write the named subsets of all_sequences.csv (the author's published file, all 326
episodes): cooking_sequences.csv and clearing_up_sequences.csv, the rows whose ID marks
that activity (the thesis's Table 3.1). Run it after replacing all_sequences.csv."""

from __future__ import annotations

import csv
from pathlib import Path

from cramlite.evaluation.data import activity_of

HERE = Path(__file__).resolve().parent
SUBSETS = {"cooking": "cooking_sequences.csv", "cleaning up": "clearing_up_sequences.csv"}


def main() -> None:
    with (HERE / "all_sequences.csv").open(newline="") as handle:
        reader = csv.DictReader(handle)
        fields, rows = reader.fieldnames, list(reader)
    for activity, name in SUBSETS.items():
        with (HERE / name).open("w", newline="") as out:
            writer = csv.DictWriter(out, fieldnames=fields, lineterminator="\n")
            writer.writeheader()
            writer.writerows(r for r in rows if activity_of(r) == activity)


if __name__ == "__main__":
    main()

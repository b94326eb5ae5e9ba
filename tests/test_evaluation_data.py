"""Loading human sequences: the published format, repeated items, bad rows."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from cramlite.evaluation.data import DataError, load_episodes
from tests.conftest import run_cli

HEADER = ["ID", "sequence", "coordinates", "start_coordinates", "strong_k", "mid_k", "food_k",
          "containment", "error"]
COOKING = ["s13-d21", "cutting_board,knife,plate,pan,plate",
           "cutting_board: (1,2,2);knife: (1,2,2);plate: (3,1,3);pan: (2,0,1);plate: (0,4,3)",
           "[2,2,2],[2,2,2],[1,1,2],[1,1,2],[1,1,2]", "cutting_board", "0", "plate",
           "knife,plate", "0.7"]
CLEANING = ["k01", "fork,plate,cup", "fork: (0,0,1);plate: (0,0,1);cup: (1,0,1)",
            "[2,0,1],[2,0,1],[2,0,1]", "fork", "plate", "0", "0", "0.6"]


def write_csv(tmp_path: Path, *rows: list[str], name: str = "data.csv") -> Path:
    path = tmp_path / name
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(HEADER)
        writer.writerows(rows)
    return path


def test_shipped_table_setting_data_loads() -> None:
    from tests.test_evaluation_metrics import DATA
    episodes, bad = load_episodes(DATA)
    assert len(episodes) == 186 and not bad
    assert {e.activity for e in episodes} == {"table setting"}


def test_cooking_and_cleaning_rows(tmp_path: Path) -> None:
    episodes, _ = load_episodes(write_csv(tmp_path, COOKING, CLEANING))
    cook, clean = episodes
    assert cook.activity == "cooking" and clean.activity == "cleaning up"
    items = cook.sequence_items()
    # the two plates are distinct items at their own positions, in order of occurrence
    assert [c.name for c in items] == ["cutting_board", "knife", "plate", "pan", "plate"]
    assert items[2].position == (3.0, 1.0, 3.0) and items[4].position == (0.0, 4.0, 3.0)
    assert items[2].category == "food" and items[2].contained
    assert items[0].category == "strong" and not items[0].contained
    assert items[1].contained and items[3].category == "none"
    assert clean.sequence_items()[1].category == "mid"
    assert cook.published_baseline == pytest.approx(0.7)


def test_more_occurrences_than_positions_share_the_last_position(tmp_path: Path) -> None:
    row = ["E01_14", "placemat,glass,glass,glass", "placemat: (3,3,1);glass: (2,0,1)",
           "[3,2,2],[1,4,1],[3,3,1],[3,3,1]", "placemat", "0", "", "glass", "0.6"]
    (episode,), _ = load_episodes(write_csv(tmp_path, row))
    assert [c.position for c in episode.sequence_items()[1:]] == [(2.0, 0.0, 1.0)] * 3


def test_item_without_coordinates_fails_or_is_skipped(tmp_path: Path) -> None:
    bad = list(CLEANING)
    bad[0], bad[1] = "k02", "fork,plate,teapot"
    path = write_csv(tmp_path, COOKING, bad)
    with pytest.raises(DataError, match=r"row k02: coordinates: .*'teapot'.*no coordinates"):
        load_episodes(path)
    episodes, skipped = load_episodes(path, on_bad_row="skip")
    assert [e.id for e in episodes] == ["s13-d21"]
    assert [(b.id, b.field) for b in skipped] == [("k02", "coordinates")]


def test_fewer_start_positions_than_steps(tmp_path: Path) -> None:
    bad = list(CLEANING)
    bad[3] = "[2,0,1],[2,0,1]"
    with pytest.raises(DataError, match=r"row k01: start_coordinates: expected at least 3"):
        load_episodes(write_csv(tmp_path, bad))


def test_malformed_coordinates_and_missing_columns(tmp_path: Path) -> None:
    bad = list(CLEANING)
    bad[2] = "fork: 0,0,1;plate: (0,0,1);cup: (1,0,1)"
    with pytest.raises(DataError, match=r"row k01: coordinates: expected 'name: \(x,y,z\)'"):
        load_episodes(write_csv(tmp_path, bad))
    path = tmp_path / "nocols.csv"
    path.write_text("ID,sequence\nx,a\n")
    with pytest.raises(DataError, match="missing column"):
        load_episodes(path)


def test_cli_reports_bad_rows_by_id_and_field(tmp_path: Path) -> None:
    bad = list(CLEANING)
    bad[0], bad[1] = "k02", "fork,plate,teapot"
    path = write_csv(tmp_path, COOKING, bad)
    failed = run_cli("evaluate", str(path))
    assert failed.returncode == 2 and "Traceback" not in failed.stderr
    assert "row k02: coordinates" in failed.stderr and len(failed.stderr.splitlines()) == 1
    skipped = run_cli("evaluate", str(path), "--on-bad-row", "skip", "--json")
    assert skipped.returncode == 0, skipped.stderr
    assert "skipped" in skipped.stderr and "k02" in skipped.stderr
    missing = run_cli("evaluate", str(tmp_path / "none.csv"))
    assert missing.returncode == 2 and "none.csv" in missing.stderr


def test_duplicate_episode_ids_are_refused_or_skipped(tmp_path: Path) -> None:
    """Results are keyed and paired by ID (compare's Wilcoxon pairs): two episodes with
    one ID once gave both the second one's scores."""
    twice = ["k01", *CLEANING[1:]]
    path = write_csv(tmp_path, CLEANING, COOKING, twice)
    with pytest.raises(DataError, match="duplicate") as info:
        load_episodes(path)
    assert info.value.field == "ID"
    episodes, bad = load_episodes(path, on_bad_row="skip")
    assert [e.id for e in episodes] == ["k01", "s13-d21"] and bad[0].field == "ID"
    result = run_cli("compare", str(path), "--strategies", "opm,nearest", "--repeats", "1")
    assert result.returncode == 2 and "row k01: ID: duplicate" in result.stderr


def test_a_row_without_an_id_is_refused_or_skipped_by_its_row_number(tmp_path: Path) -> None:
    path = write_csv(tmp_path, COOKING, ["", *COOKING[1:]])
    with pytest.raises(DataError, match="data row 2: ID: expected the episode's ID"):
        load_episodes(path)
    episodes, bad = load_episodes(path, on_bad_row="skip")
    assert [e.id for e in episodes] == ["s13-d21"] and bad[0].id == "? (data row 2)"
    result = run_cli("evaluate", str(path))
    assert result.returncode == 2 and "data row 2: ID" in result.stderr

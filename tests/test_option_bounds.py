"""Numeric options have bounds (#29): a value no one needs that would allocate gigabytes or
run for years (`--repeats 1000000000`), or is not a number at all (nan, 1e400), is one
line naming the option and what was expected, exit 2, before anything runs."""

from __future__ import annotations

import pytest

from cramlite.cli import main

CASES = [
    ("evaluate table-setting --repeats 1000000000", "--repeats", "[1, 100000]"),
    ("compare table-setting --repeats 100001", "--repeats", "[1, 100000]"),
    ("reproduce --repeats 0", "--repeats", "[1, 100000]"),
    ("train table-setting --epochs 10000000", "--epochs", "[1, 100000]"),
    ("simulate --episodes 1000001", "--episodes", "[1, 1000000]"),
    ("fit table-setting --workers 100000", "--workers", "[1, 1024]"),
    ("bench --workers 2000", "--workers", "[1, 1024]"),
    ("bench --random-setups 100001", "--random-setups", "[1, 100000]"),
    ("bench --trial-timeout nan", "--trial-timeout", "seconds > 0"),
    ("bench --trial-timeout 1e308", "--trial-timeout", "<= 604800"),
    ("run v1 --seed 1e400", "--seed", "2^64 - 1"),
    ("run v1 --seed 18446744073709551616", "--seed", "2^64 - 1"),
    ("replay t.jsonl --fps 1e308", "--fps", "<= 120"),
    ("replay t.jsonl --speed 1e-300", "--speed", "0.01 to 1000"),
    ("replay t.jsonl --tolerance-cm inf", "--tolerance-cm", "centimetres"),
    ("report out --max-replays 99999999", "--max-replays", "[0, 10000]"),
    ("reproduce --recovery-seeds 1000", "--recovery-seeds", "[1, 100]"),
]


@pytest.mark.parametrize(("command", "option", "expected"), CASES,
                         ids=[c[0] for c in CASES])
def test_a_numeric_option_out_of_bounds_is_one_line_and_exit_2(
        command: str, option: str, expected: str, capsys) -> None:
    with pytest.raises(SystemExit) as exited:
        main(command.split())
    assert exited.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"argument {option}" in err and expected in err, err


def test_the_largest_seed_is_accepted() -> None:
    from cramlite.cli.common import seed_int

    assert seed_int(str(2**64 - 1)) == 2**64 - 1


@pytest.mark.parametrize(("command", "option", "expected"), CASES,
                         ids=[c[0] for c in CASES])
def test_the_help_gives_each_bounded_option_s_range(command: str, option: str,
                                                    expected: str, capsys) -> None:
    """README: "the ranges are in `--help`"."""
    with pytest.raises(SystemExit) as exited:
        main([command.split()[0], "--help"])
    assert exited.value.code == 0
    text = capsys.readouterr().out
    start = text.index(f"  {option} ")
    following = [text.find("\n  -", start + 1), len(text)]
    block = " ".join(text[start:min(i for i in following if i > 0)].split())
    assert expected in block, block


def test_a_simulated_temperature_is_bounded_and_an_image_side_s_range_is_in_help(
        capsys) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["simulate", "--temperature", "nan"])
    assert exited.value.code == 2
    assert "expected a temperature from 0 to 1e6" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["replay", "--help"])
    assert "from 16 to 4096" in " ".join(capsys.readouterr().out.split())
    with pytest.raises(SystemExit):
        main(["show", "--help"])
    shown = capsys.readouterr().out
    assert "1-4096" in shown and "[1, 4096]" not in shown  # (said once, its own way)

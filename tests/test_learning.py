"""Issue 12: learned strategies. Tiny epochs on a slice of the shipped data."""

from __future__ import annotations

import csv
import io
import json
import re
import zipfile
from pathlib import Path

import numpy as np
import pytest

from cramlite.evaluation.data import Episode, load_episodes
from cramlite.evaluation.evaluate import evaluate
from cramlite.learning.encoding import Vocabulary, split_episodes
from cramlite.learning.modelfile import ModelFileError, load_model, save_model
from cramlite.learning.scoring import file_sha256, thesis_ape
from cramlite.learning.train import train_model
from cramlite.resources import shipped_data_path
from cramlite.strategies import Candidate, make_strategy
from tests.conftest import run_cli

DATA = shipped_data_path("table-setting")


@pytest.fixture(scope="module")
def slice_csv(tmp_path_factory) -> Path:
    """Every third shipped episode (62): quick to train on, every source present."""
    path = tmp_path_factory.mktemp("data") / "slice.csv"
    with DATA.open(newline="") as handle:
        rows = list(csv.reader(handle))
    with path.open("w", newline="") as handle:
        csv.writer(handle).writerows([rows[0], *rows[1::3]])
    return path


@pytest.fixture(scope="module")
def models(slice_csv, tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("models")
    out = {}
    for kind in ("rnn", "nn", "cpt"):
        out[kind] = folder / f"{kind}.model"
        train_model(slice_csv, kind, out[kind], seed=1, epochs=3)
    return out


def test_split_is_seeded_episode_level_and_stratified(slice_csv) -> None:
    episodes, _ = load_episodes(slice_csv)
    a = split_episodes(episodes, (0.7, 0.15, 0.15), seed=3)
    assert a == split_episodes(episodes, (0.7, 0.15, 0.15), seed=3)
    assert a != split_episodes(episodes, (0.7, 0.15, 0.15), seed=4)
    ids = a["train"] + a["validation"] + a["test"]
    assert sorted(ids) == sorted(ep.id for ep in episodes)  # each episode exactly once
    for prefix in ("a", "h"):  # the big sources are spread over all three splits
        assert all(any(i.startswith(prefix) for i in a[s]) for s in a)


@pytest.mark.parametrize("kind", ["rnn", "nn", "cpt"])
def test_training_is_reproducible_by_seed(slice_csv, models, kind, tmp_path) -> None:
    again = tmp_path / "again.model"
    train_model(slice_csv, kind, again, seed=1, epochs=3)
    episodes, _ = load_episodes(slice_csv)
    first = evaluate(episodes, f"learned:{models[kind]}", metric="expected-ape").scores
    second = evaluate(episodes, f"learned:{again}", metric="expected-ape").scores
    assert first == second
    if kind != "cpt":
        with zipfile.ZipFile(models[kind]) as one, zipfile.ZipFile(again) as two:
            assert one.read("weights.npz") == two.read("weights.npz")


def test_model_file_round_trips_and_holds_its_metadata(models, slice_csv) -> None:
    model = load_model(models["nn"])
    meta = model.meta
    assert meta["kind"] == "nn" and meta["format_version"] == 1
    assert meta["data"]["sha256"] == file_sha256(slice_csv)
    assert set(meta["split"]["ids"]) == {"train", "validation", "test"}
    assert {"keras", "jax", "numpy"} <= set(meta["versions"])
    assert set(meta["training"]["accuracy"]) == {"train", "validation", "test"}
    report = json.loads(Path(f"{models['nn']}.report.json").read_text())
    assert Path(report["files"]["loss_curves"]).stat().st_size > 5000
    with zipfile.ZipFile(models["nn"]) as archive:  # no pickle anywhere
        assert sorted(archive.namelist()) == ["model.json", "weights.npz"]


def test_numpy_forward_pass_equals_keras(models) -> None:
    """The decisions use numpy; they must be what the trained keras network computes."""
    from cramlite.learning.backend import keras as load_keras
    keras = load_keras()
    model = load_model(models["rnn"])
    layers = keras.layers
    inputs = keras.Input((None,), dtype="int32")
    hidden = layers.Embedding(len(model.vocab) + 2, 100, mask_zero=True)(inputs)
    hidden = layers.GRU(100, return_sequences=True)(hidden)
    net = keras.Model(inputs, layers.Dense(len(model.vocab))(hidden))
    net.set_weights([model.net.embedding, model.net.kernel, model.net.recurrent,
                     model.net.bias, model.net.out_kernel, model.net.out_bias])
    history = [3, 0, 5]
    tokens = np.array([[1] + [2 + h for h in history]])
    expected = np.asarray(net(tokens))[0, -1]
    assert np.allclose(model.net.logits(history), expected, atol=1e-4)


def hand_episode() -> Episode:
    names = ("plate", "cup", "fork")
    items = tuple(Candidate(n, (float(i), 0.0, 0.0)) for i, n in enumerate(names))
    return Episode(id="x1", activity="test", sequence=names, items=items, taken=(0, 1, 2),
                   start_positions=((0.0, 0.0, 0.0),) * 3)


def test_protocols_on_a_hand_made_case(tmp_path) -> None:
    """A CPT that saw plate -> cup -> fork once and plate -> plate once."""
    path = tmp_path / "cpt.model"
    sequences = [["plate", "cup", "fork"], ["plate", "plate"]]
    save_model(path, {"kind": "cpt", "vocabulary": ["cup", "fork", "plate"],
                      "split": {"ids": {"train": [], "validation": [], "test": ["x1"]}},
                      "data": {"sha256": "abc"}}, sequences=sequences)
    model = load_model(path)
    ep = hand_episode()
    # thesis: unrestricted, every position: "" -> plate (ok), plate -> cup or plate
    # (tied in support), plate,cup -> fork (ok)
    thesis = thesis_ape(model, ep, 1, np.random.default_rng(0))
    assert thesis in (0.0, 1.0)
    ranked_after_plate = model.net.model.predict_k([["plate"]], 3, multithreading=False)[0]
    assert thesis == float(ranked_after_plate[0] != "cup")
    # heldout: restricted to the remaining items: after plate, plate is gone -> cup
    assert evaluate([ep], f"learned:{path}", metric="expected-ape").scores == [0.0]
    # heldout on the model's own file scores its test episodes only
    other = Episode(id="x2", activity="test", sequence=ep.sequence, items=ep.items,
                    taken=ep.taken, start_positions=ep.start_positions)
    own = evaluate([ep, other], f"learned:{path}", data_sha256="abc")
    assert [e.id for e in own.episodes] == ["x1"]
    assert len(evaluate([ep, other], f"learned:{path}", data_sha256="other").episodes) == 2
    assert len(evaluate([ep, other], f"learned:{path}", data_sha256="abc",
                        protocol="thesis").episodes) == 2


def test_unseen_items_and_aliases(models) -> None:
    strategy = make_strategy(f"learned:{models['nn']}", rng=0)
    unknown = [Candidate("teapot", (1.0, 0.0, 0.0)), Candidate("kettle", (2.0, 0.0, 0.0))]
    strategy.reset(unknown, (0.0, 0.0, 0.0))
    assert strategy.choose(unknown, (0.0, 0.0, 0.0)).name in ("teapot", "kettle")
    # a known item is always preferred to one the model never saw
    known = [*unknown, Candidate("breakfast-cereal", (3.0, 0.0, 0.0),
                                 metadata={"type": "box", "aliases": ("cereal",)})]
    strategy.reset(known, (0.0, 0.0, 0.0))
    assert strategy.choose(known, (0.0, 0.0, 0.0)).name == "breakfast-cereal"
    vocab = Vocabulary(tuple(load_model(models["nn"]).meta["vocabulary"]))
    assert "cereal" in vocab.names and "breakfast-cereal" not in vocab.names


BAD_MODELS = [
    ("missing.model", None, "cannot read model file"),
    ("garbage.model", b"not a zip", "corrupt or not a cramlite model file"),
]


@pytest.mark.parametrize(("name", "content", "expected"), BAD_MODELS,
                         ids=[b[0] for b in BAD_MODELS])
def test_bad_model_files_exit_2(tmp_path, name, content, expected) -> None:
    path = tmp_path / name
    if content is not None:
        path.write_bytes(content)
    result = run_cli("evaluate", "table-setting", "--strategy", f"learned:{path}")
    assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1
    assert str(path) in result.stderr and expected in result.stderr


@pytest.mark.parametrize("version", [99, True, 1.0])
def test_model_of_another_format_version_is_refused(models, tmp_path, version) -> None:
    path = tmp_path / "future.model"
    with zipfile.ZipFile(models["cpt"]) as old, zipfile.ZipFile(path, "w") as new:
        meta = json.loads(old.read("model.json"))
        meta["format_version"] = version
        new.writestr("model.json", json.dumps(meta))
        new.writestr("sequences.json", old.read("sequences.json"))
    with pytest.raises(ModelFileError, match=f"format_version: expected version 1, got "
                                             f"{version!r}"):
        load_model(path)
    result = run_cli("compare", "table-setting", "--strategies", f"opm,learned:{path}")
    assert result.returncode == 2 and "format_version" in result.stderr


@pytest.mark.parametrize("field, value", [("data", None), ("split", None),
                                          ("split", {"ids": {"test": [1, 2]}})])
def test_model_with_bad_metadata_is_refused_when_it_loads(models, tmp_path, field,
                                                          value) -> None:
    path = tmp_path / "tampered.model"
    with zipfile.ZipFile(models["cpt"]) as old, zipfile.ZipFile(path, "w") as new:
        meta = json.loads(old.read("model.json"))
        meta[field] = value
        new.writestr("model.json", json.dumps(meta))
        new.writestr("sequences.json", old.read("sequences.json"))
    with pytest.raises(ModelFileError, match=f"{field}: expected"):
        load_model(path)
    result = run_cli("evaluate", "table-setting", "--strategy", f"learned:{path}")
    assert result.returncode == 2 and "Traceback" not in result.stderr


def _tampered(models, tmp_path, kind: str, arrays=None, sequences=None) -> Path:
    """A copy of a trained model file with its weights or sequences replaced."""
    path = tmp_path / f"tampered-{kind}.model"
    with zipfile.ZipFile(models[kind]) as old, zipfile.ZipFile(path, "w") as new:
        new.writestr("model.json", old.read("model.json"))
        if kind == "cpt":
            new.writestr("sequences.json", json.dumps(sequences))
        else:
            with np.load(io.BytesIO(old.read("weights.npz"))) as data:
                weights = [data[f"arr_{i}"] for i in range(len(data.files))]
            buffer = io.BytesIO()
            np.savez(buffer, *arrays(weights))
            new.writestr("weights.npz", buffer.getvalue())
    return path


@pytest.mark.parametrize("kind, arrays, sequences, expected", [
    ("nn", lambda w: w[:-1], None, "arrays; expected a kernel and a bias per layer"),
    ("nn", lambda w: [w[0][:-1], *w[1:]], None, "expected numbers of shape"),
    ("nn", lambda w: [*w[:2], w[2].T, *w[3:]], None, "expected numbers of shape"),
    ("nn", lambda w: [w[0] * np.nan, *w[1:]], None, "NaN or infinite"),
    ("rnn", lambda w: w[:5], None, "expected the GRU's 6"),
    ("rnn", lambda w: [w[0][:2], *w[1:]], None, "rows for"),
    ("rnn", lambda w: [*w[:3], w[3][0], *w[4:]], None, "expected numbers of shape"),
    ("cpt", None, {"a": 1}, "sequences.json: expected a non-empty list of sequences"),
    ("cpt", None, [["cup", 3]], "sequences.json: expected"),
    ("cpt", None, [["no-such-item"]], "sequences.json: expected"),
    ("cpt", None, [], "sequences.json: expected"),
])
def test_a_model_file_with_wrong_weights_or_sequences_is_refused(
        models, tmp_path, kind, arrays, sequences, expected) -> None:
    path = _tampered(models, tmp_path, kind, arrays, sequences)
    with pytest.raises(ModelFileError, match=re.escape(expected)):
        load_model(path)
    result = run_cli("run", "v1", "--backend", "kinematic", "--strategy", f"learned:{path}")
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and expected in lines[0], result.stderr


def test_train_refuses_bad_input(tmp_path) -> None:
    nocols = tmp_path / "nocols.csv"
    nocols.write_text("ID,sequence\nx,a\n")
    cases = [
        (["train", str(nocols), "--model", "nn", "--out", str(tmp_path / "m")],
         "missing column"),
        (["train", "table-setting", "--model", "nn", "--out", str(tmp_path)],
         "--out: is a folder"),
        (["train", "table-setting", "--model", "nn", "--out", str(tmp_path / "m"),
          "--split", "0.5,0.5"], "--split: expected three fractions"),
        (["train", "table-setting", "--model", "svm", "--out", str(tmp_path / "m")],
         "invalid choice"),
    ]
    for args, expected in cases:
        result = run_cli(*args)
        assert result.returncode == 2, args
        assert len(result.stderr.strip().splitlines()) == 1 and expected in result.stderr


def test_learned_strategy_in_run_bench_and_the_registry(models, tmp_path) -> None:
    run = run_cli("run", "v1", "--strategy", f"learned:{models['rnn']}", "--json")
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["success"] is True
    bench = run_cli("bench", "--setups", "v1", "--strategies", f"learned:{models['cpt']}",
                    "--trials", "1", "--workers", "1", "--out", str(tmp_path / "b"))
    assert bench.returncode == 0, bench.stderr
    assert "learned" in (tmp_path / "b" / "trials.csv").read_text()
    # `order`: the model on the command line answers; a request naming a model file is refused
    request = {"robot": [0, 0, 0], "items": [{"name": "cup", "position": [1, 0, 0]},
                                             {"name": "bowl", "position": [2, 0, 0]}]}
    order = run_cli("order", "--strategy", f"learned:{models['nn']}", "-",
                    stdin=json.dumps(request))
    assert order.returncode == 0, order.stderr
    assert set(json.loads(order.stdout)["order"]) == {"cup", "bowl"}
    sneaky = run_cli("order", "-", stdin=json.dumps({**request,
                                                     "strategy": f"learned:{models['nn']}"}))
    assert sneaky.returncode == 2 and "may not name a model file" in sneaky.stderr


def test_compare_command_writes_figure_and_paired_tests(models, slice_csv, tmp_path) -> None:
    out = tmp_path / "cmp"
    result = run_cli("compare", str(slice_csv), "--strategies",
                     f"opm,learned:{models['nn']},learned:{models['cpt']}", "--protocol",
                     "thesis", "--out", str(out), "--json")
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    assert summary["episodes"] == 62
    assert set(summary["wilcoxon_vs_first"]) == {f"learned:{models['nn']}",
                                                 f"learned:{models['cpt']}"}
    assert (out / "error_distributions.png").stat().st_size > 5000


def test_a_model_with_an_empty_test_split_is_refused_by_name_not_scored_on_nothing(
        tmp_path) -> None:
    """Five episodes split 0.7/0.15/0.15 leave none to test on: training says so, and
    scoring the model on its own file under heldout is a one-line error (it was a
    traceback in `compare` and a mean of nan in `evaluate`)."""
    small = tmp_path / "five.csv"
    with DATA.open(newline="") as handle:
        rows = list(csv.reader(handle))
    with small.open("w", newline="") as handle:
        csv.writer(handle).writerows(rows[:6])
    model = tmp_path / "five.model"
    trained = run_cli("train", str(small), "--model", "cpt", "--out", str(model))
    assert trained.returncode == 0, trained.stderr
    assert "test 0" in trained.stdout and "warning: the test split is empty" in trained.stdout
    for command, option in (("compare", ["--strategies", f"opm,learned:{model}"]),
                            ("evaluate", ["--strategy", f"learned:{model}"])):
        done = run_cli(command, str(small), *option)
        assert done.returncode == 2, done.stdout + done.stderr
        assert "Traceback" not in done.stderr
        assert f"learned:{model}" in done.stderr and "test split" in done.stderr, done.stderr
    # (another file, or the thesis protocol, scores it on every episode)
    assert run_cli("evaluate", str(small), "--strategy", f"learned:{model}", "--protocol",
                   "thesis").returncode == 0


@pytest.mark.parametrize(("blocked", "call", "expected"), [
    ("keras", "train_model(DATA, 'nn', OUT)", "training needs keras and jax"),
    ("cpt", "load_model(CPT)", "CPT models need the `cpt` package"),
])
def test_without_the_extra_one_line_says_how_to_install(models, tmp_path, blocked, call,
                                                        expected) -> None:
    import subprocess
    import sys
    code = (f"import sys; sys.modules[{blocked!r}] = None\n"
            "from cramlite.learning.train import train_model\n"
            "from cramlite.learning.modelfile import load_model\n"
            f"DATA = {str(DATA)!r}; OUT = {str(tmp_path / 'x.model')!r}; "
            f"CPT = {str(models['cpt'])!r}\n"
            "from cramlite.learning.backend import MissingExtraError\n"
            f"try:\n    {call}\nexcept MissingExtraError as exc:\n    print(exc)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert expected in done.stdout and "pip install 'cramlite[learn]'" in done.stdout, \
        done.stdout + done.stderr


def test_the_thesis_protocol_never_predicts_an_item_the_model_never_saw(tmp_path) -> None:
    """A CPT that saw plate -> cup -> fork: a step taking the unseen teapot is an error
    whatever is offered, and an episode of unseen items only is all errors."""
    from cramlite.learning.scoring import unseen_steps

    path = tmp_path / "cpt.model"
    save_model(path, {"kind": "cpt", "vocabulary": ["cup", "fork", "plate"],
                      "split": {"ids": {"train": [], "validation": [], "test": []}},
                      "data": {"sha256": "abc"}}, sequences=[["plate", "cup", "fork"]] * 3)
    model = load_model(path)

    def episode(names: tuple[str, ...]) -> Episode:
        items = tuple(Candidate(n, (float(i), 0.0, 0.0)) for i, n in enumerate(names))
        return Episode(id="y1", activity="test", sequence=names, items=items,
                       taken=tuple(range(len(names))), start_positions=((0.0, 0.0, 0.0),)
                       * len(names))

    mixed = episode(("teapot", "plate"))
    # "" -> plate (the teapot was taken: wrong), then "" again (the teapot is no history)
    # -> plate (right)
    assert thesis_ape(model, mixed, 1, np.random.default_rng(0)) == 1.0
    alien = episode(("teapot", "kettle"))
    for seed in range(5):
        assert thesis_ape(model, alien, 1, np.random.default_rng(seed)) == 2.0
    assert unseen_steps(model, mixed) == 1 and unseen_steps(model, alien, "n") == 2
    assert unseen_steps(model, episode(("plate", "teapot"))) == 0  # (n-1: the last is not)
    # (heldout guesses among the remaining unknown items: sometimes right)
    heldout = evaluate([alien], f"learned:{path}", metric="expected-ape").scores
    assert heldout == [0.5]

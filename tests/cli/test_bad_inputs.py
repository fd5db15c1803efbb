"""Bad inputs: one ``error:`` line naming the problem and the fix, exit status 2, nothing half-written.

The table of outcomes is docs/reliability.md; each row names its test here (by its id).
"""

import errno
import json
import shutil

import h5py
import numpy as np
import pytest
import torch

from keyin.cli.app import fail_if_refused
from keyin.data import hdf5
from keyin.data.brownian import BrownianGenerator
from keyin.data.generate import generate_dataset
from keyin.io import TEMPORARY_TAG, sha256_of
from tests.cli.runner import error_line, last_json, run
from tests.faults import fill_disk_on, make_read_only, refuse


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A good Brownian test split, broken variants of its shard (alone and as dataset folders) and of a checkpoint."""
    root = tmp_path_factory.mktemp("files")
    generate_dataset(BrownianGenerator(), root / "good" / "brownian", "brownian", {"test": 4}, 4, 0, progress=False)
    shard = root / "good" / "brownian" / "test-00000.h5"
    raw = shard.read_bytes()
    (root / "truncated.h5").write_bytes(raw[: len(raw) // 3])
    shutil.copytree(root / "good", root / "corrupt")
    flipped = bytearray(raw)
    flipped[-100] ^= 0xFF
    (root / "corrupt" / "brownian" / "test-00000.h5").write_bytes(bytes(flipped))
    shutil.copy(shard, root / "version99.h5")
    with h5py.File(root / "version99.h5", "a") as handle:
        handle.attrs["format_version"] = 99
    with h5py.File(root / "foreign.h5", "w") as handle:
        handle["frames"] = np.zeros((2, 35, 32, 32, 1), np.uint8)
    empty = {"frames": np.zeros((0, 35, 32, 32, 1), np.uint8), "length": np.zeros(0, np.int32)}
    hdf5.write_shard(root / "empty.h5", empty, {"generator": "x", "config": {}, "seed": 0, "split": "test", "n_cond": 5})
    (root / "garbage.ckpt").write_bytes(b"not a checkpoint")
    torch.save({"state_dict": {}}, root / "plain.ckpt")
    (root / "no_dataset").mkdir()
    good = hdf5.load_arrays(shard)["frames"]  # 0/255
    bad_frames = {"zero_one": good // 255, "float": good.astype(np.float32), "blank": np.zeros_like(good)}
    for name, frames in bad_frames.items():
        dataset_of(root / name, with_frames(shard, root / f"{name}.h5", frames))
    dataset_of(root / "trainable", shard)
    dataset_of(root / "bad_test", shard, test=root / "zero_one.h5")
    small = np.random.default_rng(0).integers(0, 256, (4, 35, 16, 16, 1), dtype=np.uint8)
    with_frames(shard, root / "small.h5", small)
    return root


def with_frames(shard, path, frames):
    """A copy of ``shard`` at ``path`` whose frames are ``frames``, written by h5py as a user's own script would."""
    shutil.copy(shard, path)
    with h5py.File(path, "a") as handle:
        del handle["frames"]
        handle["frames"] = frames
    return path


def dataset_of(folder, shard, test=None):
    """``folder/brownian``: a dataset whose train, val and test splits are each a copy of ``shard`` (the test
    split of ``test`` if given)."""
    target = folder / "brownian"
    target.mkdir(parents=True)
    entries = {}
    for split, source in (("train", shard), ("val", shard), ("test", test or shard)):
        shutil.copy(source, target / f"{split}-00000.h5")
        entries[split] = [{"file": f"{split}-00000.h5", "n": 4, "sha256": sha256_of(target / f"{split}-00000.h5")}]
    hdf5.write_manifest(target, "brownian", entries, {})


# The frame rows' messages ({file}: the bad file in the fixture's folder).
ZERO_ONE = "{{files}}/{file} (4 of 4 clips checked) holds uint8 frames whose largest value is 1: 0/1 images look black"
ZERO_ONE_FIX = "write the file again with frames * 255, or import the 0/1 frames with keyin-import binary=true"
FLOAT = "{{files}}/{file} holds float32 frames in [0, 255], but keyin's HDF5 format stores uint8 0-255"
FLOAT_FIX = "store frames as uint8 0-255 (float frames in [0, 1]: np.round(frames * 255).astype(np.uint8))"
BLANK = "{{files}}/{file}: all 4 clips checked (of 4) are blank, each one value throughout (e.g. 0)"
BLANK_FIX = "float frames in [0, 1] cast to uint8 become 0: store np.round(frames * 255).astype(np.uint8) instead"
FILE_TRAINING = ["scale=smoke", "dataset.train_source=files"]  # Brownian clips read from data_dir's shards
TRAIN_SPLIT = [*FILE_TRAINING, "evaluate=false"]  # the train split's files (with evaluate, the test split's come first)
FIGURE = ["figure=fig5", "ckpt=pretrained:brownian"]

# id, command, overrides ({files} is the fixture's folder), the problem named, the fix named.
BAD_INPUTS = [
    ("unknown-option", "eval", ["model=random", "dataset=nope"],
     "Could not find 'dataset/nope'", "Available options in 'dataset': brownian, custom, metaworld, metaworld_v2, pushing"),
    ("key-typo", "eval", ["model=random", "dataset.n_futur=3"],
     "unknown config key dataset.n_futur", "did you mean dataset.n_future?"),
    ("key-typo-top-level", "train", ["seeed=3"], "unknown config key seeed", "did you mean seed?"),
    ("override-syntax", "eval", ["model=random", "dataset.n_future=="],
     "Error parsing override 'dataset.n_future=='", "override_grammar"),
    ("S>N", "eval", ["model=random", "dataset.max_offset=40"],
     "dataset.max_offset=40 (S) must be <= dataset.n_future=30 (N)", "can never be supervised"),
    ("M*S<N", "eval", ["model=random", "dataset.max_offset=4"],
     "dataset.n_keyframes * dataset.max_offset = 6*4 = 24 (M*S) must be >= dataset.n_future=30", "can never be covered"),
    ("negative-size", "eval", ["model=random", "dataset.n_keyframes=-2"],
     "dataset.n_keyframes=-2", "must be a positive integer"),
    ("zero-size", "eval", ["model=random", "dataset.image_size=0"], "dataset.image_size=0", "must be a positive integer"),
    ("zero-batch", "train", ["scale=smoke", "scale.batch_size=0"], "scale.batch_size=0", "must be a positive integer"),
    ("zero-split", "generate", ["splits={test: 0}"], "splits.test=0", "must be a positive integer"),
    ("negative-seed", "eval", ["model=random", "seed=-1"], "seed=-1", "must be an integer in [0, 2**32)"),
    ("float-seed", "generate", ["seed=1.5"], "seed=1.5", "must be an integer in [0, 2**32)"),
    ("text-seed", "train", ["seed=abc"], "seed='abc'", "must be an integer in [0, 2**32)"),
    ("unknown-stage", "train", ["stage=nope"], "stage='nope'", "allowed: both, interpolator, keyframes"),
    ("nothing-to-evaluate", "eval", ["dataset=brownian"], "choose what to evaluate", "model=random|constant or ckpt="),
    ("negative-video-samples", "eval", ["model=random", "video_samples=-1"],
     "video_samples=-1", "must be an integer >= 0"),
    ("video-of-a-baseline", "eval", ["model=random", "video_samples=2"],
     "a baseline predicts no video", "needs ckpt=<a keyin, jumpy or static run>/checkpoints/keyframes/last.ckpt"),
    ("missing-file", "eval", ["model=random", "data={files}/nope.h5"], "nope.h5 does not exist", "keyin-generate"),
    ("truncated-file", "eval", ["model=random", "data={files}/truncated.h5"],
     "truncated.h5 is not a readable HDF5 file", "truncated or corrupt: regenerate it"),
    ("corrupt-shard", "eval", ["model=random", "data_dir={files}/corrupt"],
     "does not match its checksum in the manifest", "delete it and re-run `keyin-generate`"),
    ("format-version", "eval", ["model=random", "data={files}/version99.h5"],
     "has format_version 99, this keyin reads 1", "regenerate the file"),
    ("foreign-hdf5", "eval", ["model=random", "data={files}/foreign.h5"],
     "lacks the attributes", "write it with keyin.data.hdf5.write_shard"),
    ("missing-manifest", "eval", ["model=random", "data_dir={files}/no_dataset"],
     "no manifest.json in", "generate the dataset with `keyin-generate`"),
    ("missing-split", "eval", ["model=random", "split=val", "data_dir={files}/good"],
     "has no 'val' split (it has ['test'])", "generate it with `keyin-generate`"),
    ("wrong-image-size", "eval", ["model=random", "dataset=pushing", "data={files}/good/brownian/test-00000.h5"],
     "image (H, W, C) (32, 32, 1) != config (64, 64, 3)", "pick the matching dataset= option"),
    ("wrong-channels", "eval", ["model=random", "dataset.channels=3", "data={files}/good/brownian/test-00000.h5"],
     "image (H, W, C) (32, 32, 1) != config (32, 32, 3)", "pick the matching dataset= option"),
    ("empty-file", "eval", ["model=random", "data={files}/empty.h5"], "no clips in", "generate some with `keyin-generate`"),
    # frame values and sizes: every reader of keyin's HDF5 checks them (in keyin.data.clips.ShardClips)
    ("zero-one-frames", "eval", ["model=random", "data={files}/zero_one.h5"], ZERO_ONE.format(file="zero_one.h5"),
     ZERO_ONE_FIX),
    ("zero-one-frames-trained-model", "eval", ["ckpt=pretrained:brownian", "data={files}/zero_one.h5"],
     ZERO_ONE.format(file="zero_one.h5"), ZERO_ONE_FIX),
    ("zero-one-dataset", "eval", ["model=random", "data_dir={files}/zero_one"],
     ZERO_ONE.format(file="zero_one/brownian/test-00000.h5"), ZERO_ONE_FIX),
    ("zero-one-train", "train", [*TRAIN_SPLIT, "data_dir={files}/zero_one"],
     ZERO_ONE.format(file="zero_one/brownian/train-00000.h5"), ZERO_ONE_FIX),
    ("zero-one-test-split-before-training", "train", [*FILE_TRAINING, "data_dir={files}/bad_test"],
     ZERO_ONE.format(file="bad_test/brownian/test-00000.h5"), ZERO_ONE_FIX),
    ("zero-one-figures", "figures", [*FIGURE, "data={files}/zero_one.h5"], ZERO_ONE.format(file="zero_one.h5"),
     ZERO_ONE_FIX),
    ("float-frames", "eval", ["model=random", "data={files}/float.h5"], FLOAT.format(file="float.h5"), FLOAT_FIX),
    ("float-dataset", "eval", ["model=random", "data_dir={files}/float"],
     FLOAT.format(file="float/brownian/test-00000.h5"), FLOAT_FIX),
    ("float-train", "train", [*TRAIN_SPLIT, "data_dir={files}/float"],
     FLOAT.format(file="float/brownian/train-00000.h5"), FLOAT_FIX),
    ("float-figures", "figures", [*FIGURE, "data={files}/float.h5"], FLOAT.format(file="float.h5"), FLOAT_FIX),
    ("blank-clips", "eval", ["model=random", "data={files}/blank.h5"], BLANK.format(file="blank.h5"), BLANK_FIX),
    ("blank-dataset", "eval", ["model=random", "data_dir={files}/blank"],
     BLANK.format(file="blank/brownian/test-00000.h5"), BLANK_FIX),
    ("blank-train", "train", [*TRAIN_SPLIT, "data_dir={files}/blank"],
     BLANK.format(file="blank/brownian/train-00000.h5"), BLANK_FIX),
    ("blank-figures", "figures", [*FIGURE, "data={files}/blank.h5"], BLANK.format(file="blank.h5"), BLANK_FIX),
    ("wrong-size-train", "train", [*TRAIN_SPLIT, "dataset.channels=3", "data_dir={files}/trainable"],
     "{files}/trainable/brownian/train-00000.h5 does not match the dataset config: image (H, W, C) (32, 32, 1) != config "
     "(32, 32, 3)", "pick the matching dataset= option"),
    ("wrong-size-figures", "figures", [*FIGURE, "data={files}/small.h5"],
     "{files}/small.h5 does not match the dataset config: image (H, W, C) (16, 16, 1) != config (32, 32, 1)",
     "pick the matching dataset= option"),
    ("empty-train-split", "train", ["scale=smoke", "dataset.splits.train=2"],
     "the train split has 2 clips, fewer than one batch of 4", "lower scale.batch_size"),
    ("missing-checkpoint", "eval", ["ckpt={files}/nope.ckpt"], "nope.ckpt does not exist", "pass the path of a keyin checkpoint"),
    ("corrupt-checkpoint", "eval", ["ckpt={files}/garbage.ckpt"],
     "garbage.ckpt is not a loadable keyin checkpoint", "pass one that keyin-train wrote"),
    ("foreign-checkpoint", "eval", ["ckpt={files}/plain.ckpt"],
     "plain.ckpt is not a keyin checkpoint (no 'keyin_stage' entry)", "pass one that keyin-train wrote"),
    ("data-dir-is-a-file", "generate", ["data_dir={files}/garbage.ckpt"],
     "Not a directory", "choose a writable folder with hydra.run.dir= (the run dir) or data_dir="),
]


def half_written(root):
    """Files a failed command must not leave: temporaries of atomic writes, results, checkpoints."""
    return sorted(p for p in root.rglob("*") if TEMPORARY_TAG in p.name or p.name == "metrics.json" or p.suffix == ".ckpt")


QUIET = {"eval": "progress=false", "generate": "progress=false", "train": "logger=none", "figures": "n=1"}


@pytest.mark.parametrize("command,overrides,problem,fix",
                         [pytest.param(*case[1:], id=case[0]) for case in BAD_INPUTS])
def test_bad_input_gives_one_error_line(files, tmp_path, command, overrides, problem, fix):
    overrides = [o.replace("{files}", str(files)) for o in overrides]
    line = error_line(run(command, *overrides, QUIET[command], cwd=tmp_path))
    assert problem.replace("{files}", str(files)) in line and fix in line
    assert half_written(tmp_path) == [] and not (tmp_path / "data").exists()


def test_a_read_only_run_dir(tmp_path, monkeypatch):
    make_read_only(monkeypatch, tmp_path / "ro")
    line = error_line(run("eval", "model=random", f"hydra.run.dir={tmp_path}/ro/run", cwd=tmp_path))
    assert f"Read-only file system ({tmp_path}/ro/run)" in line
    assert "choose a writable folder with hydra.run.dir=" in line
    assert list(tmp_path.iterdir()) == []


def test_a_read_only_data_dir(tmp_path, monkeypatch):
    make_read_only(monkeypatch, tmp_path / "ro")
    line = error_line(run("generate", "splits={test: 3}", "progress=false", f"data_dir={tmp_path}/ro", cwd=tmp_path))
    assert f"Read-only file system ({tmp_path}/ro" in line and "data_dir= (datasets)" in line
    assert half_written(tmp_path) == [] and not (tmp_path / "ro").exists()


def test_a_full_disk_while_generating_keeps_the_finished_shards_and_resumes(tmp_path, monkeypatch):
    command = ("generate", "splits={test: 9}", "shard_size=3", "progress=false", "data_dir=data")
    fill_disk_on(monkeypatch, hdf5, lambda path: path.name == "test-00001.h5")
    line = error_line(run(*command, cwd=tmp_path))
    folder = tmp_path / "data" / "brownian"
    assert "No space left on device (data/brownian/test-00001.h5)" in line
    assert "free disk space" in line and "run the same command again" in line
    assert sorted(p.name for p in folder.iterdir()) == ["manifest.json", "test-00000.h5"]
    assert [e["file"] for e in json.loads((folder / "manifest.json").read_text())["splits"]["test"]] == ["test-00000.h5"]
    assert half_written(tmp_path) == []

    monkeypatch.undo()  # space freed: the same command finishes the job
    result = run(*command, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert last_json(result.stdout)["shards_skipped"] == 1 and len(hdf5.split_files(folder, "test")) == 3


def test_a_log_file_hydra_cannot_open_in_a_read_only_run_dir(capsys):
    # Hydra wraps the OSError of its log file in "ValueError: Unable to configure handler 'file'".
    try:
        raise ValueError("Unable to configure handler 'file'") from refuse(errno.EROFS, "run/train.log")
    except ValueError as err:
        with pytest.raises(SystemExit) as exit_:
            fail_if_refused(err)
    assert exit_.value.code == 2
    assert capsys.readouterr().err == (
        "error: Read-only file system (run/train.log); choose a writable folder with hydra.run.dir= "
        "(the run dir) or data_dir= (datasets)\n")
    fail_if_refused(ValueError("a bug, not the file system"))  # returns: the caller re-raises it


@pytest.mark.parametrize("command,overrides", [
    ("eval", ["model=random", "data={files}/good/brownian/test-00000.h5"]),
    ("eval", ["ckpt=pretrained:brownian", "data_dir={files}/trainable"]),
    ("figures", [*FIGURE, "data={files}/good/brownian/test-00000.h5", "k=1"]),
], ids=["eval-file", "eval-dataset-trained-model", "figures"])
def test_the_good_files_beside_the_bad_ones_pass_the_frame_checks(files, tmp_path, command, overrides):
    overrides = [o.replace("{files}", str(files)) for o in overrides]
    result = run(command, *overrides, QUIET[command], cwd=tmp_path)
    assert result.returncode == 0 and "error:" not in result.stderr, result.stderr[-2000:]

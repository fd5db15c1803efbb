import errno
import json
import os

import h5py
import numpy as np
import pytest

from keyin.data.brownian import BrownianGenerator
from keyin.data.clips import ShardClips
from keyin.data.generate import generate_dataset
from keyin.data.hdf5 import (
    SAMPLE_CLIPS, check_compatible, check_frame_values, inspect_shard, load_arrays, sample_rows, split_files, write_shard,
)
from keyin.errors import DatasetFormatError, UnsafePathError
from keyin.io import sha256_of

ATTRS = {"generator": "test", "config": {"a": 1}, "seed": 3, "split": "test", "n_cond": 2}


def arrays(n=3, length=6, size=8, channels=1):
    rng = np.random.default_rng(0)
    return {
        "frames": rng.integers(0, 256, (n, length, size, size, channels), dtype=np.uint8),
        "length": np.full(n, length, dtype=np.int32),
        "keyframes": rng.random((n, length)) < 0.3,
        "positions": rng.random((n, length, 2)).astype(np.float32),
    }


def test_round_trip_keeps_arrays_and_attributes(tmp_path):
    data = arrays()
    write_shard(tmp_path / "a.h5", data, ATTRS)
    loaded = load_arrays(tmp_path / "a.h5")
    for name, value in data.items():
        np.testing.assert_array_equal(loaded[name], value)
    info = inspect_shard(tmp_path / "a.h5")
    assert (info.n, info.clip_length, info.image_shape) == (3, 6, (8, 8, 1))
    assert info.config == {"a": 1} and info.n_cond == 2 and info.split == "test"
    assert [p.name for p in tmp_path.iterdir()] == ["a.h5"]  # no temporary file left


def test_missing_file_is_named(tmp_path):
    with pytest.raises(DatasetFormatError, match="does not exist"):
        inspect_shard(tmp_path / "nope.h5")


def test_truncated_file_is_refused(tmp_path):
    write_shard(tmp_path / "a.h5", arrays(), ATTRS)
    raw = (tmp_path / "a.h5").read_bytes()
    (tmp_path / "a.h5").write_bytes(raw[: len(raw) // 3])
    with pytest.raises(DatasetFormatError, match="truncated or corrupt"):
        inspect_shard(tmp_path / "a.h5")


def test_wrong_format_version_is_refused(tmp_path):
    write_shard(tmp_path / "a.h5", arrays(), ATTRS)
    with h5py.File(tmp_path / "a.h5", "a") as handle:
        handle.attrs["format_version"] = 99
    with pytest.raises(DatasetFormatError, match="format_version 99"):
        inspect_shard(tmp_path / "a.h5")


def test_foreign_hdf5_file_is_refused(tmp_path):
    with h5py.File(tmp_path / "x.h5", "w") as handle:
        handle["frames"] = np.zeros((2, 3, 8, 8, 1), np.uint8)
    with pytest.raises(DatasetFormatError, match="lacks the attributes"):
        inspect_shard(tmp_path / "x.h5")


def test_mismatched_image_size_names_both_shapes(tmp_path):
    write_shard(tmp_path / "a.h5", arrays(size=8, channels=3), ATTRS)
    with pytest.raises(DatasetFormatError, match=r"\(8, 8, 3\) != config \(32, 32, 1\)"):
        check_compatible(inspect_shard(tmp_path / "a.h5"), (32, 32, 1), 2, 4)
    with pytest.raises(DatasetFormatError, match="does not match the dataset config"):
        ShardClips([tmp_path / "a.h5"], (32, 32, 1), 2, 4)


def test_generation_resumes_and_detects_corruption(tmp_path):
    generator = BrownianGenerator()
    kwargs = dict(dataset="brownian", splits={"test": 10}, shard_size=4, seed=0, progress=False)
    first = generate_dataset(generator, tmp_path, **kwargs)
    assert first["clips"] == 10 and first["shards_skipped"] == 0
    files = split_files(tmp_path, "test")
    assert [f.name for f in files] == ["test-00000.h5", "test-00001.h5", "test-00002.h5"]
    again = generate_dataset(generator, tmp_path, **kwargs)
    assert again["clips"] == 0 and again["shards_skipped"] == 3

    before = load_arrays(files[1])["frames"]
    raw = bytearray(files[1].read_bytes())
    raw[-100] ^= 0xFF
    files[1].write_bytes(bytes(raw))
    with pytest.raises(DatasetFormatError, match="checksum"):
        split_files(tmp_path, "test")
    repaired = generate_dataset(generator, tmp_path, **kwargs)
    assert repaired["clips"] == 4 and repaired["shards_skipped"] == 2
    np.testing.assert_array_equal(load_arrays(split_files(tmp_path, "test")[1])["frames"], before)


def test_generation_is_independent_of_worker_count(tmp_path):
    generator = BrownianGenerator()
    kwargs = dict(dataset="brownian", splits={"val": 6}, shard_size=3, seed=4, progress=False)
    generate_dataset(generator, tmp_path / "one", workers=1, **kwargs)
    generate_dataset(generator, tmp_path / "two", workers=2, **kwargs)
    for a, b in zip(split_files(tmp_path / "one", "val"), split_files(tmp_path / "two", "val")):
        np.testing.assert_array_equal(load_arrays(a)["frames"], load_arrays(b)["frames"])


def test_generating_one_split_keeps_the_others_and_a_larger_split_redoes_its_short_shard(tmp_path):
    kwargs = dict(dataset="brownian", shard_size=2, seed=0, progress=False)
    generate_dataset(BrownianGenerator(), tmp_path, splits={"test": 2}, **kwargs)
    generate_dataset(BrownianGenerator(), tmp_path, splits={"val": 1}, **kwargs)
    assert [f.name for f in split_files(tmp_path, "test")] == ["test-00000.h5"]
    assert [f.name for f in split_files(tmp_path, "val")] == ["val-00000.h5"]
    again = generate_dataset(BrownianGenerator(), tmp_path, splits={"val": 3}, **kwargs)  # a larger split
    assert again["clips"] == 3 and again["shards_skipped"] == 0  # the 1-clip shard is redone with 2
    assert [inspect_shard(f).n for f in split_files(tmp_path, "val")] == [2, 1]


def test_a_folder_of_another_config_is_not_mixed_in(tmp_path):
    kwargs = dict(dataset="brownian", splits={"test": 2}, shard_size=2, seed=0, progress=False)
    generate_dataset(BrownianGenerator(), tmp_path, **kwargs)
    with pytest.raises(DatasetFormatError, match="another generator config"):
        generate_dataset(BrownianGenerator(speed=3.0), tmp_path, **kwargs)
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert manifest["config"]["speed"] == 2.0


def test_shard_clips_returns_future_keyframes_and_lengths(tmp_path):
    generate_dataset(BrownianGenerator(), tmp_path, "brownian", {"test": 3}, 3, 0, progress=False)
    clips = ShardClips(split_files(tmp_path, "test"), (32, 32, 1), 5, 30)
    item = clips[2]
    assert item["frames"].shape == (35, 1, 32, 32) and item["frames"].max() == 1.0
    raw = load_arrays(split_files(tmp_path, "test")[0])
    np.testing.assert_array_equal(item["keyframes"].numpy(), raw["keyframes"][2, 5:])
    assert int(item["future_length"]) == 30


def test_a_failed_write_keeps_the_old_file_names_the_path_and_leaves_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "a.h5"
    checksum = write_shard(path, arrays(), ATTRS)

    def disk_full(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "fsync", disk_full)
    with pytest.raises(OSError) as failure:
        write_shard(path, arrays(n=5), ATTRS)
    assert failure.value.errno == errno.ENOSPC and failure.value.filename == str(path)
    assert [p.name for p in tmp_path.iterdir()] == ["a.h5"] and sha256_of(path) == checksum


def test_a_file_without_clips_is_refused(tmp_path):
    write_shard(tmp_path / "empty.h5", arrays(n=0), ATTRS)
    with pytest.raises(DatasetFormatError, match="no clips in .*empty.h5; pass a file with clips"):
        ShardClips([tmp_path / "empty.h5"], (8, 8, 1), 2, 4)


@pytest.mark.parametrize("name", ["../outside.h5", "/etc/hostname", "sub/../../outside.h5"])
def test_a_manifest_naming_a_file_outside_its_folder_is_refused(tmp_path, name):
    folder = tmp_path / "data"
    generate_dataset(BrownianGenerator(), folder, dataset="brownian", splits={"test": 2}, shard_size=2, seed=0,
                     progress=False)
    (tmp_path / "outside.h5").write_bytes((folder / "test-00000.h5").read_bytes())
    manifest = json.loads((folder / "manifest.json").read_text())
    manifest["splits"]["test"][0]["file"] = name
    (folder / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(UnsafePathError, match="outside"):
        split_files(folder, "test", verify=False)
    with pytest.raises(UnsafePathError, match="outside"):  # and generation does not touch it
        generate_dataset(BrownianGenerator(), folder, dataset="brownian", splits={"test": 2}, shard_size=2, seed=0,
                         progress=False)


def shard_of(path, frames):
    """A shard of the given (n, 6, 8, 8, 1) uint8 frames, otherwise like :func:`arrays`'."""
    write_shard(path, {**arrays(n=len(frames)), "frames": frames}, ATTRS)
    return path


def test_the_values_checked_are_a_few_clips_spread_over_the_file():
    assert sample_rows(0) == [] and sample_rows(1) == [0] and sample_rows(3) == [0, 1, 2]
    rows = sample_rows(100_000)
    assert len(rows) == SAMPLE_CLIPS and rows[0] == 0 and rows[-1] == 99_999 and rows == sorted(set(rows))


def test_a_shard_of_0_1_frames_is_refused_naming_the_file_and_the_fix(tmp_path):
    zero_one = arrays(n=20)["frames"] // 128  # 0/1 images
    path = shard_of(tmp_path / "masks.h5", zero_one)
    with pytest.raises(DatasetFormatError) as raised:
        ShardClips([path], (8, 8, 1), 2, 4)
    assert str(raised.value) == (
        f"{path} (8 of 20 clips checked) holds uint8 frames whose largest value is 1: 0/1 images look black on keyin's "
        f"0-255 scale; write the file again with frames * 255, or import the 0/1 frames with keyin-import binary=true"
    )
    assert len(ShardClips([shard_of(tmp_path / "scaled.h5", zero_one * 255)], (8, 8, 1), 2, 4)) == 20


def test_blank_clips_are_data_but_files_of_blank_clips_only_are_refused(tmp_path):
    frames = arrays(n=4)["frames"]
    frames[1] = 0  # one blank clip
    some_blank = shard_of(tmp_path / "some_blank.h5", frames)
    all_blank = shard_of(tmp_path / "all_blank.h5", np.zeros_like(frames))
    assert len(ShardClips([some_blank], (8, 8, 1), 2, 4)) == 4
    assert len(ShardClips([some_blank, all_blank], (8, 8, 1), 2, 4)) == 8  # a blank shard among others
    with pytest.raises(DatasetFormatError) as raised:
        ShardClips([all_blank], (8, 8, 1), 2, 4)
    assert str(raised.value) == (
        f"{all_blank}: all 4 clips checked (of 4) are blank, each one value throughout (e.g. 0); float frames in [0, 1] "
        f"cast to uint8 become 0: store np.round(frames * 255).astype(np.uint8) instead and write the file again"
    )
    other = shard_of(tmp_path / "white.h5", np.full_like(frames, 255))
    with pytest.raises(DatasetFormatError, match=r"all_blank.h5 and 1 more: all 8 clips checked \(of 8\) are blank"):
        check_frame_values([inspect_shard(all_blank), inspect_shard(other)])


def test_float_frames_are_refused_with_their_values_and_the_fix(tmp_path):
    path = tmp_path / "float.h5"
    write_shard(path, arrays(), ATTRS)
    with h5py.File(path, "a") as handle:
        stored = handle["frames"][()]
        del handle["frames"]
        handle["frames"] = stored.astype(np.float32)  # 0-255 floats, where floats are [0, 1]
    with pytest.raises(DatasetFormatError) as raised:
        ShardClips([path], (8, 8, 1), 2, 4)
    low, high = stored[0].min(), stored[0].max()
    assert str(raised.value) == (
        f"{path} holds float32 frames in [{low}, {high}], but keyin's HDF5 format stores uint8 0-255; store frames as "
        f"uint8 0-255 (float frames in [0, 1]: np.round(frames * 255).astype(np.uint8)), or import them with "
        f"keyin-import, which converts float frames in [0, 1]"
    )

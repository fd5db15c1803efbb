"""The embedding cache: encode -> store -> read gives the encoder's output for the same frames; a
changed encoder or regenerated shards make it stale; it is written whole or not at all."""

import os

import h5py
import numpy as np
import pytest
import torch

from keyin.data.clips import ShardClips
from keyin.data.embeddings import (
    CACHE_FOLDER, EmbeddedClips, cache_path, cached_embeddings, encoder_fingerprint, stale_reason, split_sources,
)
from keyin.data.hdf5 import split_files, write_manifest, write_shard
from keyin.errors import DatasetFormatError
from keyin.io import temporary_path
from keyin.models import ConvEncoder

N_COND, N_FUTURE, LENGTH, SIZE = 2, 4, 6, 8


def write_dataset(folder, seed=0, shards=(3, 2)):
    """A dataset folder with a 'train' split of ``shards`` shards (clips per shard), some clips padded."""
    rng = np.random.default_rng(seed)
    entries = []
    for index, n in enumerate(shards):
        arrays = {
            "frames": rng.integers(0, 256, (n, LENGTH, SIZE, SIZE, 1), dtype=np.uint8),
            "length": rng.integers(N_COND + 1, LENGTH + 1, n).astype(np.int32),
            "keyframes": rng.random((n, LENGTH)) < 0.4,
        }
        name = f"train-{index:05d}.h5"
        sha = write_shard(folder / name, arrays, {"generator": "test", "config": {}, "seed": seed, "split": "train", "n_cond": N_COND})
        entries.append({"file": name, "n": n, "sha256": sha})
    write_manifest(folder, "toy", {"train": entries}, {})
    return folder


def encoder(seed=0):
    torch.manual_seed(seed)
    return ConvEncoder(SIZE, 1, 4, 5, coord_channels=True, norm="group")


def test_round_trip_gives_the_encoders_output_for_the_same_frames(tmp_path):
    folder, net = write_dataset(tmp_path), encoder()
    path = cached_embeddings(folder, "train", net, batch_size=2, progress=False)
    assert path == cache_path(folder, "train", encoder_fingerprint(net)) and path.parent.name == CACHE_FOLDER
    embedded = EmbeddedClips(path, N_COND, N_FUTURE, encoder_fingerprint(net))
    frames = ShardClips(split_files(folder, "train"), (SIZE, SIZE, 1), N_COND, N_FUTURE)
    assert len(embedded) == len(frames) == 5
    net.eval()
    for index in range(len(frames)):
        item, cached = frames[index], embedded[index]
        with torch.no_grad():
            expected = net(item["frames"])  # (L, E)
        torch.testing.assert_close(cached["embeddings"], expected, rtol=0, atol=1e-6)
        assert torch.equal(cached["future_length"], item["future_length"])
        assert torch.equal(cached["keyframes"], item["keyframes"])
    assert not [p for p in path.parent.iterdir() if p != path]  # no temporary left


def test_a_valid_cache_is_read_not_encoded_again(tmp_path, monkeypatch):
    folder, net = write_dataset(tmp_path), encoder()
    path = cached_embeddings(folder, "train", net, progress=False)
    monkeypatch.setattr("keyin.data.embeddings.encode_shards", lambda *a, **k: pytest.fail("encoded again"))
    assert cached_embeddings(folder, "train", net, progress=False) == path


def test_another_encoder_gets_its_own_cache_and_a_wrong_one_is_refused(tmp_path):
    folder = write_dataset(tmp_path)
    first, second = encoder(0), encoder(1)
    assert encoder_fingerprint(first) == encoder_fingerprint(encoder(0)) != encoder_fingerprint(second)
    one = cached_embeddings(folder, "train", first, progress=False)
    with torch.no_grad():
        second.head.bias.add_(0.5)  # any change of a weight changes the fingerprint
    two = cached_embeddings(folder, "train", second, progress=False)
    assert one != two and one.is_file() and two.is_file()
    assert stale_reason(one, encoder_fingerprint(second), split_sources(folder, "train")) == "made by another encoder"
    with pytest.raises(DatasetFormatError, match="another encoder"):
        EmbeddedClips(one, N_COND, N_FUTURE, encoder_fingerprint(second))


def test_regenerated_shards_make_the_cache_stale(tmp_path):
    folder, net = write_dataset(tmp_path), encoder()
    path = cached_embeddings(folder, "train", net, progress=False)
    before = EmbeddedClips(path, N_COND, N_FUTURE).embeddings.clone()
    write_dataset(tmp_path, seed=1)  # other frames under the same file names
    assert stale_reason(path, encoder_fingerprint(net), split_sources(folder, "train")).startswith("made from other shards")
    after = EmbeddedClips(cached_embeddings(folder, "train", net, progress=False), N_COND, N_FUTURE).embeddings
    assert not torch.allclose(before, after)


def test_a_killed_writers_temporary_is_removed_and_a_partial_cache_is_rewritten(tmp_path):
    folder, net = write_dataset(tmp_path), encoder()
    path = cache_path(folder, "train", encoder_fingerprint(net))
    path.parent.mkdir(parents=True)
    dead = path.with_name(f".{path.name}.tmp-999999999")
    dead.write_bytes(b"half a file")
    with h5py.File(path, "w") as handle:  # attributes right, arrays missing: a foreign or broken file
        handle.attrs["encoder"] = encoder_fingerprint(net)
        handle.attrs["sources"] = "[]"
    cached_embeddings(folder, "train", net, progress=False)
    assert not dead.exists() and not temporary_path(path).exists()
    assert len(EmbeddedClips(path, N_COND, N_FUTURE)) == 5


def test_a_failed_write_leaves_no_cache(tmp_path, monkeypatch):
    folder, net = write_dataset(tmp_path), encoder()

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", full_disk)
    with pytest.raises(OSError, match="No space"):
        cached_embeddings(folder, "train", net, progress=False)
    assert list((folder / CACHE_FOLDER).iterdir()) == []


def test_mismatched_sizes_and_unreadable_files_are_named(tmp_path):
    folder, net = write_dataset(tmp_path), encoder()
    path = cached_embeddings(folder, "train", net, progress=False)
    with pytest.raises(DatasetFormatError, match="n_cond=2"):
        EmbeddedClips(path, N_COND + 1, N_FUTURE)
    path.write_bytes(b"not hdf5")
    with pytest.raises(DatasetFormatError, match="not a readable embedding cache"):
        EmbeddedClips(path, N_COND, N_FUTURE)
    assert stale_reason(path, encoder_fingerprint(net), split_sources(folder, "train")).startswith("unreadable")

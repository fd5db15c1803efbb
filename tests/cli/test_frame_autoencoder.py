"""keyin-train model=frame_autoencoder end to end at scale=smoke on a few pushing demos: checkpoint,
metrics.json with the object scores, the reconstructions picture, and the dataset's embeddings cached
under the trained encoder."""

import json

import imageio.v3 as iio
import pytest
import torch

from keyin.data.clips import ShardClips
from keyin.data.embeddings import EmbeddedClips, cached_embeddings, encoder_fingerprint
from keyin.data.hdf5 import split_files
from keyin.lit.checkpoints import load_trained_module
from keyin.lit.frame_autoencoder import FrameAutoencoderModule
from tests.cli.runner import train_on_few_pushing_demos

TRAIN = ("model=frame_autoencoder", "dataset=pushing", "scale=smoke", "logger=none", "num_workers=0",
         "trainer.enable_progress_bar=false", "hydra.run.dir=run")


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    root = tmp_path_factory.mktemp("frames")
    return root, train_on_few_pushing_demos(root, *TRAIN)


def test_training_writes_reconstruction_scores_and_a_picture(trained):
    root, metrics = trained
    assert metrics["method"] == "frame_autoencoder" and metrics["n_sequences"] == 4
    clips = ShardClips(split_files(root / "data" / "pushing", "test"), (64, 64, 3), 1, 30)
    assert metrics["frames"] == sum(1 + int(clips[i]["future_length"]) for i in range(4))  # every valid frame
    assert 0 < metrics["bce_per_frame"] < 64 * 64 * 3
    for name in ("puck", "pusher"):  # every pushing frame shows both; 3 steps draw them nowhere near yet
        assert 0 <= metrics[f"{name}_drawn"] <= 1 and 0 <= metrics[f"{name}_iou"] <= 1
    assert json.loads((root / "run" / "metrics.json").read_text()) == metrics
    picture = iio.imread(root / "run" / "reconstructions.png")
    assert picture.shape == (8 * 68, 31 * 68, 3)  # truth and reconstruction of 4 clips, 2-pixel borders


def test_its_encoder_caches_the_datasets_embeddings(trained):
    root, _ = trained
    module, config = load_trained_module(root / "run" / "checkpoints" / "frames" / "last.ckpt", stage="frames")
    assert isinstance(module, FrameAutoencoderModule) and config["model"]["name"] == "frame_autoencoder"
    encoder = module.network.encoder
    path = cached_embeddings(root / "data" / "pushing", "val", encoder, progress=False)
    cached = EmbeddedClips(path, 1, 30, encoder_fingerprint(encoder))[2]
    frames = ShardClips(split_files(root / "data" / "pushing", "val"), (64, 64, 3), 1, 30)[2]["frames"]
    with torch.no_grad():
        torch.testing.assert_close(cached["embeddings"], encoder.eval()(frames), rtol=0, atol=1e-5)

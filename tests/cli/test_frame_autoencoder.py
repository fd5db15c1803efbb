"""keyin-train model=frame_autoencoder end to end at scale=smoke on a few pushing demos: checkpoint,
metrics.json with the object scores, the reconstructions picture, and the dataset's embeddings cached
under the trained encoder; both stages of a two-stage model on it, frozen (backbone=frames)."""

import json

import imageio.v3 as iio
import pytest
import torch

from keyin.data.clips import ShardClips
from keyin.data.embeddings import EmbeddedClips, cached_embeddings, encoder_fingerprint
from keyin.data.hdf5 import split_files
from keyin.lit.registry import load_trained_module
from keyin.lit.frame_autoencoder import FrameAutoencoderModule
from tests.cli.runner import error_line, last_json, run, train_on_few_pushing_demos

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


def test_backbone_frames_trains_both_stages_on_the_frozen_autoencoder(trained):
    root, _ = trained
    frames_ckpt = root / "run" / "checkpoints" / "frames" / "last.ckpt"
    result = run("train", "model=jumpy", "dataset=pushing", "backbone=frames", f"backbone.frames_ckpt={frames_ckpt}",
                 *[arg for arg in TRAIN if not arg.startswith(("model=", "hydra."))], "hydra.run.dir=on_frames", cwd=root)
    assert result.returncode == 0, result.stderr[-3000:]
    assert last_json(result.stdout)["backbone"] == "frames"
    assert "module(s) in eval mode" not in result.stderr  # frozen by design, said in our words instead
    autoencoder = torch.load(frames_ckpt, weights_only=True)["state_dict"]
    for stage, prefix in (("interpolator", ""), ("keyframes", "model.")):
        saved = torch.load(root / "on_frames" / "checkpoints" / stage / "last.ckpt", weights_only=True)["state_dict"]
        for name in ("encoder", "decoder"):
            weights = {key: value for key, value in saved.items() if key.startswith(f"{prefix}{name}.")}
            assert weights and all(
                torch.equal(value, autoencoder[f"network.{key[len(prefix):]}"]) for key, value in weights.items()
            ), (stage, name)


@pytest.mark.parametrize("overrides, says", [
    (("model=keyin", "backbone=frames"), "backbone=frames needs backbone.frames_ckpt="),
    (("model=tap", "backbone=frames", "backbone.frames_ckpt=x.ckpt"), "model=tap has no stage 1"),
])
def test_backbone_frames_without_its_autoencoder_or_on_a_one_stage_model_is_refused(tmp_path, overrides, says):
    assert says in error_line(run("train", *overrides, "logger=none", cwd=tmp_path))

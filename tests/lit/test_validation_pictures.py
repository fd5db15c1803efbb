"""The validation pictures of stage 2 and Surprise: what the modules draw, and what the callback
writes and sends to an image-taking logger."""

from types import SimpleNamespace

import torch

from keyin.lit.pictures import ValidationPictures
from tests.lit.test_keyframe_teacher import keyframe_module
from tests.lit.test_surprise_module import module as surprise_module


def batch() -> dict[str, torch.Tensor]:
    torch.manual_seed(1)
    keyframes = torch.zeros(3, 6, dtype=torch.bool)
    keyframes[0, [1, 4]] = keyframes[2, 2] = True
    return {"frames": torch.rand(3, 8, 1, 8, 8), "future_length": torch.tensor([6, 6, 3]), "keyframes": keyframes}


def run_callback(module, folder, monkeypatch) -> list[tuple[str, str, int]]:
    """Run the callback after a validation at step 7; returns what it sent to the loggers."""
    sent = []
    monkeypatch.setattr(
        "keyin.lit.pictures.log_picture", lambda loggers, key, path, step: sent.append((key, path.name, step))
    )
    trainer = SimpleNamespace(
        sanity_checking=False, is_global_zero=True, val_dataloaders=[batch()], global_step=7, loggers=[]
    )
    ValidationPictures(folder, count=2).on_validation_epoch_end(trainer, module)
    return sent


def test_surprise_pictures_are_the_clip_its_one_step_predictions_and_its_kl(tmp_path, monkeypatch):
    module = surprise_module()
    shown = module.validation_pictures(batch(), count=2)
    clips = batch()["frames"]
    assert shown["clips"].shape == (4, 8, 1, 8, 8)
    torch.testing.assert_close(shown["clips"][0], clips[0])  # ground truth row
    torch.testing.assert_close(shown["clips"][1, 0], clips[0, 0])  # the prediction starts from frame 0
    assert shown["truth"] == [[1, 4], [1, 4], [], []]
    assert shown["predicted"][0] == shown["predicted"][1] == module.discover(clips[:1], torch.tensor([6]))[0]
    assert shown["surprise"].shape == (2, 8) and not shown["surprise"].isnan().any()  # both clips full length
    assert module.training  # back in the mode it was in

    sent = run_callback(module, tmp_path, monkeypatch)
    assert sent == [("val/videos", "val_step000007.png", 7), ("val/surprise", "surprise_step000007.png", 7)]
    assert {p.name for p in tmp_path.iterdir()} == {"val_step000007.png", "val_step000007.gif", "surprise_step000007.png"}


def test_surprise_kl_curve_is_blank_on_padding():
    shown = surprise_module().validation_pictures({k: v[1:] for k, v in batch().items()}, count=2)
    assert not shown["surprise"][0].isnan().any()
    assert shown["surprise"][1, :5].isfinite().all() and shown["surprise"][1, 5:].isnan().all()  # 2 + 3 valid


def test_stage2_pictures_and_offset_histogram_are_written_and_sent(tmp_path, monkeypatch):
    sent = run_callback(keyframe_module(0.0), tmp_path, monkeypatch)
    assert sent == [("val/videos", "val_step000007.png", 7), ("val/offsets", "offsets_step000007.png", 7)]
    assert (tmp_path / "val_step000007.gif").exists()

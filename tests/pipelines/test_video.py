"""Video-prediction diagnostics (keyin/pipelines/video.py, scored by keyin/eval/video.py): per-frame PSNR/SSIM over valid frames, best of k."""

import math

import imageio.v3 as iio
import pytest
import torch

from keyin.eval.video import PSNR_CAP, clip_scores, summarize
from keyin.models import KEYIN
from keyin.pipelines.video import Futures, save_prior_samples, save_rollouts, score_batch
from tests.lit.test_keyframe_teacher import keyframe_module

LENGTHS = torch.tensor([4, 2])  # valid future frames of the two clips (N = 4)


def futures(n_clips: int = 2, seed: int = 0) -> torch.Tensor:
    """(B, N, 3, 64, 64) frames in [0, 0.5], so that an offset up to 0.5 stays in [0, 1]."""
    return torch.rand(n_clips, 4, 3, 64, 64, generator=torch.Generator().manual_seed(seed)) * 0.5


def test_identical_frames_score_ssim_one_and_the_capped_psnr():
    frames = futures()
    scores = clip_scores(frames, frames, LENGTHS)
    assert torch.equal(scores["psnr"], torch.full((2,), PSNR_CAP))  # not +inf
    torch.testing.assert_close(scores["ssim"], torch.ones(2))


def test_a_constant_offset_scores_its_psnr_per_clip():
    target = futures()
    offsets = torch.tensor([0.1, 0.01])
    scores = clip_scores(target + offsets.view(2, 1, 1, 1, 1), target, LENGTHS)
    torch.testing.assert_close(scores["psnr"], -10 * torch.log10(offsets**2), rtol=0, atol=1e-3)  # 20, 40 dB
    assert bool((scores["ssim"] < 1).all())


def test_padded_frames_change_nothing():
    target, predicted = futures(seed=0), futures(seed=1)
    scores = clip_scores(predicted, target, LENGTHS)
    noisy_target, noisy_predicted = target.clone(), predicted.clone()
    noisy_target[1, 2:] = torch.rand(2, 3, 64, 64)
    noisy_predicted[1, 2:] = 1.0
    noisy = clip_scores(noisy_predicted, noisy_target, LENGTHS)
    short = clip_scores(predicted[1:, :2], target[1:, :2], LENGTHS[1:])
    for name in ("psnr", "ssim"):
        assert torch.equal(scores[name], noisy[name])
        torch.testing.assert_close(scores[name][1:], short[name])


def test_best_of_k_takes_each_clips_best_sample():
    target = futures()
    offsets = torch.tensor([[0.1, 0.01], [0.01, 0.1], [0.2, 0.001]])  # (k, B): clip 0 best at 1, clip 1 at 2
    samples = [clip_scores(target + d.view(2, 1, 1, 1, 1), target, LENGTHS) for d in offsets]
    scores = {name: torch.stack([sample[name] for sample in samples]) for name in ("psnr", "ssim")}
    scores.update(psnr_posterior=torch.tensor([7.0, 9.0]), ssim_posterior=torch.tensor([0.5, 0.7]),
                  psnr_blank=torch.tensor([18.0, 20.0]), ssim_blank=torch.tensor([0.8, 0.9]))
    summary = summarize(scores)
    psnr = -10 * torch.log10(offsets**2)
    assert math.isclose(summary["psnr_best_of_k"], (40.0 + 60.0) / 2, abs_tol=1e-3)  # no one sample is best for both
    assert math.isclose(summary["psnr_mean"], float(psnr.mean()), abs_tol=1e-3)
    assert summary["ssim_best_of_k"] == float(scores["ssim"].max(0).values.mean())
    assert summary["psnr_posterior"] == 8.0 and math.isclose(summary["ssim_posterior"], 0.6, rel_tol=1e-6)
    assert summary["psnr_blank"] == 19.0 and math.isclose(summary["ssim_blank"], 0.85, rel_tol=1e-6)
    assert summary["k"] == 3


def test_a_clip_without_valid_frames_is_left_out_of_the_means():
    target = futures()
    scores = clip_scores(target + 0.1, target, torch.tensor([4, 0]))
    assert bool(scores["psnr"][1].isnan())
    summary = summarize({**{name: values[None] for name, values in scores.items()},
                         **{f"{name}_{kind}": values for name, values in scores.items() for kind in ("posterior", "blank")}})
    assert math.isclose(summary["psnr_best_of_k"], 20.0, abs_tol=1e-3)
    assert math.isclose(summary["psnr_mean"], 20.0, abs_tol=1e-3)


def rgb_model() -> KEYIN:
    """A small KEYIN model on frames of the pushing size, 64x64 RGB (N = 4 of STAGE1's 6)."""
    return keyframe_module(0.0, image_size=64, channels=3).eval().model


def rgb_clips(noisy_padding: bool = False) -> torch.Tensor:
    """(2, 6, 3, 64, 64): 2 conditioning frames and 4 future ones; clip 1 is padded after 2."""
    clips = torch.cat([futures(seed=2)[:, :2], futures(seed=3)], dim=1)
    if noisy_padding:
        clips[1, 4:] = torch.rand(2, 3, 64, 64)
    return clips


def test_rgb_scores_are_seeded_and_ignore_the_padding():
    model = rgb_model()
    runs = []
    for clips in (rgb_clips(), rgb_clips(noisy_padding=True)):
        torch.manual_seed(5)
        runs.append(score_batch(model, clips, LENGTHS, k=2))
    for name in ("psnr", "ssim"):
        assert runs[0][name].shape == (2, 2) and runs[0][f"{name}_posterior"].shape == (2,)
        assert bool(runs[0][name].isfinite().all())
        assert not torch.equal(runs[0][name][0], runs[0][name][1])  # two different samples
        for key in (name, f"{name}_posterior", f"{name}_blank"):  # the same seed, the same samples; padding unseen
            torch.testing.assert_close(runs[0][key], runs[1][key])


def test_the_blank_reference_scores_black_frames_against_the_truth():
    """A frame with a fraction p of its pixels at 1 is -10 log10(p) dB from black."""
    clips = torch.zeros(1, 8, 1, 8, 8)  # the model's clips: n_cond 2, N 6, 8x8 grey
    clips[0, 2:, 0, :4, :] = 1.0  # every future frame has half its pixels lit
    model = keyframe_module(0.0).eval().model
    blank = score_batch(model, clips, torch.tensor([6]), k=1)["psnr_blank"]
    torch.testing.assert_close(blank, torch.tensor([10 * math.log10(2.0)]))


def test_rollouts_show_truth_reconstruction_and_best_sample_per_clip(tmp_path):
    keyframes = torch.zeros(2, 4, dtype=torch.bool)
    keyframes[:, 1] = True
    clips = [dict(frames=f, future_length=n, keyframes=k) for f, n, k in zip(rgb_clips(), LENGTHS, keyframes)]
    model = rgb_model()
    torch.manual_seed(0)
    png, gif = save_rollouts(model, clips, k=2, folder=tmp_path)
    assert iio.imread(png).shape == (3 * 2 * 68, 6 * 68, 3)  # a row per clip and kind, 2-pixel borders
    movie = iio.imread(gif, index=None)
    assert movie.shape[:3] == (6, 3 * 68 * 3, 2 * 68 * 3)  # each clip's three rows in one column, 3x


def test_the_best_future_of_each_clip_is_its_highest_psnr():
    videos = torch.arange(3.0).view(3, 1, 1, 1, 1, 1).expand(3, 2, 1, 1, 1, 1)  # sample i is all i
    psnr = torch.tensor([[10.0, float("nan")], [30.0, float("nan")], [20.0, float("nan")]])
    futures = Futures(videos, [[[i], [i + 10]] for i in range(3)], {"psnr": psnr, "ssim": -psnr})
    video, keyframes, scores = futures.best()
    assert video.flatten().tolist() == [1.0, 0.0]  # clip 1 has no valid frames: the first sample
    assert keyframes == [[1], [10]] and scores["psnr"][0] == 30.0 and scores["ssim"][0] == -30.0


def test_prior_samples_picture_the_truth_and_k_samples_per_clip(tmp_path):
    keyframes = torch.zeros(2, 4, dtype=torch.bool)
    keyframes[:, 2] = True
    clips = [dict(frames=f, future_length=n, keyframes=k) for f, n, k in zip(rgb_clips(), LENGTHS, keyframes)]
    torch.manual_seed(0)
    pictured = save_prior_samples(rgb_model(), clips, k=3, folder=tmp_path, name="fig")
    assert [clip["true_keyframes"] for clip in pictured["clips"]] == [[2], [2]]
    assert [len(clip["samples"]) for clip in pictured["clips"]] == [3, 3] and pictured["k"] == 3
    best = max(sample["psnr"] for sample in pictured["clips"][0]["samples"])
    assert pictured["psnr_best_of_k"] == pytest.approx((best + max(s["psnr"] for s in pictured["clips"][1]["samples"])) / 2)
    movie = iio.imread(tmp_path / "fig.gif", index=None)
    assert movie.shape[:3] == (6, 4 * 68 * 3, 2 * 68 * 3)  # each clip's truth and 3 samples in one column, 3x
    assert iio.imread(tmp_path / "fig.png").ndim == 3

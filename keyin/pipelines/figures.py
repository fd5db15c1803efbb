"""The paper's Fig. 4, 6 and 7 from trained KEYIN models (KEYIN, Jumpy): the predictions, the
numbers each figure shows, and its PNG (drawn by :mod:`keyin.viz.figures`). Fig. 5/10, the prior
samples, is :func:`keyin.pipelines.video.save_prior_samples`."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np
import torch
from torch import Tensor
from torch.utils.data import Dataset

from keyin.data.pushing import PushingGenerator
from keyin.envs.geometry import apply_homography, passing_side, side_fractions, top_view_homography, wall_corners
from keyin.envs.layout import Layout
from keyin.eval.f1 import keyframe_lists, keyframe_scores
from keyin.eval.trajectories import demonstration_sides, puck_tracks, track_sides
from keyin.eval.video import METRICS
from keyin.models import KEYIN
from keyin.pipelines.video import first_clips, predict, predict_futures
from keyin.viz.figures import save_labeled_strips, save_trajectories
from keyin.viz.keyframes import marked_frames

MODES = ("prior", "posterior")


@torch.no_grad()
def sample_videos(model: KEYIN, clip: dict[str, Tensor], count: int) -> Tensor:
    """``count`` futures of one clip drawn from the prior given its conditioning frames.

    Args:
        model: a trained :class:`keyin.models.KEYIN` in eval mode.
        clip: an item of :class:`keyin.data.clips.ShardClips` (``frames`` (L, C, H, W),
            ``future_length`` ()).
    Returns:
        (count, L, C, H, W) the conditioning frames, then each sample's argmax-offset video.
    """
    frames = clip["frames"].expand(count, *clip["frames"].shape)
    video, _ = predict(model, frames, clip["future_length"].expand(count), "prior", sample=True)
    return video


@torch.no_grad()
def save_comparison(
    models: Mapping[str, KEYIN], clips: Dataset, count: int, mode: str, k: int, path: Path
) -> dict[str, Any]:
    """Fig. 4 (KEYIN vs Jumpy, ``mode="posterior"``) and Fig. 7 (pushing predictions): for each of
    the first ``count`` clips the truth, its true keyframes in green, then one row per model, its
    keyframes marked (red; yellow where they hit a true one): the posterior-mean reconstruction
    (``mode="posterior"``) or the best by PSNR of k prior samples (``mode="prior"``).

    Args:
        models: row label -> model; all of one ``n_cond``.
    Returns:
        ``clips``: per clip its index, ``true_keyframes`` and per model its ``keyframes``, ``psnr``,
        ``ssim``; ``summary``: per model the mean PSNR and SSIM and the keyframe F1 (exact) over
        these clips; ``mode``; ``k``.
    """
    batch = first_clips(clips, count)
    frames, lengths = batch["frames"], batch["future_length"]
    truth = keyframe_lists(batch["keyframes"])
    draws = k if mode == "prior" else 1
    best = {
        name: predict_futures(model, frames, lengths, draws, mode, sample=mode == "prior").best()
        for name, model in models.items()
    }
    n_cond = next(iter(models.values())).n_cond
    how = f"prior, best of {k}" if mode == "prior" else "posterior"
    rows, labels, shown = [], [], []
    for clip, true in enumerate(truth):
        rows.append(marked_frames(frames[clip], n_cond, true, []))
        labels.append(f"clip {clip}\nground truth")
        shown.append({"clip": clip, "true_keyframes": true})
        for name, (videos, keyframes, scores) in best.items():
            rows.append(marked_frames(videos[clip], n_cond, true, keyframes[clip]))
            labels.append(f"{name}\n({how})\nPSNR {float(scores['psnr'][clip]):.1f}")
            shown[-1][name] = {"keyframes": keyframes[clip], **{m: float(scores[m][clip]) for m in METRICS}}
    save_labeled_strips(rows, labels, path)
    n_future = frames.shape[1] - n_cond
    summary = {
        name: {**{m: float(scores[m].nanmean()) for m in METRICS}, "f1": keyframe_scores(keyframes, truth, n_future)["f1"]}
        for name, (_, keyframes, scores) in best.items()
    }
    return {"clips": shown, "summary": summary, "mode": mode, "k": draws}


def save_trajectory_figure(
    model: KEYIN,
    clips: Dataset,
    scenes: Mapping[str, np.ndarray],
    start: int,
    count: int,
    path: Path,
    generator: PushingGenerator | None = None,
    demos: int = 0,
    seed: int = 0,
    batch_size: int = 100,
) -> dict[str, Any]:
    """Fig. 6: ``count`` prior samples from the conditioning frames of test clip ``start``, the puck's
    track in each (colour segmentation of every predicted frame), over the scene with the wall; which
    way round the wall they pass (:func:`keyin.envs.geometry.passing_side`), beside the same for
    every test clip's frames and, with ``demos`` > 0, a first panel of that many demonstrator runs
    from the same start (its own detour sides and subgoals).

    Args:
        scenes: the test clips' stored ``wall`` (B, 5), ``side`` (B,), ``goal`` (B, 2), ``puck`` and
            ``pusher`` (B, L, 2) world positions.
        generator: the dataset's generator (its demonstrator), needed for ``demos`` > 0.
    Returns:
        ``samples`` and ``demonstrations`` (:func:`side_fractions`; the latter None without
        ``demos``), ``test_clips`` (:func:`demonstration_sides`) and ``start_clip``.
    """
    clip, wall = clips[start], scenes["wall"][start]
    image_size = clip["frames"].shape[-1]
    to_pixels = top_view_homography(image_size)
    tracks = puck_tracks(sample_videos(model, clip, count))  # (count, L, 2) pixels
    samples = side_fractions(track_sides(tracks, wall, image_size))
    panels, demonstrations = {}, None
    if demos:
        layout = Layout(wall, scenes["puck"][start][0], scenes["goal"][start], scenes["pusher"][start][0])
        runs = [demo.puck[:: generator.frame_skip] for demo in generator.demos_from(layout, demos, seed)]
        demonstrations = side_fractions([passing_side(run, wall) for run in runs])
        title = f"{len(runs)} demonstrations: {proportions(demonstrations)}"
        panels[title] = [apply_homography(to_pixels, run) for run in runs]
    panels[f"{count} samples: {proportions(samples)}"] = list(tracks)
    background = (clip["frames"][0].permute(1, 2, 0) * 255).round().to(torch.uint8).numpy()
    save_trajectories(background, apply_homography(to_pixels, wall_corners(wall)), tracks[0, 0], panels, path)
    return {
        "start_clip": start,
        "samples": samples,
        "demonstrations": demonstrations,
        "test_clips": demonstration_sides(clips, scenes["wall"], scenes["side"], batch_size),
    }


def proportions(fractions: Mapping[str, float]) -> str:
    """"left 48 % / right 52 %", with "through" and "none" where they occur."""
    shown = ("left", "right", *(side for side in ("through", "none") if fractions[side]))
    return " / ".join(f"{side} {100 * fractions[side]:.0f} %" for side in shown)

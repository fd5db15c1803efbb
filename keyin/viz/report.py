"""Charts: Table 1 as bars, the methods' keyframes on test clips, the histogram of chosen offsets,
Surprise's KL curves, Table 2's success rate against the success threshold."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import torch  # noqa: E402

from keyin.viz.figures import save_figure, save_labeled_strips  # noqa: E402
from keyin.viz.keyframes import marked_frames  # noqa: E402


def save_f1_bars(
    datasets: Sequence[str],
    methods: Sequence[str],
    means: Sequence[float],
    stds: Sequence[float],
    paper: Sequence[float | None],
    path: Path,
) -> Path:
    """Horizontal bars of our F1 (mean ± std over seeds), one panel per dataset, the paper's F1 as a black tick;
    the rows read top to bottom in the table's order, their names in full.

    Args:
        datasets, methods: (n,) each bar's panel and label, drawn in this order within a panel.
        means, stds: (n,) our F1 over seeds.
        paper: (n,) the paper's F1, None where the paper has none.
    """
    if not len(datasets) == len(methods) == len(means) == len(stds) == len(paper):
        raise ValueError("save_f1_bars needs one dataset, method, mean, std and paper F1 per bar")
    panels = sorted(set(datasets))
    most = max(sum(name == dataset for name in datasets) for dataset in panels)
    fig, axes = plt.subplots(1, len(panels), figsize=(6.5 * len(panels), 1.2 + 0.28 * most), squeeze=False)
    for ax, dataset in zip(axes[0], panels):
        mine = [i for i, name in enumerate(datasets) if name == dataset]  # its bars, in order
        y = np.arange(len(mine))
        ax.barh(y, [means[i] for i in mine], xerr=[stds[i] for i in mine], capsize=3, color="tab:blue", label="ours")
        theirs = [(paper[i], j) for j, i in enumerate(mine) if paper[i] is not None]
        if theirs:
            ax.scatter(*zip(*theirs), marker="|", s=200, color="black", linewidths=2, label="paper", zorder=3)
        ax.set_yticks(y, [methods[i] for i in mine], fontsize=8)
        ax.invert_yaxis()  # the table's first row on top
        ax.set_xlim(0, 1)
        ax.set_xlabel("keyframe F1 (exact)")
        ax.set_title(dataset)
        ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path, dpi=120)


def save_method_comparison(
    clips: torch.Tensor,
    n_cond: int,
    truth: Sequence[Sequence[int]],
    predicted: Mapping[str, Sequence[Sequence[int]]],
    path: Path,
) -> Path:
    """For each clip, one strip of its future frames per method (like the paper's Fig. 3-5).

    Borders: green = ground truth only, red = the method's only, yellow = both.

    Args:
        clips: (K, L, C, H, W) in [0, 1].
        truth: per clip, true future keyframe indices.
        predicted: method → per clip, its future keyframe indices.
    """
    strips = [marked_frames(clip, n_cond, truth[k], marks[k])[n_cond:] for k, clip in enumerate(clips)
              for marks in predicted.values()]
    labels = [method if m else f"clip {k}\n{method}" for k in range(len(clips)) for m, method in enumerate(predicted)]
    return save_labeled_strips(strips, labels, path)


def save_offset_histogram(offsets: torch.Tensor, max_offset: int, path: Path, title: str = "") -> Path:
    """How often each offset 1…S is chosen, one group of bars per keyframe t.

    A single tall bar per keyframe, the same for every clip, is the constant-offset collapse.

    Args:
        offsets: (B, M) chosen offsets in 1…S.
    """
    n_keys = offsets.shape[1]
    fig, ax = plt.subplots(figsize=(6, 3))
    width = 0.8 / n_keys
    values = np.arange(1, max_offset + 1)
    for t in range(n_keys):
        counts = np.bincount(offsets[:, t].numpy(), minlength=max_offset + 1)[1:]
        ax.bar(values + (t - (n_keys - 1) / 2) * width, counts / len(offsets), width, label=f"t={t + 1}")
    ax.set_xticks(values)
    ax.set_xlabel("offset")
    ax.set_ylabel("fraction of clips")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return save_figure(fig, path, dpi=100)


def save_surprise_curves(
    kl: torch.Tensor,
    n_cond: int,
    truth: Sequence[Sequence[int]],
    predicted: Sequence[Sequence[int]],
    path: Path,
    title: str = "",
) -> Path:
    """The per-step KL of a few clips over their future positions, true keyframes as green and
    the predicted (surprise) keyframes as red vertical lines; KL near 0 everywhere is the collapse.

    Args:
        kl: (K, L) KL of every clip index, conditioning frames first.
        truth, predicted: per clip, future keyframe indices.
    """
    fig, axes = plt.subplots(len(kl), 1, figsize=(6, 1.3 * len(kl) + 0.5), sharex=True, squeeze=False)
    future = np.arange(kl.shape[1]) - n_cond
    for ax, curve, true, chosen in zip(axes[:, 0], kl, truth, predicted, strict=True):
        ax.plot(future, curve.numpy(), color="black", marker=".", linewidth=1)
        for position in true:
            ax.axvline(position, color="tab:green", linewidth=2, alpha=0.5)
        for position in chosen:
            ax.axvline(position, color="tab:red", linestyle="--", linewidth=1)
        ax.set_ylabel("KL", fontsize=8)
    axes[-1, 0].set_xlabel("future position (green: true keyframe, red dashed: predicted)")
    axes[0, 0].set_title(title, fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path, dpi=100)


def save_success_curves(
    thresholds: np.ndarray, curves: Mapping[str, np.ndarray], threshold: float, path: Path
) -> Path:
    """Success rate against the success threshold (world units of final shortest-path error), one
    line per planner; the threshold of the table dashed.

    Args:
        thresholds: (T,) increasing, from 0.
        curves: legend label → (T,) success rate at each threshold.
    """
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for label, rates in curves.items():
        ax.plot(thresholds, rates, label=label)
    ax.axvline(threshold, color="black", linestyle="--", linewidth=1, label=f"threshold {threshold:g}")
    ax.set_xlim(0, float(thresholds[-1]))
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("success threshold: final shortest-path error (world units)")
    ax.set_ylabel("success rate")
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    return save_figure(fig, path, dpi=120)

"""Keyframe discovery metrics (paper §4.1.2, Table 1; docs/evaluation.md): exact-match micro F1 and its companions.

Keyframes are sets of future-frame indices per clip. The primary score is micro F1 over the test
set, ``2·ΣTP / (Σ|P| + Σ|G|)``, with exact index matches. Secondary: macro F1 (mean per-clip F1),
F1 with a ±k tolerance under one-to-one matching, the mean distance from each prediction to the
nearest ground-truth keyframe, the mean Hausdorff distance between a clip's two sets, and the
scores per video (a video's clips pooled).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Iterable, Sequence

import numpy as np

from keyin.decode.ends import sequence_ends, with_ends

if TYPE_CHECKING:
    import torch


def tolerant_matches(predicted: Sequence[int], truth: Sequence[int], tolerance: int) -> int:
    """Size of a maximum one-to-one matching with ``|p - g| <= tolerance``.

    Both sets lie on a line, so the greedy sweep (each truth, in order, takes the leftmost free
    prediction within reach) is optimal.
    """
    preds = sorted(predicted)
    matches, next_free = 0, 0
    for g in sorted(truth):
        while next_free < len(preds) and preds[next_free] < g - tolerance:
            next_free += 1
        if next_free < len(preds) and preds[next_free] <= g + tolerance:
            matches += 1
            next_free += 1
    return matches


def hausdorff(predicted: Sequence[int], truth: Sequence[int], n_future: int) -> float:
    """The Hausdorff distance between two sets of future indices: the farthest any keyframe of one
    set is from the nearest of the other. Two empty sets are 0 apart; an empty set is ``n_future``
    (the clip's length, farther than any two indices) from a non-empty one."""
    if not predicted and not truth:
        return 0.0
    if not predicted or not truth:
        return float(n_future)
    gaps = np.abs(np.subtract.outer(np.asarray(predicted), np.asarray(truth)))
    return float(max(gaps.min(axis=1).max(), gaps.min(axis=0).max()))


def keyframe_lists(keyframes: torch.Tensor) -> list[list[int]]:
    """Per clip, the indices of a (B, N) bool keyframe mask, in order."""
    return [row.nonzero().flatten().tolist() for row in keyframes]


TABLE_TOLERANCES = (1, 2)  # the ±k F1 every Table 1 report carries beside the exact one (f1_tol1, f1_tol2)


def _f1(tp: float, n_pred: float, n_true: float) -> float:
    return 1.0 if n_pred + n_true == 0 else 2.0 * tp / (n_pred + n_true)


def keyframe_scores(
    predicted: Iterable[Iterable[int]], truth: Iterable[Iterable[int]], n_future: int, tolerances: Sequence[int] = (1,)
) -> dict[str, float]:
    """Keyframe F1 and companions over a set of clips.

    Args:
        predicted: per clip, predicted future indices; duplicates and indices outside
            [0, n_future) are dropped (a keyframe past the clip is no prediction).
        truth: per clip, ground-truth future indices.
        n_future: N, the number of future frames.
        tolerances: the k of each ±k F1 (those of :data:`TABLE_TOLERANCES` are always scored).
    Returns:
        f1, precision, recall (micro, exact), f1_macro, f1_tol<k> for each k, mean_distance (mean
        over predictions of the distance to the nearest truth; NaN if none), hausdorff (mean over
        clips of :func:`hausdorff`), n_sequences, n_predicted, n_true (per clip means).
    """
    ks = sorted({*TABLE_TOLERANCES, *(int(k) for k in tolerances)})
    tp = n_pred = n_true = 0
    tolerant = dict.fromkeys(ks, 0)
    per_clip, distances, apart, n_clips = [], [], [], 0
    for pred_clip, true_clip in zip(predicted, truth, strict=True):
        preds = sorted({int(p) for p in pred_clip if 0 <= int(p) < n_future})
        trues = sorted({int(g) for g in true_clip})
        hits = len(set(preds) & set(trues))
        tp, n_pred, n_true = tp + hits, n_pred + len(preds), n_true + len(trues)
        for k in ks:
            tolerant[k] += tolerant_matches(preds, trues, tolerance=k)
        per_clip.append(_f1(hits, len(preds), len(trues)))
        apart.append(hausdorff(preds, trues, n_future))
        if trues:
            true_array = np.asarray(trues)
            distances.extend(np.abs(true_array - p).min() for p in preds)
        n_clips += 1
    return {
        "f1": _f1(tp, n_pred, n_true),
        "precision": tp / n_pred if n_pred else 0.0,
        "recall": tp / n_true if n_true else 0.0,
        "f1_macro": float(np.mean(per_clip)) if per_clip else float("nan"),
        **{f"f1_tol{k}": _f1(tolerant[k], n_pred, n_true) for k in ks},
        "mean_distance": float(np.mean(distances)) if distances else float("nan"),
        "hausdorff": float(np.mean(apart)) if apart else float("nan"),
        "n_sequences": n_clips,
        "n_predicted": n_pred / max(n_clips, 1),
        "n_true": n_true / max(n_clips, 1),
    }


def video_scores(
    predicted: Sequence[Sequence[int]], truth: Sequence[Sequence[int]], videos: Sequence[str], n_future: int
) -> dict[str, dict[str, float]]:
    """:func:`keyframe_scores` of each video's clips pooled (``videos``: per clip, its video), in
    the order the videos first appear."""
    if len(videos) != len(predicted):
        raise ValueError(f"{len(videos)} video names for {len(predicted)} clips")
    clips: dict[str, list[int]] = {}
    for index, video in enumerate(videos):
        clips.setdefault(str(video), []).append(index)
    return {
        video: keyframe_scores([predicted[i] for i in rows], [truth[i] for i in rows], n_future)
        for video, rows in clips.items()
    }


# The scores of each information-rule column (docs/evaluation.md): a padded clip's last valid frame
# removed from labels and predictions (interior), or given to every method (with ends).
COLUMN_SCORES = ("f1", "f1_tol1", "f1_tol2", "precision", "recall", "n_predicted", "n_true")


def without_ends(positions: Iterable[Iterable[int]], ends: Sequence[int | None]) -> list[list[int]]:
    """Per clip, the positions less the clip's sequence end (:func:`keyin.decode.ends.sequence_ends`)."""
    return [[int(p) for p in row if int(p) != end] for row, end in zip(positions, ends, strict=True)]


def column_scores(
    predicted: Sequence[Sequence[int]], truth: Sequence[Sequence[int]], lengths: Sequence[int], n_future: int
) -> dict[str, float]:
    """The scores of the information rule's two columns, ``<score>_interior`` and
    ``<score>_with_ends`` for each of :data:`COLUMN_SCORES`.

    *Interior*: the last valid frame of a padded clip is neither a label nor a prediction, so no
    method gains from knowing where a sequence ends. *With ends*: every method gets that frame as a
    prediction (and it is a label), so every method knows it. Full-length clips are the same in
    both. Args as :func:`keyframe_scores`, with ``lengths`` (B,) valid future frames per clip.
    """
    ends = sequence_ends(lengths, n_future)
    interior = keyframe_scores(without_ends(predicted, ends), without_ends(truth, ends), n_future)
    ended = keyframe_scores(with_ends(predicted, ends), with_ends(truth, ends), n_future)
    return {
        **{f"{score}_interior": interior[score] for score in COLUMN_SCORES},
        **{f"{score}_with_ends": ended[score] for score in COLUMN_SCORES},
    }


def discovery_summary(predicted: list[list[int]], keyframes: torch.Tensor) -> dict[str, float]:
    """What a training run logs about discovered keyframes on a validation batch.

    Args:
        predicted: per clip, discovered future indices.
        keyframes: (B, N) bool ground-truth mask.
    Returns:
        f1, f1_tol1, n_predicted, and distinct_patterns: how many different keyframe lists the
        batch got (1 for every clip is the constant-offset collapse, PROTOTYPE-FINDINGS §3).
    """
    scores = keyframe_scores(predicted, keyframe_lists(keyframes), keyframes.shape[1])
    return {
        "f1": scores["f1"],
        "f1_tol1": scores["f1_tol1"],
        "n_predicted": scores["n_predicted"],
        "distinct_patterns": float(len({tuple(row) for row in predicted})),
    }

"""The ceiling of KEYIN's segmentation decoding on pushing: an interpolator that knows the true state.

    python studies/pushing_state_segmentation.py --val data/pushing/val-00000.h5 --test data/pushing/test-00000.h5

KEYIN's ``map`` decoding picks the segmentation (at most M segments of at most S frames) that its
stage-1 interpolator renders best. Here the "interpolator" is exact linear interpolation of the
*true* object positions between the segment's boundary frames, and the cost of a segment is the
summed squared position error of its inner frames: what a perfect stage 1 whose frames were linear
in the objects' motion would see. The keyframe price λ (or the label-free knee) is chosen on the
validation clips, then scored on the test clips with the information rule's interior column.
Prints Markdown.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

from keyin.data.hdf5 import load_arrays
from keyin.decode.segmentation import KNEE, decode_by_length
from keyin.eval.f1 import column_scores, keyframe_lists

N_KEYFRAMES, N_COND = 6, 1
STATES = {"puck": ("puck",), "pusher": ("pusher",), "puck + pusher": ("puck", "pusher")}
PRICES: list[float | str] = [0.0, 1e-4, 3e-4, 1e-3, 3e-3, 1e-2, KNEE]
REST_STEPS = [0.005, 0.01, 0.02, 0.03]  # world units per saved frame below which the puck "rests" (a push moves ~0.08)


def linear_segment_costs(states: torch.Tensor, max_offset: int) -> torch.Tensor:
    """(B, N, S) summed squared error of linearly interpolating ``states`` over every segment.

    Args:
        states: (B, N + 1, D) on the extended index (K^0, then the N future frames).
    Returns:
        costs[b, a, o - 1] for the segment from extended index a to a + o; ``inf`` past the clip.
    """
    batch, n_ext, _ = states.shape
    n_future = n_ext - 1
    costs = torch.full((batch, n_future, max_offset), float("inf"), dtype=states.dtype)
    for offset in range(1, max_offset + 1):
        for start in range(0, n_future - offset + 1):
            left, right = states[:, start], states[:, start + offset]
            inner = torch.arange(1, offset, dtype=states.dtype) / offset  # (o - 1,)
            line = left[:, None] + inner[None, :, None] * (right - left)[:, None]  # (B, o - 1, D)
            error = ((states[:, start + 1 : start + offset] - line) ** 2).sum((1, 2))
            costs[:, start, offset - 1] = error
    return costs


def discover(
    arrays: dict[str, np.ndarray], objects: tuple[str, ...], price: float | str, max_offset: int,
    n_keyframes: int = N_KEYFRAMES,
) -> list[list[int]]:
    """Per clip, the interior keyframe positions of the best segmentation of the true state (at most
    ``n_keyframes`` keyframes, segments of at most ``max_offset`` frames)."""
    states = torch.from_numpy(np.concatenate([arrays[name] for name in objects], axis=-1)).double()
    states = states[:, N_COND - 1 :]  # (B, N + 1, D) extended index
    lengths = torch.from_numpy(arrays["length"].astype(np.int64)) - N_COND

    def segment_costs(rows: torch.Tensor, length: int) -> torch.Tensor:
        return linear_segment_costs(states[rows, : length + 1], max_offset)

    return decode_by_length(segment_costs, lengths, n_keyframes, max_offset, price)


def snap_to_rest_start(positions: list[list[int]], puck: np.ndarray, rest_step: float) -> list[list[int]]:
    """Move each keyframe back to the first frame of the rest it falls in.

    A segmentation boundary inside a still period of the puck is equally cheap anywhere in it; the
    subgoal was reached where the rest began. Args: per clip, future positions; ``puck`` (n, L, 2)
    on the clip axis; ``rest_step`` the move per frame below which the puck counts as still.
    """
    snapped = []
    for clip, row in enumerate(positions):
        moved: list[int] = []
        for position in row:
            frame = position + N_COND  # clip axis
            while frame > N_COND and np.linalg.norm(puck[clip, frame] - puck[clip, frame - 1]) < rest_step:
                frame -= 1
            moved.append(frame - N_COND)
        snapped.append(sorted(set(moved)))
    return snapped


def score(arrays: dict[str, np.ndarray], predicted: list[list[int]]) -> dict[str, float]:
    """The information rule's columns of ``predicted`` against the clips' labels."""
    keyframes = torch.from_numpy(arrays["keyframes"][:, N_COND:])
    lengths = (arrays["length"] - N_COND).tolist()
    return column_scores(predicted, keyframe_lists(keyframes), lengths, keyframes.shape[1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--val", type=Path, default=Path("data/pushing/val-00000.h5"))
    parser.add_argument("--test", type=Path, default=Path("data/pushing/test-00000.h5"))
    parser.add_argument("--max-offset", type=int, default=6, help="S: the dataset's max_offset (pushing 6, pushing_irregular 11)")
    args = parser.parse_args()
    began = time.perf_counter()
    val, test = (load_arrays(path) for path in (args.val, args.test))
    print(f"## Segmenting the true object positions ({args.val.parent.name})\n")
    print(f"- command: `python studies/pushing_state_segmentation.py --val {args.val} --test {args.test} --max-offset {args.max_offset}`")
    print("- the price λ (squared world units per keyframe) or the knee chosen on the validation clips' interior F1\n")
    print("| state | λ (val) | val F1 interior | test F1 interior | test ±1 F1 interior | test F1 with ends | keyframes/clip (interior) |")
    print("|---|---|---|---|---|---|---|")
    for name, objects in STATES.items():
        val_f1 = {price: score(val, discover(val, objects, price, args.max_offset))["f1_interior"] for price in PRICES}
        best = max(val_f1, key=lambda price: val_f1[price])
        result = score(test, discover(test, objects, best, args.max_offset))
        print(
            f"| {name} | {best} | {val_f1[best]:.3f} | {result['f1_interior']:.3f} | {result['f1_tol1_interior']:.3f} "
            f"| {result['f1_with_ends']:.3f} | {result['n_predicted_interior']:.2f} |"
        )
    print("\nThe puck's boundaries moved back to the start of the rest they fall in (the rest step chosen on the validation clips):\n")
    print("| state | rest step (val) | val F1 interior | test F1 interior | test ±1 F1 interior | test F1 with ends | keyframes/clip (interior) |")
    print("|---|---|---|---|---|---|---|")
    val_positions = discover(val, ("puck",), 0.0, args.max_offset)
    test_positions = discover(test, ("puck",), 0.0, args.max_offset)
    val_f1 = {step: score(val, snap_to_rest_start(val_positions, val["puck"], step))["f1_interior"] for step in REST_STEPS}
    best_step = max(val_f1, key=lambda step: val_f1[step])
    result = score(test, snap_to_rest_start(test_positions, test["puck"], best_step))
    print(
        f"| puck, λ = 0, snapped | {best_step} | {val_f1[best_step]:.3f} | {result['f1_interior']:.3f} "
        f"| {result['f1_tol1_interior']:.3f} | {result['f1_with_ends']:.3f} | {result['n_predicted_interior']:.2f} |"
    )
    print(f"\n{time.perf_counter() - began:.0f} s")


if __name__ == "__main__":
    main()

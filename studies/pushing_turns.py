"""How sharply the labelled pushing keyframes show in the puck's own trajectory.

    python studies/pushing_turns.py --split data/pushing/test-00000.h5

A pushing keyframe is the last saved frame of a push (paper App. 7: "frames at which subgoals are finished"). Discovery by interpolation
finds frames where the motion changes; this measures, from the true puck positions, where the
puck's motion changes most around each labelled keyframe c, and the exact F1 of an oracle that
reads the true trajectory and marks its sharpest turns (as many as the clip has labels). Prints
Markdown.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from keyin.data.hdf5 import load_arrays
from keyin.eval.f1 import keyframe_scores

WINDOW = range(-2, 4)  # positions relative to a labelled keyframe c that are searched for its turn


def turn_angles(puck: np.ndarray) -> np.ndarray:
    """(L, 2) puck positions -> (L,) angle in degrees between the moves into and out of each frame
    (0 at the two ends and where the puck is still)."""
    moves = np.diff(puck, axis=0)  # (L-1, 2)
    into, out = moves[:-1], moves[1:]
    norms = np.linalg.norm(into, axis=-1) * np.linalg.norm(out, axis=-1)
    cosine = np.where(norms > 1e-12, (into * out).sum(-1) / np.maximum(norms, 1e-12), 1.0)
    return np.concatenate([[0.0], np.degrees(np.arccos(np.clip(cosine, -1, 1))), [0.0]])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--split", type=Path, default=Path("data/pushing/test-00000.h5"))
    args = parser.parse_args()
    arrays = load_arrays(args.split)
    n_cond = 1
    lengths, keyframes = arrays["length"], arrays["keyframes"]
    n_future = keyframes.shape[1] - n_cond
    truth = [np.flatnonzero(marks[n_cond:length]).tolist() for length, marks in zip(lengths, keyframes)]
    print(f"{len(lengths)} clips of {args.split}, {sum(map(len, truth))} labelled keyframes\n")
    print("| object | " + " | ".join(f"turn at c{r:+d}" for r in WINDOW) + " | oracle exact F1 | oracle ±1 F1 |")
    print("|---|" + "---|" * (len(WINDOW) + 2))
    for name in ("puck", "pusher"):
        where, oracle = [], []
        for length, labels, positions in zip(lengths, truth, arrays[name]):
            angles = turn_angles(positions[:length])
            for c in labels:
                frames = [n_cond + c + r for r in WINDOW if 0 < n_cond + c + r < length - 1]
                where.append(frames[int(np.argmax(angles[frames]))] - n_cond - c)
            sharpest = np.argsort(-angles[n_cond:length], kind="stable")[: len(labels)]
            oracle.append(sorted(sharpest.tolist()))
        shares = " | ".join(f"{100 * where.count(r) / len(where):.1f} %" for r in WINDOW)
        scores = keyframe_scores(oracle, truth, n_future)
        print(f"| {name} | {shares} | {scores['f1']:.3f} | {scores['f1_tol1']:.3f} |")
    print("\nOracle: per clip, the k frames where the object's true path turns most, k = the clip's number"
          " of labels.")


if __name__ == "__main__":
    main()

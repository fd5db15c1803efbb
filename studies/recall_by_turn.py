"""Which pushing keyframes a method finds, by how sharply the puck turns there (issue 25).

    python studies/recall_by_turn.py <job dir or predictions.json>... --split data/pushing/test-00000.h5

Each labelled keyframe c (interior: a padded clip's last valid frame is left out, as in the
information rule) gets the sharpest turn of the true puck path at c-1, c or c+1
(``studies/pushing_turns.py``'s angle between the moves into and out of a frame; the turn sits
there for 78 % of the labels) and is counted as found by a method when one of its keyframes lies
at c (exact) or within one frame (±1). Prints Markdown: per method, the recall in each bin of turn
angle. The predictions must be of the same clips as ``--split`` (keyin-eval / keyin-train write
every scored clip's keyframes to ``predictions.json``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from pushing_turns import turn_angles  # noqa: E402

from keyin.data.hdf5 import load_arrays  # noqa: E402
from keyin.decode.ends import sequence_ends  # noqa: E402

N_COND = 1
BINS = (0.0, 15.0, 45.0, 90.0, 180.01)  # degrees


def keyframe_turns(puck: np.ndarray, lengths: np.ndarray, truth: list[list[int]], n_future: int) -> list[list[float]]:
    """Per clip, per interior label c, the puck's sharpest turn (degrees) at c-1, c or c+1."""
    ends = sequence_ends([int(n) - N_COND for n in lengths], n_future)
    turns = []
    for positions, length, labels, end in zip(puck, lengths, truth, ends, strict=True):
        angles = turn_angles(positions[:length])  # (length,) on the clip axis
        window = lambda c: angles[max(N_COND + c - 1, 0) : min(N_COND + c + 2, int(length))]  # noqa: E731
        turns.append([float(window(c).max()) for c in labels if c != end])
    return turns


def recall_by_bin(
    predicted: list[list[int]], truth: list[list[int]], turns: list[list[float]], lengths: list[int], n_future: int,
    tolerance: int,
) -> list[tuple[int, float]]:
    """(labels, recall) per bin of :data:`BINS`: a label is found when a prediction lies within ``tolerance``."""
    ends = sequence_ends(lengths, n_future)
    found = [[], [], [], []]
    for marks, labels, angles, end in zip(predicted, truth, turns, ends, strict=True):
        interior = [c for c in labels if c != end]
        for c, angle in zip(interior, angles, strict=True):
            bin_index = int(np.searchsorted(BINS, angle, side="right")) - 1
            found[bin_index].append(any(abs(p - c) <= tolerance for p in marks if p != end))
    return [(len(hits), float(np.mean(hits)) if hits else float("nan")) for hits in found]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("predictions", type=Path, nargs="+", help="job dirs or predictions.json files")
    parser.add_argument("--split", type=Path, default=Path("data/pushing/test-00000.h5"))
    args = parser.parse_args()
    arrays = load_arrays(args.split)
    n_future = arrays["keyframes"].shape[1] - N_COND
    truth = [np.flatnonzero(marks[N_COND:length]).tolist() for length, marks in zip(arrays["length"], arrays["keyframes"])]
    turns = keyframe_turns(arrays["puck"], arrays["length"], truth, n_future)
    lengths = [int(n) - N_COND for n in arrays["length"]]
    labels = " | ".join(f"{BINS[i]:.0f}-{min(BINS[i + 1], 180):.0f}°" for i in range(len(BINS) - 1))
    print(f"## Recall per labelled keyframe by the puck's turn there: {args.split}\n")
    print(f"- command: `python studies/recall_by_turn.py {' '.join(map(str, args.predictions))} --split {args.split}`\n")
    print(f"| method (job) | column | {labels} |")
    print("|---|---|" + "---|" * (len(BINS) - 1))
    counts_shown = False
    for given in args.predictions:
        path = given / "predictions.json" if given.is_dir() else given
        saved = json.loads(path.read_text())
        count = len(saved["truth"])
        if count > len(truth) or saved["truth"] != truth[:count] or saved.get("lengths") != lengths[:count]:
            raise SystemExit(f"{path} is not of the clips of {args.split} (or holds only its first few clips: "
                             f"score the model again with this keyin, whose predictions.json has every clip)")
        if not counts_shown:
            sizes = recall_by_bin(truth[:count], truth[:count], turns[:count], lengths[:count], n_future, 0)
            print("| labels | count | " + " | ".join(str(n) for n, _ in sizes) + " |")
            counts_shown = True
        for method, marks in saved["predicted"].items():
            for tolerance, column in ((0, "exact"), (1, "±1")):
                rows = recall_by_bin(marks, truth[:count], turns[:count], lengths[:count], n_future, tolerance)
                cells = " | ".join(f"{recall:.3f}" for _, recall in rows)
                print(f"| {method} ({path.parent.name}) | {column} | {cells} |")


if __name__ == "__main__":
    main()

"""The ceiling of KEYIN's segmentation decoding on Meta-World: an interpolator that knows the hand's path.

    python studies/metaworld_state_segmentation.py --val data/metaworld/val-00000.h5 --test data/metaworld/test-00000.h5
    python studies/metaworld_state_segmentation.py --val data/metaworld_v2/val-00000.h5 \
        --test data/metaworld_v2/test-00000.h5 --max-offset 18

As studies/pushing_state_segmentation.py does for the pushing demonstrations: the best segmentation
(at most M = 4 segments of at most S frames: 12 for dataset=metaworld, 18 for metaworld_v2) when a segment's cost is the summed squared error of
linearly interpolating the *true* hand position (xyz, metres; stored per clip) between its boundary
frames — what a perfect stage 1 whose frames were linear in the hand's motion would see. The price
per keyframe λ (or the label-free knee) is chosen on the validation clips' interior F1, then scored
on the test clips. Also: Constant and the change points on the same hand path, for scale. Prints Markdown.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import ruptures

from pushing_state_segmentation import N_COND, PRICES, discover, score
from keyin.data.hdf5 import load_arrays
from keyin.decode.changepoint import ChangepointKeyframes

N_KEYFRAMES = 4
assert N_COND == 1, "discover and score read the clips with pushing's n_cond, which is Meta-World's too"
PENALTIES = [1e-5, 3e-5, 1e-4, 3e-4, 1e-3, 3e-3, 1e-2]  # squared metres per change, for PELT on the hand velocity


def hand_changepoints(arrays: dict[str, np.ndarray], penalty: float) -> list[list[int]]:
    """PELT (l2) on the hand's velocity: where the hand turns, starts or stops, at most M per clip
    (the detector keyin's change-point rule fits to a frame signal, here to the true hand path)."""
    finder = ChangepointKeyframes(N_KEYFRAMES, N_COND, penalty, cost="l2")  # PELT's gaps are not capped at S
    found = []
    for hand, length in zip(arrays["hand"].astype(np.float64), (arrays["length"] - N_COND).tolist()):
        velocity = np.diff(hand[: length + 1], axis=0)  # (length, 3): row t moves frame t to frame t + 1
        detector = ruptures.Pelt(model="l2", min_size=1, jump=1).fit(velocity) if length >= 2 else None
        found.append(finder.positions(detector, length))
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--val", type=Path, default=Path("data/metaworld/val-00000.h5"))
    parser.add_argument("--test", type=Path, default=Path("data/metaworld/test-00000.h5"))
    parser.add_argument("--max-offset", type=int, default=12, help="S, the dataset's longest gap (metaworld_v2: 18)")
    args = parser.parse_args()
    began = time.perf_counter()
    val, test = (load_arrays(path, ("hand", "length", "keyframes")) for path in (args.val, args.test))
    print("## Segmenting the true hand path (metaworld)\n")
    print(f"- command: `python studies/metaworld_state_segmentation.py --val {args.val} --test {args.test} "
          f"--max-offset {args.max_offset}`")
    print("- each rule's setting chosen on the validation clips' interior F1\n")
    print("| rule on the hand path | setting (val) | val F1 interior | test F1 interior | test ±1 F1 interior | test F1 with ends | keyframes/clip (interior) |")
    print("|---|---|---|---|---|---|---|")
    rules = {
        "best segmentation, linear interpolation (λ or knee)": (
            PRICES, lambda arrays, price: discover(arrays, ("hand",), price, args.max_offset, N_KEYFRAMES)),
        "change points of the velocity (PELT l2, penalty)": (PENALTIES, hand_changepoints),
    }
    for name, (settings, rule) in rules.items():
        val_f1 = {setting: score(val, rule(val, setting))["f1_interior"] for setting in settings}
        best = max(val_f1, key=lambda setting: val_f1[setting])
        result = score(test, rule(test, best))
        print(f"| {name} | {best} | {val_f1[best]:.3f} | {result['f1_interior']:.3f} | {result['f1_tol1_interior']:.3f} "
              f"| {result['f1_with_ends']:.3f} | {result['n_predicted_interior']:.2f} |")
    print(f"\n{time.perf_counter() - began:.0f} s")


if __name__ == "__main__":
    main()

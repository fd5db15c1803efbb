"""Which timing levers keep a fixed keyframe pattern from matching Meta-World's labels, measured on the
labels alone (no frames rendered).

    MUJOCO_GL=egl OMP_NUM_THREADS=1 python benchmarks/metaworld_timing.py --clips 300 \
        --out benchmarks/results/metaworld_timing.md

For each setting of the grid (the speed cap's lower end ``speed_min``, the pause at a new phase
``max_pause`` in env steps, the clip's ``n_future``), the dataset's generator (conf/dataset/metaworld.yaml
otherwise) plays the first ``--clips`` episodes of the validation seeds with its renderer stubbed out:
the labels, valid lengths and redraws are exactly those keyin-generate writes (the first row is the
released dataset's val split). Scored on them by interior F1 (docs/evaluation.md), each pattern at its
best spacing on these clips (so an upper bound of a spacing chosen on other clips): every c frames
with the first M kept (c = 1..S; Jumpy's pattern) and Table 1's Constant (the c that put at most M in a
full clip). Also: the expert's success within the clip (clips / episodes played) and labels per clip.
"""

from __future__ import annotations

import argparse
import time
from datetime import date
from pathlib import Path

import numpy as np
import torch
from hydra.utils import instantiate

from choose_constant import pattern_scores
from common import cpu_model, dataset_config, publish
from keyin.data.generate import split_seed
from keyin.data.metaworld import MetaWorldGenerator

# (speed_min, max_pause, n_future): the released setting first
GRID = [(0.4, 16, 25), (0.4, 32, 25), (0.4, 48, 31), (0.25, 16, 31), (0.25, 32, 31), (0.15, 32, 41)]


def labels_only(generator: MetaWorldGenerator, clips: int) -> tuple[torch.Tensor, torch.Tensor, int]:
    """(clips, N) future keyframe flags, (clips,) valid future lengths and the episodes played, for
    the first ``clips`` val clips of ``generator`` (its renderer stubbed: one black pixel per frame)."""
    seed = split_seed(0, "val")
    flags, lengths, played = [], [], 0
    for index in range(clips):
        arrays, attempts = generator.generate(index, seed)
        flags.append(torch.from_numpy(arrays["keyframes"][generator.n_cond:]))
        lengths.append(int(arrays["length"]) - generator.n_cond)
        played += attempts
    return torch.stack(flags), torch.tensor(lengths), played


def setting(text: str) -> tuple[float, int, int]:
    """``"0.4,48,31"`` -> (speed_min, max_pause, n_future)."""
    speed_min, max_pause, n_future = text.split(",")
    return float(speed_min), int(max_pause), int(n_future)


def best_pattern(scores: dict[int, dict[str, float]]) -> tuple[int, float]:
    """The spacing of :func:`choose_constant.pattern_scores` that scores best, and its interior F1."""
    best = max(scores, key=lambda c: scores[c]["f1_interior"])
    return best, scores[best]["f1_interior"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", type=int, default=300)
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--grid", nargs="+", type=setting, default=GRID, metavar="S,PAUSE,N",
                        help="settings speed_min,max_pause,n_future to play (default: the module's GRID)")
    args = parser.parse_args()
    config = dataset_config("metaworld")
    n_keyframes, max_offset = config.n_keyframes, config.max_offset
    MetaWorldGenerator.render = lambda self, renderer, data: np.zeros((1, 1, 3), np.uint8)  # labels need no frames
    rows = ["| speed cap U(s, 1), s | pause (env steps) | n_future | success in the clip | labels / clip | "
            "every c, first M: best c, F1 | Table 1's Constant: best c, F1 | seconds |", "|---|---|---|---|---|---|---|---|"]
    for speed_min, max_pause, n_future in args.grid:
        began = time.perf_counter()
        generator = instantiate(config.generator, image_size=16, speed_min=speed_min, max_pause=max_pause, n_future=n_future)
        flags, lengths, played = labels_only(generator, args.clips)
        first_m = best_pattern(pattern_scores(flags, lengths, n_keyframes, max_offset, first_m=True))
        table = best_pattern(pattern_scores(flags, lengths, n_keyframes, max_offset, first_m=False))
        rows.append(f"| {speed_min} | {max_pause} | {n_future} | {args.clips / played:.1%} | {flags.sum(1).float().mean():.2f} | "
                    f"{first_m[0]}, {first_m[1]:.3f} | {table[0]}, {table[1]:.3f} | {time.perf_counter() - began:.0f} |")
    publish("\n".join([
        f"## Meta-World's timing levers against a fixed keyframe pattern ({args.clips} val clips per setting)\n",
        f"- command: `MUJOCO_GL=egl OMP_NUM_THREADS=1 python benchmarks/metaworld_timing.py --clips {args.clips}"
        + ("" if args.grid == GRID else " --grid " + " ".join(",".join(map(str, row)) for row in args.grid)) + "`",
        f"- machine: {cpu_model()}, {date.today()}; M = {n_keyframes}, S = {max_offset}"
        + ("; the first row is the released setting" if args.grid == GRID else "") + "\n",
        *rows,
    ]), args.out)


if __name__ == "__main__":
    main()

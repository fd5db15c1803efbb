"""Does a Meta-World clip depend on what its worker process generated before it?

    MUJOCO_GL=egl OMP_NUM_THREADS=1 python studies/metaworld_generation_determinism.py --clips 40

`keyin-generate` keeps one env per task and process (`MetaWorldGenerator.world`), so with `workers=N` the
clips a process played before a shard depend on the pool's scheduling. This generates val clips
0 … n − 1 of `dataset=metaworld_v2` in order, then again in a shuffled order in the same process, and
counts the clips whose arrays differ, and where. It repeats both passes with `mujoco.mj_forward` called
after every `env.reset()` (the candidate fix: the first frame is copied right after the reset, before
any step recomputes the bodies' positions), and counts the clips that fix would change.
"""

from __future__ import annotations

import argparse
import sys
from datetime import date
from pathlib import Path

import mujoco
import numpy as np
import torch
from hydra.utils import instantiate

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
from common import cpu_model, dataset_config, publish  # noqa: E402
from keyin.data.generate import split_seed  # noqa: E402
from keyin.data.metaworld import MetaWorldGenerator  # noqa: E402

Clip = dict[str, np.ndarray]


def forward_after_reset(generator: MetaWorldGenerator, on: bool) -> None:
    """Make every cached env's ``reset`` call ``mj_forward`` afterwards (``on``) or not."""
    for task in generator.tasks:
        env, _, _ = generator.world(task)
        plain = env.__dict__.setdefault("_plain_reset", env.reset)

        def refreshed(*args, env=env, plain=plain, **kwargs):
            out = plain(*args, **kwargs)
            mujoco.mj_forward(env.model, env.data)
            return out

        env.reset = refreshed if on else plain


def differences(first: list[Clip], second: list[Clip]) -> tuple[int, dict[str, int], set[int], int]:
    """Clips that differ, per array name the clips where it differs, the frame indices that differ, pixels."""
    clips, arrays, frames, pixels = 0, {}, set(), 0
    for a, b in zip(first, second):
        names = [name for name in a if not np.array_equal(a[name], b[name])]
        clips += bool(names)
        for name in names:
            arrays[name] = arrays.get(name, 0) + 1
        if "frames" in names:
            changed = np.abs(a["frames"].astype(int) - b["frames"].astype(int)).max(-1)  # (L, H, W)
            frames |= set(np.nonzero(changed.reshape(len(changed), -1).max(1))[0].tolist())
            pixels += int((changed > 0).sum())
    return clips, arrays, frames, pixels


def two_orders(generator: MetaWorldGenerator, seed: int, clips: int) -> tuple[list[Clip], list[Clip]]:
    """The clips generated in order, then in a shuffled order (returned in index order)."""
    in_order = [generator.generate(index, seed)[0] for index in range(clips)]
    shuffled = {}
    for index in np.random.default_rng(0).permutation(clips).tolist():
        shuffled[index] = generator.generate(index, seed)[0]
    return in_order, [shuffled[index] for index in range(clips)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", type=int, default=40)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    generator: MetaWorldGenerator = instantiate(dataset_config("metaworld_v2").generator)
    seed = split_seed(0, "val")
    rows = []
    passes = {}
    for on in (False, True):
        forward_after_reset(generator, on)
        passes[on] = two_orders(generator, seed, args.clips)
        clips, arrays, frames, pixels = differences(*passes[on])
        rows.append(f"| {'yes' if on else 'no (as shipped)'} | {clips} of {args.clips} | {arrays or '–'} | "
                    f"{sorted(frames) or '–'} | {pixels} |")
    changed, arrays, frames, pixels = differences(passes[False][0], passes[True][0])
    publish("\n".join([
        f"## Meta-World clips and the worker's history ({args.clips} val clips of dataset=metaworld_v2)\n",
        f"- command: `MUJOCO_GL=egl OMP_NUM_THREADS=1 python studies/metaworld_generation_determinism.py --clips {args.clips}`",
        f"- machine: {cpu_model()}, torch {torch.__version__}, {date.today()}\n",
        "| `mj_forward` after reset | clips that differ between the two orders | arrays that differ (clips) | frame indices that differ | pixels that differ |",
        "|---|---|---|---|---|",
        *rows,
        "",
        f"The fix changes {changed} of the {args.clips} clips generated in order (arrays {arrays or '–'}, frame indices "
        f"{sorted(frames) or '–'}, {pixels} pixels).",
    ]), args.out)


if __name__ == "__main__":
    main()

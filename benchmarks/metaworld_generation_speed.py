"""How fast `keyin-generate dataset=metaworld` makes clips on one core: rendered and kept frames per second.

    MUJOCO_GL=egl OMP_NUM_THREADS=1 python benchmarks/metaworld_generation_speed.py --clips 100

Runs the dataset's generator (conf/dataset/metaworld.yaml) in this process on clips 0 … n − 1 of the
validation seeds, after building each task's env, expert and renderer (timed apart). Counts the
rendered frames and the time spent rendering; since 2026-12-05 only kept episodes are rendered (from
copies of their physics), so rendered and kept frames are the same. Issue 46's target is 40 rendered
frames/s per core.
"""

from __future__ import annotations

import argparse
import time
from datetime import date
from pathlib import Path

import torch
from hydra.utils import instantiate

from common import cpu_model, dataset_config, publish
from keyin.data.generate import split_seed
from keyin.data.metaworld import MetaWorldGenerator


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", type=int, default=100)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    generator: MetaWorldGenerator = instantiate(dataset_config("metaworld").generator)
    seed = split_seed(0, "val")
    renders = {"frames": 0, "seconds": 0.0}
    render = MetaWorldGenerator.render

    def counted(self: MetaWorldGenerator, renderer, data):
        began = time.perf_counter()
        image = render(self, renderer, data)
        renders["frames"] += 1
        renders["seconds"] += time.perf_counter() - began
        return image

    MetaWorldGenerator.render = counted
    began = time.perf_counter()
    for task in generator.tasks:
        generator.world(task)
    build = time.perf_counter() - began
    renders.update(frames=0, seconds=0.0)
    kept = attempts = 0
    began = time.perf_counter()
    for index in range(args.clips):
        arrays, tries = generator.generate(index, seed)
        kept += int(arrays["length"])
        attempts += tries
    seconds = time.perf_counter() - began
    publish("\n".join([
        f"## Meta-World generation speed, one process ({args.clips} val clips)\n",
        f"- command: `MUJOCO_GL=egl OMP_NUM_THREADS=1 python benchmarks/metaworld_generation_speed.py --clips {args.clips}`",
        f"- machine: {cpu_model()}, torch {torch.__version__} threads {torch.get_num_threads()}, {date.today()}",
        f"- building the {len(generator.tasks)} tasks' envs, experts and renderers: {build:.1f} s (once per process)\n",
        "| clips | episodes played | rendered frames | kept frames | seconds | rendered frames/s | kept frames/s | rendering's share |",
        "|---|---|---|---|---|---|---|---|",
        f"| {args.clips} | {attempts} | {renders['frames']} | {kept} | {seconds:.1f} | {renders['frames'] / seconds:.1f} | "
        f"{kept / seconds:.1f} | {renders['seconds'] / seconds:.0%} |",
    ]), args.out)


if __name__ == "__main__":
    main()

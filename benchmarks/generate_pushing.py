"""Pushing-demo generation speed against its ceiling (physics-only and render-only rates).

    python benchmarks/generate_pushing.py --clips 40 --workers 2 \
        --out benchmarks/results/generate_pushing.md

Measures, in this order and one at a time:
1. physics only: the demonstrator's attempts (accepted or not) per second, no rendering;
then for each renderer (``--renderers``: ``analytic``, numpy, and ``mujoco``, OpenGL):
2. render only: 64x64 frames per second from one recorded demo, a clip's frames per call (1 and 2:
   best of 3 runs);
3. ``PushingGenerator.generate`` per second in one process (physics + rejections + rendering);
4. the project's writer (``keyin.data.generate.generate_dataset``) with ``--workers`` spawn
   workers, HDF5 shards included; its rate includes starting the workers (importing MuJoCo,
   building the environment: seconds), so a second run of one clip per worker measures that
   start-up and the steady rate is ``(clips - workers) / (seconds - start-up seconds)``.
The single-process ceiling is ``1 / (attempts per clip * s per attempt + frames per clip * s per
frame)``; ``workers`` processes can at best multiply it by ``min(workers, cores)``.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from common import cpu_model, publish

from keyin.data.generate import generate_dataset
from keyin.data.pushing import RENDERERS, PushingGenerator
from keyin.envs.demonstrator import run_demo


REPEATS = 3  # the ceiling rates are the best of this many runs (the machine may be shared)


def physics_rate(generator: PushingGenerator, attempts: int) -> tuple[float, float]:
    """(attempts per second, acceptance rate) of the demonstrator without rendering."""
    env = generator.environment()
    _, sampler, params = generator._parts()
    best = np.inf
    for _ in range(REPEATS):
        accepted = 0
        start = time.perf_counter()
        for index in range(attempts):
            rng = np.random.default_rng(np.random.SeedSequence(10_000 + index))
            accepted += run_demo(env, sampler.sample(rng), rng, params) is not None
        best = min(best, time.perf_counter() - start)
    return attempts / best, accepted / attempts


def render_rate(generator: PushingGenerator, frames: int) -> float:
    """Rendered frames per second from the positions and states of one recorded demo."""
    demo, _ = generator.demo(0, 0)
    index = np.arange(frames) % len(demo.states)
    clips = np.array_split(index, max(1, frames // generator.clip_length))
    generator.render_demo(demo, index[:2])  # create the GL context outside the timing
    best = np.inf
    for _ in range(REPEATS):
        start = time.perf_counter()
        for clip in clips:
            generator.render_demo(demo, clip)
        best = min(best, time.perf_counter() - start)
    return frames / best


def renderer_rows(generator: PushingGenerator, args: argparse.Namespace, attempts_per_s: float) -> list:
    """Table rows of one renderer: render rate, ceiling, 1-process and writer clips / s."""
    name = generator.renderer
    frames_per_s = render_rate(generator, args.frames)
    start, attempts = time.perf_counter(), 0
    for index in range(args.clips):
        attempts += generator.generate(index, 1000)[1]
    serial = args.clips / (time.perf_counter() - start)
    startup = writer_run(generator, args.workers, args.workers)  # one clip per worker
    stats = writer_run(generator, args.clips, args.workers)
    steady = (args.clips - args.workers) / (stats["seconds"] - startup["seconds"])
    clip_frames = generator.clip_length
    attempts_per_clip = attempts / args.clips
    ceiling = 1.0 / (attempts_per_clip / attempts_per_s + clip_frames / frames_per_s)
    cores = min(args.workers, os.cpu_count() or 1)
    return [
        (f"render only, {name}: 64x64 frames / s", f"{frames_per_s:.0f}"),
        (f"ceiling, 1 process, {name}: 1 / ({attempts_per_clip:.2f} attempts / {attempts_per_s:.1f} + "
         f"{clip_frames} frames / {frames_per_s:.0f}) clips / s", f"{ceiling:.2f}"),
        (f"`PushingGenerator.generate`, 1 process, {name}: clips / s", f"{serial:.2f}"),
        (f"`generate_dataset`, {args.workers} spawn workers, {name}, HDF5 included: clips / s "
         f"({args.clips} clips in {stats['seconds']:.1f} s)", f"{stats['clips_per_s']:.2f}"),
        (f"same with {args.workers} clips (worker start-up): s", f"{startup['seconds']:.1f}"),
        ("steady rate, start-up subtracted: clips / s", f"{steady:.2f}"),
        (f"steady rate vs {cores} x the 1-process ceiling", f"{steady / (ceiling * cores):.0%}"),
        ("rejection rate in the writer run", f"{stats['rejection_rate']:.0%}"),
        (f"50,000 training clips at the steady rate, {name}: hours", f"{50_000 / steady / 3600:.2f}"),
    ]


def writer_run(generator: PushingGenerator, clips: int, workers: int) -> dict:
    """``generate_dataset`` statistics of ``clips`` training clips in 4 shards, in a temporary folder."""
    with tempfile.TemporaryDirectory() as folder:
        return generate_dataset(
            generator, Path(folder), "pushing", {"train": clips}, shard_size=max(1, clips // 4),
            seed=0, workers=workers, progress=False,
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", type=int, default=40)
    parser.add_argument("--attempts", type=int, default=60)
    parser.add_argument("--frames", type=int, default=310)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--renderers", nargs="+", choices=RENDERERS, default=list(RENDERERS))
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    load_before = os.getloadavg()

    attempts_per_s, acceptance = physics_rate(PushingGenerator(), args.attempts)
    rows = [
        ("physics only: demonstrator attempts / s (no rendering)", f"{attempts_per_s:.1f}"),
        ("acceptance rate in that run", f"{acceptance:.0%}"),
    ]
    for name in args.renderers:
        rows += renderer_rows(PushingGenerator(renderer=name), args, attempts_per_s)
    load_after = os.getloadavg()

    command = "python " + " ".join([Path(sys.argv[0]).as_posix(), *sys.argv[1:]])
    report = "\n".join(
        [
            "# Pushing generation speed",
            "",
            f"- command: `{command}`",
            f"- machine: {cpu_model()}, {os.cpu_count()} cores, {platform.platform()}; "
            f"MUJOCO_GL={os.environ.get('MUJOCO_GL')}",
            f"- date: {datetime.datetime.now().isoformat(timespec='minutes')}",
            f"- load average before / after (the machine is shared): {load_before[0]:.2f} / "
            f"{load_after[0]:.2f}",
            "",
            "| measurement | value |",
            "|---|---|",
            *[f"| {name} | {value} |" for name, value in rows],
            "",
        ]
    )
    publish(report, args.out)


if __name__ == "__main__":
    main()

"""keyin-discover on a 10-minute video, end to end: one Brownian motion of 18,000 32x32 frames (30 fps),
its turns as labels, through the console script as a user runs it (``rule=auto``), with and without the
pictures; wall seconds of the command and F1 of the found keyframes against the turns.

    python benchmarks/discover_long_video.py --frames 18000 --threads 2 \
        --out benchmarks/results/discover_long_video_brownian.md
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

import numpy as np
import torch

from common import cpu_model, publish
from keyin.data.brownian import BrownianGenerator
from keyin.eval.f1 import keyframe_scores

N_COND = 5  # pretrained:brownian's conditioning frames: no keyframe before them


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=18000)
    parser.add_argument("--threads", type=int, default=2, help="torch threads of keyin-discover")
    parser.add_argument("--ckpt", default="pretrained:brownian")
    parser.add_argument("--rule", default="auto")
    parser.add_argument("--note", help="a line on the conditions of the run (other load on the machine)")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        arrays, _ = BrownianGenerator(n_cond=1, n_future=args.frames - 1).generate(0, seed=2026)
        np.save(Path(tmp) / "video.npy", arrays["frames"])
        turns = np.flatnonzero(arrays["keyframes"]).tolist()
        (Path(tmp) / "labels.json").write_text(json.dumps({"video.npy": turns}))
        inside = [t for t in turns if N_COND <= t < args.frames - 1]
        for pictures in ("false", "true"):
            command = [str(Path(sys.executable).parent / "keyin-discover"), f"ckpt={args.ckpt}", "input=video.npy",
                       "labels=labels.json", "fps=30", f"rule={args.rule}", f"pictures={pictures}", "progress=false",
                       f"hydra.run.dir=run_{pictures}"]
            started = time.perf_counter()
            result = subprocess.run(command, cwd=tmp, capture_output=True, text=True,
                                    env={**os.environ, "OMP_NUM_THREADS": str(args.threads)})
            wall = time.perf_counter() - started
            if result.returncode:
                raise SystemExit(result.stderr)
            summary = json.loads((Path(tmp) / f"run_{pictures}" / "metrics.json").read_text())
            record = json.loads((Path(tmp) / f"run_{pictures}" / "video.npy" / "keyframes.json").read_text())
            found = [keyframe["frame"] for keyframe in record["keyframes"]]
            scores = keyframe_scores([found], [inside], args.frames)
            rows.append(f"| {pictures} | {summary['rule']} | {summary['seconds']:.1f} | {wall:.1f} | "
                        f"{summary['kept_frames_per_second']:.0f} | {len(found)} / {len(inside)} | "
                        f"{scores['f1']:.3f} / {scores['f1_tol1']:.3f} |")
    report = "\n".join([
        f"## keyin-discover on a {args.frames}-frame ({args.frames / 30 / 60:.0f}-minute at 30 fps) Brownian video\n",
        f"- command: `OMP_NUM_THREADS={args.threads} python benchmarks/discover_long_video.py --frames {args.frames} "
        f"--threads {args.threads} --ckpt {args.ckpt} --rule {args.rule}`",
        f"- machine: {cpu_model()}, {os.cpu_count()} logical cores, {args.threads} torch thread(s), torch "
        f"{torch.__version__}, {date.today().isoformat()}",
        *([f"- note: {args.note}"] if args.note else []),
        "",
        "| pictures | rule | discovery seconds | wall seconds (the command) | kept frames/s | keyframes found / turns | F1 / ±1 F1 |",
        "|---|---|---|---|---|---|---|",
        *rows,
        "",
        "*discovery seconds*: keyin-discover's own (reading, windows, model, merge, files); *wall*: the whole command, "
        "imports and Hydra included. F1 against the turns after the model's 5 conditioning frames.",
    ])
    publish(report, args.out)


if __name__ == "__main__":
    main()

"""How fast the commands start: wall seconds of every command's ``--help``, ``keyin-train --cfg job``
and ``keyin-discover ckpt=pretrained:brownian`` on a 1200-frame mp4 of the Brownian generator
(``pictures=false``), each run several times (min / median / max), and the heaviest imports of
``keyin.cli.discover`` once its task runs (``python -X importtime``).

    python benchmarks/startup.py --runs 5 --out benchmarks/results/startup.md
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

import imageio.v3 as iio
import numpy as np

from common import cpu_model, publish
from keyin.data.brownian import BrownianGenerator

SCRIPTS = Path(sys.executable).parent
# what keyin-discover imports when it runs (keyin/cli/discover.py: discover)
TASK_IMPORTS = ("keyin.cli.discover", "keyin.data.imports", "keyin.devices", "keyin.lit.registry", "keyin.decode.trained",
                "keyin.losses.image", "keyin.pipelines.discover")


def brownian_mp4(path: Path, frames: int) -> Path:
    """One Brownian motion of ``frames`` 32x32 frames as an H.264 mp4 (30 fps)."""
    arrays, _ = BrownianGenerator(n_cond=1, n_future=frames - 1).generate(0, seed=2026)
    iio.imwrite(path, np.repeat(arrays["frames"], 3, axis=-1), plugin="pyav", codec="libx264", fps=30)
    return path


def wall_seconds(command: list[str], cwd: Path, runs: int) -> list[float]:
    times = []
    runs_a_job = not any(argument.startswith("--") for argument in command)  # --help, --cfg: no run dir
    for run in range(runs):
        started = time.perf_counter()
        subprocess.run([*command, *([f"hydra.run.dir=run{run}"] if runs_a_job else [])], cwd=cwd,
                       check=True, capture_output=True)
        times.append(time.perf_counter() - started)
    return times


def heaviest_imports(count: int = 8) -> list[tuple[str, float]]:
    """The modules with the largest cumulative import time (seconds) of what keyin-discover imports."""
    probe = "; ".join(f"import {module}" for module in TASK_IMPORTS)
    stderr = subprocess.run([sys.executable, "-X", "importtime", "-c", probe], capture_output=True, text=True,
                            check=True).stderr
    rows = []
    for line in stderr.splitlines()[1:]:
        _, cumulative, name = line.split("|")
        if not name.startswith("   "):  # top-level imports only (one space after the bar)
            rows.append((name.strip(), int(cumulative) / 1e6))
    return sorted(rows, key=lambda row: -row[1])[:count]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--frames", type=int, default=1200)
    parser.add_argument("--note", help="a line on the conditions of the run (other load on the machine)")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        brownian_mp4(folder / "video.mp4", args.frames)
        commands = {
            f"keyin-{name} --help": [str(SCRIPTS / f"keyin-{name}"), "--help"]
            for name in ("discover", "eval", "train", "plan", "report")
        }
        commands.update({
            "keyin-reproduce table=brownian_table1 --help": [str(SCRIPTS / "keyin-reproduce"), "table=brownian_table1", "--help"],
            "keyin-train experiment=brownian_keyin_stated --cfg job": [
                str(SCRIPTS / "keyin-train"), "experiment=brownian_keyin_stated", "--cfg", "job"],
            f"keyin-discover ckpt=pretrained:brownian input=video.mp4 ({args.frames} frames) pictures=false": [
                str(SCRIPTS / "keyin-discover"), "ckpt=pretrained:brownian", "input=video.mp4", "pictures=false",
                "progress=false"],
        })
        for name, command in commands.items():
            times = wall_seconds(command, folder, args.runs)
            rows.append(f"| `{name}` | {min(times):.2f} | {statistics.median(times):.2f} | {max(times):.2f} |")
    imports = [f"| `{name}` | {seconds:.2f} |" for name, seconds in heaviest_imports()]
    report = "\n".join([
        "## How fast the commands start\n",
        f"- command: `python benchmarks/startup.py --runs {args.runs} --frames {args.frames}`",
        f"- machine: {cpu_model()}, {os.cpu_count()} logical cores, torch threads: default, "
        f"OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'unset')}, {date.today().isoformat()}",
        *([f"- note: {args.note}"] if args.note else []),
        "",
        f"| command | min s | median s | max s (wall, {args.runs} runs) |",
        "|---|---|---|---|",
        *rows,
        "",
        "Targets (issue 60): each `--help` ≤ 1.5 s, the discovery ≤ 5 s on a 2-core machine.\n",
        "Heaviest top-level imports once keyin-discover's task runs (`python -X importtime`, cumulative):\n",
        "| module | s |",
        "|---|---|",
        *imports,
    ])
    publish(report, args.out)


if __name__ == "__main__":
    main()

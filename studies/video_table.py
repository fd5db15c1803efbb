"""The video-prediction diagnostics of several keyin-eval jobs as one Markdown table, per method over seeds.

    python studies/video_table.py docs/results/video/jobs/*

Reads each job's ``metrics.json`` (``keyin-eval ckpt=... video_samples=k``: its ``video`` entry) and
prints, per method, the mean ± standard deviation over its seeds of the best-of-k, mean and posterior
PSNR and SSIM, then the all-black frames' scores on the same clips (one prediction, so the same in
every column), and per seed the best-of-k PSNR of each method (paired: the same clips and seed).
"""

from __future__ import annotations

import argparse
import json
import statistics
from pathlib import Path

SCORES = ("psnr_best_of_k", "psnr_mean", "psnr_posterior", "ssim_best_of_k", "ssim_posterior")


def spread(values: list[float], digits: int) -> str:
    """``mean ± std`` (std over seeds; a single seed shows its value alone)."""
    if len(values) == 1:
        return f"{values[0]:.{digits}f}"
    return f"{statistics.mean(values):.{digits}f} ± {statistics.stdev(values):.{digits}f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("jobs", type=Path, nargs="+", help="keyin-eval run dirs (or copies) with a metrics.json")
    args = parser.parse_args()
    by_method: dict[str, dict[int, dict]] = {}
    for job in args.jobs:
        metrics = json.loads((job / "metrics.json").read_text())
        if "video" not in metrics:
            raise SystemExit(f"{job}/metrics.json has no video scores: run keyin-eval with video_samples=k")
        by_method.setdefault(metrics["method"], {})[metrics["seed"]] = metrics
    runs = [m for seeds in by_method.values() for m in seeds.values()]
    clips, k = {m["n_sequences"] for m in runs}, {m["video"]["k"] for m in runs}
    if len(clips) != 1 or len(k) != 1:
        raise SystemExit(f"the jobs scored different clips or sample counts ({sorted(clips)} clips, k = {sorted(k)})")
    print(f"{clips.pop()} test clips, best of k = {k.pop()} prior samples; mean ± std over seeds\n")
    print("| method | seeds | " + " | ".join(SCORES) + " |")
    print("|---|---|" + "---|" * len(SCORES))
    for method, seeds in sorted(by_method.items()):
        cells = [spread([seeds[s]["video"][score] for s in sorted(seeds)], 3 if "ssim" in score else 2) for score in SCORES]
        print(f"| {method} | {', '.join(map(str, sorted(seeds)))} | " + " | ".join(cells) + " |")
    blank = {m["seed"]: m["video"]["psnr_blank"] for m in runs}  # the same clips per seed, whatever the method
    ssim_blank = {m["seed"]: m["video"]["ssim_blank"] for m in runs}
    psnr, ssim = spread(list(blank.values()), 2), spread(list(ssim_blank.values()), 3)
    print(f"| all-black frames (no model) | {', '.join(map(str, sorted(blank)))} | {psnr} | {psnr} | {psnr} | {ssim} | {ssim} |")
    all_seeds = sorted({m["seed"] for m in runs})
    methods = sorted(by_method)
    print("\nBest-of-k PSNR per seed:\n")
    print("| seed | " + " | ".join(methods) + " |")
    print("|---|" + "---|" * len(methods))
    for seed in all_seeds:
        cells = [f"{by_method[m][seed]['video']['psnr_best_of_k']:.2f}" if seed in by_method[m] else "–" for m in methods]
        print(f"| {seed} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()

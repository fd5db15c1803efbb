"""keyin-report <sweep dir> [<sweep dir> ...]: the paper's Table 1 and/or Table 2 from the sweeps' metrics.json files.

For keyframe jobs (keyin-train, keyin-eval) writes ``table1.md``, ``table1.csv``, ``table1_f1.png``
(bars with the paper's numbers) and, per dataset, ``examples_<dataset>.png`` (each method's
keyframes on the first test clips); for planning jobs (keyin-plan) ``table2.md``, ``table2.csv``
and ``table2_success.png`` (success rate against the threshold); into ``--out`` (default:
``<first sweep dir>/report``).
"""

from __future__ import annotations

import argparse
import json
import math
from datetime import date
from pathlib import Path
from typing import TYPE_CHECKING

from omegaconf import OmegaConf

from keyin.cli.app import fail
from keyin.errors import KeyinError
from keyin.eval.report import (
    brief_table,
    collect_metrics,
    csv_table,
    is_planning,
    markdown_table,
    method_sort_key,
    ranking_changes,
    read_metrics,
    summarise,
)
from keyin.io import atomic_write_text
from keyin.paths import inside

if TYPE_CHECKING:  # torch, the datasets, scipy and matplotlib are imported where a table needs them: --help answers at once
    import torch


def example_predictions(records: list[dict], dataset: str) -> tuple[Path, dict[str, list[list[int]]], list[list[int]]]:
    """The lowest seed's ``predictions.json`` of every method on ``dataset``.

    Returns:
        a job dir (for its config), method → per-clip predictions, the true keyframes.
    """
    predicted, truth, job = {}, None, None
    for record in sorted(records, key=lambda r: r["seed"]):
        path = Path(record["path"]) / "predictions.json"
        if record["dataset"] != dataset or record["method"] in predicted or not path.is_file():
            continue
        saved = json.loads(path.read_text())
        if record["saved_as"] in saved["predicted"]:  # the job's own name for its method (a row may rename it)
            predicted[record["method"]] = saved["predicted"][record["saved_as"]]
            truth, job = saved["truth"], Path(record["path"])
    return job, {method: predicted[method] for method in sorted(predicted, key=method_sort_key)}, truth


def job_data_dir(job: Path, data_dir: str) -> Path:
    """The job's ``data_dir``; a relative one is taken from the folder the job ran in (Hydra's
    ``runtime.cwd``), so the report finds the data wherever it is run from."""
    hydra_file = job / ".hydra" / "hydra.yaml"
    if Path(data_dir).is_absolute() or not hydra_file.is_file():
        return Path(data_dir)
    return Path(OmegaConf.load(hydra_file).hydra.runtime.cwd) / data_dir


def job_config(job: Path) -> Path:
    """A job's composed config: Hydra's ``.hydra/config.yaml`` in a run dir, or the ``config.yaml``
    that keyin-reproduce copied beside its metrics.json."""
    hydra_file = job / ".hydra" / "config.yaml"
    return hydra_file if hydra_file.is_file() else job / "config.yaml"


def example_clips(job: Path, count: int) -> tuple[torch.Tensor, int]:
    """The first ``count`` test clips of the job's dataset, rebuilt from its saved Hydra config."""
    import torch
    from hydra.utils import instantiate

    from keyin.data.datamodule import split_clips

    cfg = OmegaConf.load(job_config(job))
    dataset = cfg.dataset
    clips = split_clips(dataset, instantiate(dataset.generator), "test", None, job_data_dir(job, cfg.data_dir))
    frames = torch.stack([clips[i]["frames"] for i in range(min(count, len(clips)))])
    return frames, dataset.n_cond


def report(sweep: list[Path], out: Path, n_examples: int, threshold: float | None = None) -> list[Path]:
    """Table 2 from the sweeps' keyin-plan jobs and Table 1 from their keyframe jobs (whichever they
    have), the jobs of several sweep folders merged by method and seed."""
    jobs = read_metrics(sweep)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    if any(is_planning(metrics) for _, metrics in jobs):
        written += planning_table(sweep, out, threshold)
    if not all(is_planning(metrics) for _, metrics in jobs):
        written += keyframe_table(sweep, out, n_examples)
    return written


def described(sweep: list[Path]) -> str:
    """The sweep folders as Markdown code spans."""
    return ", ".join(f"`{folder}`" for folder in sweep)


def planning_table(sweep: list[Path], out: Path, threshold: float | None) -> list[Path]:
    """``table2.md``, ``table2.csv`` and ``table2_success.png`` (success rate against the threshold)."""
    from keyin.eval.planning_report import (
        collect_planning,
        difference_markdown,
        machines_markdown,
        outcome_markdown,
        planning_csv,
        planning_markdown,
        sensitivity_markdown,
        success_curves,
        summarise_planning,
        sweep_threshold,
    )
    from keyin.viz.report import save_success_curves

    jobs = collect_planning(sweep)
    threshold = sweep_threshold(jobs) if threshold is None else threshold
    rows = summarise_planning(jobs, threshold)
    header = (
        f"# Planning on the pushing tasks (paper Table 2)\n\nFrom {described(sweep)} by `keyin-report "
        f"{' '.join(map(str, sweep))}` on "
        f"{date.today()}; final shortest-path distance to the goal around the wall (world units), mean ± std "
        f"over tasks; success = final error ≤ {threshold:g}. The paper states no threshold (docs/planning.md, 'Success threshold'): "
        f"compare the curve in table2_success.png.\n\n"
    )
    outcomes = outcome_markdown(rows)
    if outcomes:
        outcomes = (
            "\n## How the tasks ended\n\nEvery goal lies across the wall from its start: `untouched` never moved the "
            "puck, `reached then lost` came within the threshold and left, `not crossed` ended on the start's side "
            "of the wall's centre line, `crossed missed` crossed it and stopped away from the goal.\n\n" + outcomes
        )
    differences = difference_markdown(rows, threshold)
    sensitivity = sensitivity_markdown(rows, threshold)
    if sensitivity:
        sensitivity = (
            "\n## Servo settings\n\nThe servo observing the true puck position (`state`) or segmenting it from the "
            "rendered 64×64 image (`pixels`), its time budget counted in servo steps (2 environment steps) or in "
            "environment steps; success on the tasks each planner played in every setting.\n\n" + sensitivity
        )
    table = planning_markdown(rows, threshold) + "\n" + machines_markdown(rows)
    text = header + table + ("\n" + differences if differences else "") + sensitivity + outcomes
    written = [out / "table2.md", out / "table2.csv"]
    atomic_write_text(written[0], text)
    atomic_write_text(written[1], planning_csv(rows, threshold))
    written.append(save_success_curves(*success_curves(rows), threshold, out / "table2_success.png"))
    print(text)
    return written


def keyframe_table(sweep: list[Path], out: Path, n_examples: int) -> list[Path]:
    """``table1.md``, ``table1.csv``, ``table1_f1.png`` and the example figures."""
    from keyin.viz.report import save_f1_bars, save_method_comparison

    records = collect_metrics(sweep)
    rows = summarise(records)
    header = (
        f"# Keyframe discovery F1 (paper Table 1)\n\nFrom {described(sweep)} by `keyin-report "
        f"{' '.join(map(str, sweep))}` on {date.today()}; "
        f"mean ± std over seeds (n − 1), exact-match micro F1 on the test clips: *interior* leaves a "
        f"padded clip's last valid frame out of labels and predictions, *with ends* gives it to every "
        f"method, *as given* scores each method's own keyframes (docs/evaluation.md). *train + score*: "
        f"each job's wall time training, over every run that resumed it (a job run by code before a5978bf, "
        f"2026-12-07: in its last process only), and scoring, mean over the seeds that recorded it (named where some did not); "
        f"a stage 1 shared by a seed's jobs counts only in the job that trained it. Scales: "
        f"{', '.join(sorted({str(r['scale']) for r in records if r.get('scale')})) or '– (evaluation jobs only)'}.\n\n"
    )
    written = [out / "table1.md", out / "table1.csv"]
    atomic_write_text(written[0], header + markdown_table(rows) + "\n" + ranking_changes(rows))
    atomic_write_text(written[1], csv_table(rows))
    # The bars are the interior column (docs/evaluation.md) unless a job predates it.
    score = "f1_interior" if not any(math.isnan(row.mean["f1_interior"]) for row in rows) else "f1"
    written.append(save_f1_bars(
        [row.dataset for row in rows], [row.method for row in rows], [row.mean[score] for row in rows],
        [row.std[score] for row in rows], [row.paper_f1 for row in rows], out / "table1_f1.png",
    ))
    for dataset in sorted({row.dataset for row in rows}) if n_examples > 0 else ():
        job, predicted, truth = example_predictions(records, dataset)
        if not predicted or not job_config(job).is_file():
            continue
        clips, n_cond = example_clips(job, min(n_examples, len(truth)))
        predicted = {method: per_clip[: len(clips)] for method, per_clip in predicted.items()}
        written.append(save_method_comparison(clips, n_cond, truth[: len(clips)], predicted, inside(out, f"examples_{dataset}.png", "a metrics.json's dataset")))
    print(header + markdown_table(rows))
    return written


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="keyin-report", description=__doc__.split("\n\n")[0])
    parser.add_argument("sweep", type=Path, nargs="+",
                        help="one or more sweep dirs (e.g. runs/multirun/brownian_table1); their jobs are merged by "
                             "method and seed, and a method with the same seed in two of them is refused")
    parser.add_argument("--out", type=Path, default=None, help="output dir (default: <first sweep>/report)")
    parser.add_argument("--examples", type=int, default=4, help="test clips in the example figures (0: draw none, e.g. where the test data is not on this machine)")
    parser.add_argument("--brief", action="store_true",
                        help="print a short table (method, F1 interior, the paper's F1, its metrics.json) and write no files")
    parser.add_argument("--threshold", type=float, default=None,
                        help="Table 2's success threshold in world units (default: the one the jobs used)")
    args = parser.parse_args(argv)
    for folder in args.sweep:
        if not folder.is_dir():
            fail(f"{folder} is not a directory; pass the sweep dir of keyin-train -m or keyin-plan -m")
    try:
        if args.brief:
            print(brief_table(collect_metrics(args.sweep)))
            return
        for path in report(args.sweep, args.out or args.sweep[0] / "report", args.examples, args.threshold):
            print(f"wrote {path}")
    except (KeyinError, ValueError) as err:
        fail(str(err))


if __name__ == "__main__":
    main()

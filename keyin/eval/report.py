"""The paper's Table 1 from a sweep: collect ``metrics.json`` files, aggregate over seeds, format.

Every training or evaluation job writes ``metrics.json`` (method, dataset, seed, scores, and the
``variants`` of a method, e.g. Surprise without its index shift). A table row is one
(dataset, method): the mean and standard deviation over seeds, with the paper's figure beside it.
``keyin-plan`` jobs (their metrics name a ``planner``) make Table 2 instead
(:mod:`keyin.eval.planning_report`).
"""

from __future__ import annotations

import csv
import importlib.resources
import io
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Hashable, Iterable, Mapping, Sequence

import numpy as np
from omegaconf import DictConfig, OmegaConf

from keyin import CHOICES_KEY, CONFIG_MODULE, RENAMED_SINCE_0_1
from keyin.decode.registry import Offsets

# Paper Table 1 (keyframe F1; paper §4.1.2). Jumpy is not in it (its keyframes are Constant's).
# KEYIN's figure stands beside the paper's method (keyin_paper) and beside ours (keyin_plus).
PAPER_TABLE1 = {
    "brownian": {"random": 0.15, "constant": 0.17, "static": 0.21, "surprise": 0.73, "keyin_paper": 0.84, "keyin_plus": 0.84},
    "pushing": {"random": 0.18, "constant": 0.23, "static": 0.18, "surprise": 0.10, "keyin_paper": 0.30, "keyin_plus": 0.30},
}
PAPER_ROWS = ("random", "constant", "static", "jumpy", "surprise", "keyin_paper")  # the paper's methods, as published
PAPER_METHOD = "keyin_paper"  # the paper's KEYIN; rows named keyin_paper_<choice> change the choice their name gives
STATED_ROWS = "keyin_paper_stated"  # rows running every choice the paper states, the budget in their name (docs/decisions.md)
STATED_RUN = {"backbone": "paper", "scale": "paper"}  # the frame model and sizes the paper states (metrics.json's keys)
STATED_CHOICES = {  # what backbone=paper scale=paper compose for model=keyin on every dataset, as the paper states it
    "model.keyframes.lstm_hidden": 256, "model.keyframes.lstm_layers": 2,  # "a simple two-layer LSTM with a
    "model.interpolator.lstm_hidden": 256, "model.interpolator.lstm_layers": 2,  # 256-dimensional state ... for all"
    "model.interpolator.mlp_hidden": 256,
    "model.keyframes.lr": 2e-4, "model.interpolator.lr": 2e-4,  # "a learning rate of 2e-4"
    "scale.batch_size": 30, "scale.stage1_batch_size": 30,  # "batch size of 30"
    "model.interpolator.kl_weight": 1e-3,  # "The KL-divergence term for the interpolator VAE is 10^-3"
    "model.keyframes.beta_ke": 1.0, "model.keyframes.beta_ki": 0.0, "model.keyframes.beta_kl": 0.05,
    "model.keyframes.frozen": "lstm_inter",  # "we freeze LSTM_inter weights"
    "model.keyframes.delta_input": "argmax",  # Init_inter = MLP(K^e,t-1, K^e,t, δ̂^t), δ̂ = argmax δ
    "model.keyframes.n_keyframes": 6,
    "model.interpolator.foreground_weight": 1.0,  # "sigmoid and ... BCE loss": the plain BCE
    "model.keyframes.teacher_weight": 0.0, "model.keyframes.offset_evidence": False,  # the paper's loss alone
    "model.keyframes.discovery": Offsets.name,  # the argmax offsets
}  # (docs/decisions.md, "The paper's stated configuration"; tests/test_configs.py adds the dataset's own: Brownian's segments)
METHOD_ORDER = ("random", "constant", "static", "jumpy", "surprise", "keyin")
SCORES = (
    "f1_interior", "f1_with_ends", "f1", "f1_tol1_interior", "f1_tol1", "f1_tol2_interior", "f1_tol2", "precision", "recall",
    "n_predicted", "hausdorff", "train_seconds", "score_seconds",
)  # the information rule's columns (docs/evaluation.md) first; a keyin 0.1 job has only the rest
TIMES = ("train_seconds", "score_seconds")  # a job's wall times training and scoring, where it recorded them


@dataclass
class TableRow:
    """One (dataset, method) over its seeds."""

    dataset: str
    method: str
    seeds: list[int]
    mean: dict[str, float]
    std: dict[str, float]
    paper_f1: float | None
    timed_seeds: list[int]  # the seeds whose job recorded its wall times (the time columns average these)


Roots = Path | Sequence[Path]


def read_metrics(roots: Roots) -> list[tuple[Path, dict[str, Any]]]:
    """Every job's ``metrics.json`` under one sweep folder or several (each file once, however the
    folders nest): (the job's folder, its content).

    Raises:
        ValueError: if there is none.
    """
    roots = [Path(roots)] if isinstance(roots, (str, Path)) else [Path(root) for root in roots]
    paths = sorted({path.resolve() for root in roots for path in root.rglob("metrics.json")})
    if not paths:
        named = ", ".join(str(root) for root in roots)
        raise ValueError(f"no metrics.json under {named}; run the sweep first (keyin-train -m ... or keyin-plan -m ...)")
    return [(path.parent, json.loads(path.read_text())) for path in paths]


def is_planning(metrics: dict[str, Any]) -> bool:
    """A ``keyin-plan`` job's metrics (Table 2) rather than a keyframe job's (Table 1)."""
    return "planner" in metrics


def finds_no_keyframes(metrics: dict[str, Any]) -> bool:
    """A job that trains no keyframe model (TAP's subgoal predictor, a frame autoencoder): no row of Table 1."""
    return "f1" not in metrics and ("argmin_last" in metrics or metrics.get("method") == "frame_autoencoder")


def collect_metrics(root: Roots) -> list[dict[str, Any]]:
    """Every keyframe job's metrics under ``root`` (one sweep folder or several, merged by method and
    seed), one record per method and variant (planning jobs and those of :func:`finds_no_keyframes` are left out).

    Raises:
        ValueError: if no metrics.json is found, or one lacks method/dataset/f1.
    """
    records = []
    for folder, metrics in read_metrics(root):
        if is_planning(metrics) or finds_no_keyframes(metrics):
            continue
        missing = [key for key in ("method", "dataset", "f1") if key not in metrics]
        if missing:
            raise ValueError(f"{folder / 'metrics.json'} lacks {', '.join(missing)}: not a keyin metrics.json")
        common = {key: metrics.get(key) for key in ("dataset", "seed", "scale")}
        common.update(seed=metrics.get("seed", 0), path=str(folder))
        config = job_config(folder) if str(metrics["method"]).startswith(PAPER_METHOD) else None
        records.append({**metrics, **common, "method": row_name(metrics["method"], metrics, config),
                        "saved_as": metrics["method"]})
        for name, scores in metrics.get("variants", {}).items():
            records.append({**scores, **common, "method": row_name(name, metrics, config), "saved_as": name})
    return records


def job_config(folder: Path) -> Mapping[str, Any] | None:
    """A job's composed config: ``config.yaml`` in a committed job folder, ``.hydra/config.yaml`` in a run dir; None
    where it has neither."""
    path = next((p for p in (folder / "config.yaml", folder / ".hydra" / "config.yaml") if p.is_file()), None)
    return None if path is None else OmegaConf.load(path)


def row_name(name: str, metrics: dict[str, Any], config: Mapping[str, Any] | None = None) -> str:
    """The row of a method or variant ``name`` of the job whose ``metrics`` (and composed ``config``) these are: a
    keyin 0.1 name (no ``keyin_version``) in today's names (:func:`current_name`), then :func:`named_as_run`."""
    return named_as_run(name if "keyin_version" in metrics else current_name(name), metrics, config)


def named_as_run(method: str, metrics: dict[str, Any], config: Mapping[str, Any] | None = None) -> str:
    """The row name of a job of the paper's method (``keyin_paper``, ``keyin_paper_<choice>``) that changed the frame
    model or sizes the paper states names them, as the overrides that ran it: ``keyin_paper · backbone=ours scale=cpu``;
    on the stated frame model and sizes, any other stated value its ``config`` changed (:data:`STATED_CHOICES`):
    ``keyin_paper · model.keyframes.lr=0.001``. So a row named plain ``keyin_paper`` ran the stated ones (issue 62), as
    far as its job's files say. Other methods keep their names."""
    if not method.startswith(PAPER_METHOD):
        return method
    changed = [f"{key}={metrics[key]}" for key, stated in STATED_RUN.items() if metrics.get(key) not in (None, stated)]
    if not changed and config is not None:  # a key the job's config lacks or cannot resolve is not known changed
        changed = [f"{key}={value}" for key, stated in STATED_CHOICES.items() if (value := OmegaConf.select(
            config, key, default=None, throw_on_resolution_failure=False)) not in (None, stated)]
    return f"{method} · {' '.join(changed)}" if changed else method


def model_run(config: DictConfig) -> dict[str, Any]:
    """A model's frame model and sizes as a job's metrics.json records them (``backbone``, ``scale``), from the run
    config stored in its checkpoint: the config-group choices keyin-train records there (since 2026-12-07), else the frame
    model's name and the preset its sizes and budgets are (:func:`scale_preset`); None where neither says."""
    def known(key: str) -> Any:
        return OmegaConf.select(config, key, default=None, throw_on_resolution_failure=False)

    scale = known("scale")
    return {
        "backbone": known(f"{CHOICES_KEY}.backbone") or known("backbone.name"),
        "scale": known(f"{CHOICES_KEY}.scale") or (scale_preset(scale, known("dataset.name")) if scale else None),
    }


def scale_preset(scale: DictConfig, dataset: str | None) -> str | None:
    """The ``scale=`` preset whose every size and budget a run config's ``scale`` holds, with the dataset's own values
    merged over it as keyin-train composes them (``conf/scale_dataset/<preset>_<dataset>.yaml``); keys one side lacks
    (added since) left out. None where no one preset matches (a value overridden on the command line, a preset changed
    since): for a checkpoint written before keyin-train recorded its choices."""
    conf = importlib.resources.files(CONFIG_MODULE)
    matches = []
    for file in sorted((conf / "scale").iterdir(), key=lambda file: file.name):
        preset = file.name.removesuffix(".yaml")
        values = OmegaConf.create(file.read_text(encoding="utf-8"))
        if (per_dataset := conf / "scale_dataset" / f"{preset}_{dataset}.yaml").is_file():
            values = OmegaConf.merge(values, OmegaConf.create(per_dataset.read_text(encoding="utf-8")))
        values = OmegaConf.to_container(values, resolve=True)
        if all(scale[key] == value for key, value in values.items() if key in scale):
            matches.append(preset)
    return matches[0] if len(matches) == 1 else None


def method_of(row: str) -> str:
    """The method a row name starts with: ``keyin_paper`` of ``keyin_paper · backbone=ours scale=cpu``."""
    return row.split(" · ")[0]


def current_name(method: str) -> str:
    """A keyin 0.1 method or variant name (``keyin``, ``keyin_offsets``) in this version's names."""
    base, _, variant = method.partition("_")
    new = RENAMED_SINCE_0_1.get(base)
    return method if new is None else f"{new}_{variant}" if variant else new


def row_source(method: str) -> str:
    """``paper`` for a method as the paper published it (:data:`PAPER_ROWS`, and the rows of every stated choice),
    ``changed`` for the paper's KEYIN with the choices its name gives changed (:func:`named_as_run`, the grid's
    ``keyin_paper_<choice>``), ``ours`` for our additions and variants (keyin_plus, change-point, Surprise without its
    shift, ...)."""
    if method in PAPER_ROWS or method.startswith(STATED_ROWS) and " · " not in method:
        return "paper"
    return "changed" if method.startswith(PAPER_METHOD) else "ours"


def paper_figure(dataset: str, method: str) -> float | None:
    """The paper's Table 1 F1 beside a row: its own, or KEYIN's beside every row of the paper's KEYIN."""
    figures = PAPER_TABLE1.get(dataset, {})
    return figures.get(PAPER_METHOD if method.startswith(PAPER_METHOD) else method)


def method_sort_key(method: str) -> tuple[int, int, str]:
    """Table order: the paper's rows first, in the paper's order; then ours, beside the method they build on."""
    if method in PAPER_ROWS:
        return (0, PAPER_ROWS.index(method), method)
    base = method.split("_")[0]
    return (1, METHOD_ORDER.index(base) if base in METHOD_ORDER else len(METHOD_ORDER), method)


def group_by_seed(
    records: Iterable[dict[str, Any]], key: Callable[[dict], Hashable], describe: Callable[[dict], str]
) -> dict[Hashable, dict[int, dict[str, Any]]]:
    """Records (each with ``seed`` and ``path``) grouped by ``key``, then by seed.

    Raises:
        ValueError: if a group has a seed twice (two sweeps under one root), naming both files.
    """
    groups: dict[Hashable, dict[int, dict[str, Any]]] = {}
    for record in records:
        seeds = groups.setdefault(key(record), {})
        if record["seed"] in seeds:
            raise ValueError(
                f"{describe(record)} with seed {record['seed']} appears twice ({seeds[record['seed']]['path']} "
                f"and {record['path']}); report one sweep at a time"
            )
        seeds[record["seed"]] = record
    return groups


def summarise(records: Iterable[dict[str, Any]]) -> list[TableRow]:
    """Mean and standard deviation (n - 1; 0 for one seed) over seeds of each (dataset, method).

    Raises:
        ValueError: if a (dataset, method, seed) appears twice (two sweeps under one root).
    """
    groups = group_by_seed(records, lambda r: (r["dataset"], r["method"]), lambda r: f"{r['method']} on {r['dataset']}")
    rows = []
    for (dataset, method), by_seed in sorted(groups.items(), key=lambda item: (item[0][0], method_sort_key(item[0][1]))):
        values = {score: np.array([float(r.get(score, math.nan)) for r in by_seed.values()]) for score in SCORES}
        ddof = 1 if len(by_seed) > 1 else 0
        recorded = np.logical_and.reduce([~np.isnan(values[score]) for score in TIMES])  # per seed
        mean = {score: float(v.mean()) for score, v in values.items()}
        mean.update({score: float(values[score][recorded].mean()) if recorded.any() else math.nan for score in TIMES})
        rows.append(
            TableRow(
                dataset=dataset,
                method=method,
                seeds=sorted(by_seed),
                mean=mean,
                std={score: float(v.std(ddof=ddof)) for score, v in values.items()},
                paper_f1=paper_figure(dataset, method),
                timed_seeds=sorted(seed for seed, timed in zip(by_seed, recorded) if timed),
            )
        )
    return rows


def _paper(value: float | None) -> str:
    return "–" if value is None else f"{value:.2f}"


def _score(value: float, digits: int = 3) -> str:
    return "–" if math.isnan(value) else f"{value:.{digits}f}"


def _spread(mean: float, std: float) -> str:
    return "–" if math.isnan(mean) else f"{mean:.3f} ± {std:.3f}"


def _minutes(row: TableRow) -> str:
    """A job's mean training and scoring wall time in minutes over the seeds that recorded it, naming
    them where some did not (–: none did, or a variant, scored in its method's job)."""
    if not row.timed_seeds:
        return "–"
    minutes = f"{row.mean['train_seconds'] / 60:.1f} + {row.mean['score_seconds'] / 60:.1f}"
    if len(row.timed_seeds) < len(row.seeds):
        minutes += f" (seed{'s' if len(row.timed_seeds) > 1 else ''} {', '.join(map(str, row.timed_seeds))})"
    return minutes


def brief_table(records: list[dict[str, Any]]) -> str:
    """What a person reads after a demo: per method its interior F1 (mean ± std over seeds), the
    paper's F1 and the metrics.json files it comes from."""
    paths: dict[tuple[str, str], list[str]] = {}
    for record in records:
        paths.setdefault((record["dataset"], record["method"]), []).append(f"{record['path']}/metrics.json")
    lines = ["| dataset | method | F1 interior | F1 (paper) | metrics |", "|---|---|---|---|---|"]
    for row in summarise(records):
        files = ", ".join(sorted(set(paths[(row.dataset, row.method)])))
        lines.append(f"| {row.dataset} | {row.method} | {_spread(row.mean['f1_interior'], row.std['f1_interior'])} | "
                     f"{_paper(row.paper_f1)} | {files} |")
    return "\n".join(lines)


def markdown_table(rows: list[TableRow]) -> str:
    """Table 1 as Markdown: F1 mean ± std over seeds in the information rule's two columns
    (interior, with ends; docs/evaluation.md) and as the method gives its keyframes, the paper's F1,
    and companions, each job's wall time training (over every run that resumed it) and scoring (mean over seeds; a
    stage 1 shared by several jobs counts in the one that trained it); the paper's methods first, our additions after them (``row``: :func:`row_source`) (the mean Hausdorff distance in frames; –: a job written before the column existed)."""
    lines = [
        "| dataset | method | row | F1 interior | F1 with ends | F1 as given | F1 (paper) | ±1 F1 interior | ±1 F1 as given "
        "| ±2 F1 interior | precision | recall | keyframes/clip | Hausdorff | train + score (min) | seeds |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        m, s = row.mean, row.std
        lines.append(
            f"| {row.dataset} | {row.method} | {row_source(row.method)} | {_spread(m['f1_interior'], s['f1_interior'])} | "
            f"{_spread(m['f1_with_ends'], s['f1_with_ends'])} | {_spread(m['f1'], s['f1'])} | {_paper(row.paper_f1)} | "
            f"{_score(m['f1_tol1_interior'])} | {m['f1_tol1']:.3f} | {_score(m['f1_tol2_interior'])} | "
            f"{m['precision']:.3f} | {m['recall']:.3f} | {m['n_predicted']:.2f} | "
            f"{_score(m['hausdorff'], 2)} | {_minutes(row)} | {len(row.seeds)} |"
        )
    return "\n".join(lines) + "\n"


TOLERANCE_SCORES = {"exact": "f1_interior", "±1": "f1_tol1_interior", "±2": "f1_tol2_interior"}


def rankings(rows: list[TableRow]) -> dict[str, dict[str, list[str]]]:
    """Per dataset, its methods best first by each score of :data:`TOLERANCE_SCORES` (interior F1 at 0, ±1
    and ±2 frames), each ranking over the rows that have that score (a job may predate ±2)."""
    ranked: dict[str, dict[str, list[str]]] = {}
    for dataset in sorted({row.dataset for row in rows}):
        own = [row for row in rows if row.dataset == dataset]
        ranked[dataset] = {
            name: [row.method for row in sorted((r for r in own if not math.isnan(r.mean[score])), key=lambda r: -r.mean[score])]
            for name, score in TOLERANCE_SCORES.items()
        }
    return ranked


def ranking_changes(rows: list[TableRow]) -> str:
    """Markdown: where the order of the methods by exact F1 changes when a keyframe may be ±1 or ±2 frames off.

    Per dataset and tolerance, each method whose rank moves, as "method exact rank → rank at ±k" (ranks among
    the methods scored at both; "no change" where none moves); rows that lack the score are named."""
    lines = ["## Where the ranking changes with the tolerance", ""]
    for dataset, ranked in rankings(rows).items():
        for name in ("±1", "±2"):
            both = [method for method in ranked["exact"] if method in ranked[name]]
            tolerant = [method for method in ranked[name] if method in both]
            moved = [
                f"{method} {i + 1} → {tolerant.index(method) + 1}" for i, method in enumerate(both) if tolerant[i] != method
            ]
            said = ", ".join(moved) if moved else "no change"
            missing = [method for method in ranked["exact"] if method not in both]
            if not both:
                said = "no method scored"
            if missing:
                said += f" (not scored at {name}: {', '.join(missing)}; their jobs predate the column)"
            lines.append(f"- {dataset}, ranks by exact F1 → at {name}: {said}.")
    return "\n".join(lines) + "\n"


def csv_table(rows: list[TableRow]) -> str:
    """The same table as CSV, one column per mean and std."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["dataset", "method", "seeds", "paper_f1", *(f"{s}_{k}" for s in SCORES for k in ("mean", "std"))])
    for row in rows:
        writer.writerow(
            [row.dataset, row.method, " ".join(map(str, row.seeds)), "" if row.paper_f1 is None else row.paper_f1]
            + [f"{value:.6g}" for s in SCORES for value in (row.mean[s], row.std[s])]
        )
    return out.getvalue()

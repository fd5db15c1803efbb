"""keyin-discover's throughput: kept frames per second through its real path on one long clip with
known keyframes (a Brownian motion, or pushing demos back to back), and the time of each part.

    python benchmarks/discover_speed.py --frames 600 [--ckpt <stage-2 checkpoint> ...] [--rules map boundaries] \
        --out benchmarks/results/discover_speed.md

Models: smoke-sized keyin_plus (untrained weights: the speed does not depend on them) at Brownian's
sizes (32x32 grey, 5 + 30 frames, M 6, S 10) and at pushing's (64x64 RGB, 1 + 30, M 6, S 6), and
with ``--ckpt`` trained checkpoints (``pretrained:<name>`` too), whose merged keyframes are also scored
against the clip's labels when the model was trained on the clip's dataset (``--clip``; the clip is
fitted to every model's size). Every model runs each rule of ``--rules`` (default: map with the label-free knee,
the rule keyin-discover's ``auto`` falls back to) through
``keyin.pipelines.discover.discover_videos``, as keyin-discover does; the parts are timed by wrapping
the functions that path calls: decoding (PyAV and fitting, of the clip written as an mp4),
``KEYIN.keyframes`` (encoder and posterior, run by the rule and by the score), the interpolator's
segment costs (per window, or once per video for all its windows: ``video_costs``, keyin-discover's
path for map, map_pruned and segmentation; map_pruned's only for the segments its windows price), the DP,
and the files (JSON and pictures). ``--per-window`` also runs those rules with each window computing its own
segment costs (the path before the windows shared them) and checks that the keyframes are the same.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import os
import tempfile
import time
from collections import defaultdict
from datetime import date
from pathlib import Path
from typing import Iterator

import imageio.v3 as iio
import numpy as np
import torch
from hydra import compose, initialize_config_module
from hydra.utils import instantiate

import keyin.decode.rules
import keyin.decode.segmentation
import keyin.pipelines.discover
from common import cpu_model, publish
from keyin.cli.app import CONFIG_MODULE
from keyin.data.brownian import BrownianGenerator
from keyin.data.hdf5 import load_arrays
from keyin.data.imports import ImportSpec, read_videos
from keyin.decode.changepoint import ChangepointKeyframes
from keyin.decode.registry import rule_named
from keyin.decode.trained import KeyframeReader
from keyin.eval.f1 import keyframe_scores
from keyin.lit.registry import load_trained_module
from keyin.models.keyin import KEYIN
from keyin.pipelines.discover import discover_videos
from keyin.pretrained import is_pretrained

PARTS = {  # part -> (owner, attribute) of the function timed
    "encoder + posterior": (KEYIN, "keyframes"),
    "segment costs": (keyin.decode.rules, "interpolation_costs"),
    "video segment costs": (KeyframeReader, "video_costs"),
    "DP": (keyin.decode.segmentation, "best_segmentation"),
    "files": (keyin.pipelines.discover, "write_video_folder"),
}


@contextlib.contextmanager
def timed_parts() -> Iterator[dict[str, float]]:
    """Seconds spent in each of :data:`PARTS` while the block runs."""
    seconds: dict[str, float] = defaultdict(float)
    originals = {part: getattr(owner, name) for part, (owner, name) in PARTS.items()}

    def timer(part, function):
        @functools.wraps(function)
        def timed(*args, **kwargs):
            started = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                seconds[part] += time.perf_counter() - started
        return timed

    for part, (owner, name) in PARTS.items():
        setattr(owner, name, timer(part, originals[part]))
    try:
        yield seconds
    finally:
        for part, (owner, name) in PARTS.items():
            setattr(owner, name, originals[part])


def smoke_module(dataset: str) -> KeyframeReader:
    """keyin_plus at scale=smoke on ``dataset``'s sizes, as initialised, read by its rule."""
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        cfg = compose("train", overrides=["scale=smoke", "model=keyin_plus", f"dataset={dataset}"])
    torch.manual_seed(0)
    stage1 = instantiate(cfg.model.interpolator)
    return instantiate(cfg.model.keyframes, stage1=dict(stage1.hparams)).eval().reader()


def long_clip(folder: Path, n_frames: int, kind: str, data_dir: Path) -> tuple[Path, Path, list[int]]:
    """A long clip as .npy (lossless) and .mp4, and its labelled keyframes: ``brownian``, one Brownian
    motion of ``n_frames`` 32x32 frames and its turns; ``pushing``, the first pushing test demos
    (64x64 RGB, each to its last valid frame) back to back until ``n_frames``, and their labels."""
    if kind == "brownian":
        arrays, _ = BrownianGenerator(n_cond=1, n_future=n_frames - 1).generate(0, seed=12345)
        frames, labels = arrays["frames"], np.flatnonzero(arrays["keyframes"]).tolist()
    else:
        demos = load_arrays(data_dir / "pushing" / "test-00000.h5", ("frames", "keyframes", "length"))
        parts, labels, start = [], [], 0
        for demo, flags, length in zip(demos["frames"], demos["keyframes"], demos["length"]):
            if start >= n_frames:
                break
            parts.append(demo[:length])
            labels += [start + int(t) for t in np.flatnonzero(flags[:length])]
            start += int(length)
        frames = np.concatenate(parts)[:n_frames]
        labels = [t for t in labels if t < len(frames)]
    np.save(folder / "clip.npy", frames)
    rgb = frames if frames.shape[-1] == 3 else np.repeat(frames, 3, axis=-1)
    iio.imwrite(folder / "clip.mp4", rgb, plugin="pyav", codec="libx264", fps=10)
    return folder / "clip.npy", folder / "clip.mp4", labels


def run(module, label: str, rule: str, clip: Path, movie: Path, turns: list[int], out: Path, shared: bool = True) -> dict:
    """One model and rule through keyin-discover's path (``shared``: the segment costs once per video,
    as keyin-discover computes them); its times, frames per second and F1 on the clip."""
    sizes = module.config.stage1_hparams()
    n_cond, n_future = sizes["n_cond"], sizes["n_future"]
    spec = ImportSpec(image_size=sizes["image_size"], channels=sizes["channels"], n_cond=n_cond, n_future=n_future,
                      window_stride=n_future // 2)
    started = time.perf_counter()
    read_videos(movie, spec, None, None, progress=False)
    decode = time.perf_counter() - started
    videos, _, _ = read_videos(clip, spec, None, None, progress=False)
    discoverer = functools.partial(module.discover, discovery=rule, keyframe_cost="knee")
    reads_costs = rule_named(rule).reads_segment_costs
    shared = shared and reads_costs and module.config.frames.plain_bce  # else each window computes its own
    folder = out / label / f"{rule}-{shared}"
    with timed_parts() as parts:
        video_costs = module.video_costs if shared else None  # the timed method
        started = time.perf_counter()
        segments = (functools.partial(module.kept_segments, discovery=rule)
                    if shared and rule_named(rule).prunes_segments else None)
        summary = discover_videos(videos, discoverer, module.keyframe_probabilities, folder, {}, n_cond,
                                  n_future, 1, n_future // 2, progress=False, video_costs=video_costs, segments=segments)
        total = time.perf_counter() - started
    record = json.loads((folder / summary["videos"]["clip.npy"]["folder"] / "keyframes.json").read_text())
    found = [keyframe["frame"] for keyframe in record["keyframes"]]
    inside = [t for t in turns if n_cond <= t < len(videos[0].frames) - 1]
    scores = keyframe_scores([found], [inside], len(videos[0].frames))
    parts = dict(parts, decode=decode, rest=total - sum(parts.values()))
    name = f"{label}, {rule}" + (" per window" if reads_costs and not shared else "")
    return dict(label=name, keyframes=found, frames=summary["kept_frames"], windows=summary["windows"], total=total, parts=parts,
                found=len(found), turns=len(inside), f1=scores["f1"], f1_tol1=scores["f1_tol1"])


def changepoint_row(clip: Path, turns: list[int], dataset: str) -> str:
    """The label-free baseline on the same frames: ruptures' PELT over the whole clip at the dataset's
    settings chosen on its validation clips (``dataset.tuned.changepoint``), its time and F1 on the turns
    the models are scored on (after the dataset's conditioning frames, before the last frame)."""
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        cfg = compose("train", overrides=[f"dataset={dataset}"])
    settings, n_cond = cfg.dataset.tuned.changepoint, cfg.dataset.n_cond
    frames = np.load(clip)  # (T, H, W, C) uint8
    started = time.perf_counter()
    clips = torch.from_numpy(frames).permute(0, 3, 1, 2)[None].float() / 255.0  # (1, T, C, H, W)
    detector = ChangepointKeyframes(len(frames), 1, settings.penalty, settings.signal, settings.cost)
    positions = detector(clips, torch.tensor([len(frames) - 1]))[0]
    seconds = time.perf_counter() - started
    found = [p + 1 for p in positions if n_cond <= p + 1 < len(frames) - 1]  # future position p is frame p + 1
    inside = [t for t in turns if n_cond <= t < len(frames) - 1]
    scores = keyframe_scores([found], [inside], len(frames))
    label = f"ruptures PELT on the {settings.signal.replace('_', ' ')} ({settings.cost}, penalty {settings.penalty:g}), no model"
    return (f"| {label} | {len(frames)} / – | {len(frames) / seconds:.0f} | – | – | – | – | – | – | – | – | "
            f"{scores['f1']:.3f} / {scores['f1_tol1']:.3f} ({len(found)} found, {len(inside)} labelled) |")


def row(result: dict, scored: bool) -> str:
    parts = result["parts"]
    model_seconds = result["total"] - parts.get("files", 0.0)
    cells = [result["label"], f"{result['frames']} / {result['windows']}",
             f"{result['frames'] / model_seconds:.0f}", f"{result['frames'] / (result['total'] + parts['decode']):.0f}"]
    cells += [f"{1000 * parts.get(p, 0.0) / result['frames']:.2f}" for p in ("decode", *PARTS, "rest")]
    cells.append(f"{result['f1']:.3f} / {result['f1_tol1']:.3f} ({result['found']} found, {result['turns']} labelled)"
                 if scored else "– (untrained, or another dataset's model)")
    return "| " + " | ".join(cells) + " |"


@torch.no_grad()
def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=600, help="frames of the long clip")
    parser.add_argument("--ckpt", nargs="*", default=[], help="also trained stage-2 checkpoints (pretrained:<name> too)")
    parser.add_argument("--rules", nargs="+", default=["map"], help="the rules each model runs (map, map_pruned, boundaries, offsets)")
    parser.add_argument("--per-window", action="store_true",
                        help="also run map with each window's own segment costs, and check the keyframes are the same")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--clip", choices=("brownian", "pushing"), default="brownian",
                        help="the long clip: one Brownian motion, or pushing test demos back to back (needs data/pushing)")
    parser.add_argument("--data-dir", type=Path, default=Path("data"))
    parser.add_argument("--note", help="a line on the conditions of the run (other load on the machine)")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    models = [("smoke, Brownian size (32x32x1)", smoke_module("brownian"), False),
              ("smoke, pushing size (64x64x3)", smoke_module("pushing"), False)]
    for ckpt in args.ckpt:
        module, config = load_trained_module(ckpt, "keyframes")
        name = ckpt if is_pretrained(ckpt) else Path(ckpt).parents[2].name
        models.append((f"trained {config['model']['name']} ({name})", module, config["dataset"]["name"] == args.clip))
    with tempfile.TemporaryDirectory() as tmp:
        clip, movie, turns = long_clip(Path(tmp), args.frames, args.clip, args.data_dir)
        baseline = changepoint_row(clip, turns, args.clip)
        results = [(run(module, label, rule, clip, movie, turns, Path(tmp), shared), scored)
                   for label, module, scored in models for rule in args.rules
                   for shared in ((True, False) if args.per_window and rule_named(rule).reads_segment_costs
                                  and module.config.frames.plain_bce else (True,))
                   if rule_named(rule).runs_on(module.config.predictor.offset_evidence)]
    for (shared, _), (alone, _) in zip(results, results[1:]):
        if alone["label"] == shared["label"] + " per window" and alone["keyframes"] != shared["keyframes"]:
            raise SystemExit(f"{shared['label']}: the shared segment costs found other keyframes than the per-window ones")
    command = " ".join(["python benchmarks/discover_speed.py", f"--frames {args.frames}", f"--threads {args.threads}",
                        f"--clip {args.clip}"]
                       + ([f"--ckpt {' '.join(args.ckpt)}"] if args.ckpt else []) + [f"--rules {' '.join(args.rules)}"]
                       + (["--per-window"] if args.per_window else []))
    report = "\n".join([
        f"## keyin-discover throughput on a {args.frames}-frame {args.clip} clip\n",
        f"- command: `PYTHONPATH=. {command}`",
        f"- machine: {cpu_model()}, {os.cpu_count()} logical cores, {args.threads} thread(s) used, torch "
        f"{torch.__version__}, {date.today().isoformat()}",
        *([f"- note: {args.note}"] if args.note else []),
        "- path: keyin.pipelines.discover.discover_videos with each rule (map with the label-free knee), windows every n_future // 2 "
        "kept frames (each frame in about two windows), batches of 32 windows, frame stride 1; map's segment costs "
        "computed once per video and shared by its windows unless marked *per window*",
        "",
        "| model | kept frames / windows | frames/s (model) | frames/s (all) | decode | encoder + posterior | "
        "segment costs | video segment costs | DP | files | rest | F1 / ±1 F1 of the merged keyframes |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
        *(row(result, scored) for result, scored in results),
        baseline,
        "",
        "Parts in milliseconds per kept frame. *frames/s (model)*: kept frames over the time from the windows to the "
        "merged keyframes (files excluded); *all*: over decoding, that and writing the JSON and pictures. *decode*: "
        "PyAV decoding of the clip as an mp4 and fitting its frames to the model's size (the discovery itself reads "
        "the lossless .npy of the same clip); *encoder + posterior*: `KEYIN.keyframes`, run once by the rule and once "
        "by the score; *segment costs*: per window (map *per window*); *video segment costs*: once per video, shared by its "
        "windows (keyin-discover's path; the embeddings of its frames included); *rest*: cutting windows, the merge, Python. "
        "The PELT row: its frames/s over the signal and the search, from the frames in memory.",
    ])
    publish(report, args.out)


if __name__ == "__main__":
    main()

"""keyin-discover ckpt=<stage-2 checkpoint> input=<videos>: the keyframes of whole videos, found in
overlapping windows and merged in each video's own frames and seconds (docs/discover.md)."""

from __future__ import annotations

import functools
import sys
from collections import defaultdict
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

from omegaconf import DictConfig

from keyin.cli.app import keyin_main, run_dir, user_errors, write_metrics
from keyin.cli.checks import optional_name, require_int_at_least, require_positive_int
from keyin.decode.prices import KNEE
from keyin.decode.registry import EXACT_RULE, PAPER_RULE, RULES, rule_named
from keyin.errors import ConfigError, DatasetFormatError

if TYPE_CHECKING:  # torch, the model and the video readers are imported when the command runs: --help answers at once
    from keyin.data.imports import ImportedVideo, ImportSpec

BATCH_SIZES = {"cpu": 32, "gpu": 256}  # batch_size=null: windows per model call on each kind of device


AUTO = "auto"  # rule=auto: a shipped model's recorded default rule, else the exact rule (keyin.decode.registry.EXACT_RULE)


def check_discover(cfg: DictConfig) -> None:
    """The settings keyin-discover reads before it loads anything."""
    for key, what in (("ckpt", "<run dir>/best (or <run dir>/checkpoints/keyframes/last.ckpt) of a keyin-train run"),
                      ("input", "a video file, a folder of videos or of PNG/JPG frames, an .npy/.npz, a robomimic "
                                ".hdf5 or a LeRobot v2 folder")):
        if cfg[key] is None:
            raise ConfigError(f"{key}= is required: {what}")
    if cfg.rule not in (None, AUTO, *RULES):
        raise ConfigError(f"rule={cfg.rule} is not a rule of KEYIN; choose one of {', '.join(RULES)}, {AUTO} or null")
    cost = cfg.keyframe_cost
    nats = isinstance(cost, (int, float)) and not isinstance(cost, bool) and cost >= 0
    if cost is not None and cost != KNEE and not nats:
        raise ConfigError(f"keyframe_cost={cost!r} must be {KNEE} (label-free), nats per keyframe >= 0, or null")
    logit = cfg.candidate_logit
    if logit is not None and not (isinstance(logit, (int, float)) and not isinstance(logit, bool)):
        raise ConfigError(f"candidate_logit={logit!r} must be a number (rule=map_pruned's least boundary logit of a "
                          f"keyframe, e.g. -4) or null for the checkpoint's")
    require_positive_int(cfg.frame_stride, "frame_stride")
    if cfg.batch_size is not None:
        require_positive_int(cfg.batch_size, "batch_size")
    require_int_at_least(cfg.seam, "seam", 0)
    if cfg.fps is not None and not (isinstance(cfg.fps, (int, float)) and cfg.fps > 0):
        raise ConfigError(f"fps={cfg.fps!r} must be a positive number (frames per second) or null")


def window_stride(cfg: DictConfig, n_future: int) -> int:
    """Kept frames between window starts: ``window_stride``, by default half a window's future."""
    stride = max(1, n_future // 2) if cfg.window_stride is None else cfg.window_stride
    most = max(1, n_future - 1)
    if not isinstance(stride, int) or isinstance(stride, bool) or not 1 <= stride <= most:
        raise ConfigError(
            f"window_stride={stride!r} must be a whole number in 1..{most} (the checkpoint's n_future - 1): a larger "
            f"one leaves frames that no window may mark; or null for {max(1, n_future // 2)}"
        )
    return stride


def read_input(cfg: DictConfig, spec: ImportSpec) -> list[ImportedVideo]:
    """Every video of ``input=`` decoded, checked and fitted to the model (and its labels checked)
    before anything is written; notes on the fitting and warnings on skipped videos to stderr."""
    from keyin.data.frames import fit_note
    from keyin.data.imports import read_videos
    from keyin.data.labels import check_known, read_labels

    labels_path = Path(cfg.labels) if cfg.labels else None
    labels = read_labels(labels_path) if labels_path else None
    videos, skipped, seen = read_videos(Path(cfg.input), spec, labels, labels_path, cfg.progress, "reading", "input")
    if labels is not None:
        check_known(labels, labels_path, seen)
    if not videos:
        raise DatasetFormatError(f"no video of {cfg.input} is long enough for one window ({skipped[0]}); pass longer "
                                 f"videos or a smaller frame_stride")
    fitted = defaultdict(list)
    for video in videos:
        fitted[fit_note(video.stored_shape, spec.image_size, spec.channels)].append(video.where)
    for note, where in fitted.items():
        if note:
            print(f"note: {where[0]}{f' and {len(where) - 1} more' if len(where) > 1 else ''}: {note}, the model's "
                  f"frames ({spec.image_size}x{spec.image_size}, channels={spec.channels})", file=sys.stderr)
    for reason in skipped:
        print(f"warning: {reason}: skipped", file=sys.stderr)
    return videos


def chosen_rule(cfg: DictConfig, module: Any) -> str:
    """``rule=``, where ``auto`` is a shipped model's recorded default (the cheapest rule within 0.01
    of the exact rule ``map`` on its validation clips, said on stderr) and otherwise the exact rule; null:
    the model's own."""
    from keyin.pretrained import recorded_rule

    if cfg.rule != AUTO:
        return cfg.rule or module.discovery
    recorded = recorded_rule(cfg.ckpt)
    if recorded is None:
        return EXACT_RULE
    if recorded["rule"] != EXACT_RULE:
        scores = ", ".join(f"{rule} {f1:.3f}" for rule, f1 in recorded["val_f1_interior"].items())
        print(f"note: rule={recorded['rule']}, {cfg.ckpt}'s recorded default: the cheapest rule within "
              f"{recorded['tolerance']} of {EXACT_RULE}'s interior F1 on {recorded['val_clips']} validation clips "
              f"({scores}); rule={EXACT_RULE} for the exact segmentation", file=sys.stderr)
    return recorded["rule"]


def model_record(cfg: DictConfig, module: Any, trained: Mapping[str, Any]) -> dict[str, Any]:
    """What keyframes.json says about the model and its rule."""
    sizes = module.config.stage1_hparams()
    rule = rule_named(chosen_rule(cfg, module))
    if not rule.runs_on(module.config.predictor.offset_evidence):
        raise ConfigError(f"rule={rule.name} needs a model with offset evidence (model=keyin_plus), which {cfg.ckpt} "
                          f"has not; pass rule={EXACT_RULE} or rule={PAPER_RULE}")
    prices = module.prices(cfg.keyframe_cost, None if cfg.candidate_logit is None else float(cfg.candidate_logit))
    return {"checkpoint": str(Path(cfg.ckpt).resolve()), "method": trained["model"]["name"], "rule": rule.name,
            "keyframe_cost": prices.keyframe_cost if rule.reads_segment_costs else None,
            "candidate_logit": prices.candidate_logit if rule.prunes_segments else None,
            **{key: sizes[key] for key in ("image_size", "channels", "n_cond", "n_future")}}


@user_errors
def discover(cfg: DictConfig) -> dict:
    check_discover(cfg)
    from keyin.data.imports import ImportSpec
    from keyin.devices import batch_size_on, choose_device, device_record
    from keyin.lit.registry import load_trained_module
    from keyin.pipelines.discover import discover_videos

    device = choose_device(cfg.device)
    module, trained = load_trained_module(cfg.ckpt, stage="keyframes", device=device)
    model = model_record(cfg, module, trained)
    rule = rule_named(model["rule"])
    if cfg.compile:
        from keyin.lit.run import compile_frame_networks  # Lightning, only for this

        compile_frame_networks(module)
    n_cond, n_future = model["n_cond"], model["n_future"]
    stride = window_stride(cfg, n_future)
    spec = ImportSpec(image_size=model["image_size"], channels=model["channels"], n_cond=n_cond, n_future=n_future,
                      frame_stride=cfg.frame_stride, window_stride=stride, binary=bool(cfg.binary), fps=cfg.fps,
                      camera_key=optional_name(cfg.camera_key))
    videos = read_input(cfg, spec)
    batch_size = batch_size_on(device, cfg.batch_size, **BATCH_SIZES)
    ran = {**device_record(device), "batch_size": batch_size}
    discoverer = functools.partial(module.discover, discovery=rule.name, keyframe_cost=model["keyframe_cost"],
                                   candidate_logit=model["candidate_logit"])
    summary = discover_videos(
        videos, discoverer, module.keyframe_probabilities, run_dir(), {**model, **ran}, n_cond, n_future,
        cfg.frame_stride, stride, seam=cfg.seam, batch_size=batch_size, progress=cfg.progress,
        pictures=bool(cfg.pictures), video_costs=module.video_costs if rule.reads_segment_costs else None,
        segments=functools.partial(module.kept_segments, discovery=rule.name, candidate_logit=model["candidate_logit"])
        if rule.prunes_segments and module.config.frames.plain_bce else None,
    )
    summary.update(rule=model["rule"], keyframe_cost=model["keyframe_cost"], method=model["method"], **ran)
    write_metrics(summary, run_dir())
    return summary


main = keyin_main("discover")(discover)  # the console script: Hydra, then discover(cfg)


if __name__ == "__main__":
    main()

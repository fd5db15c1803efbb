"""Config validation: turn a bad value into one line naming the key, the value and what is allowed."""

from __future__ import annotations

from typing import Any, Mapping

from keyin.errors import ConfigError

DATASET_SIZES = ("image_size", "channels", "n_cond", "n_future", "n_keyframes", "max_offset")


def require_int_at_least(value: Any, key: str, minimum: int) -> int:
    """``value`` itself if it is an integer >= ``minimum`` (a bool is not one)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        allowed = "a positive integer" if minimum == 1 else f"an integer >= {minimum}"
        raise ConfigError(f"{key}={value!r} must be {allowed}")
    return value


def require_positive_int(value: Any, key: str) -> int:
    return require_int_at_least(value, key, 1)


def require_seed(value: Any, key: str = "seed") -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2**32:
        raise ConfigError(f"{key}={value!r} must be an integer in [0, 2**32)")
    return value


def optional_name(value: Any) -> str | None:
    """A setting that is null or a name; a name typed as a number on the command line becomes its text."""
    return None if value is None else str(value)


def check_dataset(dataset: Mapping[str, Any]) -> None:
    """Sizes positive, image size a power of two, and S <= N <= M·S (paper §3.1; docs/architecture.md, "Index conventions")."""
    for key in DATASET_SIZES:
        require_positive_int(dataset.get(key), f"dataset.{key}")
    size = dataset["image_size"]
    if size < 8 or size & (size - 1):
        raise ConfigError(f"dataset.image_size={size} must be a power of two >= 8 (32, 64, ...)")
    n_future, n_keys, max_offset = dataset["n_future"], dataset["n_keyframes"], dataset["max_offset"]
    if max_offset > n_future:
        raise ConfigError(
            f"dataset.max_offset={max_offset} (S) must be <= dataset.n_future={n_future} (N): "
            f"an offset longer than the clip can never be supervised"
        )
    if n_keys * max_offset < n_future:
        raise ConfigError(
            f"dataset.n_keyframes * dataset.max_offset = {n_keys}*{max_offset} = "
            f"{n_keys * max_offset} (M*S) must be >= dataset.n_future={n_future} (N), or the end "
            f"of the clip can never be covered"
        )
    if dataset.get("train_source") not in ("generated", "files"):
        raise ConfigError(
            f"dataset.train_source={dataset.get('train_source')!r}; allowed: generated, files"
        )


def check_common(cfg: Mapping[str, Any]) -> None:
    """Checks every entry point shares: the seed and the dataset."""
    require_seed(cfg.get("seed"))
    check_dataset(cfg["dataset"])


STAGES = ("both", "interpolator", "keyframes")
# What a scale= preset may hold: sizes, budgets and batch sizes, never a method choice.
SCALE_KEYS = (
    "embed_dim", "conv_width", "lstm_hidden", "lstm_layers", "mlp_hidden", "inter_latent", "surprise_latent",
    "key_latent", "batch_size", "stage1_batch_size", "ae_frames", "lr_stage1", "lr_surprise", "lr_stage2", "lr_tap",
    "lr_frames", "stage1_steps", "surprise_steps", "stage2_steps", "tap_steps", "frames_steps", "val_every",
    "checkpoint_every", "val_clips", "eval_clips", "teacher_clips",
)
# Where the method choices that keyin 0.1 kept under scale. (and loss.) live now.
MOVED_KEYS = {
    **{f"scale.{key}": f"backbone.{key}" for key in (
        "norm", "coord_channels", "inter_step_input", "inter_offset_min", "inter_offset_max", "foreground_weight")},
    **{f"loss.{key}": f"backbone.{key}" for key in ("foreground_weight", "foreground_threshold")},
    **{f"scale.{key}": f"model.keyframes.{key}" for key in (
        "teacher_weight", "teacher_keyframe_cost", "offset_evidence", "discovery", "map_keyframe_cost",
        "map_boundary_weight")},
    "loss.teacher_weight": "model.keyframes.teacher_weight",
}


def moved_key_message(key: str) -> str | None:
    """The one-line answer to a method choice given where keyin 0.1 kept it (``scale.teacher_weight``)."""
    new = MOVED_KEYS.get(key)
    if new is None:
        return None
    return (
        f"{key} is where keyin 0.1 kept a method choice, which lives in {new} now: set {new}=... instead "
        f"(scale= holds sizes and budgets only; model=keyin_plus and backbone=ours hold our additions' "
        f"values; docs/architecture.md)"
    )
SCALE_COUNTS = (
    "batch_size", "stage1_batch_size", "stage1_steps", "stage2_steps", "surprise_steps", "tap_steps", "frames_steps",
    "val_every", "checkpoint_every", "val_clips", "eval_clips",
)


def is_two_stage(model: Mapping[str, Any]) -> bool:
    """Whether ``model`` trains KEYIN's two stages (keyin, jumpy, static), not one module of its own or nothing."""
    return bool(model["trainable"]) and "module" not in model


def check_frozen_frames(cfg: Mapping[str, Any]) -> None:
    """backbone=frames names its frame autoencoder and serves two-stage models (and untrained baselines,
    which use no frame model, so that one sweep covers a table's rows)."""
    backbone = cfg["backbone"]
    if not backbone.get("frozen_frames"):
        return
    if cfg["model"]["trainable"] and not is_two_stage(cfg["model"]):  # an untrained baseline uses no frame model at all
        raise ConfigError(
            f"backbone=frames freezes the encoder and decoder of KEYIN's stage 1; model={cfg['model']['name']} "
            f"has no stage 1 (use it with keyin, keyin_plus, jumpy or static, or pick backbone=ours)"
        )
    if not backbone.get("frames_ckpt") and cfg["stage"] != "keyframes":
        raise ConfigError(
            "backbone=frames needs backbone.frames_ckpt=<run dir>/checkpoints/frames/last.ckpt, a frame "
            "autoencoder trained with the same sizes (keyin-train model=frame_autoencoder dataset=... backbone=ours)"
        )


def check_training(cfg: Mapping[str, Any]) -> None:
    """What keyin-train needs beyond the common checks."""
    if cfg["stage"] not in STAGES:
        raise ConfigError(f"stage={cfg['stage']!r}; allowed: {', '.join(STAGES)}")
    if cfg["stage"] != "both" and not is_two_stage(cfg["model"]):
        raise ConfigError(
            f"stage={cfg['stage']} needs a two-stage model (keyin, jumpy, static); "
            f"model={cfg['model']['name']} has {'one stage' if cfg['model']['trainable'] else 'no training'}: drop stage="
        )
    check_frozen_frames(cfg)
    for key in cfg["scale"]:
        if key not in SCALE_KEYS:
            raise ConfigError(
                moved_key_message(f"scale.{key}")
                or f"scale.{key} is not a size or budget; a scale= preset holds only {', '.join(SCALE_KEYS)}"
            )
    for key in SCALE_COUNTS:
        require_positive_int(cfg["scale"][key], f"scale.{key}")
    require_positive_int(cfg["num_workers"] + 1, "num_workers + 1")

"""KEYIN's sizes and choices as typed configs (paper §3.1, §4): what :meth:`keyin.models.KEYIN.from_config`
builds the model from. Checkpoints keep them as plain dicts (:func:`dataclasses.asdict`); :meth:`KEYINConfig.from_dict`
reads one back."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Mapping, TypeVar

Config = TypeVar("Config")
PAPER_BETAS = (0.9, 0.999)  # Adam's β1, β2 (paper section 4)


def adam_spec(lr: float) -> dict[str, Any]:
    """The paper's Adam at ``lr`` as an optimizer spec (:func:`keyin.lit.optimizers.optimizer_partial` builds it)."""
    return {"_target_": "torch.optim.Adam", "_partial_": True, "lr": lr, "betas": list(PAPER_BETAS)}


def picked(cls: type[Config], values: Mapping[str, Any]) -> Config:
    """A config dataclass of the entries of ``values`` that name its fields (others ignored; missing
    ones take the field's default)."""
    return cls(**{field.name: values[field.name] for field in dataclasses.fields(cls) if field.name in values})


@dataclass(frozen=True)
class FrameModelConfig:
    """CNN_enc / CNN_dec (``backbone=``) and the image likelihood they are trained with: changed pixels
    weigh ``foreground_weight`` (1: the plain BCE; keyin/losses/image.py)."""

    image_size: int
    channels: int
    embed_dim: int
    conv_width: int
    coord_channels: bool = False
    norm: str = "batch"
    foreground_weight: float = 1.0
    foreground_threshold: float = 0.1

    @property
    def plain_bce(self) -> bool:
        """Whether the image likelihood is the plain BCE (no pixel weighs more)."""
        return self.foreground_weight == 1


@dataclass(frozen=True)
class InterpolatorConfig:
    """MLP_init_inter and LSTM_inter (:class:`keyin.models.Interpolator`); ``latent_dim`` 0: deterministic."""

    latent_dim: int
    lstm_hidden: int
    lstm_layers: int
    mlp_hidden: int
    step_input: str = "boundaries"  # keyin.models.interpolator.STEP_INPUTS (stage 1's, no decoding rule)


@dataclass(frozen=True)
class PredictorConfig:
    """LSTM_cond, LSTM_inf and LSTM_key with the offset head (:class:`keyin.models.KeyframePredictor`);
    ``offset_mode`` "fixed" is Jumpy (every offset ``fixed_offset``), "static" Static."""

    n_keyframes: int
    latent_dim: int
    lstm_hidden: int
    lstm_layers: int
    attn_scale: bool = True
    offset_mode: str = "predicted"
    fixed_offset: int | None = None
    offset_evidence: bool = False


@dataclass(frozen=True)
class KEYINConfig:
    """The whole model: stage 1's frame model and interpolator, stage 2's keyframe predictor, the clip
    sizes it was trained on (``n_cond`` + ``n_future`` frames, offsets up to ``max_offset``) and what
    its forward does (:class:`keyin.models.KEYIN`'s ``delta_input``, ``gumbel_offsets``, ``interpolate_from``)."""

    frames: FrameModelConfig
    interpolator: InterpolatorConfig
    predictor: PredictorConfig
    n_cond: int
    n_future: int
    max_offset: int
    delta_input: str = "soft"
    gumbel_offsets: bool = False
    interpolate_from: str = "predicted"

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> "KEYINConfig":
        """The config of :func:`dataclasses.asdict`'s dict (a checkpoint's ``net``)."""
        parts = {"frames": FrameModelConfig, "interpolator": InterpolatorConfig, "predictor": PredictorConfig}
        return picked(cls, {**values, **{key: picked(part, values[key]) for key, part in parts.items()}})

    @classmethod
    def of_stage1(cls, stage1: Mapping[str, Any], predictor: PredictorConfig, **forward: Any) -> "KEYINConfig":
        """The model of a stage-1 module's hyper-parameters (its frame model, interpolator and clip
        sizes) with this ``predictor`` and the ``forward`` choices."""
        return cls(
            frames=picked(FrameModelConfig, stage1), interpolator=picked(InterpolatorConfig, stage1), predictor=predictor,
            n_cond=stage1["n_cond"], n_future=stage1["n_future"], max_offset=stage1["max_offset"], **forward,
        )

    def stage1_hparams(self) -> dict[str, Any]:
        """The sizes of stage 1 in a stage-1 module's terms (:meth:`of_stage1` reads them back)."""
        sizes = {"n_cond": self.n_cond, "n_future": self.n_future, "max_offset": self.max_offset}
        return {**dataclasses.asdict(self.frames), **dataclasses.asdict(self.interpolator), **sizes}

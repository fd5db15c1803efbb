"""Small untrained models saved as keyin checkpoints of the pushing dataset, for the learned
planners' tests (16x16 RGB, one conditioning frame)."""

from pathlib import Path

import lightning as L
import torch

from keyin import __version__
from keyin.lit.checkpoints import CONFIG_KEY, STAGE_KEY, VERSION_KEY
from keyin.lit.interpolator import InterpolatorModule
from keyin.lit.keyframes import KeyframeModule
from keyin.lit.surprise import SurpriseModule
from keyin.lit.tap import TAPModule

SIZE = 16
KEYFRAMES, KEY_LATENT = 3, 2
CONV = dict(image_size=SIZE, channels=3, embed_dim=8, conv_width=4, coord_channels=True, norm="batch", mlp_hidden=16)


def keyframe_module(**additions) -> KeyframeModule:
    """``additions``: keyword arguments of our additions (``offset_evidence``, ``discovery``, ...)."""
    torch.manual_seed(0)
    stage1 = InterpolatorModule(
        **CONV, n_cond=1, n_future=6, max_offset=3, latent_dim=2, lstm_hidden=16, lstm_layers=1,
        step_input="boundaries", offset_min=1, offset_max=3, kl_weight=0.0, ae_weight=1.0, lr=1e-3,
    )
    return KeyframeModule.from_flat(
        stage1=dict(stage1.hparams), n_keyframes=KEYFRAMES, latent_dim=KEY_LATENT, lstm_hidden=16, lstm_layers=1,
        attn_scale=True, offset_mode="predicted", fixed_offset=None, beta_ke=1.0, beta_ki=0.0, beta_kl=0.05,
        normalize_key_targets=True, lr=1e-3, **additions,
    )


def tap_module() -> TAPModule:
    torch.manual_seed(0)
    return TAPModule(**CONV, n_cond=1, lr=1e-3)


def save(module: L.LightningModule, path: Path, model: str, dataset: str = "pushing") -> str:
    """Write ``module`` as keyin-train would (its stage, and the run config's model and dataset)."""
    torch.save({
        "state_dict": module.state_dict(),
        "hyper_parameters": dict(module.hparams),
        STAGE_KEY: module.stage,
        VERSION_KEY: __version__,
        CONFIG_KEY: {"model": {"name": model}, "dataset": {"name": dataset}},
    }, path)
    return str(path)


def surprise_module(skips: bool = False) -> SurpriseModule:
    torch.manual_seed(0)
    return SurpriseModule(
        **{key: value for key, value in CONV.items() if key != "mlp_hidden"}, n_cond=1, n_future=6,
        n_keyframes=KEYFRAMES, latent_dim=2, lstm_hidden=16, predictor_layers=1, posterior_layers=1, beta=1.0, lr=1e-3,
        skips=skips,
    )

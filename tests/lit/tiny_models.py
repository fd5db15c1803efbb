"""Every trained model of keyin at a tiny size (8x8 frames, 2 + 6 frames a clip), built from a seed,
and a batch for it: what the device, precision and DDP tests run each model's steps on."""

from __future__ import annotations

from typing import Callable

import lightning as L
import torch

from keyin.lit.frame_autoencoder import FrameAutoencoderModule
from keyin.lit.interpolator import InterpolatorModule
from keyin.lit.keyframes import KeyframeModule
from keyin.lit.surprise import SurpriseModule
from keyin.lit.tap import TAPModule

SIZE, CHANNELS, N_COND, N_FUTURE, MAX_OFFSET, KEYFRAMES = 8, 1, 2, 6, 3, 2
CONV = dict(image_size=SIZE, channels=CHANNELS, embed_dim=8, conv_width=4)
# the two frame models of conf/backbone/: the paper's and ours (group norm, coordinates, foreground weights)
BACKBONES = {
    "paper": dict(norm="batch", coord_channels=False, step_input="autoregressive", offset_min=2, foreground_weight=1.0),
    "ours": dict(norm="group", coord_channels=True, step_input="boundaries", offset_min=1, foreground_weight=3.0),
}


def stage1(backbone: str = "ours", latent_dim: int = 2, **options) -> InterpolatorModule:
    torch.manual_seed(0)
    settings = dict(
        **CONV, **BACKBONES[backbone], n_cond=N_COND, n_future=N_FUTURE, max_offset=MAX_OFFSET, latent_dim=latent_dim,
        lstm_hidden=8, lstm_layers=1, mlp_hidden=8, offset_max=MAX_OFFSET, kl_weight=0.1, ae_weight=1.0, lr=1e-3,
        ae_frames=4, diagnostic_clips=4,
    )
    return InterpolatorModule(**{**settings, **options})


def stage2(backbone: str = "ours", **options) -> KeyframeModule:
    """KEYIN's stage 2 (``offset_mode`` "fixed": Jumpy, "static": Static) on a fresh stage 1."""
    hparams = dict(stage1(backbone).hparams)
    torch.manual_seed(1)
    defaults = dict(offset_mode="predicted", fixed_offset=None)
    return KeyframeModule.from_flat(
        stage1=hparams, n_keyframes=KEYFRAMES, latent_dim=2, lstm_hidden=8, lstm_layers=1, attn_scale=True,
        beta_ke=1.0, beta_ki=0.0, beta_kl=0.05, normalize_key_targets=True, lr=1e-3, **{**defaults, **options},
    )


def surprise() -> SurpriseModule:
    torch.manual_seed(0)
    return SurpriseModule(**CONV, coord_channels=True, norm="group", n_cond=N_COND, n_future=N_FUTURE,
                          n_keyframes=KEYFRAMES, latent_dim=2, lstm_hidden=8, predictor_layers=1, posterior_layers=1,
                          beta=0.1, lr=1e-3, ae_weight=1.0, foreground_weight=2.0)


def tap(norm: str = "group") -> TAPModule:
    torch.manual_seed(0)
    return TAPModule(**CONV, coord_channels=True, norm=norm, n_cond=N_COND, mlp_hidden=8, lr=1e-3, ae_weight=1.0,
                     foreground_weight=2.0)


def frame_autoencoder() -> FrameAutoencoderModule:
    torch.manual_seed(0)
    return FrameAutoencoderModule(**CONV, coord_channels=True, norm="group", n_cond=N_COND, lr=1e-3, frames_per_clip=2)


# name -> a fresh module: both KEYIN stages on both backbones, our additions, and every baseline that trains
MODELS: dict[str, Callable[[], L.LightningModule]] = {
    "stage1_paper": lambda: stage1("paper", latent_dim=0),
    "stage1_ours": lambda: stage1("ours"),
    "keyin_paper": lambda: stage2("paper"),
    "keyin_plus": lambda: stage2("ours", offset_evidence=True, discovery="map", teacher_weight=1.0, teacher_leaves=True),
    "jumpy": lambda: stage2("paper", offset_mode="fixed", fixed_offset=2),
    "static": lambda: stage2("paper", offset_mode="static"),
    "surprise": surprise,
    "tap": tap,
    "frame_autoencoder": frame_autoencoder,
}


def batch(clips: int = 4, seed: int = 0) -> dict[str, torch.Tensor]:
    """(clips, 2 + 6, 1, 8, 8) random binary frames, the last clip two frames short (padding), and
    two labelled keyframes a clip."""
    generator = torch.Generator().manual_seed(seed)
    frames = (torch.rand(clips, N_COND + N_FUTURE, CHANNELS, SIZE, SIZE, generator=generator) > 0.7).float()
    future_length = torch.full((clips,), N_FUTURE)
    future_length[-1] = N_FUTURE - 2
    frames[-1, N_COND + N_FUTURE - 2 :] = 0.0
    keyframes = torch.zeros(clips, N_FUTURE, dtype=torch.bool)
    keyframes[:, [1, 3]] = True
    return {"frames": frames, "future_length": future_length, "keyframes": keyframes}

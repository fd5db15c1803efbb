"""KEYIN's generative model (paper §3.1): encoder, keyframe predictor, interpolator, decoder.

One module for everything that runs the model: training and discovery use the posterior forward
(:meth:`KEYIN.forward`), video prediction the prior forward, and planning renders the keyframes of
given latents (:meth:`KEYIN.keyframe_images`). The Jumpy and Static baselines are the same model
with another offset head (``KeyframePredictor.offset_mode``).
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from keyin.models.config import FrameModelConfig, InterpolatorConfig, KEYINConfig
from keyin.models.conv import ConvDecoder, ConvEncoder
from keyin.models.interpolator import Interpolator
from keyin.models.keyframe_predictor import Chain, KeyframeOutput, KeyframePredictor
from keyin.models.state import sub_state_dict
from keyin.models.positions import argmax_frames, position_distributions, soft_keyframe_targets

STAGE1 = ("encoder", "decoder", "interpolator")  # the networks stage 1 trains and stage 2 freezes
# What stage 2 freezes (an open choice: the paper writes "we freeze LSTM_inter weights and only use it to
# backpropagate the error to the rest of the model"; our default, all of stage 1: docs/architecture.md, "Frozen modules"):
FROZEN_IN_STAGE2 = {
    "stage1": STAGE1,  # everything stage 1 trained (our default)
    "interpolator": ("interpolator",),  # MLP_init_inter and LSTM_inter; the encoder and decoder train on
    "lstm_inter": ("interpolator.lstm",),  # LSTM_inter alone, as the paper's sentence reads
}
# What the frozen interpolator is told of each segment's offset in stage 2 (an open choice of the paper,
# docs/decisions.md, issue 43): "soft" δ^t itself, "argmax" onehot(argmax δ^t) as the paper writes
# (δ̂^t, "hat" = argmax) and as stage 1 trained on, "straight_through" that one-hot forward and δ^t's
# gradient backward.
DELTA_INPUTS = ("soft", "argmax", "straight_through")
# Which keyframe embeddings the interpolator reads in the posterior forward (stage 2 and discovery): the
# predicted K̂^{e,t} (the paper's) or K̃^{e,t}(δ), the embeddings of the frames δ puts the keyframes at (ours:
# the predictor cannot then re-code a segment in K̂ and walk away from the true keyframes; docs/decisions.md,
# "Which term of the paper's loss walks away from the true keyframes"). The prior forward always reads K̂.
INTERPOLATE_FROM = ("predicted", "frames")


def interpolator_offsets(offset_probs: Tensor, delta_input: str) -> Tensor:
    """The offset code the interpolator reads, (..., S), from the offset distributions (..., S).

    Args:
        offset_probs: δ, entry a the probability of offset a + 1.
        delta_input: one of :data:`DELTA_INPUTS`.
    """
    if delta_input == "soft":
        return offset_probs
    hard = F.one_hot(offset_probs.argmax(-1), offset_probs.shape[-1]).to(offset_probs)
    if delta_input == "argmax":
        return hard
    if delta_input == "straight_through":
        return hard + offset_probs - offset_probs.detach()
    raise ValueError(f"delta_input must be one of {DELTA_INPUTS}, got {delta_input!r}")


def stage1_networks(
    frames: FrameModelConfig, interpolator: InterpolatorConfig, max_offset: int
) -> tuple[ConvEncoder, ConvDecoder, Interpolator]:
    """The encoder, decoder and interpolator stage 1 trains; their weights come from its checkpoint."""
    conv = dict(
        image_size=frames.image_size, channels=frames.channels, width=frames.conv_width, embed_dim=frames.embed_dim,
        coord_channels=frames.coord_channels, norm=frames.norm,
    )
    inter = Interpolator(  # made first: the fresh weights' random draws in their order of before
        frames.embed_dim, max_offset, interpolator.latent_dim, interpolator.lstm_hidden, interpolator.lstm_layers,
        interpolator.mlp_hidden, interpolator.step_input,
    )
    return ConvEncoder(**conv), ConvDecoder(**conv), inter


class KEYIN(nn.Module):
    """The keyframe model and the interpolator between its keyframes.

    Args:
        encoder, decoder, interpolator: stage 1's networks (frozen during stage 2).
        predictor: LSTM_cond, LSTM_inf with the attention posterior, LSTM_key and the offset head.
        n_cond: conditioning frames at the start of every clip.
        delta_input: what the interpolator reads of δ (:data:`DELTA_INPUTS`).
        gumbel_offsets: (an aid the paper does not have) in training, the posterior forward's δ is a
            straight-through Gumbel-softmax sample of the offset logits: one-hot forward, so the soft
            loss scores one sampled segmentation per clip, and the relaxed sample's gradient backward.
        interpolate_from: what the posterior forward's interpolator reads as keyframes (:data:`INTERPOLATE_FROM`).
    """

    def __init__(
        self,
        encoder: ConvEncoder,
        decoder: ConvDecoder,
        interpolator: Interpolator,
        predictor: KeyframePredictor,
        n_cond: int,
        delta_input: str = "soft",
        gumbel_offsets: bool = False,
        interpolate_from: str = "predicted",
    ) -> None:
        super().__init__()
        if delta_input not in DELTA_INPUTS:
            raise ValueError(f"delta_input must be one of {DELTA_INPUTS}, got {delta_input!r}")
        if interpolate_from not in INTERPOLATE_FROM:
            raise ValueError(f"interpolate_from must be one of {INTERPOLATE_FROM}, got {interpolate_from!r}")
        self.encoder, self.decoder, self.interpolator, self.predictor = encoder, decoder, interpolator, predictor
        self.n_cond = n_cond
        self.delta_input = delta_input
        self.gumbel_offsets = gumbel_offsets
        self.interpolate_from = interpolate_from

    @classmethod
    def from_config(cls, config: KEYINConfig) -> "KEYIN":
        """The model ``config`` sizes, with fresh weights (a checkpoint's replace them)."""
        encoder, decoder, interpolator = stage1_networks(config.frames, config.interpolator, config.max_offset)
        sizes = config.predictor
        predictor = KeyframePredictor(
            config.frames.embed_dim, sizes.n_keyframes, config.max_offset, sizes.latent_dim, sizes.lstm_hidden,
            sizes.lstm_layers, attn_scale=sizes.attn_scale, offset_mode=sizes.offset_mode, fixed_offset=sizes.fixed_offset,
            offset_evidence=sizes.offset_evidence,
        )
        return cls(encoder, decoder, interpolator, predictor, config.n_cond, delta_input=config.delta_input,
                   gumbel_offsets=config.gumbel_offsets, interpolate_from=config.interpolate_from)

    def load_stage1(self, state_dict: dict[str, Tensor]) -> None:
        """Copy the stage-1 networks' weights from a stage-1 state dict (``encoder.*``, ...)."""
        for name in STAGE1:
            getattr(self, name).load_state_dict(sub_state_dict(state_dict, f"{name}."))

    def freeze_stage1(self, frozen: str = "stage1") -> None:
        """No gradients into the stage-1 networks that ``frozen`` names (:data:`FROZEN_IN_STAGE2`) and
        eval mode for them; gradients still flow through."""
        for name in FROZEN_IN_STAGE2[frozen]:
            self.get_submodule(name).requires_grad_(False).eval()

    def keyframes(
        self, clips: Tensor, future_length: Tensor, mode: str = "posterior", sample: bool = True, chain: Chain = "soft"
    ) -> tuple[Tensor, KeyframeOutput]:
        """The clips' embeddings (B, L, E) and the keyframe predictor's output, without interpolating.

        Args: as :meth:`forward`; ``chain`` as :meth:`KeyframePredictor.forward` (the readout's "argmax").
        """
        embeddings = self.encoder(clips)  # (B, L, E)
        cond_emb, future_emb = embeddings[:, : self.n_cond], embeddings[:, self.n_cond :]
        return embeddings, self.predictor(cond_emb, future_emb, future_length, mode=mode, sample=sample, chain=chain)

    def forward(
        self, clips: Tensor, future_length: Tensor, mode: str = "posterior", sample: bool = True
    ) -> dict[str, Tensor | None]:
        """Keyframes, offsets and interpolated frames of a batch of clips.

        Args:
            clips: (B, L, C, H, W) in [0, 1], L = n_cond + n_future.
            future_length: (B,) valid future frames.
            mode: "posterior" (the keyframes of these clips) or "prior" (a sample given the
                conditioning frames only).
            sample: draw the keyframe latents; False takes their mean.
        Returns:
            ``key_emb`` (B, M, E), ``offset_probs`` and ``offset_logits`` (B, M, S), ``mu`` /
            ``log_sigma`` (B, M, Zk), ``attention`` (B, M, N) or None, ``future_emb`` (B, N, E),
            ``boundary_emb`` (B, N + 1, E) on the extended index (K^0, then the future),
            ``boundary_scores`` (B, N) or None, and ``frames`` (B, M, S, C·H·W): the probabilities of
            the frames interpolated after each keyframe's predecessor.
        """
        embeddings, keys = self.keyframes(clips, future_length, mode, sample)
        if self.gumbel_offsets and self.training and mode == "posterior":
            keys = keys._replace(offset_probs=F.gumbel_softmax(keys.offset_logits, hard=True))
        key_emb = keys.key_emb
        if self.interpolate_from == "frames" and mode == "posterior":
            keyframe_pos, _ = position_distributions(keys.offset_probs)
            key_emb = soft_keyframe_targets(keyframe_pos, future_length, embeddings[:, self.n_cond :], normalize=True)
        frames = self.interpolate(
            embeddings[:, self.n_cond - 1], key_emb, interpolator_offsets(keys.offset_probs, self.delta_input)
        )
        return {
            "key_emb": keys.key_emb,
            "offset_probs": keys.offset_probs,
            "offset_logits": keys.offset_logits,
            "mu": keys.mu,
            "log_sigma": keys.log_sigma,
            "attention": keys.attention,
            "future_emb": embeddings[:, self.n_cond :],
            "boundary_emb": embeddings[:, self.n_cond - 1 :],
            "boundary_scores": keys.boundary_scores,
            "frames": frames,
        }

    def interpolate(self, first: Tensor, key_emb: Tensor, offsets: Tensor) -> Tensor:
        """The frames interpolated after each keyframe's predecessor, the interpolator's latent drawn
        from its prior (stage 2 does so, paper §3.2; a deterministic interpolator has none).

        Args:
            first: (B, E) K^{e,0}, the last conditioning embedding.
            key_emb: (B, M, E) keyframe embeddings.
            offsets: (B, M, S) the offset code each segment's interpolation reads.
        Returns:
            (B, M, S, C·H·W) pixel probabilities.
        """
        starts = torch.cat([first[:, None], key_emb[:, :-1]], dim=1)  # (B, M, E)
        n_clips, n_keys, max_offset = offsets.shape
        latent = torch.randn(n_clips * n_keys, self.interpolator.latent_dim, device=key_emb.device)
        inter_emb = self.interpolator(starts.flatten(0, 1), key_emb.flatten(0, 1), offsets.flatten(0, 1), latent)
        # float32: these probabilities meet the loss's logs (a half-precision sigmoid rounds to 1 near 1)
        frames = torch.sigmoid(self.decoder(inter_emb.flatten(0, 1)).float())  # (B·M·S, C, H, W)
        return frames.reshape(n_clips, n_keys, max_offset, -1)

    def argmax_video(self, clips: Tensor, out: dict[str, Tensor | None]) -> Tensor:
        """(B, L, C, H, W): the conditioning frames, then the frames of the argmax offsets of ``out``
        (a :meth:`forward` of these clips); frames past the last keyframe are black."""
        future = argmax_frames(out["offset_probs"], out["frames"], clips.shape[1] - self.n_cond)  # (B, N, D)
        return torch.cat([clips[:, : self.n_cond], future.view_as(clips[:, self.n_cond :])], dim=1)

    def keyframe_images(self, cond_emb: Tensor, z: Tensor, last_only: bool = False) -> Tensor:
        """The keyframes that the prior's latents ``z`` give after the conditioning embeddings.

        Args:
            cond_emb: (B, n_cond, E) encoded conditioning frames.
            z: (B, M, Zk) keyframe latents.
            last_only: only the last keyframe.
        Returns:
            (B, M or 1, C, H, W) pixel probabilities.
        """
        keys = self.predictor(cond_emb, mode="prior", z=z)
        embeddings = keys.key_emb[:, -1:] if last_only else keys.key_emb  # (B, K, E)
        return torch.sigmoid(self.decoder(embeddings))

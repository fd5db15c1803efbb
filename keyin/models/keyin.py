"""KEYIN's generative model (paper §3, REFERENCE §2.4): encoder, keyframe predictor, interpolator, decoder.

One module for everything that runs the model: training and discovery use the posterior forward
(:meth:`KEYIN.forward`), video prediction the prior forward, and planning renders the keyframes of
given latents (:meth:`KEYIN.keyframe_images`). The Jumpy and Static baselines are the same model
with another offset head (``KeyframePredictor.offset_mode``).
"""

from __future__ import annotations

import torch
from torch import Tensor, nn

from keyin.losses.soft_keyframe import argmax_frames
from keyin.models.conv import ConvDecoder, ConvEncoder
from keyin.models.interpolator import Interpolator
from keyin.models.keyframe_predictor import Chain, KeyframeOutput, KeyframePredictor

STAGE1 = ("encoder", "decoder", "interpolator")  # the networks stage 1 trains and stage 2 freezes


class KEYIN(nn.Module):
    """The keyframe model and the interpolator between its keyframes.

    Args:
        encoder, decoder, interpolator: stage 1's networks (frozen during stage 2).
        predictor: LSTM_cond, LSTM_inf with the attention posterior, LSTM_key and the offset head.
        n_cond: conditioning frames at the start of every clip.
    """

    def __init__(
        self,
        encoder: ConvEncoder,
        decoder: ConvDecoder,
        interpolator: Interpolator,
        predictor: KeyframePredictor,
        n_cond: int,
    ) -> None:
        super().__init__()
        self.encoder, self.decoder, self.interpolator, self.predictor = encoder, decoder, interpolator, predictor
        self.n_cond = n_cond

    def load_stage1(self, state_dict: dict[str, Tensor]) -> None:
        """Copy the stage-1 networks' weights from a stage-1 state dict (``encoder.*``, ...)."""
        for name in STAGE1:
            prefix = f"{name}."
            getattr(self, name).load_state_dict({k[len(prefix) :]: v for k, v in state_dict.items() if k.startswith(prefix)})

    def freeze_stage1(self) -> None:
        """No gradients into the stage-1 networks and eval mode for them; gradients still flow through."""
        for name in STAGE1:
            getattr(self, name).requires_grad_(False).eval()

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
        starts = torch.cat([embeddings[:, self.n_cond - 1 : self.n_cond], keys.key_emb[:, :-1]], dim=1)  # (B, M, E)
        n_clips, n_keys, max_offset = keys.offset_probs.shape
        latent = torch.randn(
            n_clips * n_keys, self.interpolator.latent_dim, device=clips.device
        )  # stage 2 samples the interpolator latent from the prior (paper §3.2)
        inter_emb = self.interpolator(
            starts.flatten(0, 1), keys.key_emb.flatten(0, 1), keys.offset_probs.flatten(0, 1), latent
        )  # (B·M, S, E)
        frames = torch.sigmoid(self.decoder(inter_emb.flatten(0, 1)))  # (B·M·S, C, H, W)
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
            "frames": frames.reshape(n_clips, n_keys, max_offset, -1),
        }

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

"""The interpolator LSTM_inter with MLP_init_inter, and its seq2seq-VAE posterior (paper §3.1-3.2).

Step inputs (`step_input`):

* "autoregressive" (paper §3.1, "Intermediate prediction"): step i reads [Î^e_{i-1}, z] with Î^e_{-1} = start. Every
  output is built on the previous output, so errors compound along the segment, and the step index
  and the offset are only available through the recurrent state. The prototype's interpolator of
  this kind had an error growing almost linearly with the offset (PROTOTYPE-FINDINGS §2), which
  biased stage 2 toward short constant offsets.
* "boundaries" (our proposal, the default): step i reads [start, end, δ, z, onehot(i)]. Linear
  motion, Î^e_i ≈ start + (i+1)/o · (end − start), is then a smooth function of the current step's
  own input at every offset, with nothing to accumulate; all S steps run as one nn.LSTM call.
"""

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from keyin.data.segments import segment_frames
from keyin.models.recurrent import MLP, LSTMBlock, init_forget_bias, state_from_vector

STEP_INPUTS = ("boundaries", "autoregressive")
LATENTS = ("posterior", "prior", "mean")


class Interpolator(nn.Module):
    """Predicts the S frame embeddings of a segment from its boundary keyframes (paper §3.1).

    MLP_init_inter([start, end, δ, z]) gives the full initial state of LSTM_inter (h and c of every
    layer), which is unrolled for S steps with a tanh output head. Output i is the frame at position
    p^{t-1} + 1 + i and is meaningful iff the offset is ≥ i + 1 (docs/architecture.md, "Index conventions").

    Args:
        embed_dim: E.
        max_offset: S.
        latent_dim: Zi; 0 makes the interpolator deterministic (no latent input at all).
        hidden: LSTM_inter hidden size per layer.
        layers: LSTM_inter layers.
        mlp_hidden: MLP_init_inter hidden width.
        step_input: "boundaries" or "autoregressive" (see the module docstring).
        mlp_layers: number of Linear layers of MLP_init_inter.
    """

    def __init__(
        self,
        embed_dim: int,
        max_offset: int,
        latent_dim: int,
        hidden: int,
        layers: int,
        mlp_hidden: int,
        step_input: str = "boundaries",
        mlp_layers: int = 3,
    ) -> None:
        super().__init__()
        if step_input not in STEP_INPUTS:
            raise ValueError(f"step_input must be one of {STEP_INPUTS}, got {step_input!r}")
        if latent_dim < 0:
            raise ValueError(f"latent_dim must be >= 0, got {latent_dim}")
        self.embed_dim = embed_dim
        self.max_offset = max_offset
        self.latent_dim = latent_dim
        self.hidden = hidden
        self.layers = layers
        self.step_input = step_input
        segment_dim = 2 * embed_dim + max_offset + latent_dim
        self.init_mlp = MLP(segment_dim, 2 * layers * hidden, mlp_hidden, mlp_layers)
        step_dim = segment_dim + max_offset if step_input == "boundaries" else embed_dim + latent_dim
        self.lstm = LSTMBlock(step_dim, embed_dim, hidden, layers, learn_initial_state=False)

    def _latent(self, z: Tensor | None, start: Tensor) -> Tensor:
        """Validate z; (R, 0) for a deterministic interpolator."""
        if self.latent_dim == 0:
            if z is not None and z.shape[-1] != 0:
                raise ValueError("a deterministic interpolator (latent_dim=0) takes no z")
            return start.new_zeros(start.shape[0], 0)
        if z is None or z.shape != (start.shape[0], self.latent_dim):
            shape = None if z is None else tuple(z.shape)
            raise ValueError(f"z must have shape ({start.shape[0]}, {self.latent_dim}), got {shape}")
        return z

    def forward(self, start: Tensor, end: Tensor, offset_probs: Tensor, z: Tensor | None = None) -> Tensor:
        """Interpolate R segments.

        Args:
            start: (R, E) embedding of the segment's first boundary K̂^{e,t-1}.
            end: (R, E) embedding of its last boundary K̂^{e,t}.
            offset_probs: (R, S) offset distribution δ^t (one-hot in stage 1).
            z: (R, Zi) interpolator latent; None (or (R, 0)) when latent_dim = 0.
        Returns:
            (R, S, E) frame embeddings Î^{e,t}_i in (-1, 1); row i sits at offset i + 1 from start.
        """
        latent = self._latent(z, start)  # (R, Zi)
        n_rows = start.shape[0]
        segment = torch.cat([start, end, offset_probs, latent], dim=-1)  # (R, 2E + S + Zi)
        init_vector = self.init_mlp(segment)  # (R, 2·layers·hidden)
        state = state_from_vector(init_vector, self.layers, self.hidden)  # (h, c), each (layers, R, hidden)
        if self.step_input == "boundaries":
            step_index = torch.eye(self.max_offset, dtype=start.dtype, device=start.device)  # (S, S)
            step_inputs = torch.cat(
                [segment.unsqueeze(1).expand(-1, self.max_offset, -1), step_index.expand(n_rows, -1, -1)],
                dim=-1,
            )  # (R, S, 2E + S + Zi + S): [start, end, δ, z, onehot(i)] at step i
            outputs, _ = self.lstm(step_inputs, state)  # (R, S, E)
            return torch.tanh(outputs)
        previous_frame = start  # Î^e_{-1} := start
        frames = []
        for _ in range(self.max_offset):
            output, state = self.lstm.step(torch.cat([previous_frame, latent], dim=-1), state)  # (R, E)
            previous_frame = torch.tanh(output)
            frames.append(previous_frame)
        return torch.stack(frames, dim=1)  # (R, S, E)


class InterpolatorPosterior(nn.Module):
    """q(z_i | segment): a 1-layer LSTM over the target embeddings (paper §3.2, a seq2seq VAE; stage 1 only).

    Only built for a stochastic interpolator (latent_dim ≥ 1); a deterministic one needs none.

    Args:
        embed_dim: E.
        latent_dim: Zi ≥ 1.
        hidden: LSTM hidden size.
    """

    def __init__(self, embed_dim: int, latent_dim: int, hidden: int) -> None:
        super().__init__()
        if latent_dim < 1:
            raise ValueError(
                f"InterpolatorPosterior needs latent_dim >= 1, got {latent_dim}; "
                "a deterministic interpolator (latent_dim=0) has no posterior"
            )
        self.lstm = nn.LSTM(embed_dim, hidden, batch_first=True)
        init_forget_bias(self.lstm)
        self.head = nn.Linear(hidden, 2 * latent_dim)

    def forward(self, targets: Tensor, mask: Tensor) -> tuple[Tensor, Tensor]:
        """Posterior Gaussian from the output at the last valid step.

        The LSTM runs forward from a zero state, so the output at step o − 1 has seen exactly the o
        valid targets; later (padding) steps cannot influence it.

        Args:
            targets: (R, S, E) target embeddings, the first o of each row valid.
            mask: (R, S) bool, a prefix of True (o ≥ 1 entries) per row.
        Returns:
            mu (R, Zi), log_sigma (R, Zi).
        """
        outputs, _ = self.lstm(targets)  # (R, S, hidden)
        last_valid = (mask.sum(dim=1) - 1).clamp(min=0)  # (R,)
        index = last_valid[:, None, None].expand(-1, 1, outputs.shape[-1])  # (R, 1, hidden)
        final_output = outputs.gather(1, index).squeeze(1)  # (R, hidden)
        mu, log_sigma = self.head(final_output).chunk(2, dim=-1)  # (R, Zi) each
        return mu, log_sigma


def interpolate_segments(
    interpolator: Interpolator, posterior: InterpolatorPosterior | None, embeddings: Tensor,
    clip: Tensor, start: Tensor, offset: Tensor, latent: str,
) -> tuple[Tensor, Tensor, tuple[Tensor, Tensor] | None]:
    """Interpolate segments of encoded clips between their boundary frames (stage 1).

    Args:
        embeddings: (B, L, E) encoded clips.
        clip, start, offset: (R,) the segments (boundaries at ``start`` and ``start + offset``).
        latent: "posterior" (z drawn from q(z | targets); a deterministic interpolator has none),
            "prior" (z ~ N(0, I)) or "mean" (z = 0).
    Returns:
        predicted (R, S, E), valid (R, S) bool, and the posterior's (mu, log_sigma), each (R, Zi),
        where z was drawn from it (else None).
    """
    if latent not in LATENTS:
        raise ValueError(f"latent must be one of {LATENTS}, got {latent!r}")
    device = embeddings.device
    clip, start, offset = clip.to(device), start.to(device), offset.to(device)
    frames, valid = segment_frames(start, offset, interpolator.max_offset)
    z = embeddings.new_zeros(clip.shape[0], interpolator.latent_dim)
    stats = None
    if posterior is not None and latent == "posterior":
        stats = posterior(embeddings[clip[:, None], frames], valid)
        z = stats[0] + stats[1].exp() * torch.randn_like(stats[0])
    elif latent == "prior":
        z = torch.randn_like(z)
    offset_onehot = F.one_hot(offset - 1, interpolator.max_offset).float()
    predicted = interpolator(embeddings[clip, start], embeddings[clip, start + offset], offset_onehot, z)
    return predicted, valid, stats

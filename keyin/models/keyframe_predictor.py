"""The keyframe predictor: LSTM_cond, LSTM_inf + attention posterior, LSTM_key (paper §3.1).

Also the Static and Jumpy baselines, which differ only in where the offset distributions come from
(`offset_mode`, :mod:`keyin.models.offset_heads`).
"""

from typing import NamedTuple

import torch
import torch.nn.functional as F
from torch import Tensor, nn
from torch.nn.utils.rnn import pack_padded_sequence, pad_packed_sequence

from keyin.precision import in_float32
from keyin.models.attention import attention_posterior
from keyin.models.offset_heads import offset_head
from keyin.models.positions import initial_position, shifted_positions
from keyin.models.recurrent import LSTMBlock, init_forget_bias

MODES = ("posterior", "prior")
# How keyframe t's offset evidence places keyframe t - 1: "soft" at D^{t-1} (the soft loss's
# expected position, training), "argmax" where the argmax offsets put it (the readout's own chain);
# or (B, M) given offsets (a teacher's: teacher forcing of the previous keyframe's position).
CHAINS = ("soft", "argmax")
Chain = str | Tensor


class KeyframeOutput(NamedTuple):
    """What the keyframe predictor produces for M keyframes.

    Attributes:
        key_emb: (B, M, E) keyframe embeddings K̂^{e,t}, t = 1…M, in (-1, 1).
        offset_probs: (B, M, S) δ^t; entry a is the probability of offset a + 1.
        offset_logits: (B, M, S) logits of δ^t.
        mu: (B, M, Zk) posterior means (zeros in prior mode).
        log_sigma: (B, M, Zk) posterior log standard deviations (zeros in prior mode).
        z: (B, M, Zk) the latents fed to LSTM_key.
        attention: (B, M, N) attention weights α over the future frames; None in prior mode.
        boundary_scores: (B, N) per-frame boundary logits of ``offset_evidence`` (posterior mode);
            None otherwise.
    """

    key_emb: Tensor
    offset_probs: Tensor
    offset_logits: Tensor
    mu: Tensor
    log_sigma: Tensor
    z: Tensor
    attention: Tensor | None
    boundary_scores: Tensor | None = None


class KeyframePredictor(nn.Module):
    """Predicts M keyframe embeddings and their offset distributions (paper §3.1, eq. 1-2).

    LSTM_cond runs over the conditioning embeddings; its final state initialises LSTM_key
    (Init_key = Final_cond, so both share `hidden` and `layers`). In posterior mode a bidirectional
    LSTM_inf reads the future embeddings and emits a key (E) and a value [μ, log σ] (2Zk) per frame;
    keyframe t attends with the query K̂^{e,t-1} (K^{e,0} = the last conditioning embedding). LSTM_key
    reads [z^t, K̂^{e,t-1}] and emits K̂^{e,t} = tanh(Linear) and the offset logits.

    Args:
        embed_dim: E.
        n_keyframes: M.
        max_offset: S.
        latent_dim: Zk.
        hidden: hidden size per layer of every LSTM.
        layers: number of layers of every LSTM.
        attn_scale: divide attention scores by √E and learn an inverse temperature (init 1);
            False is the paper's plain inner product.
        offset_mode: "predicted" (KEYIN: softmax of a head on LSTM_key), "static" (learned logits
            (M, S) shared by all sequences: the Static baseline), "fixed" (one-hot at
            `fixed_offset` for every keyframe: the Jumpy baseline).
        fixed_offset: the constant offset in 1…S; required by, and only allowed with, "fixed".
        offset_evidence: (our addition, "predicted" mode only) in posterior mode, add to the offset
            logits of keyframe t the log-probability that the candidate position is the first
            boundary after the previous keyframe (soft position ``D^{t-1}``), from per-frame
            boundary scores read off LSTM_inf. Finding a direction change is local; counting the
            frames to it through z and LSTM_key is not, and that is what kept δ from becoming
            clip-specific (docs/decisions.md). The boundary head starts at zero (probability 1/2
            everywhere: a mild preference for short offsets). Prior mode has no future frames and
            uses the offset head alone.
    """

    def __init__(
        self,
        embed_dim: int,
        n_keyframes: int,
        max_offset: int,
        latent_dim: int,
        hidden: int,
        layers: int,
        attn_scale: bool = True,
        offset_mode: str = "predicted",
        fixed_offset: int | None = None,
        offset_evidence: bool = False,
    ) -> None:
        super().__init__()
        if offset_evidence and offset_mode != "predicted":
            raise ValueError("offset_evidence needs offset_mode='predicted'")
        self.embed_dim = embed_dim
        self.n_keyframes = n_keyframes
        self.max_offset = max_offset
        self.latent_dim = latent_dim
        self.attn_scale = attn_scale
        self.offset_mode = offset_mode
        self.fixed_offset = fixed_offset
        self.offset_evidence = offset_evidence

        # Only the final state of LSTM_cond is used, so it has no output projection.
        self.cond_lstm = LSTMBlock(embed_dim, None, hidden, layers)

        self.inference_projection = nn.Linear(embed_dim, hidden)
        self.inference_lstm = nn.LSTM(hidden, hidden, num_layers=layers, batch_first=True, bidirectional=True)
        init_forget_bias(self.inference_lstm)
        self.inference_key_head = nn.Linear(2 * hidden, embed_dim)
        self.inference_value_head = nn.Linear(2 * hidden, 2 * latent_dim)
        if offset_evidence:
            self.boundary_head = nn.Linear(2 * hidden, 1)
            nn.init.zeros_(self.boundary_head.weight)
            nn.init.zeros_(self.boundary_head.bias)
            self.beyond_score = nn.Parameter(torch.zeros(()))  # positions past the clip's end
        else:
            self.boundary_head = None
            self.register_parameter("beyond_score", None)
        if attn_scale:
            self.attention_inv_temperature = nn.Parameter(torch.tensor(1.0))
        else:
            self.register_parameter("attention_inv_temperature", None)

        self.key_lstm = LSTMBlock(latent_dim + embed_dim, None, hidden, layers, learn_initial_state=False)
        self.key_head = nn.Linear(hidden, embed_dim)
        self.offset_head = offset_head(offset_mode, hidden, n_keyframes, max_offset, fixed_offset)

    def infer(self, future_emb: Tensor, lengths: Tensor | None) -> tuple[Tensor, Tensor, Tensor, Tensor | None]:
        """LSTM_inf: attention keys and values (and boundary scores) for every future frame.

        With `lengths`, the sequences are packed so that frames beyond a clip's length influence
        nothing (the backward direction starts at the last valid frame).

        Args:
            future_emb: (B, N, E).
            lengths: (B,) valid lengths in 0…N, or None if all N frames are valid.
        Returns:
            keys (B, N, E), values (B, N, 2Zk), mask (B, N) bool (True = valid), boundary scores
            (B, N) (None without ``offset_evidence``).
        """
        batch_size, n_frames, _ = future_emb.shape
        projected = self.inference_projection(future_emb)  # (B, N, hidden)
        if lengths is None:
            features, _ = self.inference_lstm(projected)  # (B, N, 2·hidden)
            mask = torch.ones(batch_size, n_frames, dtype=torch.bool, device=future_emb.device)
        else:
            # Packing needs lengths ≥ 1 on the CPU; an empty clip's single dummy frame stays masked.
            packed = pack_padded_sequence(
                projected, lengths.clamp(min=1).cpu(), batch_first=True, enforce_sorted=False
            )
            packed_features, _ = self.inference_lstm(packed)
            features, _ = pad_packed_sequence(packed_features, batch_first=True, total_length=n_frames)
            mask = torch.arange(n_frames, device=future_emb.device) < lengths.to(future_emb.device)[:, None]
        keys = self.inference_key_head(features)  # (B, N, E)
        values = self.inference_value_head(features)  # (B, N, 2Zk)
        scores = self.boundary_head(features).squeeze(-1) if self.boundary_head is not None else None
        return keys, values, mask, scores

    @in_float32  # a cumulative sum of log-probabilities: float32 under mixed precision
    def _extended_scores(self, scores: Tensor, mask: Tensor, length: int) -> tuple[Tensor, Tensor]:
        """Boundary logits on the extended index (index k = future position k - 1; K^0 and every
        position past the clip score ``beyond_score``), (B, length), and their
        ``Σ_{i≤j} log(1 - p[i])``, (B, length)."""
        frame_scores = torch.where(mask, scores, self.beyond_score)  # (B, N)
        extended = self.beyond_score.expand(scores.shape[0], length).clone()
        extended[:, 1 : frame_scores.shape[1] + 1] = frame_scores
        return extended, F.logsigmoid(-extended).cumsum(-1)

    @in_float32
    def _add_boundary_evidence(self, offset_logits: Tensor, scores: Tensor, mask: Tensor, chain: Chain = "soft") -> Tensor:
        """Offset logits plus the log-probability that offset a + 1 reaches the *first* boundary.

        With ``p[j] = σ(s[j])`` the boundary probability at extended index j, keyframe t after a
        previous keyframe at k gets ``log p[k+a+1] + Σ_{k<i≤k+a} log(1 - p[i])`` (no boundary
        skipped), in expectation over the soft position ``D^{t-1}``. The first boundary, not the
        highest-scoring one within S frames: a softmax over the raw scores jumps over a boundary
        whenever a later one scores higher (docs/decisions.md).

        Args:
            offset_logits: (B, M, S) from the offset head.
            scores: (B, N) per-frame boundary logits; mask: (B, N) valid frames.
            chain: "soft" (the previous keyframe at ``D^{t-1}``), "argmax" (at the position of
                the argmax offsets so far, one-hot: what the argmax readout reads), or (B, M)
                offsets in 1…S (values < 1, a teacher's "no keyframe", count as 1) whose sums place it.
        Returns:
            (B, M, S) logits; keyframe t's depend on δ^1…δ^{t-1} through ``D^{t-1}``.
        """
        batch, n_keys, max_offset = offset_logits.shape
        n_ext = n_keys * max_offset + 1
        extended, none_through = self._extended_scores(scores, mask, n_ext)
        # log p[j] + Σ_{i<j} log(1 - p[i]); the Σ_{i≤k} part is removed per previous position below.
        first_at = F.logsigmoid(extended) + F.pad(none_through[:, :-1], (1, 0))
        previous_pos = initial_position(batch, n_ext, offset_logits)  # D^0
        logits = []
        for t in range(n_keys):
            shifted = shifted_positions(previous_pos, max_offset)  # (B, S, L_ext)
            skipped_before = (previous_pos * none_through).sum(-1, keepdim=True)  # (B, 1)
            evidence = torch.einsum("bak,bk->ba", shifted, first_at) - skipped_before  # (B, S)
            logit = offset_logits[:, t] + evidence  # (B, S)
            if isinstance(chain, Tensor):
                previous_pos = shifted[torch.arange(batch), chain[:, t].clamp(1, max_offset) - 1]  # one-hot, given path
            elif chain == "argmax":
                previous_pos = shifted[torch.arange(batch), logit.argmax(-1)]  # one-hot at the argmax path
            else:
                previous_pos = torch.einsum("bak,ba->bk", shifted, torch.softmax(logit, dim=-1))  # D^t
            logits.append(logit)
        return torch.stack(logits, dim=1)

    def forward(
        self,
        cond_emb: Tensor,
        future_emb: Tensor | None = None,
        lengths: Tensor | None = None,
        mode: str = "posterior",
        sample: bool = True,
        z: Tensor | None = None,
        chain: Chain = "soft",
    ) -> KeyframeOutput:
        """Predict the keyframes.

        Args:
            cond_emb: (B, T, E) conditioning embeddings; the last one is K^{e,0}.
            future_emb: (B, N, E) future embeddings; required in posterior mode, ignored in prior mode.
            lengths: (B,) valid future lengths (posterior mode); None means all N are valid.
            mode: "posterior" (z^t from the attention posterior, training) or "prior" (z^t ~ N(0, I)).
            sample: draw z^t; False uses the mean (μ^t in posterior mode, 0 in prior mode).
            z: (B, M, Zk) latents to use in prior mode (the CEM planner's), overriding `sample`.
            chain: where the offset evidence places each previous keyframe (:data:`CHAINS`; no
                effect without ``offset_evidence``).
        Returns:
            KeyframeOutput.
        """
        if mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
        if isinstance(chain, Tensor):
            if tuple(chain.shape) != (cond_emb.shape[0], self.n_keyframes):
                raise ValueError(f"given offsets must have shape (B, M) = ({cond_emb.shape[0]}, {self.n_keyframes}), got {tuple(chain.shape)}")
        elif chain not in CHAINS:
            raise ValueError(f"chain must be one of {CHAINS} or (B, M) offsets, got {chain!r}")
        if mode == "posterior" and future_emb is None:
            raise ValueError("posterior mode needs future_emb")
        if mode == "posterior" and z is not None:
            raise ValueError("z can only be given in prior mode")
        batch_size = cond_emb.shape[0]
        latent_shape = (batch_size, self.n_keyframes, self.latent_dim)
        if z is not None and tuple(z.shape) != latent_shape:
            raise ValueError(f"z must have shape {latent_shape}, got {tuple(z.shape)}")

        _, state = self.cond_lstm(cond_emb)  # Init_key = Final_cond: (h, c), each (layers, B, hidden)
        previous_key = cond_emb[:, -1]  # K^{e,0}: (B, E)
        if mode == "posterior":
            keys, values, mask, boundary_scores = self.infer(future_emb, lengths)  # (B, N, ·), (B, N)
            inv_temperature = self.attention_inv_temperature if self.attn_scale else 1.0
        else:
            boundary_scores = None  # no future frames to score
            prior_z = z
            if prior_z is None:
                prior_z = cond_emb.new_zeros(latent_shape)
                if sample:
                    prior_z = torch.randn_like(prior_z)

        key_embs, hidden_outputs, mus, log_sigmas, latents, attentions = [], [], [], [], [], []
        for t in range(self.n_keyframes):
            if mode == "posterior":
                mu, log_sigma, weights = attention_posterior(
                    previous_key, keys, values, mask, inv_temperature, self.attn_scale
                )  # (B, Zk), (B, Zk), (B, N)
                latent = mu + log_sigma.exp() * torch.randn_like(mu) if sample else mu
                attentions.append(weights)
            else:
                latent = prior_z[:, t]  # (B, Zk)
                mu = log_sigma = torch.zeros_like(latent)
            hidden_output, state = self.key_lstm.step(torch.cat([latent, previous_key], dim=-1), state)
            previous_key = torch.tanh(self.key_head(hidden_output))  # K̂^{e,t}: (B, E)
            key_embs.append(previous_key)
            hidden_outputs.append(hidden_output)
            mus.append(mu)
            log_sigmas.append(log_sigma)
            latents.append(latent)

        offset_logits = self.offset_head(torch.stack(hidden_outputs, dim=1))  # (B, M, S)
        if boundary_scores is not None:
            offset_logits = self._add_boundary_evidence(offset_logits, boundary_scores, mask, chain)
        return KeyframeOutput(
            key_emb=torch.stack(key_embs, dim=1),  # (B, M, E)
            offset_probs=torch.softmax(offset_logits, dim=-1),  # (B, M, S)
            offset_logits=offset_logits,
            mu=torch.stack(mus, dim=1),  # (B, M, Zk)
            log_sigma=torch.stack(log_sigmas, dim=1),
            z=torch.stack(latents, dim=1),
            attention=torch.stack(attentions, dim=1) if attentions else None,  # (B, M, N)
            boundary_scores=boundary_scores,  # (B, N) or None
        )

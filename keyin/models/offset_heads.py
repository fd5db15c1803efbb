"""Where keyframe offsets come from: the one place KEYIN, Static and Jumpy differ (paper §3.1, §4 "Baselines").

Each head maps LSTM_key's outputs (B, M, hidden) to offset logits (B, M, S) over offsets 1…S:
KEYIN predicts them per keyframe, Static learns one pattern shared by every clip, Jumpy fixes one
offset. Only the predicted head reads its input; every head builds only its own parameters (unused
ones would get no gradient and break DDP).
"""

import torch
from torch import Tensor, nn

OFFSET_MODES = ("predicted", "static", "fixed")
# Logit of the impossible offsets in "fixed" mode: softmax gives an exact one-hot, and unlike −∞ it
# keeps log-softmax and entropy (0 · log 0) finite.
FIXED_OFFSET_OFF_LOGIT = -1.0e4


class PredictedOffsets(nn.Linear):
    """KEYIN: the offset logits of keyframe t are a linear map of LSTM_key's output at t."""

    def __init__(self, hidden: int, max_offset: int) -> None:
        super().__init__(hidden, max_offset)


class StaticOffsets(nn.Module):
    """Static: learned logits (M, S), the same for every clip."""

    def __init__(self, n_keyframes: int, max_offset: int) -> None:
        super().__init__()
        self.logits = nn.Parameter(torch.zeros(n_keyframes, max_offset))

    def forward(self, hidden_outputs: Tensor) -> Tensor:
        return self.logits.expand(hidden_outputs.shape[0], -1, -1)


class FixedOffsets(nn.Module):
    """Jumpy: every keyframe at ``offset`` (1…S) after the previous one (a one-hot, no parameters)."""

    def __init__(self, n_keyframes: int, max_offset: int, offset: int) -> None:
        super().__init__()
        if not 1 <= offset <= max_offset:
            raise ValueError(f"fixed_offset must be in 1..max_offset={max_offset}, got {offset}")
        self.n_keyframes, self.max_offset, self.offset = n_keyframes, max_offset, offset

    def forward(self, hidden_outputs: Tensor) -> Tensor:
        logits = hidden_outputs.new_full((self.max_offset,), FIXED_OFFSET_OFF_LOGIT)  # (S,)
        logits[self.offset - 1] = 0.0
        return logits.expand(hidden_outputs.shape[0], self.n_keyframes, -1)


def offset_head(mode: str, hidden: int, n_keyframes: int, max_offset: int, fixed_offset: int | None) -> nn.Module:
    """The head of ``mode`` (:data:`OFFSET_MODES`); ``fixed_offset`` is required by "fixed" and only
    allowed with it."""
    if mode not in OFFSET_MODES:
        raise ValueError(f"offset_mode must be one of {OFFSET_MODES}, got {mode!r}")
    if (mode == "fixed") != (fixed_offset is not None):
        raise ValueError("fixed_offset is required by offset_mode='fixed' and only allowed with it")
    if mode == "predicted":
        return PredictedOffsets(hidden, max_offset)
    if mode == "static":
        return StaticOffsets(n_keyframes, max_offset)
    return FixedOffsets(n_keyframes, max_offset, fixed_offset)

"""The Jumpy and Static baselines: where their offsets come from, and what the soft loss becomes."""

import torch
import torch.nn.functional as F

from keyin.losses.soft_keyframe import keyin_loss
from keyin.models import KeyframePredictor
from keyin.models.distributions import gaussian_kl
from keyin.models.positions import argmax_frames

E, M, S, N, Z, D = 8, 6, 10, 30, 4, 12


def predictor(offset_mode: str, fixed_offset: int | None = None) -> KeyframePredictor:
    torch.manual_seed(0)
    return KeyframePredictor(E, M, S, Z, hidden=16, layers=1, offset_mode=offset_mode, fixed_offset=fixed_offset)


def test_jumpy_soft_loss_equals_hard_indexing():
    c, batch = 6, 3
    model = predictor("fixed", fixed_offset=c)
    cond, future_emb = torch.randn(batch, 2, E), torch.rand(batch, N, E) * 2 - 1
    out = model(cond, future_emb)
    assert torch.equal(out.offset_probs, F.one_hot(torch.full((batch, M), c - 1), S).float())
    inter = torch.rand(batch, M, S, D) * 0.98 + 0.01
    frames = torch.rand(batch, N, D)
    terms = keyin_loss(
        offset_probs=out.offset_probs, key_emb_pred=out.key_emb, future_emb=future_emb,
        inter_frames_pred=inter, future_frames=frames, kl_per_key=gaussian_kl(out.mu, out.log_sigma),
        lengths=torch.full((batch,), N), beta_ke=1.0, beta_ki=0.0, beta_kl=0.05,
    )
    # Hard indexing: frame j is output j mod c of segment j div c; keyframe t sits at t·c - 1.
    hard_frames = torch.stack([inter[:, j // c, j % c] for j in range(N)], dim=1)
    torch.testing.assert_close(terms["soft_frames"], hard_frames)
    torch.testing.assert_close(argmax_frames(out.offset_probs, inter, N), hard_frames)
    hard_inter = F.binary_cross_entropy(hard_frames, frames, reduction="sum") / batch
    torch.testing.assert_close(terms["inter"], hard_inter)
    inside = N // c  # keyframes 1…5 inside the clip, the 6th beyond it
    assert terms["c"].tolist() == [[1.0] * inside + [0.0] * (M - inside)] * batch
    targets = future_emb[:, c - 1 :: c]  # (B, 5, E)
    hard_key_emb = ((out.key_emb[:, :inside] - targets) ** 2).sum(-1).mean(-1).mean()
    torch.testing.assert_close(terms["key_emb"], hard_key_emb)


def test_static_offsets_are_the_same_for_every_input_and_trainable():
    model = predictor("static")
    with torch.no_grad():
        model.offset_head.logits.normal_()
    first = model(torch.randn(4, 2, E), torch.randn(4, N, E))
    second = model(torch.randn(4, 2, E), torch.randn(4, N, E), mode="posterior")
    prior = model(torch.randn(4, 2, E), mode="prior")
    for out in (first, second, prior):
        assert torch.equal(out.offset_probs, first.offset_probs[:1].expand_as(out.offset_probs))
    assert not torch.equal(first.offset_probs[0, 0], first.offset_probs[0, 1])  # one row per keyframe
    first.offset_probs.sum().backward()
    names = {name for name, p in model.named_parameters() if p.grad is not None}
    assert names >= {"offset_head.logits"} and not any(name.startswith("offset_head.weight") for name in names)

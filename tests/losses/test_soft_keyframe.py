"""Soft keyframe loss (paper §3.2, Alg. 2) against a brute-force enumeration of all offset choices."""

import itertools
import math

import pytest
import torch
import torch.nn.functional as F

from keyin.losses.soft_keyframe import bce_sum, in_sequence_probs, keyin_loss
from keyin.models.positions import soft_keyframe_targets
from keyin.models.distributions import gaussian_kl
from keyin.models.positions import argmax_frames, argmax_positions, position_distributions, soft_frames

ATOL = 1e-10
BETAS = {"beta_ke": 1.0, "beta_ki": 0.7, "beta_kl": 0.05}


def assert_close(actual: torch.Tensor, expected: torch.Tensor, atol: float = 1e-12,
                 name: str = "") -> None:
    """Same shape and max |actual - expected| <= atol; NaN anywhere fails.

    (torch.testing.assert_close would do, but its first call imports torch.distributed.tensor,
    which takes ~10 s on a small machine.)
    """
    assert actual.shape == expected.shape, (name, actual.shape, expected.shape)
    max_diff = float((actual.detach() - expected.detach()).abs().max())
    assert max_diff <= atol, f"{name}: max abs diff {max_diff:.3e} > {atol:.1e}"


# --------------------------------------------------------------------------------------------
# Brute-force reference: enumerate every offset combination (o^1, ..., o^M) ∈ {1..S}^M.
# --------------------------------------------------------------------------------------------


def _bce_reference(prob: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Σ_d -[y log p + (1 - y) log(1 - p)] with p clamped to [1e-6, 1 - 1e-6]."""
    prob = prob.clamp(1e-6, 1 - 1e-6)
    return -(target * torch.log(prob) + (1 - target) * torch.log(1 - prob)).sum()


def enumerate_reference(inputs: dict, normalize: bool) -> dict:
    """Every quantity of the soft loss from the exact joint distribution of the offsets.

    Keyframe t of a combination sits at position p^t = -1 + Σ_{s<=t} o^s and output i of segment t
    at p^{t-1} + 1 + i (i < o^t). Everything is an explicit sum over combinations, weighted by
    Π_t δ^t[o^t - 1].
    """
    offset_probs = inputs["offset_probs"]
    n_batch, n_keys, max_offset = offset_probs.shape
    n_future = inputs["future_frames"].shape[1]
    n_ext = n_keys * max_offset + 1
    zero = offset_probs.new_zeros(())
    out = {name: [] for name in ("keyframe_pos", "frame_pos", "c", "emb_targets", "img_targets",
                                 "coverage", "mixed", "key", "key_emb", "key_img", "kl", "inter")}
    for b in range(n_batch):
        n_valid = int(inputs["lengths"][b])
        keyframe_pos = [[zero] * n_ext for _ in range(n_keys)]
        frame_pos = [[[zero] * n_ext for _ in range(max_offset)] for _ in range(n_keys)]
        in_seq = [zero] * n_keys
        emb_sum = [torch.zeros_like(inputs["future_emb"][b, 0])] * n_keys
        img_sum = [torch.zeros_like(inputs["future_frames"][b, 0])] * n_keys
        coverage = [zero] * n_future
        mixed_sum = [torch.zeros_like(inputs["future_frames"][b, 0])] * n_future
        for offsets in itertools.product(range(1, max_offset + 1), repeat=n_keys):
            prob = math.prod(offset_probs[b, t, o - 1] for t, o in enumerate(offsets))
            position = -1
            for t, offset in enumerate(offsets):
                for i in range(offset):
                    frame_position = position + 1 + i
                    frame_pos[t][i][frame_position + 1] = frame_pos[t][i][frame_position + 1] + prob
                    if frame_position < n_future:
                        coverage[frame_position] = coverage[frame_position] + prob
                        mixed_sum[frame_position] = (
                            mixed_sum[frame_position] + prob * inputs["inter_frames_pred"][b, t, i]
                        )
                position += offset
                keyframe_pos[t][position + 1] = keyframe_pos[t][position + 1] + prob
                if position < n_valid:
                    in_seq[t] = in_seq[t] + prob
                    emb_sum[t] = emb_sum[t] + prob * inputs["future_emb"][b, position]
                    img_sum[t] = img_sum[t] + prob * inputs["future_frames"][b, position]
        if normalize:
            emb_targets = [emb_sum[t] / max(in_seq[t], 1e-6) for t in range(n_keys)]
            img_targets = [img_sum[t] / max(in_seq[t], 1e-6) for t in range(n_keys)]
        else:
            emb_targets, img_targets = emb_sum, img_sum
        mixed = [mixed_sum[j] / coverage[j] for j in range(n_future)]

        key_weight_sum = max(sum(in_seq), 1e-6)
        key_emb = sum(in_seq[t] * ((inputs["key_emb_pred"][b, t] - emb_targets[t]) ** 2).sum()
                      for t in range(n_keys)) / key_weight_sum
        key_img = sum(in_seq[t] * _bce_reference(inputs["key_frames_pred"][b, t], img_targets[t])
                      for t in range(n_keys)) / key_weight_sum
        kl = sum(in_seq[t] * inputs["kl_per_key"][b, t] for t in range(n_keys)) / key_weight_sum
        inter = sum((_bce_reference(mixed[j], inputs["future_frames"][b, j])
                     for j in range(n_valid)), start=zero)

        out["keyframe_pos"].append(torch.stack([torch.stack(row) for row in keyframe_pos]))
        out["frame_pos"].append(torch.stack([torch.stack([torch.stack(r) for r in seg])
                                             for seg in frame_pos]))
        out["c"].append(torch.stack(in_seq))
        out["emb_targets"].append(torch.stack(emb_targets))
        out["img_targets"].append(torch.stack(img_targets))
        out["coverage"].append(torch.stack(coverage))
        out["mixed"].append(torch.stack(mixed))
        out["key_emb"].append(key_emb)
        out["key_img"].append(key_img)
        out["kl"].append(kl)
        out["inter"].append(inter)
        out["key"].append(BETAS["beta_ke"] * key_emb + BETAS["beta_ki"] * key_img
                          + BETAS["beta_kl"] * kl)
    out = {name: torch.stack(values) for name, values in out.items()}
    for name in ("key", "key_emb", "key_img", "kl", "inter"):
        out[name] = out[name].mean()
    out["loss"] = out["key"] + out["inter"]
    return out


def vectorised(inputs: dict, normalize: bool) -> dict:
    """The same quantities from the functions under test."""
    keyframe_pos, frame_pos = position_distributions(inputs["offset_probs"])
    n_future = inputs["future_frames"].shape[1]
    mixed, coverage = soft_frames(frame_pos, inputs["inter_frames_pred"], n_future)
    loss = keyin_loss(
        **{k: v for k, v in inputs.items() if k != "offset_logits"},
        **BETAS,
        normalize_key_targets=normalize,
    )
    return {
        "keyframe_pos": keyframe_pos,
        "frame_pos": frame_pos,
        "c": in_sequence_probs(keyframe_pos, inputs["lengths"]),
        "emb_targets": soft_keyframe_targets(keyframe_pos, inputs["lengths"],
                                             inputs["future_emb"], normalize),
        "img_targets": soft_keyframe_targets(keyframe_pos, inputs["lengths"],
                                             inputs["future_frames"], normalize),
        "coverage": coverage,
        "mixed": mixed,
        **{name: loss[name] for name in ("loss", "key", "key_emb", "key_img", "kl", "inter")},
        "loss_c": loss["c"],
        "loss_coverage": loss["coverage"],
        "loss_soft_frames": loss["soft_frames"],
    }


def make_inputs(seed: int, n_keys: int, max_offset: int, n_future: int, lengths: list[int],
                n_emb: int = 3, n_pixels: int = 4, dtype=torch.float64,
                offset_logits: torch.Tensor | None = None) -> dict:
    """Random leaf tensors; probabilities kept inside (0.02, 0.98) so no clamp is active."""
    gen = torch.Generator().manual_seed(seed)
    n_batch = len(lengths)

    def rand(*shape):
        return torch.rand(*shape, generator=gen, dtype=dtype)

    def randn(*shape):
        return torch.randn(*shape, generator=gen, dtype=dtype)

    if offset_logits is None:
        offset_logits = randn(n_batch, n_keys, max_offset)
    offset_logits = offset_logits.clone().requires_grad_()
    leaves = {
        "offset_logits": offset_logits,
        "key_emb_pred": randn(n_batch, n_keys, n_emb),
        "future_emb": randn(n_batch, n_future, n_emb),
        "inter_frames_pred": 0.02 + 0.96 * rand(n_batch, n_keys, max_offset, n_pixels),
        "future_frames": rand(n_batch, n_future, n_pixels),
        "kl_per_key": rand(n_batch, n_keys) * 3,
        "key_frames_pred": 0.02 + 0.96 * rand(n_batch, n_keys, n_pixels),
    }
    for tensor in leaves.values():
        tensor.requires_grad_()
    return {
        **leaves,
        "offset_probs": torch.softmax(offset_logits, dim=-1),
        "lengths": torch.tensor(lengths),
    }


BRUTE_FORCE_CASES = [
    # (M, S, N, lengths)
    (3, 4, 7, [7, 7, 7]),
    (3, 4, 7, [7, 3, 5]),  # variable length, one clip shorter than S (c^1 < 1)
    (2, 3, 6, [6, 1, 4]),  # M*S == N exactly
]
LEAF_NAMES = ("offset_logits", "key_emb_pred", "future_emb", "inter_frames_pred", "future_frames",
              "kl_per_key", "key_frames_pred")


@pytest.mark.parametrize("normalize", [True, False])
@pytest.mark.parametrize("n_keys,max_offset,n_future,lengths", BRUTE_FORCE_CASES)
def test_every_quantity_matches_enumeration(n_keys, max_offset, n_future, lengths, normalize):
    inputs = make_inputs(0, n_keys, max_offset, n_future, lengths)
    expected = enumerate_reference(inputs, normalize)
    actual = vectorised(inputs, normalize)
    for name, value in expected.items():
        assert_close(actual[name], value, atol=ATOL, name=name)
    assert_close(actual["loss_c"], expected["c"], atol=ATOL)
    assert_close(actual["loss_coverage"], expected["coverage"], atol=ATOL)
    assert_close(actual["loss_soft_frames"], expected["mixed"], atol=ATOL)
    # The case must exercise what it claims: soft (not one-hot) positions and a non-trivial c.
    c = expected["c"].detach()
    assert ((c > 0.01) & (c < 0.99)).any()


@pytest.mark.parametrize(
    "n_keys,max_offset,n_future,lengths,normalize",
    [(*BRUTE_FORCE_CASES[1], True), (*BRUTE_FORCE_CASES[2], False)],
)
def test_gradients_match_enumeration(n_keys, max_offset, n_future, lengths, normalize):
    inputs = make_inputs(1, n_keys, max_offset, n_future, lengths)
    expected = enumerate_reference(inputs, normalize)
    actual = vectorised(inputs, normalize)
    gen = torch.Generator().manual_seed(2)
    # One random linear functional of every quantity, so each one's gradient is compared.
    projections = {name: torch.randn(value.shape, generator=gen, dtype=value.dtype)
                   for name, value in expected.items()}
    leaves = [inputs[name] for name in LEAF_NAMES]

    def grads(values):
        scalar = sum((projections[name] * values[name]).sum() for name in projections)
        return torch.autograd.grad(scalar, leaves, retain_graph=True)

    for name, grad_expected, grad_actual in zip(LEAF_NAMES, grads(expected), grads(actual)):
        assert grad_expected.abs().max() > 0, name
        assert_close(grad_actual, grad_expected, atol=ATOL, name=name)

    # And the loss alone, w.r.t. every input.
    loss_grads_expected = torch.autograd.grad(expected["loss"], leaves, retain_graph=True)
    loss_grads_actual = torch.autograd.grad(actual["loss"], leaves)
    for name, grad_expected, grad_actual in zip(LEAF_NAMES, loss_grads_expected, loss_grads_actual):
        assert_close(grad_actual, grad_expected, atol=ATOL, name=name)


def test_gradcheck_keyin_loss():
    # Tiny on purpose: full-mode gradcheck costs two forward calls per input element.
    inputs = make_inputs(3, n_keys=2, max_offset=3, n_future=4, lengths=[4, 2], n_emb=2,
                         n_pixels=1)
    leaves = tuple(inputs[name].detach().requires_grad_() for name in LEAF_NAMES)

    def loss_fn(offset_logits, key_emb_pred, future_emb, inter_frames_pred, future_frames,
                kl_per_key, key_frames_pred):
        return keyin_loss(
            torch.softmax(offset_logits, -1), key_emb_pred, future_emb, inter_frames_pred,
            future_frames, kl_per_key, inputs["lengths"], **BETAS,
            key_frames_pred=key_frames_pred,
        )["loss"]

    assert torch.autograd.gradcheck(loss_fn, leaves, eps=1e-6, atol=1e-7)


# --------------------------------------------------------------------------------------------
# Invariants (docs/architecture.md, "Index conventions") at the Brownian sizes M=6, S=10, N=30.
# --------------------------------------------------------------------------------------------


def _random_offsets(seed: int, n_batch: int = 4, n_keys: int = 6, max_offset: int = 10):
    gen = torch.Generator().manual_seed(seed)
    logits = 2 * torch.randn(n_batch, n_keys, max_offset, generator=gen, dtype=torch.float64)
    return torch.softmax(logits, -1)


def test_keyframe_distributions_sum_to_one():
    keyframe_pos, frame_pos = position_distributions(_random_offsets(4))
    assert keyframe_pos.shape == (4, 6, 61) and frame_pos.shape == (4, 6, 10, 61)
    assert_close(keyframe_pos.sum(-1), torch.ones(4, 6, dtype=torch.float64))
    # Keyframe t can only sit at positions t-1 ... t*S-1 (extended t ... t*S).
    for t in range(1, 7):
        assert keyframe_pos[:, t - 1, :t].abs().max() == 0
        assert keyframe_pos[:, t - 1, t * 10 + 1:].abs().sum() == 0


def test_in_sequence_probs_first_is_one_and_non_increasing():
    keyframe_pos, _ = position_distributions(_random_offsets(5))
    full = in_sequence_probs(keyframe_pos, torch.full((4,), 30))
    assert_close(full[:, 0], torch.ones(4, dtype=torch.float64))
    assert float(full[:, -1].max()) < 1.0  # P(p^6 <= 29) < 1 for soft offsets
    variable = in_sequence_probs(keyframe_pos, torch.tensor([30, 17, 5, 1]))
    for c in (full, variable):
        assert (c[:, 1:] <= c[:, :-1] + 1e-12).all()
    assert (variable <= full + 1e-12).all() and float((full - variable).max()) > 0.1


def test_coverage_is_survival_function_of_last_keyframe():
    keyframe_pos, frame_pos = position_distributions(_random_offsets(6))
    _, coverage = soft_frames(frame_pos, torch.zeros(4, 6, 10, 1, dtype=torch.float64), 30)
    # cov_j = P(p^M >= j) = 1 - P(p^M <= j - 1) = 1 - Σ_{k <= j} D^M[k] (extended k = position+1).
    survival = 1 - keyframe_pos[:, -1].cumsum(-1)[:, :30]
    assert_close(coverage, survival)
    # Over all extended indices k >= 1 as well, and it never exceeds 1.
    all_coverage = frame_pos.sum((1, 2))[:, 1:]
    assert_close(all_coverage, 1 - keyframe_pos[:, -1].cumsum(-1)[:, :-1])
    assert float(all_coverage.max()) <= 1 + 1e-12 and float(coverage[:, -1].min()) < 1


def _one_hot_offsets(offsets: list[list[int]], max_offset: int) -> torch.Tensor:
    return F.one_hot(torch.tensor(offsets) - 1, max_offset).to(torch.float64)


def test_one_hot_offsets_7_6_8_7_6_7():
    offsets = [7, 6, 8, 7, 6, 7]
    offset_probs = _one_hot_offsets([offsets], 10)
    keyframe_pos, frame_pos = position_distributions(offset_probs)
    assert argmax_positions(offset_probs).tolist() == [[6, 12, 20, 27, 33, 40]]
    assert (keyframe_pos[0].argmax(-1) - 1).tolist() == [6, 12, 20, 27, 33, 40]
    assert torch.equal(keyframe_pos[0].max(-1).values, torch.ones(6, dtype=torch.float64))
    c = in_sequence_probs(keyframe_pos, torch.tensor([30]))
    assert c.tolist() == [[1.0, 1.0, 1.0, 1.0, 0.0, 0.0]]

    # Frame j (extended j+1) is sourced from exactly one (t, i), with weight 1.
    weights = frame_pos[0, :, :, 1:31]  # (M, S, N)
    assert torch.equal(weights.sum((0, 1)), torch.ones(30, dtype=torch.float64))
    assert set(weights.unique().tolist()) == {0.0, 1.0}
    sources = []
    for j in range(30):
        (t, i), = torch.nonzero(weights[:, :, j]).tolist()
        sources.append((t + 1, i))
    assert sources[:7] == [(1, i) for i in range(7)]
    assert sources[7:13] == [(2, i) for i in range(6)]
    assert sources[13:21] == [(3, i) for i in range(8)]
    assert sources[21:28] == [(4, i) for i in range(7)]
    assert sources[28:30] == [(5, 0), (5, 1)]
    # Outputs past each segment's offset have no weight anywhere.
    for t, offset in enumerate(offsets):
        assert frame_pos[0, t, offset:].abs().max() == 0


def test_one_hot_offsets_reduce_to_hard_indexing():
    gen = torch.Generator().manual_seed(7)
    offsets = [[7, 6, 8, 7, 6, 7], [10, 10, 1, 3, 2, 9], [1, 1, 1, 10, 10, 10]]
    lengths = torch.tensor([30, 25, 30])
    n_batch, n_keys, max_offset, n_future, n_emb, n_pixels = 3, 6, 10, 30, 5, 8
    inputs = {
        "offset_probs": _one_hot_offsets(offsets, max_offset),
        "key_emb_pred": torch.randn(n_batch, n_keys, n_emb, generator=gen, dtype=torch.float64),
        "future_emb": torch.randn(n_batch, n_future, n_emb, generator=gen, dtype=torch.float64),
        "inter_frames_pred": 0.02 + 0.96 * torch.rand(n_batch, n_keys, max_offset, n_pixels,
                                                      generator=gen, dtype=torch.float64),
        "future_frames": torch.rand(n_batch, n_future, n_pixels, generator=gen,
                                    dtype=torch.float64),
        "kl_per_key": torch.rand(n_batch, n_keys, generator=gen, dtype=torch.float64),
        "key_frames_pred": 0.02 + 0.96 * torch.rand(n_batch, n_keys, n_pixels, generator=gen,
                                                    dtype=torch.float64),
        "lengths": lengths,
    }
    result = keyin_loss(**inputs, **BETAS)

    losses = []
    for b in range(n_batch):
        n_valid = int(lengths[b])
        positions = [sum(offsets[b][:t + 1]) - 1 for t in range(n_keys)]
        inside = [t for t in range(n_keys) if positions[t] < n_valid]
        key = sum(
            BETAS["beta_ke"] * ((inputs["key_emb_pred"][b, t]
                                 - inputs["future_emb"][b, positions[t]]) ** 2).sum()
            + BETAS["beta_ki"] * _bce_reference(inputs["key_frames_pred"][b, t],
                                                inputs["future_frames"][b, positions[t]])
            + BETAS["beta_kl"] * inputs["kl_per_key"][b, t]
            for t in inside
        ) / len(inside)
        # Hard sequence: concat_t Î^t_{0:o^t} (paper §3.1), truncated to the clip.
        sequence = torch.cat([inputs["inter_frames_pred"][b, t, :offsets[b][t]]
                              for t in range(n_keys)])
        assert sequence.shape[0] >= n_future
        assert_close(result["soft_frames"][b], sequence[:n_future], atol=1e-15)
        inter = sum(_bce_reference(sequence[j], inputs["future_frames"][b, j])
                    for j in range(n_valid))
        losses.append(key + inter)
    assert_close(result["loss"], torch.stack(losses).mean(), atol=1e-10)


# --------------------------------------------------------------------------------------------
# Padding, mixed precision, degenerate coverage.
# --------------------------------------------------------------------------------------------


def test_padded_frames_never_influence_the_loss():
    lengths = [7, 3, 5]
    inputs = make_inputs(8, 3, 4, 7, lengths)
    padded = ~(torch.arange(7) < torch.tensor(lengths)[:, None])  # (B, N) True past n_b

    def loss_and_grads(future_frames, future_emb):
        future_frames = future_frames.detach().clone().requires_grad_()
        future_emb = future_emb.detach().clone().requires_grad_()
        args = {k: v for k, v in inputs.items() if k != "offset_logits"}
        args.update(future_frames=future_frames, future_emb=future_emb)
        loss = keyin_loss(**args, **BETAS)["loss"]
        leaves = [args.get(name, inputs[name]) for name in LEAF_NAMES]
        return loss, dict(zip(LEAF_NAMES, torch.autograd.grad(loss, leaves, retain_graph=True)))

    base_loss, base_grads = loss_and_grads(inputs["future_frames"], inputs["future_emb"])
    future_frames = inputs["future_frames"].detach().clone()
    future_emb = inputs["future_emb"].detach().clone()
    future_frames[padded] = float("nan")
    future_emb[padded] = 1e6
    changed_loss, changed_grads = loss_and_grads(future_frames, future_emb)

    assert torch.equal(changed_loss, base_loss)
    for name in LEAF_NAMES:  # every input's gradient is unchanged, and finite
        assert torch.equal(changed_grads[name], base_grads[name]), name
    for name in ("future_frames", "future_emb"):
        assert changed_grads[name][padded].abs().max() == 0, name
        assert changed_grads[name][~padded].abs().max() > 0, name
    assert changed_grads["future_frames"][~padded].abs().min() > 0


def test_float32_outside_autocast():
    inputs = make_inputs(9, 6, 10, 30, [30, 21], n_emb=16, n_pixels=64, dtype=torch.float32)
    args = {k: v for k, v in inputs.items() if k != "offset_logits"}
    plain = keyin_loss(**args, **BETAS)
    _, frame_pos = position_distributions(args["offset_probs"].detach())
    with torch.no_grad():
        plain_mixed, _ = soft_frames(frame_pos, args["inter_frames_pred"], 30)
    with torch.autocast("cpu", dtype=torch.bfloat16):
        # Sanity: autocast is active here and would change the mixing if keyin_loss let it.
        assert torch.bmm(frame_pos[:, 0], frame_pos[:, 0].transpose(1, 2)).dtype == torch.bfloat16
        with torch.no_grad():
            bare_mixed, _ = soft_frames(frame_pos, args["inter_frames_pred"], 30)
        assert float((bare_mixed - plain_mixed).abs().max()) > 1e-4
        under_autocast = keyin_loss(**args, **BETAS)
    assert under_autocast["loss"].dtype == torch.float32
    assert under_autocast["soft_frames"].dtype == torch.float32
    assert_close(under_autocast["loss"], plain["loss"], atol=1e-6 * float(plain["loss"].detach()))
    assert_close(under_autocast["soft_frames"], plain["soft_frames"], atol=1e-7)
    # Low-precision inputs (as a model under autocast emits them) are upcast before any math.
    low_precision = {k: (v.to(torch.bfloat16) if v.is_floating_point() else v)
                     for k, v in args.items()}
    result = keyin_loss(**low_precision, **BETAS)
    assert result["loss"].dtype == torch.float32 and result["c"].dtype == torch.float32


def test_no_nan_when_coverage_is_zero():
    # Offsets all 1 (exactly) and nearly 1 (peaked logits): positions >= 3 are (almost) unreached.
    n_keys, max_offset, n_future = 3, 4, 7
    exact_logits = torch.full((2, n_keys, max_offset), -torch.inf, dtype=torch.float64)
    exact_logits[..., 0] = 0.0
    peaked_logits = torch.zeros(2, n_keys, max_offset, dtype=torch.float64)
    peaked_logits[..., 0] = 40.0
    for logits in (exact_logits, peaked_logits):
        inputs = make_inputs(10, n_keys, max_offset, n_future, [7, 5], offset_logits=logits)
        result = keyin_loss(**{k: v for k, v in inputs.items() if k != "offset_logits"}, **BETAS)
        assert float(result["coverage"][:, 3:].detach().max()) < 1e-15
        assert torch.isfinite(result["soft_frames"]).all() and torch.isfinite(result["loss"])
        leaves = [inputs[name] for name in LEAF_NAMES[1:]] + [inputs["offset_probs"]]
        for grad in torch.autograd.grad(result["loss"], leaves):
            assert torch.isfinite(grad).all()
        if torch.isinf(logits).any():
            assert result["coverage"][:, 3:].abs().max() == 0
            assert result["soft_frames"][:, 3:].abs().max() == 0


def test_loss_gradient_wrt_offset_logits_is_finite_and_nonzero():
    inputs = make_inputs(11, 6, 10, 30, [30, 30, 18], n_emb=8, n_pixels=16, dtype=torch.float32)
    result = keyin_loss(**{k: v for k, v in inputs.items() if k != "offset_logits"}, **BETAS)
    grad, = torch.autograd.grad(result["loss"], inputs["offset_logits"])
    assert torch.isfinite(grad).all()
    assert (grad.abs().amax(-1) > 0).all()  # every keyframe's offset distribution gets a signal


# --------------------------------------------------------------------------------------------
# Small helpers, hand-worked values and input validation.
# --------------------------------------------------------------------------------------------


def test_argmax_positions_hand_worked():
    offset_probs = torch.tensor([[[0.1, 0.7, 0.2], [0.6, 0.3, 0.1], [0.2, 0.2, 0.6]]])
    assert argmax_positions(offset_probs).tolist() == [[1, 2, 5]]


def test_gaussian_kl():
    mu = torch.tensor([[0.0, 0.0], [1.0, -2.0]], dtype=torch.float64)
    log_sigma = torch.tensor([[0.0, 0.0], [0.5, -0.3]], dtype=torch.float64)
    kl = gaussian_kl(mu, log_sigma)
    assert kl.shape == (2,) and kl[0] == 0
    by_hand = sum(-ls + (math.exp(2 * ls) + m**2) / 2 - 0.5 for m, ls in [(1.0, 0.5), (-2.0, -0.3)])
    assert_close(kl[1], torch.tensor(by_hand, dtype=torch.float64))
    library = torch.distributions.kl_divergence(
        torch.distributions.Normal(mu, log_sigma.exp()), torch.distributions.Normal(0.0, 1.0)
    ).sum(-1)
    assert_close(kl, library)


def test_bce_sum_values_mask_and_clamp():
    probs = torch.tensor([[[0.2, 0.9], [0.5, 0.5], [0.0, 1.0]]], dtype=torch.float64)
    targets = torch.tensor([[[0.0, 1.0], [0.3, 0.6], [1.0, 0.0]]], dtype=torch.float64)
    per_frame = bce_sum(probs, targets)
    assert per_frame.shape == (1, 3)
    by_hand = torch.tensor(-math.log(0.8) - math.log(0.9), dtype=torch.float64)
    assert_close(per_frame[0, 0], by_hand)
    assert_close(per_frame[0, 1], torch.tensor(2 * math.log(2), dtype=torch.float64))
    # Clamped to [1e-6, 1 - 1e-6]: a confident wrong pixel costs -log(1e-6), not inf.
    clamped = torch.tensor(-2 * math.log(1e-6), dtype=torch.float64)
    assert_close(per_frame[0, 2], clamped, atol=1e-8)
    mask = torch.tensor([[True, False, True]])
    targets_nan = targets.clone()
    targets_nan[0, 1] = float("nan")
    masked = bce_sum(probs, targets_nan, mask)
    assert masked[0, 1] == 0
    assert_close(masked[0, [0, 2]], per_frame[0, [0, 2]])


def test_too_few_positions_raise():
    _, frame_pos = position_distributions(_random_offsets(12, n_keys=2, max_offset=3))
    with pytest.raises(ValueError, match="M\\*S"):
        soft_frames(frame_pos, torch.zeros(4, 2, 3, 1, dtype=torch.float64), 7)


def test_key_image_term_needs_decoded_keyframes():
    inputs = make_inputs(13, 3, 4, 7, [7, 7])
    args = {k: v for k, v in inputs.items() if k not in ("offset_logits", "key_frames_pred")}
    with pytest.raises(ValueError, match="key_frames_pred"):
        keyin_loss(**args, **BETAS)
    result = keyin_loss(**args, beta_ke=1.0, beta_ki=0.0, beta_kl=0.05)
    assert "key_img" not in result
    assert_close(result["key"], result["key_emb"] + 0.05 * result["kl"])


def test_argmax_frames_take_each_position_from_the_segment_that_covers_it():
    torch.manual_seed(0)
    offsets = torch.tensor([[2, 3, 1], [1, 1, 1]])  # positions 1, 4, 5 and 0, 1, 2
    probs = F.one_hot(offsets - 1, 4).float() * 0.7 + 0.1  # argmax = the offsets, not one-hot
    predicted = torch.rand(2, 3, 4, 5)
    frames = argmax_frames(probs, predicted, n_future=6)
    for b, row in enumerate(offsets.tolist()):
        position = -1
        for t, offset in enumerate(row):
            for i in range(offset):
                if position + 1 + i < 6:
                    torch.testing.assert_close(frames[b, position + 1 + i], predicted[b, t, i])
            position += offset
        assert frames[b, position + 1 :].abs().sum() == 0  # nothing past the last keyframe

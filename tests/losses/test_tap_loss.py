"""TAP's minimum-over-time loss (paper §4.2; docs/architecture.md, "Baselines") on hand-made clips: the frame it picks, the frames it
may never pick, its gradient and the training pairs it is given."""

import pytest
import torch
import torch.nn.functional as F

from keyin.losses.tap import (
    admissible_frames,
    argmin_times,
    frame_bce,
    min_over_time_bce,
    sample_pairs,
    shortest_gap,
    whole_clip_pairs,
)

LENGTH = 10


def clip(seed: int = 0) -> torch.Tensor:
    """(1, L, 1, 4, 4) binary frames, all different."""
    generator = torch.Generator().manual_seed(seed)
    return (torch.rand(1, LENGTH, 1, 4, 4, generator=generator, dtype=torch.float64) > 0.5).double()


def sure_logits(frame: torch.Tensor) -> torch.Tensor:
    """Logits that predict a binary frame with probability 1 - 1e-9 per pixel."""
    return (2 * frame - 1) * 20.0


def mask(start: int, goal: int, n_valid: int = LENGTH, margin: int = 1) -> torch.Tensor:
    return admissible_frames(torch.tensor([start]), torch.tensor([goal]), torch.tensor([n_valid]), LENGTH, margin)


def admitted(start: int, goal: int, n_valid: int = LENGTH, margin: int = 1) -> list[int]:
    return torch.nonzero(mask(start, goal, n_valid, margin)[0]).flatten().tolist()


def test_the_end_margin_excludes_frames_next_to_start_and_goal():
    assert admitted(0, 9, margin=0) == list(range(1, 9))
    assert admitted(0, 9, margin=1) == list(range(2, 8))
    assert admitted(2, 9, margin=2) == [5, 6]
    assert admitted(2, 6, margin=1) == [4]  # b - a = shortest_gap(1): one frame left
    assert shortest_gap(1) == 4 and admitted(2, 5, margin=1) == []


def test_padding_is_never_admissible_even_before_the_goal():
    assert admitted(0, 9, n_valid=6, margin=1) == [2, 3, 4, 5]


def test_a_prediction_of_frame_3_has_zero_loss_at_frame_3():
    frames = clip()
    loss, argmin = min_over_time_bce(sure_logits(frames[:, 3]), frames, mask(0, 9))
    assert argmin.tolist() == [3]
    assert 0 <= float(loss) < 1e-6


@pytest.mark.parametrize("copied", [0, 1, 8, 9])  # the start, inside each margin, the goal
def test_an_exact_copy_of_an_inadmissible_frame_is_never_chosen(copied):
    frames = clip()
    loss, argmin = min_over_time_bce(sure_logits(frames[:, copied]), frames, mask(0, 9))
    assert 2 <= int(argmin) <= 7 and float(loss) > 1.0


def test_an_exact_copy_of_a_padding_frame_is_never_chosen():
    frames = clip()
    frames[:, 6:] = frames[:, 5:6]  # valid frames 0…5, then the last one repeated
    frames[:, 7:] = 1 - frames[:, 7:]  # padding that differs from every valid frame
    _, argmin = min_over_time_bce(sure_logits(frames[:, 8]), frames, mask(0, 9, n_valid=6))
    assert 2 <= int(argmin) <= 5


def test_the_loss_is_the_least_per_frame_bce_over_admissible_frames():
    frames = clip().repeat(3, 1, 1, 1, 1)
    logits = torch.randn(3, 1, 4, 4, dtype=torch.float64, generator=torch.Generator().manual_seed(1))
    start, goal, n_valid = torch.tensor([0, 1, 3]), torch.tensor([9, 6, 8]), torch.tensor([10, 10, 9])
    admissible = admissible_frames(start, goal, n_valid, LENGTH, margin=1)
    loss, argmin = min_over_time_bce(logits, frames, admissible)
    for b in range(3):
        per_frame = {
            t: float(F.binary_cross_entropy_with_logits(logits[b], frames[b, t], reduction="sum"))
            for t in range(LENGTH) if admissible[b, t]
        }
        best = min(per_frame, key=per_frame.get)
        assert int(argmin[b]) == best and float(loss[b]) == pytest.approx(per_frame[best], abs=1e-9)
    assert frame_bce(logits, frames).shape == (3, LENGTH)


def test_the_frame_is_chosen_by_the_plain_kl_and_scored_with_its_weights():
    """A perfect prediction of frame 6 picks frame 6 although frame 2 weighs fewer changed pixels and
    holds less entropy (the bias that made TAP copy its start, docs/baselines.md); brute force: the
    least plain BCE above each frame's entropy, and the chosen frame's weighted BCE as the loss."""
    generator = torch.Generator().manual_seed(4)
    frames = torch.full((1, LENGTH, 1, 4, 4), 0.5, dtype=torch.float64)
    frames[:, :, :, :, :2] = torch.rand(1, LENGTH, 1, 4, 2, generator=generator, dtype=torch.float64) * 0.6 + 0.2
    frames[:, 2, :, :, :2] = frames[:, 0, :, :, :2]  # frame 2: as the first frame, nothing changed
    weights = 1 + 19 * ((frames - frames[:, :1]).abs() > 0.1).double()  # changed pixels weigh 20 (losses/image.py)
    admissible = mask(0, 9)
    target = 6
    logits = torch.logit(frames[:, target])
    per_frame_weighted = frame_bce(logits, frames, weights)[0]
    assert per_frame_weighted[2] < per_frame_weighted[target]  # the weighted minimum: frame 2
    loss, argmin = min_over_time_bce(logits, frames, admissible, weights)
    excess = {t: float(F.binary_cross_entropy_with_logits(logits[0], frames[0, t], reduction="sum")
                       - F.binary_cross_entropy(frames[0, t], frames[0, t], reduction="sum"))
              for t in range(LENGTH) if admissible[0, t]}
    assert int(argmin) == target == min(excess, key=excess.get) and excess[target] == pytest.approx(0.0, abs=1e-9)
    assert float(loss) == pytest.approx(float(per_frame_weighted[target]))


def test_the_gradient_flows_through_the_chosen_frame_only():
    frames = clip()
    logits = (0.3 * sure_logits(frames[:, 4])).requires_grad_()
    loss, argmin = min_over_time_bce(logits, frames, mask(0, 9))
    loss.sum().backward()
    assert int(argmin) == 4
    expected = torch.sigmoid(logits.detach()) - frames[:, 4]  # d BCE / d logit against frame 4 alone
    assert torch.allclose(logits.grad, expected, atol=1e-12)


def test_a_clip_without_an_admissible_frame_is_refused():
    frames = clip()
    with pytest.raises(ValueError, match="no admissible frame"):
        min_over_time_bce(torch.zeros(1, 1, 4, 4, dtype=torch.float64), frames, mask(2, 5))


def test_sampled_pairs_stay_inside_the_valid_frames_and_cover_every_gap():
    torch.manual_seed(0)
    n_valid = torch.tensor([31, 12, 5]).repeat_interleave(2000)
    start, goal = sample_pairs(n_valid, shortest=4)
    gap = goal - start
    assert (start >= 0).all() and (goal <= n_valid - 1).all() and (gap >= 4).all()
    assert set(gap[:2000].tolist()) == set(range(4, 31))  # the whole valid clip is possible
    assert set(start[4000:].tolist()) == {0} and set(gap[4000:].tolist()) == {4}
    start, goal = sample_pairs(n_valid, shortest=4, longest=6)
    assert set((goal - start).tolist()) == {4, 5, 6} and (goal <= n_valid - 1).all()
    assert set(start[:2000].tolist()) == set(range(0, 31 - 4))  # every start that fits a gap of 4


def test_a_clip_too_short_for_a_pair_is_refused():
    with pytest.raises(ValueError, match="at least 5 valid frames, got 4"):
        sample_pairs(torch.tensor([10, 4]), shortest=4)


def test_evaluation_pairs_and_argmin_times():
    start, goal = whole_clip_pairs(torch.tensor([31, 11]))
    assert start.tolist() == [0, 0] and goal.tolist() == [30, 10]
    relative, at_last = argmin_times(torch.tensor([15, 8]), start, goal, margin=1)
    assert relative.tolist() == pytest.approx([0.5, 0.8]) and at_last.tolist() == [False, True]

"""The Surprise baseline's loss (keyin/losses/svg.py): the loss per clip and the
ratio that says whether the KL sits where the turns are."""

import torch

from keyin.losses.svg import SVGTerms, kl_reveal_ratio, svg_loss


def test_the_loss_is_the_weighted_sum_of_the_terms_per_clip():
    terms = SVGTerms(torch.ones(2, 3), torch.full((2, 3), 2.0), torch.ones(2, 3, dtype=torch.bool), torch.tensor(4.0))
    assert float(svg_loss(terms, beta=0.5, ae_weight=0.25)) == (6 + 0.5 * 12 + 0.25 * 4) / 2


def test_the_reveal_ratio_compares_the_kl_after_a_vertex_with_that_of_the_other_future_steps():
    """2 + 4 frames, a vertex at future frame 1 (clip frame 3): its KL step predicts frame 4. The step
    of frame 1 (a conditioning frame) and the padded last step count for neither side."""
    kl = torch.tensor([[9.0, 1.0, 2.0, 6.0, 100.0]])  # steps predicting frames 1 … 5
    valid = torch.tensor([[True, True, True, True, False]])
    keyframes = torch.tensor([[False, True, False, False]])
    assert float(kl_reveal_ratio(kl, valid, keyframes, n_cond=2)) == 6.0 / 1.5

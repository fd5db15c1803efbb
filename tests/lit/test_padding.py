"""Padded frames (past a clip's ``future_length``) never enter a loss or the attention (docs/architecture.md, "Padding and masking").

Each test computes a loss twice on the same batch, once with the padding replaced by noise, and
asserts the two are equal: the pushing demonstrations have clips of 26-31 frames padded to 31.
"""

import dataclasses

import pytest
import torch

from keyin.data.segments import partition_segments
from keyin.lit.interpolator import InterpolatorModule
from tests.lit.test_keyframe_teacher import STAGE1, keyframe_module

LENGTHS = torch.tensor([6, 3, 4])  # valid future frames of the three clips (N = 6)


def padded_batches() -> tuple[dict[str, torch.Tensor], dict[str, torch.Tensor]]:
    """The same clips twice: padding that repeats the last valid frame, and padding that is noise."""
    generator = torch.Generator().manual_seed(1)
    frames = (torch.rand(3, 8, 1, 8, 8, generator=generator) > 0.8).float()
    n_cond = STAGE1["n_cond"]
    noisy = frames.clone()
    for clip, length in enumerate(LENGTHS.tolist()):
        last = n_cond + length
        frames[clip, last:] = frames[clip, last - 1]
        noisy[clip, last:] = torch.rand(noisy[clip, last:].shape, generator=generator)
    keyframes = torch.zeros(3, 6, dtype=torch.bool)
    keyframes[:, 1] = True  # so that the diagnostic has bent segments too
    return (
        {"frames": frames, "future_length": LENGTHS, "keyframes": keyframes},
        {"frames": noisy, "future_length": LENGTHS, "keyframes": keyframes},
    )


def test_stage1_segments_stay_inside_each_clips_valid_frames():
    lengths = torch.tensor([31, 27, 5, 2])
    clip, start, offset = partition_segments(lengths, 1, 6, torch.Generator().manual_seed(0))
    assert bool((start + offset <= lengths[clip] - 1).all())
    for index, length in enumerate(lengths.tolist()[:2]):  # and reaches the end of each long clip
        assert int((start + offset)[clip == index].max()) > length - 1 - 6


@pytest.mark.parametrize("foreground_weight", [1.0, 5.0])
def test_stage1_loss_ignores_the_padding(foreground_weight):
    torch.manual_seed(0)
    module = InterpolatorModule(**STAGE1, foreground_weight=foreground_weight)
    module.log_dict = lambda *args, **kwargs: None
    losses = []
    for batch in padded_batches():
        module.segment_rng.manual_seed(0)
        losses.append(module.training_step(batch, 0))
    assert torch.equal(losses[0], losses[1])


def test_stage1_diagnostic_ignores_the_padding():
    torch.manual_seed(0)
    module = InterpolatorModule(**STAGE1)
    tables = [module.offset_contrast(batch, latent="mean") for batch in padded_batches()]
    values = [torch.tensor([[row["straight"], row["bent"]] for row in table.values()]) for table in tables]
    assert torch.equal(values[0].isnan(), values[1].isnan()) and not bool(values[0][:, 0].isnan().any())
    assert torch.allclose(values[0].nan_to_num(), values[1].nan_to_num())


@pytest.mark.parametrize("foreground_weight", [1.0, 5.0])
def test_stage2_loss_teacher_and_attention_ignore_the_padding(foreground_weight):
    module = keyframe_module(teacher_weight=10.0, offset_evidence=True, foreground_weight=foreground_weight)
    module.teacher = dataclasses.replace(module.teacher, clips=0)  # every clip, the short ones included
    results = []
    for batch in padded_batches():
        torch.manual_seed(2)
        terms = module._shared_step(batch, "train")
        torch.manual_seed(2)
        attention = module.model(batch["frames"], batch["future_length"])["attention"].detach()
        results.append((terms["loss"], terms["teacher"], attention))
    (loss, teacher, attention), (noisy_loss, noisy_teacher, noisy_attention) = results
    assert torch.equal(loss, noisy_loss) and torch.equal(teacher, noisy_teacher)
    assert torch.allclose(attention, noisy_attention)
    padding = ~(torch.arange(6)[None] < LENGTHS[:, None])  # (B, N)
    assert float(attention.masked_select(padding[:, None, :].expand_as(attention)).abs().max()) == 0.0


def test_stage1_and_stage2_weigh_pixels_as_stage1_says():
    """A threshold below 0 marks every pixel as changed: weight 5 gives exactly 5x the plain BCE."""
    batch = padded_batches()[0]
    stage1_losses, inter_losses = [], []
    for weight in (1.0, 5.0):
        torch.manual_seed(0)
        module = InterpolatorModule(**STAGE1, foreground_weight=weight, foreground_threshold=-1.0)
        module.log_dict = lambda *args, **kwargs: None
        module.segment_rng.manual_seed(0)
        stage1_losses.append(module.training_step(batch, 0))  # kl_weight 0: BCE terms only
        stage2 = keyframe_module(teacher_weight=0.0, foreground_weight=weight, foreground_threshold=-1.0)
        torch.manual_seed(2)
        inter_losses.append(stage2._shared_step(batch, "train")["inter"])
    assert torch.allclose(stage1_losses[1], 5 * stage1_losses[0])
    assert torch.allclose(inter_losses[1], 5 * inter_losses[0])

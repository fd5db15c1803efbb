"""Stage 1's terms against per-segment, per-frame loops."""

import pytest
import torch
import torch.nn.functional as F

from keyin.data.segments import segment_frames, valid_frames
from keyin.losses.interpolation import autoencoding_bce, autoencoding_pick, offset_contrast, segment_bce
from keyin.models.conv import decode_in_one_batch

torch.manual_seed(0)
DECODER = torch.nn.Sequential(torch.nn.Linear(4, 2 * 3 * 3), torch.nn.Unflatten(1, (2, 3, 3)))


def test_segment_bce_sums_each_segments_own_frames():
    clips = torch.rand(2, 7, 2, 3, 3)
    weights = torch.rand(2, 7, 2, 3, 3) + 0.5
    clip, start, offset = torch.tensor([0, 1, 1]), torch.tensor([0, 2, 1]), torch.tensor([3, 1, 4])
    predicted = torch.randn(3, 4, 4)
    positions, valid = segment_frames(start, offset, 4)
    bce = segment_bce(DECODER(predicted[valid]), valid, clips, weights, clip, positions)
    for row in range(3):
        expected = sum(
            F.binary_cross_entropy_with_logits(
                DECODER(predicted[row, i : i + 1])[0], clips[clip[row], start[row] + 1 + i],
                weights[clip[row], start[row] + 1 + i], reduction="sum",
            )
            for i in range(int(offset[row]))
        )
        assert bce[row].item() == pytest.approx(expected.item(), rel=1e-5)
    flat = segment_bce(DECODER(predicted[valid]), valid, clips.flatten(2), weights.flatten(2), clip, positions)
    assert torch.equal(flat, bce)  # flattened frames (B, L, D) score the same


def test_autoencoding_bce_of_a_subset_is_rescaled_to_all_frames():
    frames, embeddings = torch.rand(6, 2, 3, 3), torch.randn(6, 4)
    full = autoencoding_bce(DECODER(embeddings), frames, None)
    assert full.item() == pytest.approx(F.binary_cross_entropy_with_logits(DECODER(embeddings), frames, reduction="sum").item())
    # every 3-frame subset, weighted by how often randperm draws it, averages to the full sum
    picks = [autoencoding_pick(6, 3, torch.Generator().manual_seed(s)) for s in range(400)]
    estimates = [autoencoding_bce(DECODER(embeddings[pick]), frames[pick], None, 6) for pick in picks]
    assert torch.stack(estimates).mean().item() == pytest.approx(full.item(), rel=0.02)
    assert autoencoding_pick(6, 6) is None and autoencoding_pick(6, 0) is None  # all frames: nothing to draw


def test_decoding_in_one_batch_gives_each_set_its_own_logits():
    first, second = torch.randn(5, 4), torch.randn(3, 4)
    logits = decode_in_one_batch(DECODER, first, second)
    assert [tuple(part.shape) for part in logits] == [(5, 2, 3, 3), (3, 2, 3, 3)]
    torch.testing.assert_close(logits[0], DECODER(first))
    torch.testing.assert_close(logits[1], DECODER(second))


def test_offset_contrast_splits_segments_at_labelled_keyframes():
    keyframes = torch.zeros(1, 6, dtype=torch.bool)
    keyframes[0, 3] = True

    def score(clip, start, offset):  # a segment costs 2 per frame if it bends at frame 3, else 1
        bent = (start < 3) & (start + offset > 3)
        return offset * (1.0 + bent.float()), offset

    table = offset_contrast(score, keyframes, last=torch.tensor([5]), first=1, max_offset=3)
    # frames 1..5: offset 1 never bends, offset 2 bends at starts 1 and 2 only, both offset-3 segments bend
    assert table[1]["straight"] == 1.0 and table[1]["bent"] != table[1]["bent"]
    assert table[2] == {"straight": 1.0, "bent": 2.0, "all": pytest.approx(4 / 3)}  # all: every segment (two straight, one bent)
    assert table[3]["bent"] == 2.0 and table[3]["straight"] != table[3]["straight"]


def test_valid_frames_marks_the_unpadded_prefix():
    assert valid_frames(torch.tensor([2, 0, 3]), 3).tolist() == [[True, True, False], [False] * 3, [True] * 3]

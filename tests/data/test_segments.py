"""Segment helpers follow the device of their inputs (keyin ran on a GPU for the first time 2026-11-24)."""

import torch

from keyin.data.segments import segment_frames


def test_segment_frames_stay_on_the_device_of_their_segments():
    """The meta device stands in for a GPU: nothing may be built on the CPU and mixed in."""
    frames, valid = segment_frames(torch.tensor([0, 2], device="meta"), torch.tensor([1, 3], device="meta"), 3)
    assert frames.device.type == valid.device.type == "meta" and frames.shape == valid.shape == (2, 3)


def test_all_segments_lists_every_segment_inside_in_order():
    """Brute force: every (clip, start, offset) with the offset among those asked and both boundaries in
    [first, last], ordered by clip, then start, then offset; none where no segment fits."""
    from keyin.data.segments import all_segments

    for batch, first, last, offsets in ((2, 0, 6, range(1, 4)), (3, 4, 11, range(2, 3)), (1, 0, 2, range(1, 5)), (2, 3, 4, range(2, 4))):
        expected = [(c, a, o) for c in range(batch) for a in range(first, last + 1) for o in offsets if a + o <= last]
        found = list(zip(*(index.tolist() for index in all_segments(batch, first, last, offsets))))
        assert found == expected

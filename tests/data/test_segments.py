"""Segment helpers follow the device of their inputs (keyin ran on a GPU for the first time 2026-11-24)."""

import torch

from keyin.data.segments import segment_frames


def test_segment_frames_stay_on_the_device_of_their_segments():
    """The meta device stands in for a GPU: nothing may be built on the CPU and mixed in."""
    frames, valid = segment_frames(torch.tensor([0, 2], device="meta"), torch.tensor([1, 3], device="meta"), 3)
    assert frames.device.type == valid.device.type == "meta" and frames.shape == valid.shape == (2, 3)

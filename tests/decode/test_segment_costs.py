"""Segment helpers follow the device of their inputs (keyin ran on a GPU for the first time 2026-11-24)."""

import torch

from keyin.decode.segment_costs import boundary_segment_costs


def test_boundary_costs_stay_on_the_device_of_the_scores():
    """The meta device stands in for a GPU (segment indices used to be CPU tensors)."""
    costs = boundary_segment_costs(torch.zeros(2, 5, device="meta"), 3)
    assert costs.device.type == "meta" and costs.shape == (2, 5, 3)

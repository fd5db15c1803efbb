"""TAP's network: one frame from a start and a goal frame, through a shared encoder."""

import torch

from keyin.models import TAPNetwork


def test_the_network_predicts_one_frame_of_logits_from_start_and_goal():
    torch.manual_seed(0)
    network = TAPNetwork(image_size=64, channels=3, embed_dim=16, conv_width=4, coord_channels=True, norm="group",
                         mlp_hidden=16, mlp_layers=3)
    start, goal = torch.rand(2, 3, 64, 64), torch.rand(2, 3, 64, 64)
    logits = network(start, goal)
    assert logits.shape == (2, 3, 64, 64) and torch.isfinite(logits).all()
    assert not torch.allclose(network(goal, start), logits)  # the order of start and goal matters
    assert [name for name, _ in network.named_children()] == ["encoder", "bottleneck", "decoder"]  # one encoder

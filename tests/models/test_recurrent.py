"""LSTMBlock, MLP, state_from_vector (paper §4)."""

import pytest
import torch
from torch import nn

from keyin.models.recurrent import MLP, LSTMBlock, state_from_vector

BATCH, STEPS, IN_DIM, OUT_DIM, HIDDEN, LAYERS = 3, 4, 5, 6, 8, 2


def test_forward_shapes():
    block = LSTMBlock(IN_DIM, OUT_DIM, HIDDEN, LAYERS)

    outputs, (h, c) = block(torch.randn(BATCH, STEPS, IN_DIM))

    assert outputs.shape == (BATCH, STEPS, OUT_DIM)
    assert h.shape == c.shape == (LAYERS, BATCH, HIDDEN)


def test_learned_initial_state_is_zero_at_init_and_used():
    torch.manual_seed(0)
    block = LSTMBlock(IN_DIM, OUT_DIM, HIDDEN, LAYERS)
    inputs = torch.randn(BATCH, STEPS, IN_DIM)
    zeros = torch.zeros(LAYERS, BATCH, HIDDEN)
    assert block.initial_h.abs().sum() == 0 and block.initial_c.abs().sum() == 0

    with torch.no_grad():
        block.initial_h.normal_()
        block.initial_c.normal_()
    learned_outputs, _ = block(inputs)
    given = (block.initial_h[:, None].expand(-1, BATCH, -1), block.initial_c[:, None].expand(-1, BATCH, -1))
    given_outputs, _ = block(inputs, given)
    zero_outputs, _ = block(inputs, (zeros, zeros))

    torch.testing.assert_close(learned_outputs, given_outputs)
    assert not torch.allclose(learned_outputs, zero_outputs)
    learned_outputs.sum().backward()
    assert block.initial_h.grad.abs().sum() > 0 and block.initial_c.grad.abs().sum() > 0


def test_block_without_learned_state_has_no_such_parameters_and_needs_a_state():
    block = LSTMBlock(IN_DIM, OUT_DIM, HIDDEN, LAYERS, learn_initial_state=False)

    assert not any(name.startswith("initial_") for name, _ in block.named_parameters())
    with pytest.raises(ValueError, match="state"):
        block(torch.randn(BATCH, STEPS, IN_DIM))


def test_steps_match_sequence():
    torch.manual_seed(0)
    block = LSTMBlock(IN_DIM, OUT_DIM, HIDDEN, LAYERS)
    inputs = torch.randn(BATCH, STEPS, IN_DIM)

    sequence_outputs, (sequence_h, sequence_c) = block(inputs)
    state = None
    step_outputs = []
    for index in range(STEPS):
        output, state = block.step(inputs[:, index], state)
        step_outputs.append(output)

    assert step_outputs[0].shape == (BATCH, OUT_DIM)
    torch.testing.assert_close(torch.stack(step_outputs, dim=1), sequence_outputs)
    torch.testing.assert_close(state[0], sequence_h)
    torch.testing.assert_close(state[1], sequence_c)


def test_effective_forget_bias_is_one():
    block = LSTMBlock(IN_DIM, OUT_DIM, HIDDEN, LAYERS)

    for layer in range(LAYERS):
        bias = getattr(block.lstm, f"bias_ih_l{layer}") + getattr(block.lstm, f"bias_hh_l{layer}")
        torch.testing.assert_close(bias[HIDDEN : 2 * HIDDEN], torch.ones(HIDDEN))
        assert not torch.allclose(bias[:HIDDEN], torch.ones(HIDDEN))  # input gate untouched


def test_no_output_projection_returns_hidden_outputs():
    block = LSTMBlock(IN_DIM, None, HIDDEN, LAYERS)

    outputs, (h, _) = block(torch.randn(BATCH, STEPS, IN_DIM))

    assert outputs.shape == (BATCH, STEPS, HIDDEN)
    torch.testing.assert_close(outputs[:, -1], h[-1])


def test_state_from_vector_layout():
    h = torch.randn(LAYERS, BATCH, HIDDEN)
    c = torch.randn(LAYERS, BATCH, HIDDEN)
    state_vector = torch.cat([h.transpose(0, 1).flatten(1), c.transpose(0, 1).flatten(1)], dim=1)

    rebuilt_h, rebuilt_c = state_from_vector(state_vector, LAYERS, HIDDEN)

    assert state_vector.shape == (BATCH, 2 * LAYERS * HIDDEN)
    torch.testing.assert_close(rebuilt_h, h)
    torch.testing.assert_close(rebuilt_c, c)
    assert rebuilt_h.is_contiguous() and rebuilt_c.is_contiguous()
    block = LSTMBlock(IN_DIM, OUT_DIM, HIDDEN, LAYERS, learn_initial_state=False)
    block(torch.randn(BATCH, STEPS, IN_DIM), (rebuilt_h, rebuilt_c))


@pytest.mark.parametrize("layers", [1, 3])
def test_mlp_structure(layers):
    mlp = MLP(IN_DIM, OUT_DIM, HIDDEN, layers)
    linears = [m for m in mlp.modules() if isinstance(m, nn.Linear)]
    activations = [m for m in mlp.modules() if isinstance(m, nn.LeakyReLU)]

    assert len(linears) == layers
    assert len(activations) == layers - 1
    assert all(act.negative_slope == 0.2 for act in activations)
    assert isinstance(list(mlp.modules())[-1], nn.Linear)  # linear output
    assert mlp(torch.randn(2, BATCH, IN_DIM)).shape == (2, BATCH, OUT_DIM)


def test_mlp_needs_a_layer():
    with pytest.raises(ValueError, match="layer"):
        MLP(IN_DIM, OUT_DIM, HIDDEN, 0)

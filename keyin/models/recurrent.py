"""Recurrent building blocks shared by every recurrent module (paper §4).

The paper: "a simple two-layer LSTM with a 256-dimensional state in each layer for all recurrent
modules. Each LSTM has a linear projection layer before and after it."
"""

import torch
from torch import Tensor, nn

LSTMState = tuple[Tensor, Tensor]
"""(h, c), each (layers, B, hidden), as nn.LSTM takes and returns them."""


def init_forget_bias(lstm: nn.LSTM) -> None:
    """Set every layer's (and direction's) effective forget-gate bias to 1.

    nn.LSTM adds two biases, `bias_ih` and `bias_hh`, with gates ordered (input, forget, cell, output);
    the forget slice of `bias_ih` is set to 1 and that of `bias_hh` to 0, so their sum is exactly 1
    (blox-nn fills both with 1, an effective 2). Long memory at init helps the
    keyframe LSTM carry the conditioning state across M steps.

    Args:
        lstm: the LSTM to modify in place.
    """
    hidden = lstm.hidden_size
    with torch.no_grad():
        for name, bias in lstm.named_parameters():
            if name.startswith("bias_ih"):
                bias[hidden : 2 * hidden].fill_(1.0)
            elif name.startswith("bias_hh"):
                bias[hidden : 2 * hidden].fill_(0.0)


def state_from_vector(state_vector: Tensor, layers: int, hidden: int) -> LSTMState:
    """Turn a flat vector (e.g. an MLP's output) into a full LSTM state.

    Layout: the first layers·hidden entries are h (layer by layer), the rest c. Both are used as
    they are, without squashing: a tanh on h would bound it like the LSTM's own h but saturate the
    MLP's gradient; the LSTM's gates bound every later state anyway.

    Args:
        state_vector: (B, 2·layers·hidden).
        layers: number of LSTM layers.
        hidden: hidden size per layer.
    Returns:
        (h, c), each (layers, B, hidden), contiguous.
    """
    batch_size = state_vector.shape[0]
    h_and_c = state_vector.reshape(batch_size, 2, layers, hidden)  # (B, 2, layers, hidden)
    h_and_c = h_and_c.permute(1, 2, 0, 3)  # (2, layers, B, hidden)
    return h_and_c[0].contiguous(), h_and_c[1].contiguous()


class LSTMBlock(nn.Module):
    """Linear → multi-layer nn.LSTM → Linear (paper §4).

    Args:
        input_dim: size of each step's input.
        output_dim: size of each step's output; None returns the top layer's hidden output
            (size `hidden`) unprojected, for callers with their own heads or that only need the state.
        hidden: LSTM hidden size per layer.
        layers: number of LSTM layers.
        learn_initial_state: keep a learned initial state (zeros at init) used when no state is
            given. Blocks always initialised from elsewhere (LSTM_key from LSTM_cond, LSTM_inter
            from an MLP) turn it off so that no parameter is left without a gradient (DDP requires it).
    """

    def __init__(
        self,
        input_dim: int,
        output_dim: int | None,
        hidden: int = 256,
        layers: int = 2,
        learn_initial_state: bool = True,
    ) -> None:
        super().__init__()
        self.hidden = hidden
        self.layers = layers
        self.input_projection = nn.Linear(input_dim, hidden)
        self.lstm = nn.LSTM(hidden, hidden, num_layers=layers, batch_first=True)
        init_forget_bias(self.lstm)
        self.output_projection = nn.Identity() if output_dim is None else nn.Linear(hidden, output_dim)
        if learn_initial_state:
            self.initial_h = nn.Parameter(torch.zeros(layers, hidden))
            self.initial_c = nn.Parameter(torch.zeros(layers, hidden))
        else:
            self.register_parameter("initial_h", None)
            self.register_parameter("initial_c", None)

    def initial_state(self, batch_size: int) -> LSTMState:
        """The learned initial state repeated over the batch.

        Args:
            batch_size: B.
        Returns:
            (h, c), each (layers, B, hidden).
        Raises:
            ValueError: if the block was built with learn_initial_state=False.
        """
        if self.initial_h is None:
            raise ValueError("this LSTMBlock has no learned initial state; pass `state` explicitly")
        shape = (self.layers, batch_size, self.hidden)
        initial_h = self.initial_h.unsqueeze(1).expand(shape).contiguous()
        initial_c = self.initial_c.unsqueeze(1).expand(shape).contiguous()
        return initial_h, initial_c

    def forward(self, inputs: Tensor, state: LSTMState | None = None) -> tuple[Tensor, LSTMState]:
        """Run the block over a sequence.

        Args:
            inputs: (B, T, input_dim).
            state: (h, c), each (layers, B, hidden); None uses the learned initial state.
        Returns:
            outputs (B, T, output_dim) and the final state (h, c), each (layers, B, hidden).
        """
        if state is None:
            state = self.initial_state(inputs.shape[0])
        projected = self.input_projection(inputs)  # (B, T, hidden)
        # cuDNN's LSTM backward needs training mode: a frozen block in eval mode that a later stage
        # trains through (stage 2 through stage 1) runs on PyTorch's own kernels instead.
        with torch.backends.cudnn.flags(enabled=self.training or not torch.is_grad_enabled()):
            hidden_outputs, state = self.lstm(projected, state)  # (B, T, hidden)
        return self.output_projection(hidden_outputs), state  # (B, T, output_dim)

    def step(self, step_input: Tensor, state: LSTMState | None = None) -> tuple[Tensor, LSTMState]:
        """Run one step.

        Args:
            step_input: (B, input_dim).
            state: (h, c), each (layers, B, hidden); None uses the learned initial state.
        Returns:
            output (B, output_dim) and the new state.
        """
        outputs, state = self(step_input.unsqueeze(1), state)
        return outputs.squeeze(1), state


class MLP(nn.Module):
    """Fully connected network with LeakyReLU(0.2) between layers and a linear output.

    Args:
        input_dim: input size.
        output_dim: output size.
        hidden: width of the hidden layers.
        layers: number of Linear layers (≥ 1; 1 is a single Linear).
    """

    def __init__(self, input_dim: int, output_dim: int, hidden: int, layers: int) -> None:
        super().__init__()
        if layers < 1:
            raise ValueError(f"an MLP needs at least one layer, got layers={layers}")
        sizes = [input_dim] + [hidden] * (layers - 1) + [output_dim]
        modules: list[nn.Module] = []
        for index, (size_in, size_out) in enumerate(zip(sizes[:-1], sizes[1:])):
            if index > 0:
                modules.append(nn.LeakyReLU(0.2))
            modules.append(nn.Linear(size_in, size_out))
        self.network = nn.Sequential(*modules)

    def forward(self, inputs: Tensor) -> Tensor:
        """Apply the network.

        Args:
            inputs: (..., input_dim).
        Returns:
            (..., output_dim).
        """
        return self.network(inputs)

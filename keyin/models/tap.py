"""TAP's goal-conditioned bottleneck predictor (Jayaraman et al. 2019; paper §4.2).

Start and goal frames are embedded by one shared encoder, their embeddings concatenated and
squeezed through an MLP bottleneck, and one frame between them is decoded. The encoder and decoder
are KEYIN's (:mod:`keyin.models.conv`), sized by the same scale preset.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn

from keyin.models.conv import ConvDecoder, ConvEncoder, decode_in_one_batch
from keyin.models.recurrent import MLP


class TAPNetwork(nn.Module):
    """(start, goal) frames → logits of one frame between them.

    Args:
        image_size: H = W.
        channels: C.
        embed_dim: E, the encoder's embedding and the bottleneck's output size.
        conv_width: F of the encoder and decoder.
        coord_channels: CoordConv planes in the encoder and decoder.
        norm: "batch", "group" or "none".
        mlp_hidden: width of the bottleneck MLP's hidden layers.
        mlp_layers: Linear layers of the bottleneck MLP.
    """

    def __init__(
        self,
        image_size: int,
        channels: int,
        embed_dim: int,
        conv_width: int,
        coord_channels: bool,
        norm: str,
        mlp_hidden: int,
        mlp_layers: int = 3,
    ) -> None:
        super().__init__()
        conv = dict(
            image_size=image_size, channels=channels, width=conv_width, embed_dim=embed_dim,
            coord_channels=coord_channels, norm=norm,
        )
        self.encoder = ConvEncoder(**conv)
        self.bottleneck = MLP(2 * embed_dim, embed_dim, mlp_hidden, mlp_layers)
        self.decoder = ConvDecoder(**conv)

    def forward(self, start: Tensor, goal: Tensor) -> Tensor:
        """Predict the frame between ``start`` and ``goal``.

        Args:
            start, goal: (B, C, H, W) in [0, 1].
        Returns:
            (B, C, H, W) logits.
        """
        embeddings = self.encoder(torch.stack([start, goal], dim=1))  # (B, 2, E), one batch through the encoder
        return self.decoder(self.bottleneck(embeddings.flatten(1)))  # (B, 2E) → (B, E) → (B, C, H, W)

    def predict_and_reconstruct(self, start: Tensor, goal: Tensor) -> tuple[Tensor, Tensor]:
        """The frame between ``start`` and ``goal`` (B, C, H, W) and both decoded from their own embeddings (B, 2, C, H, W),
        logits, in one encoder and one decoder batch (a BatchNorm decoder: :func:`keyin.models.conv.decode_in_one_batch`).

        Args:
            start, goal: (B, C, H, W) in [0, 1].
        """
        images = torch.stack([start, goal], dim=1)  # (B, 2, C, H, W)
        embeddings = self.encoder(images)  # (B, 2, E)
        between = self.bottleneck(embeddings.flatten(1))  # (B, E)
        prediction, own = decode_in_one_batch(self.decoder, between, embeddings.flatten(0, 1))
        return prediction, own.view_as(images)

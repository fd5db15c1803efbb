"""A frame encoder and decoder trained together on single frames, then frozen (issue 25).

Stage 1 spends most of a CPU step in the convolutions of 64×64 frames (docs/decisions.md, "Cost").
Trained alone, on frames rather than clips, the pair learns to draw the scene once; frozen, its
encoder turns a whole dataset into embeddings once (:mod:`keyin.data.embeddings`) and its decoder is
called only where pixels are needed.
"""

from torch import Tensor, nn

from keyin.models.conv import ConvDecoder, ConvEncoder


class FrameAutoencoder(nn.Module):
    """:class:`ConvEncoder` and :class:`ConvDecoder` of one size, as one module to train and freeze.

    Args:
        image_size: H = W, a power of two ≥ 8.
        channels: C.
        width: F, the encoder's first (finest) block's feature maps.
        embed_dim: E.
        coord_channels: x/y coordinate planes in encoder and decoder.
        norm: "batch", "group" or "none".
    """

    def __init__(self, image_size: int, channels: int, width: int, embed_dim: int, coord_channels: bool, norm: str) -> None:
        super().__init__()
        conv = dict(image_size=image_size, channels=channels, width=width, embed_dim=embed_dim,
                    coord_channels=coord_channels, norm=norm)
        self.encoder = ConvEncoder(**conv)
        self.decoder = ConvDecoder(**conv)

    def forward(self, frames: Tensor) -> tuple[Tensor, Tensor]:
        """Embed frames and decode the embeddings.

        Args:
            frames: (..., C, H, W) in [0, 1].
        Returns:
            embeddings (..., E) in (-1, 1) and logits (..., C, H, W).
        """
        embeddings = self.encoder(frames)
        return embeddings, self.decoder(embeddings)

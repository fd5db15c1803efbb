"""DCGAN-style convolutional frame encoder and decoder (paper §3.1, §4).

The encoder has log2(H) - 2 stride-2 blocks (3 at 32×32, 4 at 64×64, as the paper's "three / four
layers") and a 4×4 valid head to a 1×1 embedding; the decoder mirrors it. Optional CoordConv inputs
(two fixed planes holding the pixel's x and y in [-1, 1]) make position-like embeddings easy to
learn, which is what a linear-motion interpolator needs on the Brownian data.
"""

import math
from typing import Callable

import torch
from torch import Tensor, nn

NORMS = ("batch", "group", "none")
MAX_GROUPS = 8


def conv_depth(image_size: int) -> int:
    """Number of stride-2 blocks for a square image (paper §4: three at 32x32, four at 64x64).

    Args:
        image_size: H = W; a power of two, at least 8.
    Returns:
        log2(image_size) - 2 (3 at 32, 4 at 64).
    Raises:
        ValueError: if image_size is not a power of two ≥ 8.
    """
    if image_size < 8 or image_size & (image_size - 1):
        raise ValueError(f"image_size must be a power of two >= 8 (e.g. 32 or 64), got {image_size}")
    return image_size.bit_length() - 3


def coordinate_planes(size: int, like: Tensor) -> Tensor:
    """Two fixed planes with each pixel's x (first) and y (second) coordinate in [-1, 1].

    Args:
        size: H = W of the planes.
        like: any tensor; the planes take its device and dtype.
    Returns:
        (1, 2, size, size).
    """
    axis = torch.linspace(-1.0, 1.0, size, device=like.device, dtype=like.dtype)
    y_plane, x_plane = torch.meshgrid(axis, axis, indexing="ij")
    return torch.stack([x_plane, y_plane]).unsqueeze(0)


def with_coordinates(features: Tensor) -> Tensor:
    """Concatenate the coordinate planes of the features' resolution as two extra channels.

    Args:
        features: (B, C, H, W) with H = W.
    Returns:
        (B, C + 2, H, W).
    """
    planes = coordinate_planes(features.shape[-1], features)
    return torch.cat([features, planes.expand(features.shape[0], -1, -1, -1)], dim=1)


def normalization(norm: str, channels: int) -> nn.Module:
    """The normalisation layer named by `norm` for `channels` feature maps.

    GroupNorm uses gcd(8, channels) groups, so that small widths still divide evenly.

    Args:
        norm: "batch", "group" or "none".
        channels: number of feature maps.
    Returns:
        BatchNorm2d, GroupNorm or Identity.
    """
    if norm == "batch":
        return nn.BatchNorm2d(channels)
    if norm == "group":
        return nn.GroupNorm(math.gcd(MAX_GROUPS, channels), channels)
    return nn.Identity()


def _check_norm(norm: str) -> None:
    if norm not in NORMS:
        raise ValueError(f"norm must be one of {NORMS}, got {norm!r}")


class ConvEncoder(nn.Module):
    """Frames in [0, 1] → tanh embeddings (paper §3.1, CNN_enc).

    Stride-2 conv4 blocks with widths F, 2F, 4F (, 8F), LeakyReLU(0.2), normalisation on all but the
    first block, then a 4×4 valid conv head to E and tanh (keeps embedding-space MSE well scaled).

    Args:
        image_size: H = W, a power of two ≥ 8.
        channels: C.
        width: F, the first block's number of feature maps.
        embed_dim: E.
        coord_channels: concatenate x/y coordinate planes to the input of the first conv.
        norm: "batch", "group" or "none".
    """

    def __init__(
        self,
        image_size: int,
        channels: int,
        width: int,
        embed_dim: int,
        coord_channels: bool = False,
        norm: str = "batch",
    ) -> None:
        super().__init__()
        _check_norm(norm)
        depth = conv_depth(image_size)
        self.image_shape = (channels, image_size, image_size)
        self.coord_channels = coord_channels
        blocks: list[nn.Module] = []
        in_channels = channels + 2 if coord_channels else channels
        for index in range(depth):
            out_channels = width * 2**index
            blocks.append(nn.Conv2d(in_channels, out_channels, 4, stride=2, padding=1))
            if index > 0:
                blocks.append(normalization(norm, out_channels))
            blocks.append(nn.LeakyReLU(0.2))
            in_channels = out_channels
        self.blocks = nn.Sequential(*blocks)
        self.head = nn.Conv2d(in_channels, embed_dim, 4)

    def forward(self, frames: Tensor) -> Tensor:
        """Embed frames.

        Args:
            frames: (..., C, H, W) in [0, 1]; any number of leading dims.
        Returns:
            (..., E) in (-1, 1).
        """
        return self.embed_with_skips(frames)[0]

    def embed_with_skips(self, frames: Tensor) -> tuple[Tensor, list[Tensor]]:
        """Embed frames and keep every block's output, for a decoder with skip connections.

        Args:
            frames: (..., C, H, W) in [0, 1]; any number of leading dims.
        Returns:
            (..., E) embeddings in (-1, 1), and per block i the features (..., F·2^i, H/2^(i+1), H/2^(i+1)),
            finest first.
        """
        if tuple(frames.shape[-3:]) != self.image_shape:
            raise ValueError(f"expected frames (..., {self.image_shape}), got {tuple(frames.shape)}")
        leading_shape = frames.shape[:-3]
        features = frames.reshape(-1, *self.image_shape)  # (B', C, H, W)
        if self.coord_channels:
            features = with_coordinates(features)  # (B', C+2, H, W)
        skips = []
        for layer in self.blocks:
            features = layer(features)
            if isinstance(layer, nn.LeakyReLU):  # the end of a block
                skips.append(features.reshape(*leading_shape, *features.shape[1:]))
        embeddings = torch.tanh(self.head(features)).flatten(1)  # (B', E) from (B', F·2^(depth-1), 4, 4)
        return embeddings.reshape(*leading_shape, -1), skips


class ConvDecoder(nn.Module):
    """Embeddings → frame logits, the mirror of ConvEncoder (paper §3.1, CNN_dec).

    A 4×4 transposed conv from 1×1 to 4×4, then stride-2 transposed conv4 blocks halving the width
    up to H; normalisation and LeakyReLU(0.2) after every layer but the last. The output is
    **logits**, not probabilities: callers apply `torch.sigmoid` for images and use
    `binary_cross_entropy_with_logits` (or the sigmoid before the soft loss's mixtures) — keeping the
    sigmoid outside lets reconstruction losses use the numerically stable logit form.

    Args:
        image_size: H = W, a power of two ≥ 8.
        channels: C.
        width: F, the feature maps of the last hidden layer (the encoder's first).
        embed_dim: E.
        coord_channels: concatenate x/y coordinate planes of the current resolution before each
            stride-2 upsampling conv.
        norm: "batch", "group" or "none".
        skips: each upsampling conv also reads the encoder's features of the same resolution
            (SVG's skip connections: :meth:`ConvEncoder.embed_with_skips` of a context frame).
    """

    def __init__(
        self,
        image_size: int,
        channels: int,
        width: int,
        embed_dim: int,
        coord_channels: bool = False,
        norm: str = "batch",
        skips: bool = False,
    ) -> None:
        super().__init__()
        _check_norm(norm)
        depth = conv_depth(image_size)
        self.coord_channels = coord_channels
        self.skips = skips
        top_channels = width * 2 ** (depth - 1)
        self.head = nn.Sequential(
            nn.ConvTranspose2d(embed_dim, top_channels, 4),
            normalization(norm, top_channels),
            nn.LeakyReLU(0.2),
        )
        extra_channels = 2 if coord_channels else 0
        self.upsampling = nn.ModuleList()
        in_channels = top_channels
        for index in reversed(range(depth)):
            is_last = index == 0
            out_channels = channels if is_last else width * 2 ** (index - 1)
            skip_channels = width * 2**index if skips else 0  # the encoder block of this resolution
            layers: list[nn.Module] = [
                nn.ConvTranspose2d(in_channels + extra_channels + skip_channels, out_channels, 4, stride=2, padding=1)
            ]
            if not is_last:
                layers += [normalization(norm, out_channels), nn.LeakyReLU(0.2)]
            self.upsampling.append(nn.Sequential(*layers))
            in_channels = out_channels

    def forward(self, embeddings: Tensor, skips: list[Tensor] | None = None) -> Tensor:
        """Decode embeddings to logits.

        Args:
            embeddings: (..., E); any number of leading dims.
            skips: with ``skips=True`` only, and then required: the encoder's block features
                (..., F·2^i, h_i, h_i), finest first, with the embeddings' leading dims.
        Returns:
            (..., C, H, W) logits; `torch.sigmoid` of them are pixel probabilities.
        """
        if self.skips != (skips is not None):
            raise ValueError(f"this decoder was built with skips={self.skips}; pass skips "
                             f"{'from ConvEncoder.embed_with_skips' if self.skips else 'None'}")
        leading_shape = embeddings.shape[:-1]
        features = embeddings.reshape(-1, embeddings.shape[-1], 1, 1)  # (B', E, 1, 1)
        features = self.head(features)  # (B', F·2^(depth-1), 4, 4)
        if self.training or skips is not None:
            features = self._upsample(features, skips)
        else:
            features = self._upsample_eval(features)
        return features.reshape(*leading_shape, *features.shape[1:])

    def _upsample(self, features: Tensor, skips: list[Tensor] | None) -> Tensor:
        """(B', F·2^(depth-1), 4, 4) → (B', C, H, W) logits through the upsampling blocks."""
        coarsest_first = [] if skips is None else [skip.reshape(-1, *skip.shape[-3:]) for skip in reversed(skips)]
        for index, block in enumerate(self.upsampling):
            if self.coord_channels:
                features = with_coordinates(features)  # (B', channels + 2, h, h)
            if coarsest_first:
                features = torch.cat([features, coarsest_first[index]], dim=1)  # (B', ... + F·2^i, h, h)
            features = block(features)  # (B', channels / 2 or C, 2h, 2h)
        return features

    def _upsample_eval(self, features: Tensor) -> Tensor:
        """:meth:`_upsample` without skips, as eval mode computes it, on a CPU 1.2-1.3× faster (docs/decisions.md;
        not measured on a GPU):
        feature maps in ``channels_last``, and each conv's response to the coordinate planes, the same
        for every frame, computed once per call as a per-pixel bias instead of convolving planes
        concatenated to every frame. The same logits to float rounding; gradients still flow."""
        features = features.contiguous(memory_format=torch.channels_last)
        for block in self.upsampling:
            conv = block[0]
            if self.coord_channels:
                n_features = conv.in_channels - 2
                planes = coordinate_planes(features.shape[-1], features)  # (1, 2, h, h)
                bias = nn.functional.conv_transpose2d(planes, conv.weight[n_features:], conv.bias, conv.stride, conv.padding)
                features = nn.functional.conv_transpose2d(
                    features, conv.weight[:n_features], None, conv.stride, conv.padding
                ) + bias  # (B', channels / 2 or C, 2h, 2h)
            else:
                features = conv(features)
            for layer in list(block)[1:]:  # its normalisation and activation, if any
                features = layer(features)
        return features.contiguous()


def decode_in_one_batch(decoder: Callable[[Tensor], Tensor], *embeddings: Tensor) -> tuple[Tensor, ...]:
    """Decode several sets of embeddings, each (R_i, E), in one call and split the logits back.

    A BatchNorm decoder in train mode normalises each call by that call's statistics; decoding two kinds of embedding
    apart (interpolated and auto-encoded frames, a prediction and its inputs) teaches it two normalisations, and its
    running statistics (eval mode) hold neither (docs/decisions.md, "One decoder batch a step"). One call trains the
    normalisation eval mode reproduces.

    Returns:
        the logits of each set, (R_i, ...).
    """
    return decoder(torch.cat(embeddings)).split([len(part) for part in embeddings])

"""Colour-segmentation centroid: numpy and torch, sub-pixel accuracy, missing puck."""

import numpy as np
import pytest
import torch

from keyin.envs.segmentation import PUCK_RGB, centroid_distance, puck_centroid


def disc_image(centre, radius=1.92, size=64, background=(0.85, 0.85, 0.85)):
    """Pixels whose centre lies within ``radius`` of ``centre`` (column, row) get the puck colour."""
    image = np.tile(np.asarray(background, np.float32), (size, size, 1))
    rows, cols = np.mgrid[0:size, 0:size] + 0.5
    inside = (cols - centre[0]) ** 2 + (rows - centre[1]) ** 2 <= radius**2
    image[inside] = PUCK_RGB
    return (image * 255).round().astype(np.uint8)


@pytest.mark.parametrize("centre", [(10.3, 40.7), (32.0, 32.0), (50.5, 5.2)])
def test_centroid_of_a_disc_within_half_a_pixel(centre):
    found, mass = puck_centroid(disc_image(centre))
    assert np.linalg.norm(found - centre) < 0.5
    assert 8 < mass < 16  # about pi * 1.92^2 = 11.6 pixels


def test_batched_torch_matches_numpy():
    images = np.stack([disc_image((12.0, 20.0)), disc_image((40.0, 33.0))])
    numpy_centroids, _ = puck_centroid(images)
    torch_centroids, _ = puck_centroid(torch.from_numpy(images).float() / 255.0)
    assert isinstance(torch_centroids, torch.Tensor)
    assert np.allclose(torch_centroids.numpy(), numpy_centroids, atol=1e-4)


def test_no_puck_gives_nan_and_the_diagonal_cost():
    empty = disc_image((30.0, 30.0), radius=0.0)
    centroid, mass = puck_centroid(empty)
    assert np.all(np.isnan(centroid)) and mass < 0.5
    cost = centroid_distance(empty, disc_image((30.0, 30.0)))
    assert cost == pytest.approx(np.hypot(64, 64))
    cost = centroid_distance(disc_image((10.0, 10.0)), disc_image((13.0, 14.0)))
    assert cost == pytest.approx(5.0, abs=0.5)

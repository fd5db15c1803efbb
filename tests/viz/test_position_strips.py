"""The annotated GIF's position bars, drawn for all frames at once, against drawing each frame's alone."""

import numpy as np

from keyin.viz.discovered import PREDICTED, STRIP_HEIGHT, TRUE, position_strips


def one_strip(width: int, n_frames: int, now: int, found: list[int], labels: list[int]) -> np.ndarray:
    """Brute force: frame ``now``'s bar, shading, ticks and marker drawn one by one."""
    column = lambda frame: min(width - 1, frame * width // n_frames)  # noqa: E731
    strip = np.full((STRIP_HEIGHT, width, 3), 40, dtype=np.uint8)
    strip[:, : column(now)] = 90
    for marks, colour, rows in ((labels, TRUE, slice(None, STRIP_HEIGHT // 2)), (found, PREDICTED, slice(STRIP_HEIGHT // 2, None))):
        for frame in marks:
            strip[rows, column(frame)] = colour
    strip[:, column(now)] = 255
    return strip


def test_every_frames_bar_is_the_one_drawn_alone():
    for width, n_frames, found, labels in ((32, 50, [3, 17, 49], [3, 20]), (128, 7, [1, 2], []), (40, 400, [], [0, 399])):
        strips = position_strips(width, n_frames, found, labels)
        assert strips.shape == (n_frames, STRIP_HEIGHT, width, 3) and strips.dtype == np.uint8
        for now in range(n_frames):
            np.testing.assert_array_equal(strips[now], one_strip(width, n_frames, now, found, labels))

import numpy as np
import torch
from torch.utils.data import DataLoader

from keyin.data.brownian import BrownianGenerator, direction_change_frames
from keyin.data.clips import GeneratedClips

GEN = BrownianGenerator()


def test_same_index_gives_the_same_clip_and_different_indices_differ():
    a, _ = GEN.generate(17, seed=5)
    b, _ = GEN.generate(17, seed=5)
    c, _ = GEN.generate(18, seed=5)
    for name in a:
        np.testing.assert_array_equal(a[name], b[name])
    assert not np.array_equal(a["positions"], c["positions"])


def test_clips_do_not_depend_on_the_worker_count():
    clips = GeneratedClips(GEN, size=12, seed=3, n_future=30)
    serial = next(iter(DataLoader(clips, batch_size=12, num_workers=0)))
    parallel = torch.cat(
        [b["frames"] for b in DataLoader(clips, batch_size=3, num_workers=2)], dim=0
    )
    torch.testing.assert_close(serial["frames"], parallel)


def test_keyframes_are_exactly_the_direction_changes_of_the_stored_positions():
    for index in range(200):
        arrays, _ = GEN.generate(index, seed=0)
        np.testing.assert_array_equal(arrays["keyframes"], direction_change_frames(arrays["positions"]))


def test_motion_follows_the_generator_spec():
    for index in range(100):
        arrays, _ = GEN.generate(index, seed=1)
        positions = arrays["positions"].astype(np.float64)
        steps = np.diff(positions, axis=0)
        np.testing.assert_allclose(np.linalg.norm(steps, axis=-1), GEN.speed, atol=1e-4)
        assert positions.min() >= GEN.radius - 1e-4 and positions.max() <= 32 - GEN.radius + 1e-4
        vertices = np.flatnonzero(arrays["keyframes"])
        assert np.all(np.diff(vertices) >= GEN.segment_min)
        assert np.all(np.diff(vertices) <= GEN.segment_max)
        for v in vertices:
            cos = steps[v - 1] @ steps[v] / GEN.speed**2
            assert np.degrees(np.arccos(np.clip(cos, -1, 1))) >= GEN.min_turn_deg - 1e-3


def test_rendered_disc_sits_at_the_position():
    arrays, _ = GEN.generate(0, seed=0)
    frames = arrays["frames"][..., 0]
    assert frames.shape == (35, 32, 32) and set(np.unique(frames)) <= {0, 255}
    for frame, (x, y) in zip(frames, arrays["positions"]):
        rows, cols = np.nonzero(frame)
        assert 9 <= len(rows) <= 16
        assert abs(cols.mean() + 0.5 - x) < 0.5 and abs(rows.mean() + 0.5 - y) < 0.5


def test_about_four_keyframes_per_clip_in_the_future_window():
    counts = [GEN.generate(i, seed=7)[0]["keyframes"][5:].sum() for i in range(500)]
    assert 3.8 < np.mean(counts) < 4.6

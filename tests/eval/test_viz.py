import imageio.v3 as iio
import numpy as np
import torch

from keyin.viz.keyframes import CONDITION, HIT, PREDICTED, TRUE, marked_frames, save_keyframe_pictures


def test_borders_mark_truth_predictions_hits_and_conditioning():
    frames = torch.zeros(6, 1, 4, 4)
    marked = marked_frames(frames, n_cond=2, truth=[0, 2], predicted=[2, 3], border=1)
    assert marked.shape == (6, 6, 6, 3)
    corners = [tuple(image[0, 0]) for image in marked]
    assert corners == [CONDITION, CONDITION, TRUE, (0, 0, 0), HIT, PREDICTED]
    assert (marked[:, 1:-1, 1:-1] == 0).all()  # the image itself is untouched


def test_png_has_one_row_per_clip_and_gif_one_frame_per_step(tmp_path):
    clips = torch.rand(3, 5, 1, 8, 8)
    png, gif = save_keyframe_pictures(tmp_path, clips, 2, [[0]] * 3, [[1]] * 3)
    assert iio.imread(png).shape == (3 * 12, 5 * 12, 3)
    movie = iio.imread(gif, index=None)
    assert movie.shape[0] == 5 and movie.shape[2] == 3 * movie.shape[1]
    assert np.array_equal(iio.imread(png)[:12, :12, :], marked_frames(clips[0], 2, [0], [1])[0])


def test_gif_stacks_consecutive_clips_in_columns(tmp_path):
    clips = torch.arange(6.0).view(6, 1, 1, 1, 1).expand(6, 5, 1, 8, 8) / 5  # clip i is grey i / 5
    _, gif = save_keyframe_pictures(tmp_path, clips, 2, [[]] * 6, [[]] * 6, per_column=3)
    movie = iio.imread(gif, index=None)
    cell = 12 * (256 // 12)  # a bordered frame, scaled
    assert movie.shape[1:3] == (3 * cell, 2 * cell)  # (identical frames may be merged)
    centres = movie[0, cell // 2 :: cell, cell // 2 :: cell, 0].astype(int)  # (row, column)
    expected = (np.arange(6).reshape(2, 3).T * 255 / 5).round()  # clips 0-2 down column 0, 3-5 down column 1
    assert np.abs(centres - expected).max() <= 2


def test_plan_pictures_put_each_subgoal_over_the_frame_that_last_pursued_it(tmp_path):
    from keyin.viz.planning import last_step_per_subgoal, save_plan_pictures, with_goal

    assert last_step_per_subgoal(np.array([0, 0, 2, 2, 3]), 4) == [2, None, 4, 5]
    goal = np.zeros((4, 4, 3), np.uint8)
    frames = np.stack([np.full((4, 4, 3), 10 * (t + 1), np.uint8) for t in range(6)])  # frame t is grey 10(t+1)
    assert (with_goal(frames[:1], goal) == round(10 * (1 - 0.35))).all() and (with_goal(goal[None], goal) == 0).all()
    subgoals = np.stack([np.full((4, 4, 3), 200 + k, np.uint8) for k in range(3)] + [goal])  # 3 subgoals, the goal
    png, gif = save_plan_pictures(tmp_path, "task", frames[0], subgoals, frames, np.array([0, 0, 2, 2, 2]), gap=1)
    canvas = iio.imread(png)[::2, ::2]  # written at twice the size
    assert canvas.shape == (2 * 4 + 3, 5 * 5 + 1, 3)
    top = [int(canvas[1, 1 + 5 * c, 0]) for c in range(5)]
    bottom = [int(canvas[6, 1 + 5 * c, 0]) for c in range(5)]
    assert top == [10, 200, 201, 202, 0]
    # start frame; subgoal 0 last pursued at step 2 (frame 2); subgoal 1 skipped (blank); subgoal 2 at step 5;
    # the goal never pursued: the episode's last frame (frame 5) — every executed frame blended with the goal
    assert bottom == [round(0.65 * 10), round(0.65 * 30), 255, round(0.65 * 60), round(0.65 * 60)]
    movie = iio.imread(gif, index=None)
    assert movie.shape[0] == 6 and movie.shape[2] > movie.shape[1]  # a frame beside its subgoal, per step


def test_labelled_strips_take_one_label_per_strip(tmp_path):
    import pytest

    from keyin.viz.figures import save_labeled_strips
    from keyin.viz.report import save_method_comparison

    strips = [marked_frames(torch.rand(5, 3, 8, 8), 2, [0], [1]) for _ in range(3)]
    assert iio.imread(save_labeled_strips(strips, ["a", "b", "c\nd"], tmp_path / "strips.png")).ndim == 3
    with pytest.raises(ValueError, match="one label per strip"):
        save_labeled_strips(strips, ["a"], tmp_path / "bad.png")
    path = save_method_comparison(torch.rand(2, 5, 1, 8, 8), 2, [[0], [1]], {"a": [[0], []], "b": [[1], [2]]}, tmp_path / "m.png")
    assert iio.imread(path).ndim == 3


def test_trajectories_are_drawn_over_the_scene(tmp_path):
    from keyin.viz.figures import save_trajectories

    tracks = [np.array([[10.0, 50.0], [np.nan, np.nan], [30.0, 10.0]]), np.array([[10.0, 50.0], [50.0, 12.0]])]
    wall = np.array([[20.0, 30.0], [44.0, 30.0], [44.0, 32.0], [20.0, 32.0]])
    background = np.full((64, 64, 3), 200, np.uint8)
    path = save_trajectories(background, wall, tracks[0][0], {"demos": tracks, "samples": tracks[:1]}, tmp_path / "t.png")
    assert iio.imread(path).shape[1] > iio.imread(path).shape[0]  # two panels side by side


def test_contact_sheet_shows_each_keyframe_enlarged_in_reading_order(tmp_path):
    """Eight solid grey frames of levels 20, 40, …: each cell's centre has its frame's level, left to
    right then down (six columns), and every frame is drawn at the same whole-pixel scale."""
    from keyin.viz.discovered import SHEET_COLUMNS, save_contact_sheet

    levels = [20 * (i + 1) for i in range(8)]
    images = np.stack([np.full((16, 16, 1), level, dtype=np.uint8) for level in levels])
    sheet = iio.imread(save_contact_sheet(tmp_path / "sheet.png", images, [f"frame {i}" for i in range(8)], "take"))
    assert sheet.ndim == 3 and sheet.shape[1] % SHEET_COLUMNS == 0
    cell_width = sheet.shape[1] // SHEET_COLUMNS
    first_row = [sheet[:, column * cell_width + cell_width // 2, 0] for column in range(SHEET_COLUMNS)]
    second_row = [sheet[:, column * cell_width + cell_width // 2, 0] for column in range(2)]
    runs = [np.flatnonzero(column == level) for column, level in zip(first_row + second_row, levels)]
    assert all(len(run) == len(runs[0]) >= 16 for run in runs)  # each frame as tall, enlarged
    assert all(runs[i][0] == runs[0][0] for i in range(SHEET_COLUMNS)) and runs[SHEET_COLUMNS][0] > runs[0][-1]


def test_a_long_row_label_is_drawn_whole_left_of_its_strip(tmp_path):
    from keyin.viz.figures import save_labeled_strips

    long = "keyin_paper_delta_st · backbone=ours scale=cpu"
    strips = [marked_frames(torch.rand(5, 3, 32, 32), 2, [0], [1]) for _ in range(2)]
    short = iio.imread(save_labeled_strips(strips, ["a", "clip 0\nrandom"], tmp_path / "short.png"))
    image = iio.imread(save_labeled_strips(strips, ["a", f"clip 0\n{long}"], tmp_path / "long.png"))
    assert image.shape[1] > short.shape[1]  # the figure widens for the long name, the strips keep their size
    assert (image[:, :3, :3] > 200).all()  # white: no letter runs off the figure's left edge

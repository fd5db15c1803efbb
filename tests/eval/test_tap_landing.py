"""Where TAP's chosen frames land in time on whole clips (keyin/eval/tap.py), on hand-made argmins."""

import torch

from keyin.eval.tap import landing_deciles, score_whole_clips


def test_landing_deciles_count_each_tenth():
    relative = torch.tensor([0.05, 0.1, 0.15, 0.5, 0.95, 0.999])
    assert landing_deciles(relative) == [0.1667, 0.3333, 0, 0, 0, 0.1667, 0, 0, 0, 0.3333]


def test_whole_clips_report_the_middle_third_and_the_deciles():
    clips = [{"frames": torch.zeros(11, 1, 2, 2), "future_length": torch.tensor(10)} for _ in range(4)]
    chosen = torch.tensor([2, 5, 5, 8])  # a = 0, b = 10: 0.2, 0.5, 0.5, 0.8

    def terms(frames, n_valid, start, goal):
        assert start.tolist() == [0] * 4 and goal.tolist() == [10] * 4
        return torch.ones(len(frames)), chosen

    scores = score_whole_clips(terms, clips, n_cond=1, margin=1)
    assert scores["argmin_middle"] == 0.5 and scores["argmin_relative"] == 0.5
    assert scores["argmin_deciles"] == [0, 0, 0.25, 0, 0, 0.5, 0, 0, 0.25, 0]
    assert scores["argmin_last"] == 0.25  # frame 8 = b - margin - 1

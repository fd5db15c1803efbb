"""score_methods' predictions.json holds every scored clip's keyframes, labels and valid lengths,
in order, for every method; keyin-report reads its first clips, recall_by_turn all of them."""

import json

import torch

from keyin.eval.discovery import discover, score_methods

N = 6


def hand_made_clips(count: int = 7) -> list[dict[str, torch.Tensor]]:
    """Clips of 1 + N frames; clip k has a label at k % N and k % 3 + 4 valid future frames."""
    clips = []
    for k in range(count):
        keyframes = torch.zeros(N, dtype=torch.bool)
        keyframes[k % N] = True
        clips.append({"frames": torch.full((1 + N, 1, 8, 8), k / count), "future_length": torch.tensor(k % 3 + 4),
                      "keyframes": keyframes})
    return clips


def brightness_rule(frames: torch.Tensor, future_length: torch.Tensor) -> list[list[int]]:
    """A keyframe at the clip's brightness index (the clip number), inside its valid frames."""
    index = (frames[:, 0, 0, 0, 0] * 7).round().long()
    return [[int(k) % int(n)] for k, n in zip(index, future_length)]


def test_predictions_json_holds_every_clip_of_every_method_in_order(tmp_path):
    clips = hand_made_clips()
    every_other = lambda frames, lengths: [[1, 3]] * len(frames)  # noqa: E731
    score_methods({"bright": brightness_rule, "fixed": every_other}, clips, 1, N, tmp_path, batch_size=3)
    saved = json.loads((tmp_path / "predictions.json").read_text())
    assert saved["clips"] == list(range(7))
    assert saved["truth"] == [[k % N] for k in range(7)]
    assert saved["lengths"] == [k % 3 + 4 for k in range(7)]
    assert saved["predicted"]["bright"] == discover(brightness_rule, clips, batch_size=2).predicted
    assert saved["predicted"]["bright"] == [[k % (k % 3 + 4)] for k in range(7)]
    assert saved["predicted"]["fixed"] == [[1, 3]] * 7

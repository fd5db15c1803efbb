"""Keyframes of whole videos: an oracle discoverer that reads each frame's number from its picture
shows that keyframes.json's frames are the original file's frames, at frame stride 1 and 2; a long
clip's known turns survive the windows' merge; a crash leaves no half-written folder."""

import dataclasses
import functools
import json

import imageio.v3 as iio
import numpy as np
import pytest
import torch

from keyin.data.imports import ImportSpec, read_videos
from keyin.data.sources import decoded_frames
from keyin.data.windows import kept_keyframes
from keyin.pipelines.discover import FILES, discover_video, discover_videos, folder_names, window_batches
from keyin.viz import discovered
from tests.videos import EVENTS, FPS, LEVEL0, LEVEL_STEP, frame_numbers, frames, write_video

N_COND, N_FUTURE = 2, 10


def spec(frame_stride: int, window_stride: int = 5) -> ImportSpec:
    return ImportSpec(image_size=8, channels=1, n_cond=N_COND, n_future=N_FUTURE, frame_stride=frame_stride,
                      window_stride=window_stride)


def oracle(targets):
    """A discoverer that marks the future frames whose picture shows one of the original frames
    ``targets``, and a scorer that scores each future frame its number / 1000."""
    def discoverer(clips, future_length):
        return [[p for p, number in enumerate(frame_numbers(clip)[N_COND:][:length]) if number in targets]
                for clip, length in zip(clips, future_length.tolist())]

    def scorer(clips, future_length):
        return torch.tensor([frame_numbers(clip)[N_COND:] for clip in clips], dtype=torch.float32) / 1000

    return discoverer, scorer


@pytest.fixture(scope="module")
def video_file(tmp_path_factory):
    return write_video(tmp_path_factory.mktemp("windowed") / "take.mp4", frames(40))


@pytest.mark.parametrize("frame_stride", [1, 2])
def test_keyframes_are_the_original_files_frames_at_stride(video_file, frame_stride):
    (video,), _, _ = read_videos(video_file, spec(frame_stride), None, None, progress=False)
    targets = {kept * frame_stride for kept in kept_keyframes(EVENTS, frame_stride, len(video.frames))}
    found = discover_video(video, *oracle(targets), N_COND, N_FUTURE, frame_stride)
    assert [k.frame for k in found] == sorted(targets)  # each event once, though several windows saw it
    assert [k.time for k in found] == [frame / FPS for frame in sorted(targets)]
    assert [k.score for k in found] == [frame / 1000 for frame in sorted(targets)]
    originals = list(decoded_frames(video_file))
    levels = [float(originals[k.frame].mean()) for k in found]
    assert np.round((np.array(levels) - LEVEL0) / LEVEL_STEP).astype(int).tolist() == sorted(targets)


def test_a_long_clips_known_turns_survive_the_merge_of_its_windows(tmp_path):
    """A 240-frame clip whose frame t is grey level t; the oracle marks the turns in every window
    but is wrong at the windows' edges (misses a turn within a frame of them, adds one on the first
    frame a window may mark); the merge keeps each turn once and drops the edges' mistakes."""
    turns = [11, 30, 41, 57, 70, 88, 99, 120, 131, 152, 160, 181, 195, 210, 226]
    np.save(tmp_path / "long.npy", np.broadcast_to(np.arange(240, dtype=np.uint8)[:, None, None, None], (240, 8, 8, 1)))
    (video,), _, _ = read_videos(tmp_path / "long.npy", spec(1, window_stride=4), None, None, progress=False)

    def edge_blind(clips, future_length):
        numbers = [np.round(clip.mean(dim=(1, 2, 3)).numpy() * 255).astype(int).tolist() for clip in clips]
        return [sorted({0, *(p for p, n in enumerate(row[N_COND:]) if n in turns and 1 < p < length - 3)})
                for row, length in zip(numbers, future_length.tolist())]

    found = discover_video(video, edge_blind, lambda clips, lengths: torch.ones(len(clips), N_FUTURE), N_COND,
                           N_FUTURE, frame_stride=1)
    assert len(video.starts) == 58  # starts 0, 4, …, 228
    assert [k.frame for k in found] == [N_COND, *turns]  # frame 2: the first window's own first frame


def test_every_video_gets_a_whole_folder_of_files(video_file, tmp_path):
    videos, _, _ = read_videos(video_file.parent, spec(2), {"take.mp4": EVENTS}, None, progress=False)
    summary = discover_videos(videos, *oracle({6, 16}), tmp_path, {"method": "oracle"}, N_COND, N_FUTURE, 2, 5,
                              progress=False)
    assert summary["videos"] == {"take.mp4": {"folder": "take.mp4", "keyframes": 2}} and summary["kept_frames"] == 20
    folder = tmp_path / "take.mp4"
    assert sorted(p.name for p in folder.iterdir()) == sorted(FILES)
    record = json.loads((folder / "keyframes.json").read_text())
    assert [k["frame"] for k in record["keyframes"]] == [6, 16] and record["labels"] == EVENTS
    assert record["fps"] == FPS and record["frames"] == 40 and record["first_candidate"] == 4
    assert record["windows"] == {"count": 3, "stride": 10, "starts": [0, 10, 20]}
    assert iio.imread(folder / "annotated.gif", index=None).shape[0] == 20
    for picture in ("contact_sheet.png", "timeline.png"):
        assert iio.imread(folder / picture).ndim == 3


def test_a_crash_while_writing_leaves_no_folder_and_no_temporary(video_file, tmp_path, monkeypatch):
    videos, _, _ = read_videos(video_file, spec(1), None, None, progress=False)

    def fail(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(discovered, "save_timeline", fail)  # imported by discover when it draws
    with pytest.raises(OSError):
        discover_videos(videos, *oracle(set()), tmp_path, {}, N_COND, N_FUTURE, 1, 5, progress=False)
    assert list(tmp_path.iterdir()) == []


def test_folder_names_are_safe_and_unique():
    assert folder_names(["clips.npz[frames][3]", "a b.mp4", "a?b.mp4", "..", "demos.hdf5[demo_0]"]) == [
        "clips.npz_frames_3", "a_b.mp4", "a_b.mp4-2", "video", "demos.hdf5_demo_0"]


@pytest.mark.parametrize("price", [20.0, "knee"])
def test_windows_sharing_their_videos_segment_costs_find_the_same_keyframes(tmp_path, price):
    """keyin-discover computes map's segment costs once per video for its overlapping windows: each
    window receives its own costs (brute force: computed from the window alone) and the keyframes are
    those of every window computing its own (a small untrained KEYIN, two conditioning frames, random
    frames, the last windows padded)."""
    import functools

    from keyin.decode.segment_costs import interpolation_costs
    from tests.lit.test_keyframe_teacher import keyframe_module

    module = keyframe_module(teacher_weight=0.0, offset_evidence=True, discovery="map").reader()
    np.save(tmp_path / "noise.npy", np.random.default_rng(0).integers(0, 256, (45, 8, 8, 1), dtype=np.uint8))
    n_future = module.config.n_future
    windows = ImportSpec(image_size=8, channels=1, n_cond=N_COND, n_future=n_future, frame_stride=1, window_stride=3)
    (video,), _, _ = read_videos(tmp_path / "noise.npy", windows, None, None, progress=False)
    received = []

    def discoverer(clips, future_length, costs=None):
        received.append((clips, future_length, costs))
        return module.discover(clips, future_length, keyframe_cost=price, costs=costs)

    args = (video, discoverer, module.keyframe_probabilities, N_COND, n_future, 1)
    alone = discover_video(*args, batch_size=4)
    assert all(costs is None for _, _, costs in received)
    received.clear()
    shared = discover_video(*args, batch_size=4, video_costs=module.video_costs)
    assert len(alone) > 3 and shared == alone
    model, offsets = module.model.eval(), torch.arange(1, module.model.interpolator.max_offset + 1)
    for clips, lengths, costs in received:
        own = interpolation_costs(model.interpolator, model.decoder, model.encoder(clips)[:, N_COND - 1 :],
                                  clips[:, N_COND:].flatten(2))
        for row, length in enumerate(lengths.tolist()):
            inside = torch.arange(n_future)[:, None] + offsets <= length  # (N, S): the segment ends in the window
            assert torch.equal(torch.isfinite(costs[row]), inside)
            torch.testing.assert_close(costs[row][inside], own[row][inside])


def test_map_pruned_windows_share_the_costs_of_the_segments_any_of_them_prices(tmp_path):
    """keyin-discover renders the union of the windows' pruned segments once per video: the keyframes are
    those of every window pruning and pricing its own, and each window receives the costs of its own
    segments (brute force: computed from the window alone)."""
    from keyin.decode.segment_costs import interpolation_costs
    from tests.lit.test_keyframe_teacher import keyframe_module

    module = keyframe_module(teacher_weight=0.0, offset_evidence=True, discovery="map_pruned").reader()
    np.save(tmp_path / "noise.npy", np.random.default_rng(1).integers(0, 256, (45, 8, 8, 1), dtype=np.uint8))
    n_future = module.config.n_future
    windows = ImportSpec(image_size=8, channels=1, n_cond=N_COND, n_future=n_future, frame_stride=1, window_stride=3)
    (video,), _, _ = read_videos(tmp_path / "noise.npy", windows, None, None, progress=False)
    clips = next(iter(window_batches(video, N_COND, n_future, 64)))[1]
    _, keys = module.model.eval().keyframes(clips, torch.full((len(clips),), n_future), mode="posterior", sample=False,
                                            chain="argmax")
    module.saved_prices = module.prices(candidate_logit=float(keys.boundary_scores.detach().median()))  # about half the frames are candidates
    received = []

    def discoverer(clips, future_length, costs=None):
        received.append((clips, future_length, costs))
        return module.discover(clips, future_length, keyframe_cost=20.0, costs=costs)

    rendered = []

    def video_costs(frames, keep):
        rendered.append(keep)
        return module.video_costs(frames, keep)

    args = (video, discoverer, module.keyframe_probabilities, N_COND, n_future, 1)
    alone = discover_video(*args, batch_size=4)
    received.clear()
    segments = functools.partial(module.kept_segments, discovery="map_pruned")
    shared = discover_video(*args, batch_size=4, video_costs=video_costs, segments=segments)
    assert len(alone) > 3 and shared == alone
    (union,) = rendered
    full = module.video_costs(torch.from_numpy(video.frames))
    assert (torch.isfinite(full) & ~union).any()  # the video's costs left segments out
    model = module.model
    for clips, lengths, costs in received:
        keep = segments(clips, lengths)
        own = interpolation_costs(model.interpolator, model.decoder, model.encoder(clips)[:, N_COND - 1 :],
                                  clips[:, N_COND:].flatten(2))
        torch.testing.assert_close(costs[keep], own[keep])  # each window's segments are in the union, at its own costs


def test_window_relative_pixel_weights_keep_each_windows_own_costs():
    from tests.lit.test_keyframe_teacher import keyframe_module

    module = keyframe_module(teacher_weight=0.0).reader()
    module.config = dataclasses.replace(module.config, frames=dataclasses.replace(module.config.frames, foreground_weight=20.0))  # changed pixels weigh more: relative to a window's first frame
    assert module.video_costs(torch.zeros(5, 8, 8, 1, dtype=torch.uint8)) is None


def test_segment_costs_passed_where_no_rule_reads_them_are_refused():
    from tests.lit.test_keyframe_teacher import batch, keyframe_module

    module, clips = keyframe_module(teacher_weight=0.0).reader(), batch()
    costs = torch.zeros(3, 6, 3)
    with pytest.raises(ValueError, match="reads no segment costs"):
        module.discover(clips["frames"], clips["future_length"], discovery="offsets", costs=costs)
    with pytest.raises(ValueError, match=r"\(B, N, S\)"):
        module.discover(clips["frames"], clips["future_length"], discovery="map", costs=costs[:, :5])

"""The merge of overlapping windows' keyframes: ownership against a brute-force reference, the seams,
and a long clip with known turns seen by a discoverer that is wrong at every window's edges."""

import pytest

from keyin.data.windows import window_starts
from keyin.decode.merge import WindowKeyframes, merge_windows, window_owners

N_COND, N_FUTURE = 2, 10
CLIP = N_COND + N_FUTURE


def windows_of(n_kept: int, stride: int, marks=lambda first, last: []) -> list[WindowKeyframes]:
    """The windows keyin-discover cuts from ``n_kept`` frames, each marking ``marks(first, last)``
    (kept frames of its candidate span) with score 1."""
    windows = []
    for start in window_starts(n_kept, CLIP, N_COND, stride, min_future=1):
        length = min(CLIP, n_kept - start)
        kept = marks(start + N_COND, start + length - 2)
        windows.append(WindowKeyframes(start, length, [k - start - N_COND for k in kept], [1.0] * len(kept)))
    return windows


def reference_owner(windows: list[WindowKeyframes], frame: int) -> int:
    """The owner of ``frame`` by the rule's words: the most central window holding it, the earliest on a tie."""
    best, owner = -1, -1
    for index, window in enumerate(windows):
        first, last = window.start + N_COND, window.start + window.length - 2
        if first <= frame <= last and min(frame - first, last - frame) > best:
            best, owner = min(frame - first, last - frame), index
    return owner


@pytest.mark.parametrize("n_kept, stride", [(40, 5), (41, 5), (23, 10), (60, 3), (12, 10), (37, 1)])
def test_every_frame_has_the_owner_the_rule_names(n_kept, stride):
    windows = windows_of(n_kept, stride)
    owners = window_owners(windows, N_COND)
    assert owners.tolist() == [reference_owner(windows, frame) for frame in range(n_kept)]


@pytest.mark.parametrize("stride", range(1, N_FUTURE))
def test_only_the_conditioning_frames_and_the_videos_last_frame_are_never_keyframes(stride):
    owners = window_owners(windows_of(40, stride), N_COND)
    assert owners[:N_COND].tolist() == [-1, -1] and owners[-1] == -1
    assert (owners[N_COND:-1] >= 0).all()


def test_windows_a_whole_future_apart_leave_each_windows_last_frame_to_no_one():
    owners = window_owners(windows_of(40, N_FUTURE), N_COND)
    assert (owners == -1).nonzero()[0].tolist() == [0, 1, 11, 21, 31, 39]


def test_a_window_keeps_only_the_keyframes_on_frames_it_owns():
    # two windows (starts 0 and 5) both mark kept frames 8 and 9: 8 is more central in the first, 9 in the second
    windows = [WindowKeyframes(0, CLIP, [6, 7], [0.1, 0.2]), WindowKeyframes(5, CLIP, [1, 2], [0.3, 0.4])]
    merged = merge_windows(windows, N_COND, seam=0)
    assert [(k.kept, k.window, k.score) for k in merged] == [(8, 0, 0.1), (9, 1, 0.4)]


def test_a_seam_keeps_the_higher_score_of_two_windows_a_frame_apart_and_seam_0_keeps_both():
    windows = [WindowKeyframes(0, CLIP, [6], [0.9]), WindowKeyframes(5, CLIP, [2], [0.4])]  # kept 8 (first), 9 (second)
    assert [(k.kept, k.score) for k in merge_windows(windows, N_COND, seam=1)] == [(8, 0.9)]
    assert [k.kept for k in merge_windows(windows, N_COND, seam=0)] == [8, 9]


def test_neighbours_within_one_window_are_both_kept():
    merged = merge_windows([WindowKeyframes(0, CLIP, [3, 4], [0.5, 0.6])], N_COND, seam=1)
    assert [k.kept for k in merged] == [5, 6]


TURNS = [9, 17, 23, 31, 38, 46, 52, 61, 67, 74, 83, 90, 96, 104, 111, 117]  # a 125-frame clip's known turns


def edge_blind(first: int, last: int) -> list[int]:
    """What a discoverer that is wrong at a window's edges marks in its candidate span: the true turns
    but those within a frame of either edge, and a spurious keyframe on the span's first frame."""
    inside = [turn for turn in TURNS if first + 1 < turn < last - 1]
    return sorted({first, *inside})


@pytest.mark.parametrize("stride", [4, 5])
def test_a_long_clip_recovers_its_known_turns_from_windows_wrong_at_their_edges(stride):
    windows = windows_of(125, stride, edge_blind)
    assert len(windows) > 20
    merged = merge_windows(windows, N_COND)
    assert [k.kept for k in merged] == [N_COND, *TURNS]  # the video's first candidate has no window farther in


def test_without_overlap_the_edges_mistakes_stay():
    merged = merge_windows(windows_of(125, N_FUTURE - 1, edge_blind), N_COND)  # spans that touch, no more
    assert set(TURNS) - {k.kept for k in merged}  # turns at window edges are lost: why windows overlap

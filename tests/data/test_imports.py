"""keyin-import's library side: each source format imported and read back through keyin's own
reader (ShardClips over split_files), the labels and origins of the clips, the split by video, and
bad input refused with nothing written."""

import json

import numpy as np
import pytest
from PIL import Image

from keyin.data.clips import ShardClips
from keyin.data.hdf5 import inspect_shard, read_manifest, split_files
from keyin.data.imports import ImportSpec, clip_origins, import_videos
from keyin.errors import DatasetFormatError
from tests.videos import (
    EVENTS, FPS, frame_numbers, frames, write_lerobot, write_png_folder, write_robomimic, write_video,
)

N_COND, N_FUTURE = 2, 10
SPEC = ImportSpec(image_size=16, channels=1, n_cond=N_COND, n_future=N_FUTURE)
ALL_TRAIN = {"train": 1.0}


def import_to(tmp_path, source, fractions=ALL_TRAIN, **options):
    """Import ``source`` into tmp_path/data/custom; ``options`` are ImportSpec fields or import_videos arguments."""
    spec_keys = set(ImportSpec.__dataclass_fields__)
    spec = ImportSpec(**{**SPEC.__dict__, **{k: v for k, v in options.items() if k in spec_keys}})
    rest = {k: v for k, v in options.items() if k not in spec_keys}
    folder = tmp_path / "data" / "custom"
    stats = import_videos(source, folder, "custom", spec, fractions, seed=0, shard_size=3, progress=False, **rest)
    return folder, stats


def clips(folder, split="train", image=(16, 16, 1)):
    return ShardClips(split_files(folder, split), image, N_COND, N_FUTURE)


def labels_file(tmp_path, labels):
    path = tmp_path / "labels.json"
    path.write_text(json.dumps(labels))
    return path


@pytest.mark.parametrize("stride", [1, 2])
def test_an_mp4_imports_into_clips_whose_frames_keyframes_and_origins_are_the_originals(tmp_path, stride):
    video = write_video(tmp_path / "walk.mp4", frames(40))
    folder, stats = import_to(tmp_path, video, frame_stride=stride, labels=labels_file(tmp_path, {"walk.mp4": EVENTS}))
    read, origins = clips(folder), clip_origins(folder, "train")
    kept = len(range(0, 40, stride))
    assert stats["videos"] == 1 and len(read) == len(origins) == len(range(0, kept - N_COND, N_FUTURE))
    marked = set()
    for index, origin in enumerate(origins):
        item = read[index]
        assert item["frames"].shape == (N_COND + N_FUTURE, 1, 16, 16)
        valid = N_COND + int(item["future_length"])
        shown = [origin.frame(p) for p in range(valid)]
        assert frame_numbers(item["frames"])[:valid] == shown  # the mapping names the frame the clip shows
        assert origin.video == "walk.mp4" and origin.frame_stride == stride and origin.fps == FPS
        assert origin.time(1) == pytest.approx(origin.frame(1) / FPS)
        marked |= {origin.frame(N_COND + p) for p in item["keyframes"].nonzero().flatten().tolist()}
    nearest_kept = {stride * ((e + (stride - 1) // 2) // stride) for e in EVENTS}
    assert marked == nearest_kept  # every label, through stride and windows, on the future axis


def test_a_short_video_is_one_clip_padded_with_its_last_frame(tmp_path):
    folder, _ = import_to(tmp_path, write_video(tmp_path / "short.webm", frames(8)))
    (item,) = clips(folder)
    assert int(item["future_length"]) == 6
    assert frame_numbers(item["frames"]) == [0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 7]
    assert inspect_shard(split_files(folder, "train")[0]).generator == "keyin-import"


def test_a_png_folder_imports_in_natural_frame_order_exactly(tmp_path):
    folder, _ = import_to(tmp_path, write_png_folder(tmp_path / "frames", frames(30)), channels=3)
    read = clips(folder, image=(16, 16, 3))
    assert [frame_numbers(read[i]["frames"]) for i in range(len(read))] == [list(range(12)), list(range(10, 22)),
                                                                           [*range(20, 30), 29, 29]]
    assert read_manifest(folder)["sources"][0]["fps"] is None


def test_an_npz_of_videos_is_split_by_video_never_by_window(tmp_path):
    videos = np.stack([frames(32)] * 10).astype(np.float32) / 255  # (n, T, H, W, C) in [0, 1]
    np.savez(tmp_path / "clips.npz", frames=videos)
    fractions = {"train": 0.6, "val": 0.2, "test": 0.2}
    folder, stats = import_to(tmp_path, tmp_path / "clips.npz", fractions=fractions, fps=5.0)
    sources = read_manifest(folder)["sources"]
    assert [s["id"] for s in sources] == [f"clips.npz[frames][{i}]" for i in range(10)]
    assert stats["clips"] == {"train": 18, "val": 6, "test": 6}  # 3 clips a video
    for split in fractions:
        origins = clip_origins(folder, split)
        assert {o.video for o in origins} == {s["id"] for s in sources if s["split"] == split}
        assert all(o.fps == 5.0 for o in origins)
    assert len(clips(folder, "val")) == 6


def test_a_robomimic_file_imports_each_demo_from_its_camera(tmp_path):
    path = write_robomimic(tmp_path / "demos.hdf5", [frames(20), frames(26), frames(14)], camera_key="eye")
    folder, stats = import_to(tmp_path, path, camera_key="eye", labels=labels_file(tmp_path, {"demos.hdf5[demo_1]": [3]}))
    assert [(s["id"], s["camera"]) for s in read_manifest(folder)["sources"]] == [(f"demos.hdf5[demo_{i}]", "eye") for i in range(3)]
    read, origins = clips(folder), clip_origins(folder, "train")
    assert len(read) == 2 + 3 + 2
    keyed = [(o.video, o.frame(N_COND + int(p))) for i, o in enumerate(origins) for p in read[i]["keyframes"].nonzero()]
    assert keyed == [("demos.hdf5[demo_1]", 3)]
    assert "2 video(s) have no labels" in stats["warnings"][0]


def test_a_lerobot_folder_imports_each_episode_from_the_camera_asked_for(tmp_path):
    lengths = [20, 26, 14]
    top = [frames(n) for n in lengths]
    wrist = [frames(n)[::-1].copy() for n in lengths]  # the wrist camera plays each episode backwards
    cameras = {"observation.images.top": top, "observation.images.wrist": wrist}
    root = write_lerobot(tmp_path / "pusht", cameras, fps=2 * FPS)  # info.json's rate, not the mp4 stream's
    labels = labels_file(tmp_path, {"pusht[episode_2]": [5]})
    folder, stats = import_to(tmp_path, root, camera_key="observation.images.wrist", labels=labels)
    sources = read_manifest(folder)["sources"]
    assert [s["id"] for s in sources] == [f"pusht[episode_{i}]" for i in range(3)]  # episode 2 is in chunk-001
    assert all(s["fps"] == 2 * FPS and s["camera"] == "observation.images.wrist" for s in sources)
    read, origins = clips(folder), clip_origins(folder, "train")
    assert len(read) == 2 + 3 + 2 and stats["videos"] == 3
    assert frame_numbers(read[0]["frames"]) == list(range(19, 7, -1))  # the wrist video, frame by frame
    keyed = [(o.video, o.frame(N_COND + int(p))) for i, o in enumerate(origins) for p in read[i]["keyframes"].nonzero()]
    assert keyed == [("pusht[episode_2]", 5)]


def test_a_one_camera_lerobot_folder_needs_no_camera_key_nor_episodes_jsonl(tmp_path):
    root = write_lerobot(tmp_path / "solo", {"observation.image": [frames(20), frames(30)]}, version="v2.0")
    (root / "meta" / "episodes.jsonl").unlink()  # then info.json's total_episodes lists them
    folder, stats = import_to(tmp_path, root)
    assert [s["id"] for s in read_manifest(folder)["sources"]] == ["solo[episode_0]", "solo[episode_1]"]
    assert {s["camera"] for s in read_manifest(folder)["sources"]} == {"observation.image"}  # the one it picked
    assert frame_numbers(clips(folder)[0]["frames"]) == list(range(12))


def test_a_folder_of_lerobot_folders_imports_every_episode_of_each(tmp_path):
    source = tmp_path / "datasets"
    write_lerobot(source / "b_set", {"observation.image": [frames(20)]})
    write_lerobot(source / "a_set", {"observation.image": [frames(20), frames(20)]})
    folder, _ = import_to(tmp_path, source)
    assert [s["id"] for s in read_manifest(folder)["sources"]] == ["a_set[episode_0]", "a_set[episode_1]", "b_set[episode_0]"]


def test_a_folder_of_videos_imports_each_and_skips_a_too_short_one_with_a_warning(tmp_path):
    source = tmp_path / "videos"
    source.mkdir()
    write_video(source / "b.gif", frames(15))
    write_video(source / "a.avi", frames(20))
    write_video(source / "tiny.mp4", frames(2))
    (source / "notes.txt").write_text("not a video: passed over")
    (source / "._a.avi").write_bytes(b"a hidden resource fork: passed over")
    folder, stats = import_to(tmp_path, source)
    assert [s["id"] for s in read_manifest(folder)["sources"]] == ["a.avi", "b.gif"]
    assert stats["skipped"] == 1 and "tiny.mp4 has 2 frame(s)" in stats["warnings"][0]


def test_csv_labels_give_the_same_keyframes_as_json(tmp_path):
    video = write_video(tmp_path / "walk.mp4", frames(40))
    csv = tmp_path / "labels.csv"
    csv.write_text("video,frame\n" + "".join(f"walk.mp4,{e}\n" for e in EVENTS))
    by_csv = clips(import_to(tmp_path / "csv", video, labels=csv)[0])
    by_json = clips(import_to(tmp_path / "json", video, labels=labels_file(tmp_path, {"walk.mp4": EVENTS}))[0])
    assert [by_csv[i]["keyframes"].tolist() for i in range(4)] == [by_json[i]["keyframes"].tolist() for i in range(4)]


def test_a_second_import_replaces_the_folder_only_with_overwrite(tmp_path):
    folder, _ = import_to(tmp_path, write_video(tmp_path / "a.mp4", frames(40)))
    with pytest.raises(DatasetFormatError, match="already exists; pass overwrite=true"):
        import_to(tmp_path, tmp_path / "a.mp4")
    import_to(tmp_path, tmp_path / "a.mp4", frame_stride=2, overwrite=True)
    assert len(clips(folder)) == 2
    assert sorted(p.name for p in folder.parent.iterdir()) == ["custom"]  # no temporary left


@pytest.fixture(scope="module")
def bad(tmp_path_factory):
    """A folder of bad sources and labels (and one good video for the labels)."""
    root = tmp_path_factory.mktemp("bad")
    (root / "text.mp4").write_text("this is not a video")
    good = write_video(root / "good.mp4", frames(40)).read_bytes()
    (root / "cut.mp4").write_bytes(good[: len(good) // 4])
    np.save(root / "empty.npy", np.zeros((0, 16, 16, 1), np.uint8))
    Image.fromarray(frames(1, 20, 20)[0]).save(write_png_folder(root / "mixed", frames(5)) / "frame9.png")
    np.save(root / "binary.npy", (frames(20) > 100).astype(np.uint8))
    np.save(root / "float255.npy", frames(20).astype(np.float32))
    np.save(root / "flat.npy", frames(20)[..., 0])
    np.save(root / "blank.npy", np.zeros((2, 20, 16, 16, 1), np.uint8))  # two videos, all 0
    write_robomimic(root / "demos.hdf5", [frames(20)])
    two_cameras = {"observation.images.top": [frames(20)], "observation.images.wrist": [frames(20)]}
    write_lerobot(root / "lerobot", two_cameras)
    write_lerobot(root / "lerobot_v3", {"observation.image": [frames(20)]}, version="v3.0")
    write_lerobot(root / "lerobot_gap", {"observation.image": [frames(20), frames(20)]})
    (root / "lerobot_gap/videos/chunk-000/observation.image/episode_000001.mp4").unlink()
    for name, change in (("chunks", {"chunks_size": 0}), ("features", {"features": ["observation.image"]}),
                         ("fps", {"fps": None})):
        info_path = write_lerobot(root / f"lerobot_bad_{name}", {"observation.image": [frames(20)]}) / "meta" / "info.json"
        info_path.write_text(json.dumps({**json.loads(info_path.read_text()), **change}))
    episodes = write_lerobot(root / "lerobot_twice", {"observation.image": [frames(20)]}) / "meta" / "episodes.jsonl"
    episodes.write_text(episodes.read_text() * 2)
    labels_file(root, {"good.mp4": [12, 40]}).rename(root / "past.json")
    labels_file(root, {"bad.mp4": [1]}).rename(root / "unknown.json")
    return root


# id, source, import options ({bad}: the fixture's folder), what the error says.
BAD_INPUTS = [
    ("not-a-video", "text.mp4", {}, "{bad}/text.mp4 is not a readable video"),
    ("corrupt-video", "cut.mp4", {}, "{bad}/cut.mp4 is not a readable video"),
    ("zero-frames", "empty.npy", {}, "{bad}/empty.npy has zero frames; remove it from the source"),
    ("mixed-sizes", "mixed", {}, "{bad}/mixed mixes image sizes or kinds: frame0.png is 32x24 colour, frame9.png is "
     "20x20 colour; give every frame of a video one size and kind"),
    ("uint8-0-1", "binary.npy", {}, "{bad}/binary.npy holds uint8 frames whose largest value is 1: 0/1 images look "
     "black on keyin's 0-255 scale; store them as 0/255 (frames * 255), as float in [0, 1], or pass binary=true"),
    ("float-0-255", "float255.npy", {}, "float255.npy: float frames must lie in [0, 1], but a frame holds values in [10, 10]; divide 0-255"),
    ("all-blank", "blank.npy", {}, "every video of {bad}/blank.npy is blank (e.g. {bad}/blank.npy (video blank.npy[0]) "
     "is 0 throughout); float frames in [0, 1] cast to uint8 become 0: store np.round(frames * 255).astype(np.uint8) "
     "instead, or pass videos that show something"),
    ("no-channel-axis", "flat.npy", {}, "frames are (T, H, W, C) or (n, T, H, W, C) (grey frames need their channel"),
    ("camera-key", "demos.hdf5", {"camera_key": "wrist"},
     "data/demo_0/obs has no 'wrist'; set camera_key= to the camera to import (agentview_image)"),
    ("lerobot-which-camera", "lerobot", {},
     "{bad}/lerobot has 2 cameras; pick one: camera_key=observation.images.top, camera_key=observation.images.wrist"),
    ("lerobot-camera-key", "lerobot", {"camera_key": "front"}, "{bad}/lerobot has no camera 'front'; pick one"),
    ("lerobot-v3", "lerobot_v3", {}, "{bad}/lerobot_v3/meta/info.json says codebase_version v3.0; keyin reads "
     "LeRobot's v2.0/v2.1 layout"),
    ("lerobot-missing-video", "lerobot_gap", {}, "{bad}/lerobot_gap: 1 episode video(s) for camera 'observation.image' "
     "do not exist, e.g. episode 1's {bad}/lerobot_gap/videos/chunk-000/observation.image/episode_000001.mp4"),
    ("lerobot-chunks-size", "lerobot_bad_chunks", {}, "info.json holds chunks_size=0 (a whole number >= 1); fix the file"),
    ("lerobot-features", "lerobot_bad_features", {}, "info.json holds features of type list (an object of feature name"),
    ("lerobot-fps", "lerobot_bad_fps", {}, "info.json holds fps=None (a number > 0); fix the file"),
    ("lerobot-episode-twice", "lerobot_twice", {}, "episodes.jsonl lists episode 0 more than once; keep one line per episode"),
    ("label-past-end", "good.mp4", {"labels": "past.json"},
     "{bad}/past.json: video 'good.mp4' has keyframe 40, past its end: {bad}/good.mp4 has 40 frames (0-39); fix the label"),
    ("label-unknown-video", "good.mp4", {"labels": "unknown.json"},
     "labels the video 'bad.mp4', which is not in the source (its videos: good.mp4)"),
    ("missing", "nope", {}, "source {bad}/nope does not exist; pass source="),
]


@pytest.mark.parametrize("source, options, message", [row[1:] for row in BAD_INPUTS], ids=[row[0] for row in BAD_INPUTS])
def test_a_bad_input_names_the_file_and_the_fix_and_writes_nothing(bad, tmp_path, source, options, message):
    options = {key: bad / value if key == "labels" else value for key, value in options.items()}
    with pytest.raises(DatasetFormatError) as raised:
        import_to(tmp_path, bad / source, **options)
    assert message.format(bad=bad) in str(raised.value)
    assert list(tmp_path.iterdir()) == []


def test_binary_true_scales_0_1_frames_to_0_255(tmp_path):
    videos = np.zeros((2, 40, 16, 16, 1), np.uint8)
    videos[0, :, :8] = 1  # the first video's top half is on; the second is blank, which one video of two may be
    np.save(tmp_path / "binary.npy", videos)
    folder, _ = import_to(tmp_path, tmp_path / "binary.npy", binary=True)
    first = clips(folder)[0]["frames"]
    assert float(first[..., :8, :].min()) == 1.0 and float(first[..., 8:, :].max()) == 0.0
    assert float(clips(folder)[4]["frames"].max()) == 0.0


def test_one_blank_video_is_imported_but_a_source_of_blank_videos_only_is_refused(tmp_path):
    videos = np.zeros((2, 40, 16, 16, 1), np.uint8)
    videos[0, 5:, 4:12, 4:12] = 255  # a square appears in the first video
    np.save(tmp_path / "one_blank.npy", videos)
    _, stats = import_to(tmp_path / "one", tmp_path / "one_blank.npy")
    assert stats["videos"] == 2
    np.save(tmp_path / "all_blank.npy", np.full((2, 40, 16, 16, 1), 255, np.uint8))
    with pytest.raises(DatasetFormatError, match=r"every video of .*all_blank.npy is blank \(e.g. .* is 255 throughout\)"):
        import_to(tmp_path / "all", tmp_path / "all_blank.npy")
    assert not (tmp_path / "all").exists()

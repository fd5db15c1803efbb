"""keyin-discover end to end on a smoke-sized (untrained) checkpoint: every video's files and their
shapes, frames fitted to the checkpoint's size with a note, and bad input as one error line with
nothing written but the run dir's own config."""

import json

import imageio.v3 as iio
import numpy as np
import pytest
import torch

from keyin.lit.checkpoints import STAGE_KEY
from tests.checkpoints import untrained_checkpoint
from tests.cli.runner import error_line, last_json, run
from tests.videos import EVENTS, FPS, frames, write_robomimic, write_video

SIZES = ("dataset=custom", "dataset.image_size=16", "dataset.channels=1", "dataset.n_future=10")  # n_cond 2
FILES = ["annotated.gif", "contact_sheet.png", "keyframes.json", "timeline.png"]


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    """A keyin_plus smoke checkpoint for 16x16 grey clips, two mp4s (40 and 23 frames, 24x32 RGB) and their labels."""
    root = tmp_path_factory.mktemp("discover")
    untrained_checkpoint(root / "keyin.ckpt", *SIZES, "model=keyin_plus")
    (root / "videos").mkdir()
    write_video(root / "videos" / "long.mp4", frames(40))
    write_video(root / "videos" / "short.mp4", frames(23))
    (root / "labels.json").write_text(json.dumps({"long.mp4": EVENTS}))
    return root


def written(folder):
    """What a run wrote besides Hydra's own files."""
    return sorted(p.name for p in folder.iterdir() if p.name != ".hydra" and p.suffix != ".log")


@pytest.mark.parametrize("frame_stride", [1, 2])
def test_every_video_gets_its_keyframes_json_and_pictures(root, frame_stride):
    result = run("discover", "ckpt=keyin.ckpt", "input=videos", "labels=labels.json", f"frame_stride={frame_stride}",
                 "progress=false", f"hydra.run.dir=run{frame_stride}", cwd=root)
    assert result.returncode == 0, result.stderr
    assert "note: " in result.stderr and "24x32 RGB frames are centre-cropped to 24x24, resized to 16x16 and made grey" \
        in result.stderr  # the checkpoint's size and channels, not the video's
    summary = last_json(result.stdout)
    assert summary["rule"] == "map" and summary["keyframe_cost"] == "knee" and summary["method"] == "keyin_plus"
    folder = root / f"run{frame_stride}"
    assert written(folder) == ["long.mp4", "metrics.json", "short.mp4"]
    for name, n_frames in (("long.mp4", 40), ("short.mp4", 23)):
        assert written(folder / name) == FILES
        record = json.loads((folder / name / "keyframes.json").read_text())
        assert record["frames"] == n_frames and record["fps"] == FPS and record["frame_stride"] == frame_stride
        assert record["model"]["image_size"] == 16 and record["model"]["n_cond"] == 2
        found = [k["frame"] for k in record["keyframes"]]
        assert found == sorted(set(found)) and all(record["first_candidate"] <= f < n_frames for f in found)
        assert all(f % frame_stride == 0 for f in found)
        assert [k["time"] for k in record["keyframes"]] == [pytest.approx(f / FPS) for f in found]
        assert all(0 <= k["score"] <= 1 for k in record["keyframes"])
        assert summary["videos"][name] == {"folder": name, "keyframes": len(found)}
        movie = iio.imread(folder / name / "annotated.gif", index=None)
        assert movie.shape[0] == -(-n_frames // frame_stride) and movie.shape[-1] == 3
    assert json.loads((folder / "long.mp4" / "keyframes.json").read_text())["labels"] == EVENTS


def test_without_pictures_only_keyframes_json_is_written_with_the_same_keyframes(root):
    runs = {}
    for pictures in ("true", "false"):
        result = run("discover", "ckpt=keyin.ckpt", "input=videos/long.mp4", "rule=boundaries", f"pictures={pictures}",
                     "progress=false", f"hydra.run.dir=pictures_{pictures}", cwd=root)
        assert result.returncode == 0, result.stderr
        runs[pictures] = root / f"pictures_{pictures}" / "long.mp4"
    assert written(runs["false"]) == ["keyframes.json"] and written(runs["true"]) == FILES
    found = {key: json.loads((folder / "keyframes.json").read_text())["keyframes"] for key, folder in runs.items()}
    assert found["false"] == found["true"]


def test_map_pruned_records_its_candidate_logit(root):
    result = run("discover", "ckpt=keyin.ckpt", "input=videos/long.mp4", "rule=map_pruned", "candidate_logit=-2",
                 "pictures=false", "progress=false", "hydra.run.dir=pruned", cwd=root)
    assert result.returncode == 0, result.stderr
    model = json.loads((root / "pruned" / "long.mp4" / "keyframes.json").read_text())["model"]
    assert model["rule"] == "map_pruned" and model["candidate_logit"] == -2.0 and model["keyframe_cost"] == "knee"


@pytest.fixture(scope="module")
def bad(root):
    """Bad inputs beside the good checkpoint."""
    (root / "notes.txt").write_text("not a video")
    (root / "text.mp4").write_text("not a video either")
    good = (root / "videos" / "long.mp4").read_bytes()
    (root / "cut.mp4").write_bytes(good[: len(good) // 4])
    np.save(root / "empty.npy", np.zeros((0, 16, 16, 1), np.uint8))
    np.save(root / "masks.npy", (frames(20) > 100).astype(np.uint8))
    write_robomimic(root / "masks.hdf5", [(frames(20) > 100).astype(np.uint8)])
    write_robomimic(root / "float.hdf5", [frames(20).astype(np.float32)])  # 0-255 floats
    write_robomimic(root / "blank.hdf5", [np.zeros((20, 24, 32, 3), np.uint8)] * 2)
    torch.save({STAGE_KEY: "interpolator", "state_dict": {}}, root / "stage1.ckpt")
    untrained_checkpoint(root / "paper.ckpt", *SIZES, "model=keyin")  # the paper's KEYIN: no boundary scores
    return root


BAD_INPUTS = [
    ("not-a-video", ["input=notes.txt"], "notes.txt is not a file keyin imports"),
    ("text-as-mp4", ["input=text.mp4"], "text.mp4 is not a readable video"),
    ("corrupt-mp4", ["input=cut.mp4"], "cut.mp4 is not a readable video"),
    ("zero-frames", ["input=empty.npy"], "empty.npy has zero frames; remove it from the source"),
    ("frames-0-1", ["input=masks.npy"], "masks.npy holds uint8 frames whose largest value is 1: 0/1 images look "
     "black on keyin's 0-255 scale; store them as 0/255 (frames * 255), as float in [0, 1], or pass binary=true"),
    ("hdf5-frames-0-1", ["input=masks.hdf5"], "masks.hdf5 (video masks.hdf5[demo_0]) holds uint8 frames whose largest "
     "value is 1: 0/1 images look black on keyin's 0-255 scale; store them as 0/255 (frames * 255)"),
    ("hdf5-float-0-255", ["input=float.hdf5"], "float.hdf5 (video float.hdf5[demo_0]): float frames must lie in [0, 1], "
     "but a frame holds values in [10, 10]; divide 0-255 frames by 255"),
    ("hdf5-all-blank", ["input=blank.hdf5"], "every video of blank.hdf5 is blank (e.g. blank.hdf5 (video "
     "blank.hdf5[demo_0]) is 0 throughout); float frames in [0, 1] cast to uint8 become 0: store "
     "np.round(frames * 255).astype(np.uint8) instead, or pass videos that show something"),
    ("missing-input", ["input=nope"], "input nope does not exist; pass input=<"),
    ("missing-checkpoint", ["ckpt=nope.ckpt"], "checkpoint nope.ckpt does not exist; pass the path of a keyin checkpoint"),
    ("stage-1-checkpoint", ["ckpt=stage1.ckpt"], "stage1.ckpt is a 'interpolator' checkpoint but a 'keyframes' one is needed"),
    ("no-checkpoint", ["ckpt=null"], "ckpt= is required"),
    ("window-stride", ["window_stride=10"], "window_stride=10 must be a whole number in 1..9"),
    ("keyframe-cost", ["keyframe_cost=cheap"], "keyframe_cost='cheap' must be knee (label-free), nats per keyframe"),
    ("boundaries-without-evidence", ["ckpt=paper.ckpt", "rule=boundaries"],
     "rule=boundaries needs a model with offset evidence (model=keyin_plus), which paper.ckpt has not; pass rule=map"),
    ("map-pruned-without-evidence", ["ckpt=paper.ckpt", "rule=map_pruned"],
     "rule=map_pruned needs a model with offset evidence (model=keyin_plus), which paper.ckpt has not; pass rule=map"),
    ("candidate-logit", ["candidate_logit=high"], "candidate_logit='high' must be a number (rule=map_pruned's least"),
    ("unknown-video-label", ["labels=labels.json", "input=videos/short.mp4"], "labels the video 'long.mp4', which is not"),
]


@pytest.mark.parametrize("overrides, message", [row[1:] for row in BAD_INPUTS], ids=[row[0] for row in BAD_INPUTS])
def test_bad_input_gives_one_error_line_and_writes_nothing(bad, overrides, message):
    result = run("discover", "ckpt=keyin.ckpt", "input=videos", *overrides, "progress=false", "hydra.run.dir=bad_run",
                 cwd=bad)
    assert message in error_line(result)
    assert written(bad / "bad_run") == []

"""keyin-import end to end: an imported folder of videos trains with `keyin-train dataset=custom`, and
bad input stops with one error line, nothing but the run dir written."""

import json

import numpy as np
import pytest

from keyin.data.clips import ShardClips
from keyin.data.hdf5 import split_files
from tests.cli.runner import error_line, last_json, run
from tests.videos import EVENTS, frame_numbers, frames, write_video

SIZES = ("dataset.image_size=16", "dataset.channels=1", "dataset.n_future=10")  # n_cond 2: clips of 12 frames


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    """Six labelled 40-frame mp4s imported into <root>/data/custom (0.8/0.1/0.1: 4, 1, 1 videos)."""
    root = tmp_path_factory.mktemp("import")
    (root / "videos").mkdir()
    for index in range(6):
        write_video(root / "videos" / f"take{index}.mp4", frames(40))
    (root / "labels.json").write_text(json.dumps({f"take{index}.mp4": EVENTS for index in range(6)}))
    result = run("import_videos", "source=videos", "labels=labels.json", *SIZES, "progress=false",
                 "hydra.run.dir=import_run", cwd=root)
    assert result.returncode == 0, result.stderr
    return root, last_json(result.stdout)


def test_the_import_writes_every_split_and_its_metrics(imported):
    root, metrics = imported
    assert metrics["videos"] == 6 and metrics["clips"] == {"train": 16, "val": 4, "test": 4}
    assert json.loads((root / "import_run" / "metrics.json").read_text()) == metrics
    test = ShardClips(split_files(root / "data" / "custom", "test"), (16, 16, 1), 2, 10)
    assert frame_numbers(test[0]["frames"]) == list(range(12))
    assert test[0]["keyframes"].nonzero().flatten().tolist() == [EVENTS[0] - 2]


def test_keyin_train_dataset_custom_trains_on_the_imported_folder_and_scores_its_labels(imported):
    root, _ = imported
    result = run("train", "dataset=custom", *SIZES, "scale=smoke", "logger=none", "num_workers=0",
                 "trainer.enable_progress_bar=false", "hydra.run.dir=train_run", cwd=root)
    assert result.returncode == 0, result.stderr
    metrics = last_json(result.stdout)
    assert metrics["dataset"] == "custom" and metrics["method"] == "keyin_paper"
    assert metrics["n_sequences"] == 4 and metrics["n_true"] == 1.0  # one labelled event in each test clip's future
    assert (root / "train_run" / "checkpoints" / "keyframes" / "last.ckpt").is_file()


def test_keyin_eval_scores_a_baseline_on_the_imported_test_split_per_video(imported):
    root, _ = imported
    result = run("eval", "model=random", "dataset=custom", *SIZES, "progress=false", "tolerances=[1,2]",
                 "hydra.run.dir=eval_run", cwd=root)
    assert result.returncode == 0, result.stderr
    metrics = last_json(result.stdout)
    assert metrics["n_sequences"] == 4 and {"f1_tol2", "hausdorff"} <= set(metrics)
    rows = (root / "eval_run" / "per_video.csv").read_text().splitlines()
    assert rows[0].startswith("video,clips,precision,recall") and len(rows) == 2  # the test split is one video
    sources = json.loads((root / "data" / "custom" / "manifest.json").read_text())["sources"]
    assert rows[1].split(",")[:2] == [next(s["id"] for s in sources if s["split"] == "test"), "4"]


@pytest.mark.parametrize("overrides, message", [
    (["source=videos", "labels=past.json"], "past.json: video 'take0.mp4' has keyframe 45, past its end"),
    (["source=notes.mp4"], "notes.mp4 is not a readable video"),
    ([], "source= is required"),
    (["source=videos", "fractions.test=0.5"], "fractions={'train': 0.8, 'val': 0.1, 'test': 0.5} must give each"),
    (["source=videos", "dataset.channels=2"], "dataset.channels=2 must be 1 (grey) or 3 (RGB)"),
    (["source=videos", "dataset.name=taken"], "taken already exists; pass overwrite=true"),
])
def test_bad_input_gives_one_error_line_and_no_dataset(imported, overrides, message):
    root, _ = imported
    (root / "past.json").write_text(json.dumps({"take0.mp4": [45]}))
    (root / "notes.mp4").write_text("not a video")
    (root / "data" / "taken").mkdir(exist_ok=True)
    before = sorted(p.name for p in (root / "data").iterdir())
    line = error_line(run("import_videos", *SIZES, "dataset.name=fresh", *overrides, "progress=false",
                          "hydra.run.dir=bad_run", cwd=root))
    assert message in line
    assert sorted(p.name for p in (root / "data").iterdir()) == before
    assert not (root / "bad_run" / "metrics.json").exists()


def test_other_sizes_than_the_import_name_the_sizes_it_was_imported_with(imported):
    root, _ = imported
    line = error_line(run("eval", "model=random", "dataset=custom", "progress=false", cwd=root))
    assert "image (H, W, C) (16, 16, 1) != config (64, 64, 3)" in line
    assert "pass the sizes it was imported with (dataset.image_size=16 dataset.channels=1 dataset.n_cond=2 " \
           "dataset.n_future=10) or import it again with keyin-import" in line


def test_keyin_generate_of_the_custom_dataset_points_to_keyin_import(tmp_path):
    line = error_line(run("generate", "dataset=custom", cwd=tmp_path))
    assert "dataset=custom has no generator" in line and "keyin-import source=<videos> dataset=custom" in line


def test_0_1_uint8_frames_stop_the_import_unless_binary_is_set(tmp_path):
    np.save(tmp_path / "masks.npy", (frames(20) > 100).astype(np.uint8))
    line = error_line(run("import_videos", "source=masks.npy", *SIZES, "progress=false", cwd=tmp_path))
    assert "largest value is 1: 0/1 images look black on keyin's 0-255 scale" in line and "binary=true" in line
    result = run("import_videos", "source=masks.npy", *SIZES, "binary=true", "fractions={train: 1, val: 0, test: 0}",
                 "progress=false", cwd=tmp_path)
    assert result.returncode == 0, result.stderr

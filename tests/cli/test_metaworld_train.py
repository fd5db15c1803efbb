"""dataset=metaworld end to end: a few expert demos generated (16×16 frames), then KEYIN with our
additions trained at scale=smoke and its keyframes scored on them."""

import json

from tests.cli.runner import run


def test_keyin_trains_on_a_few_generated_metaworld_demos(tmp_path):
    tiny = ("dataset=metaworld", "dataset.image_size=16")
    generated = run("generate", *tiny, "splits={train: 4, val: 2, test: 2}", "shard_size=4", "progress=false", cwd=tmp_path)
    assert generated.returncode == 0, generated.stderr
    trained = run("train", *tiny, "model=keyin_plus", "scale=smoke", "scale.batch_size=2", "scale.val_clips=2",
                  "logger=none", "trainer.enable_progress_bar=false", "hydra.run.dir=run", cwd=tmp_path)
    assert trained.returncode == 0, trained.stderr
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["dataset"] == "metaworld" and metrics["method"] == "keyin_plus" and metrics["n_sequences"] == 2
    assert 0.0 <= metrics["f1_interior"] <= 1.0

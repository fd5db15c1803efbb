"""keyin-figures end to end on smoke checkpoints: each figure's PNG and JSON, and bad input as one line."""

import json

import imageio.v3 as iio
import pytest

from tests.cli.runner import error_line, last_json, run

SMOKE = ("scale=smoke", "logger=none", "num_workers=0", "trainer.enable_progress_bar=false")
STAGE2 = "checkpoints/keyframes/last.ckpt"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Smoke runs: KEYIN and Jumpy (sharing KEYIN's stage 1) on Brownian motion, KEYIN on pushing."""
    root = tmp_path_factory.mktemp("figures")
    for data in (("splits={test: 4}",), ("dataset=pushing", "splits={train: 4, val: 2, test: 4}", "shard_size=4")):
        generated = run("generate", *data, "progress=false", cwd=root)
        assert generated.returncode == 0, generated.stderr
    jobs = {
        "keyin": ("model=keyin",),
        "jumpy": ("model=jumpy", "stage=keyframes", "interpolator_ckpt=keyin/checkpoints/interpolator/last.ckpt"),
        "pushing": ("model=keyin", "dataset=pushing", "scale.batch_size=2", "scale.val_clips=2", "scale.eval_clips=4"),
    }
    for name, overrides in jobs.items():
        trained = run("train", *SMOKE, *overrides, f"hydra.run.dir={name}", cwd=root)
        assert trained.returncode == 0, trained.stderr
    return root


def figure(root, *overrides):
    """``keyin-figures overrides... out=figures``: its printed numbers, checked against its JSON file."""
    result = run("figures", *overrides, "out=figures", "hydra.run.dir=run", cwd=root)
    assert result.returncode == 0, result.stderr
    numbers = last_json(result.stdout)
    assert json.loads((root / numbers["png"]).with_suffix(".json").read_text()) == numbers
    assert iio.imread(root / numbers["png"]).ndim == 3
    return numbers


def test_fig4_compares_keyin_and_jumpy_reconstructions_of_the_same_clips(runs):
    numbers = figure(runs, "figure=fig4", f"ckpt=keyin/{STAGE2}", f"ckpt_jumpy=jumpy/{STAGE2}", "n=2")
    assert numbers["png"] == "figures/fig4_reconstructions_brownian.png"
    assert [clip["clip"] for clip in numbers["clips"]] == [0, 1]
    assert set(numbers["summary"]) == {"keyin_paper", "jumpy"}
    jumpy = numbers["clips"][0]["jumpy"]["keyframes"]
    assert jumpy == list(range(5, 30, 6))  # Jumpy's constant offset 6 on Brownian motion
    assert 0 < numbers["clips"][0]["keyin_paper"]["psnr"] <= 100


def test_fig5_draws_k_prior_samples_per_clip_with_their_best_of_k(runs):
    numbers = figure(runs, "figure=fig5", f"ckpt=keyin/{STAGE2}", "n=2", "k=3")
    assert numbers["png"] == "figures/fig5_prior_samples_brownian.png"
    assert [len(clip["samples"]) for clip in numbers["clips"]] == [3, 3] and numbers["k"] == 3
    best = max(sample["psnr"] for sample in numbers["clips"][0]["samples"])
    assert numbers["psnr_best_of_k"] >= numbers["psnr_mean"] and best <= 100
    assert len(iio.imread(runs / "figures" / "fig5_prior_samples_brownian.gif", index=None)) == 35  # 5 + 30 frames


def test_fig6_counts_the_sides_of_sampled_and_demonstrated_trajectories(runs):
    numbers = figure(runs, "figure=fig6", f"ckpt=pushing/{STAGE2}", "trajectories=5", "demos=2", "start=1")
    assert numbers["png"] == "figures/fig6_trajectories_pushing.png" and numbers["start_clip"] == 1
    for counted, count in ((numbers["samples"], 5), (numbers["demonstrations"], 2), (numbers["test_clips"], 4)):
        assert counted["count"] == count
        assert sum(counted[side] for side in ("left", "right", "through", "none")) == pytest.approx(1.0)
    clips = numbers["test_clips"]
    assert clips["agreement"] == 1.0  # the frames show the detour the demonstrator stored
    assert clips["left"] + clips["right"] == 1.0


@pytest.mark.parametrize("mode", ["prior", "posterior"])
def test_fig7_shows_a_pushing_prediction_under_the_truth(runs, mode):
    numbers = figure(runs, "figure=fig7", f"ckpt=pushing/{STAGE2}", "n=1", f"mode={mode}", "k=2")
    assert numbers["png"] == "figures/fig7_predictions_pushing.png" and numbers["mode"] == mode
    assert numbers["k"] == (2 if mode == "prior" else 1)
    assert set(numbers["clips"][0]) == {"clip", "true_keyframes", "keyin_paper"}


@pytest.mark.parametrize(("overrides", "message"), [
    (("figure=fig5", "ckpt=keyin/checkpoints/interpolator/last.ckpt"),
     "is a 'interpolator' checkpoint but a 'keyframes' one is needed"),
    (("figure=fig6", f"ckpt=keyin/{STAGE2}"), "figure=fig6 draws the pushing scene, but ckpt= holds a model of dataset=brownian"),
    (("figure=fig4", f"ckpt=keyin/{STAGE2}"), "figure=fig4 needs ckpt_jumpy="),
    (("figure=fig4", f"ckpt=keyin/{STAGE2}", f"ckpt_jumpy=pushing/{STAGE2}"), "compare two models of one dataset and size"),
    (("figure=fig8", f"ckpt=keyin/{STAGE2}"), "figure=fig8 must be one of fig4, fig5, fig6, fig7"),
    ((f"ckpt=keyin/{STAGE2}",), "choose one with figure= one of fig4, fig5, fig6, fig7"),
    (("figure=fig6", f"ckpt=pushing/{STAGE2}", "start=4"), "start=4 must be the index of one of the 4 clips"),
    (("figure=fig7", f"ckpt=pushing/{STAGE2}", "mode=best"), "mode=best must be one of prior, posterior"),
])
def test_bad_input_gives_one_error_line_and_no_figure(runs, overrides, message):
    assert message in error_line(run("figures", *overrides, "out=bad_out", "hydra.run.dir=bad", cwd=runs))
    assert not (runs / "bad_out").exists() and not (runs / "bad" / "metrics.json").exists()

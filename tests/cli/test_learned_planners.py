"""keyin-plan with the learned planners end to end: a stage-2 checkpoint trained for a step on a few
generated pushing demos, tiny latent-CEM and servo budgets; the configs; the checkpoint errors."""

import json

import pytest
import torch
from hydra import compose, initialize_config_module
from omegaconf import OmegaConf

from keyin.cli.app import CONFIG_MODULE
from keyin.pretrained import registry
from tests.cli.runner import error_line, last_json, run

TRAIN = ("train", "dataset=pushing", "scale=smoke", "logger=none", "num_workers=0", "evaluate=false",
         "trainer.enable_progress_bar=false", "+trainer.num_sanity_val_steps=0", "scale.stage1_steps=1",
         "scale.stage2_steps=1", "scale.batch_size=2", "scale.val_clips=2", "model=keyin_plus",
         "model.keyframes.teacher_weight=0",
         "hydra.run.dir=trained")
TINY = ("planner.keyframe_samples=8", "planner.keyframe_elites=2", "planner.keyframe_iterations=1",
        "planner.servo_samples=16", "planner.elites=4", "planner.cem_iterations=1", "planner.max_timesteps=3",
        f"planner.torch_threads={torch.get_num_threads()}", "progress=false", "tasks=1")
KEYFRAMES = "trained/checkpoints/keyframes/last.ckpt"


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    root = tmp_path_factory.mktemp("learned_planners")
    generated = run("generate", "dataset=pushing", "splits={train: 4, val: 2, test: 2, planning: 1}", "progress=false",
                    cwd=root)
    assert generated.returncode == 0, generated.stderr
    trained = run(*TRAIN, cwd=root)
    assert trained.returncode == 0, trained.stderr[-3000:]
    return root


def test_keyin_plans_its_keyframes_as_subgoals(root):
    result = run("plan", "planner=keyin", f"planner.checkpoint={KEYFRAMES}", "hydra.run.dir=keyin", "seed=1",
                 "planner.model_seed=0", *TINY, cwd=root)
    assert result.returncode == 0, result.stderr[-3000:]
    metrics = last_json(result.stdout)
    assert metrics["n_tasks"] == 1 and (metrics["seed"], metrics["model_seed"]) == (1, 0)  # keyin-report's row
    (record,) = [json.loads(line) for line in (root / "keyin" / "tasks.jsonl").read_text().splitlines()]
    assert record["planner"] == "keyin_plus" and record["steps"] == 3 and record["subgoals"] == 6 + 1  # K^1..K^6, goal
    assert 0 <= record["plan_samples_without_puck"] <= 8 and 0 <= record["plan_cost_px"] <= 64 * 2**0.5
    assert len(json.loads((root / "keyin" / "plan.json").read_text())["checkpoint_sha256"]) == 64
    model = OmegaConf.load(root / "keyin" / "model_config.yaml")  # the model planned with: keyin-report names a row by it
    assert model.model.name == "keyin_plus" and (model.choices.scale, model.choices.dataset) == ("smoke", "pushing")
    assert model.choices.backbone == model.backbone.name and "hydra/launcher" not in model.choices


def test_a_shipped_model_plans_by_its_name_and_its_hash_is_recorded(root):
    result = run("plan", "planner=keyin", "planner.checkpoint=pretrained:pushing", "hydra.run.dir=shipped", *TINY, cwd=root)
    assert result.returncode == 0, result.stderr[-3000:]
    assert last_json(result.stdout)["n_tasks"] == 1
    shipped = registry()["pushing"]["sha256"]
    assert json.loads((root / "shipped" / "plan.json").read_text())["checkpoint_sha256"] == shipped
    model = OmegaConf.load(root / "shipped" / "model_config.yaml")  # trained before keyin-train recorded its choices
    assert model.model.name == "keyin_plus" and model.backbone.name == "ours" and "choices" not in model


def test_resuming_with_a_retrained_checkpoint_is_refused(root):
    checkpoint = root / "copy.ckpt"
    checkpoint.write_bytes((root / KEYFRAMES).read_bytes())
    overrides = ("planner=keyin", f"planner.checkpoint={checkpoint}", *TINY)
    assert run("plan", *overrides, "hydra.run.dir=retrained", cwd=root).returncode == 0
    checkpoint.write_bytes(checkpoint.read_bytes() + b"\0")  # another file at the same path
    assert "checkpoint_sha256=" in error_line(run("plan", *overrides, "resume=retrained", cwd=root))


@pytest.mark.parametrize("overrides,message", [
    (("planner=keyin",), "checkpoint runs/multirun/pushing_table1/keyin_plus_seed0/checkpoints/keyframes/last.ckpt "
                         "does not exist; the planner needs a model=keyin_plus dataset=pushing checkpoint: make it with "
                         "`keyin-train -m experiment=pushing_table1 model=keyin_plus seed=0`"),
    (("planner=keyin", "planner.checkpoint=trained/checkpoints/interpolator/last.ckpt"),
     "is a 'interpolator' checkpoint but a 'keyframes' one is needed"),
    (("planner=jumpy", f"planner.checkpoint={KEYFRAMES}"),
     f"{KEYFRAMES} holds a model=keyin_plus dataset=pushing checkpoint; the planner needs a model=jumpy"),
    (("planner=tap", f"planner.checkpoint={KEYFRAMES}"), "`keyin-train model=tap dataset=pushing"),
    (("planner=tap",), "checkpoint runs/pushing_tap/checkpoints/tap/last.ckpt does not exist"),
    (("planner=keyin", "planner.checkpoint=pretrained:nothing"), "no pretrained model named 'nothing'"),
    (("planner=jumpy", "planner.checkpoint=pretrained:pushing"), "holds a model=keyin_plus dataset=pushing checkpoint"),
])
def test_a_missing_or_wrong_checkpoint_gives_one_error_line(root, overrides, message):
    assert message in error_line(run("plan", *overrides, "hydra.run.dir=bad", cwd=root))


def test_jumpy_is_the_latent_cem_with_the_jumpy_model_and_table2_sweeps_the_learned_rows():
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        keyin = compose("plan", overrides=["planner=keyin"]).planner
        jumpy = compose("plan", overrides=["planner=jumpy"]).planner
        sweep = compose("plan", ["experiment=pushing_table2"], return_hydra_config=True).hydra.sweeper.params.planner
    assert jumpy.controller.subgoals._target_ == keyin.controller.subgoals._target_
    assert (jumpy.controller.subgoals.model, keyin.controller.subgoals.model) == ("jumpy", "keyin_plus")
    assert jumpy.checkpoint == "runs/multirun/pushing_table1/jumpy_seed0/checkpoints/keyframes/last.ckpt"
    assert jumpy.keyframe_samples == 200 and jumpy.keyframe_elites == 10 and jumpy.keyframe_iterations == 3
    assert {"keyin", "jumpy", "surprise", "tap"} <= set(sweep.split(","))


def test_a_latent_cem_row_is_named_after_the_model_it_plans_with():
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        rows = {
            overrides: compose("plan", overrides=["experiment=pushing_table2", *overrides, "seed=1"]).planner
            for overrides in (("planner=keyin",), ("planner=keyin", "planner.model=keyin_paper"), ("planner=jumpy",))
        }
        paper, published = (compose("train", overrides=[f"model={name}"]).model for name in ("keyin_paper", "keyin"))
    assert [planner.name for planner in rows.values()] == ["keyin_plus", "keyin_paper", "jumpy"]
    keyin_paper = rows[("planner=keyin", "planner.model=keyin_paper")]
    assert keyin_paper.checkpoint == "runs/multirun/pushing_table1/keyin_paper_seed1/checkpoints/keyframes/last.ckpt"
    assert keyin_paper.controller.subgoals.train_command.endswith("model=keyin_paper seed=1")
    assert paper == published and paper.name == "keyin_paper"  # the command it names trains the paper's model

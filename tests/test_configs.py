"""The configs: every group option and experiment composes and instantiates, ``scale=`` holds only
sizes, and every command of the old layout (tests/reference/old_commands.json, recorded before the
restructure) builds exactly the same modules under its new name."""

import itertools
import json
from pathlib import Path

import pytest
from hydra import compose, initialize_config_module
from hydra.core.hydra_config import HydraConfig
from omegaconf import OmegaConf

from keyin.cli.reproduce import sweep_overrides
from keyin.cli.app import CONFIG_MODULE
from keyin.cli.checks import SCALE_KEYS
from keyin.eval.report import STATED_CHOICES
from keyin.planning.servo import ServoParams
from tests.cli.runner import error_line, run
from tests.configs import CONFIGS, OLD_SMOKE, OLD_SMOKE_KEYIN, OLD_SMOKE_TWO_STAGES

ROOT = Path(__file__).parents[1]
OLD_COMMANDS = json.loads((Path(__file__).parent / "reference" / "old_commands.json").read_text())

# The old presets priced keyframes at 120 nats on pushing outside scale=cpu (read only by discovery=map).
OLD_PUSHING_PRICE = ("model.keyframes.map_keyframe_cost=120.0",)
OLD_CONSTANT_OFFSET = {"brownian": 6, "pushing": 4}
# keyin 0.1 froze all of stage 1 in stage 2 and fed its interpolator the soft δ on every frame model; backbone=paper
# now carries the paper's stated pair instead, LSTM_inter alone and δ̂ (docs/decisions.md, 2026-12-06).
OLD_STAGE2 = ("model.keyframes.frozen=stage1", "model.keyframes.delta_input=soft")
# keyin 0.1's teacher had no price per keyframe (outside scale=smoke) and taught interior keyframes only.
OLD_TEACHER = ("model.keyframes.teacher_keyframe_cost=0.0", "model.keyframes.teacher_leaves=false")


def new_model(scale: str, model: str) -> str:
    """The old scale=paper was the paper's method; the old cpu and smoke presets added ours to KEYIN."""
    return "keyin_plus" if model == "keyin" and scale != "paper" else model


def new_command(scale: str, dataset: str, model: str) -> list[str]:
    """The overrides that give, in the new layout, what ``scale= dataset= model=`` gave before."""
    trains_two_stages = model in ("keyin", "jumpy", "static")
    overrides = [f"scale={scale}", f"dataset={dataset}", f"model={new_model(scale, model)}"]
    if scale == "cpu" and model != "keyin":
        overrides.append("backbone=ours")  # the old cpu preset's frame model; keyin_plus picks it itself
    if scale == "smoke":
        overrides += OLD_SMOKE_KEYIN if model == "keyin" else OLD_SMOKE_TWO_STAGES if trains_two_stages else OLD_SMOKE
    if new_model(scale, model) == "keyin_plus" and scale != "smoke":
        overrides += OLD_TEACHER
    if scale != "cpu" and dataset == "pushing" and trains_two_stages:
        overrides += OLD_PUSHING_PRICE
    if trains_two_stages and "backbone=ours" not in overrides and new_model(scale, model) != "keyin_plus":
        overrides += OLD_STAGE2  # backbone=paper's stage-2 pair
    if model == "constant":  # keyin 0.1's fixed spacings; today's is chosen on validation clips
        overrides.append(f"dataset.tuned.constant_offset={OLD_CONSTANT_OFFSET[dataset]}")
    return overrides


# Options added since keyin 0.1, at the default that does what 0.1 did: module → {key: value}.
ADDED_SINCE = {
    "keyframes": {"teacher_chain": False, "teacher_leaves": False, "delta_input": "soft", "loss_reduction": "sum",
                  "frozen": "stage1", "entropy_bonus": 0.0, "entropy_bonus_steps": 0, "gumbel_offsets": False,
                  "map_candidate_logit": -4.0,  # read only by discovery=map_pruned (added 2026-12-06)
                  "interpolate_from": "predicted"},  # ours, issue 62 (added 2026-12-06)
    "interpolator": {"frozen_frames": False},
}
# Classes that moved since keyin 0.1, old path → new path.
MOVED_TARGETS = {f"keyin.eval.baselines.{name}": f"keyin.decode.baselines.{name}" for name in ("RandomKeyframes", "ConstantKeyframes")}
# Stage 2's flat keys are typed by a factory since the typed configs (issue 59).
MOVED_TARGETS["keyin.lit.keyframes.KeyframeModule"] = "keyin.lit.keyframes.KeyframeModule.from_flat"


def module_arguments(model: dict) -> dict:
    """The constructor arguments of each module a model config builds (its name aside), classes
    named where they live now, options added since at keyin 0.1's behaviour left out."""
    def today(key: str, value: dict) -> dict:
        added = ADDED_SINCE.get(key, {})
        kept = {k: v for k, v in value.items() if k not in added or v != added[k]}
        return {**kept, "_target_": MOVED_TARGETS.get(value["_target_"], value["_target_"])}

    return {key: today(key, value) if isinstance(value, dict) else value for key, value in model.items() if key != "name"}


@pytest.mark.parametrize("command", sorted(OLD_COMMANDS))
def test_every_old_command_builds_the_same_modules_under_its_new_name(command):
    old = OLD_COMMANDS[command]
    values = dict(part.split("=") for part in command.split())
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        cfg = compose("train", overrides=new_command(values["scale"], values["dataset"], values["model"]))
    model = OmegaConf.to_container(cfg.model, resolve=True)
    assert module_arguments(model) == module_arguments(old["model"])
    assert {key: cfg.scale[key] for key in old["budget"]} == old["budget"]
    assert model["name"] == {"keyin": "keyin_paper"}.get(new_model(values["scale"], values["model"]), values["model"] if values["model"] != "keyin" else "keyin_plus")


def resolve(root: str, overrides: list[str]) -> dict:
    """Compose ``root`` with ``overrides`` and resolve every interpolation outside ``hydra``, as a
    job's run dir would (``${hydra:runtime.output_dir}`` included)."""
    cfg = compose(root, overrides=overrides, return_hydra_config=True)
    cfg.hydra.runtime.output_dir = "runs/composed"
    HydraConfig.instance().set_config(cfg)
    return OmegaConf.to_container(OmegaConf.masked_copy(cfg, [key for key in cfg if key != "hydra"]), resolve=True)


def options(group: str) -> list[str]:
    return sorted(path.stem for path in (CONFIGS / group).glob("*.yaml"))


GROUPS = {
    "train": ("dataset", "backbone", "model", "loss", "trainer", "logger", "scale", "experiment"),
    "eval": ("dataset",),
    "plan": ("planner",),
    "reproduce": ("table",),
}


@pytest.mark.parametrize(
    "root, group, option",
    [(root, group, option) for root, groups in GROUPS.items() for group in groups for option in options(group)
     if not (root == "train" and option == "pushing_table2") and not (root == "plan" and group == "experiment")],
)
def test_every_group_option_composes_and_resolves(root, group, option):
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        resolve(root, [f"{group}={option}"])  # every interpolation has a value


# What each planner/low_level option gives the servo.
LOW_LEVEL = {"servo": ServoParams(), "servo_env_steps": ServoParams(action_repeat=1, max_timesteps=60, max_steps_per_subgoal=10)}


@pytest.mark.parametrize("low_level", options("planner/low_level"))
@pytest.mark.parametrize("planner", options("planner"))
def test_every_low_level_option_composes_with_every_planner(planner, low_level):
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        cfg = resolve("plan", [f"planner={planner}", f"planner/low_level@planner={low_level}"])
    assert ServoParams.from_config(cfg["planner"]) == LOW_LEVEL[low_level]


@pytest.mark.parametrize("table", options("table"))
def test_every_job_of_every_table_composes(table):
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        cfg = compose("reproduce", overrides=[f"table={table}"])
        for sweep in cfg.table.sweeps:
            if sweep.program == "export":  # python -m keyin.cli.pretrained export CKPT... --folder DIR: argv, not overrides
                args = sweep_overrides(cfg.table, sweep)
                folder, checkpoints = args[args.index("--folder") + 1], [arg for arg in args if arg.endswith(".ckpt")]
                names = [args[args.index("--name") + 1]] if "--name" in args else [Path(c).parents[2].name for c in checkpoints]
                assert sorted(sweep.creates) == sorted(f"{folder}/{name}.ckpt" for name in names)  # --name, else the run dir's
                continue
            split = (override.partition("=") for override in sweep_overrides(cfg.table, sweep) if not override.startswith("hydra."))
            # every option of every key but the seed (seeds compose alike; the experiment tests sweep them)
            choices = [[f"{key}={value}" for value in values.split(",")[: 1 if key == "seed" else None]] for key, _, values in split]
            for job in itertools.product(*choices):
                resolve(sweep.program, list(job))


@pytest.mark.parametrize("experiment", options("experiment"))
def test_every_experiment_composes_at_every_scale_and_every_job_of_its_sweep_at_the_default(experiment):
    root = "plan" if experiment == "pushing_table2" else "train"
    overrides = [f"experiment={experiment}"]
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        for scale in options("scale") if root == "train" else []:
            resolve(root, [*overrides, f"scale={scale}"])
        sweep = compose(root, overrides=overrides, return_hydra_config=True).hydra.sweeper.params or {}
        jobs = [[f"{key}={value}"] for key, values in sweep.items() for value in str(values).split(",")]
        for job in jobs or [[]]:
            resolve(root, overrides + job)


@pytest.mark.parametrize("scale", options("scale") + [f"../scale_dataset/{name}" for name in options("scale_dataset")])
def test_a_scale_preset_holds_sizes_and_budgets_only(scale):
    keys = set(OmegaConf.load(CONFIGS / "scale" / f"{scale}.yaml")) - {"defaults"}  # a preset may extend another
    assert keys <= set(SCALE_KEYS), keys - set(SCALE_KEYS)


def test_model_keyin_is_the_papers_method_at_every_scale():
    for scale in options("scale"):
        for dataset in options("dataset"):
            with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
                cfg = compose("train", overrides=[f"scale={scale}", f"dataset={dataset}", "model=keyin"])
            keyframes, interpolator = cfg.model.keyframes, cfg.model.interpolator
            assert keyframes.teacher_weight == 0 and not keyframes.offset_evidence
            assert keyframes.discovery == "offsets" and keyframes.offset_mode == "predicted"
            assert interpolator.foreground_weight == 1.0 and interpolator.norm == "batch"
            assert interpolator.step_input == "autoregressive" and interpolator.offset_min == 2


@pytest.mark.parametrize("override, now", [
    ("scale.teacher_weight=1", "model.keyframes.teacher_weight"),
    ("+scale.discovery=map", "model.keyframes.discovery"),
    ("scale.norm=group", "backbone.norm"),
    ("loss.foreground_weight=20", "backbone.foreground_weight"),
])
def test_a_method_choice_given_where_keyin_0_1_kept_it_says_where_it_lives_now(tmp_path, override, now):
    line = error_line(run("train", override, "logger=none", cwd=tmp_path))
    assert f"lives in {now} now: set {now}=... instead" in line and "scale= holds sizes and budgets only" in line


def test_pushing_irregular_is_pushing_with_irregular_timing():
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        regular = resolve("train", ["dataset=pushing", "scale=cpu"])
        irregular = resolve("train", ["dataset=pushing_irregular", "scale=cpu"])
        table = resolve("train", ["experiment=pushing_table1", "dataset=pushing_irregular"])
    timing = {"push_speed", "push_speed_spread", "min_push_frames", "max_push_frames", "max_pause_frames", "pause_speed"}
    generator = irregular["dataset"]["generator"]
    assert {key: generator[key] for key in set(generator) - timing} == {
        key: value for key, value in regular["dataset"]["generator"].items() if key not in timing
    }
    assert (generator["min_push_frames"], generator["max_push_frames"], generator["max_pause_frames"]) == (3, 9, 2)
    assert irregular["dataset"]["name"] == "pushing_irregular"  # its own data folder, data/pushing_irregular
    assert irregular["dataset"]["max_offset"] == generator["max_push_frames"] + generator["max_pause_frames"]
    assert irregular["scale"] == regular["scale"]  # scale=cpu's 64x64 pushing sizes
    assert table["dataset"]["name"] == "pushing_irregular"


# Every choice the paper states (section 4, appendix 6; docs/decisions.md, "The paper's stated configuration"):
# the config key, and the value the paper gives.
STATED = {  # every value the paper states for KEYIN on Brownian: those of every dataset, then the dataset's own
    **STATED_CHOICES,
    "model.interpolator.offset_min": 2, "model.interpolator.offset_max": 8,  # "segments of two to eight frames"
    "dataset.max_offset": 10, "dataset.n_cond": 5, "dataset.n_future": 30,
}


def test_the_stated_configuration_composes_to_every_value_the_paper_states():
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        cfg = resolve("train", ["experiment=brownian_keyin_stated"])
        paper_budget = resolve("train", ["experiment=brownian_keyin_stated", "scale.stage1_steps=100000",
                                         "scale.stage2_steps=200000"])
        paper_scale = resolve("train", ["model=keyin", "scale=paper"])  # the paper's method at the paper's scale
    for composed in (cfg, paper_budget, paper_scale):
        for key, value in STATED.items():
            node = composed
            for part in key.split("."):
                node = node[part]
            assert node == value, (key, node, value)
        assert composed["model"]["interpolator"]["latent_dim"] > 0  # "we train the interpolator in a stochastic manner"
        assert composed["model"]["interpolator"]["step_input"] == "autoregressive"
        assert composed["model"]["interpolator"]["norm"] == "batch" and not composed["model"]["interpolator"]["coord_channels"]
    assert (cfg["scale"]["stage1_steps"], cfg["scale"]["stage2_steps"]) == (10_000, 20_000)
    assert cfg["model"]["name"] == "keyin_paper_stated_10k_20k"  # the budget in the row's name
    assert (paper_budget["scale"]["stage1_steps"], paper_budget["scale"]["stage2_steps"]) == (100_000, 200_000)
    assert (paper_scale["scale"]["stage1_steps"], paper_scale["scale"]["stage2_steps"]) == (100_000, 200_000)


def test_the_stated_rows_job_configs_hold_every_value_the_paper_states():
    """The stage 1 and every published stage-2 seed of the rows README names (`keyin_paper_stated_10k_5k`, item 4's
    `keyin_paper_stated_10k_20k`), as they ran."""
    stage1 = ROOT / "docs/results/keyin_paper_stated/jobs/stated_seed0/config.yaml"
    seeds = sorted((ROOT / "docs/results/brownian_table1/jobs").glob("keyin_paper_stated_10k_5k_seed*/config.yaml"))
    assert [path.parent.name[-1] for path in seeds] == ["0", "1", "2"]  # the row's three seeds
    longer = ROOT / "docs/results/brownian_table1/jobs/keyin_paper_stated_10k_20k_seed0/config.yaml"
    for path in (stage1, *seeds, longer):
        job = OmegaConf.load(path)
        for key, value in STATED.items():
            assert OmegaConf.select(job, key) == value, (path, key, OmegaConf.select(job, key), value)
        assert job.backbone.name == "paper" and job.scale.stage1_steps == 10_000, path
    assert OmegaConf.load(stage1).model.name == "keyin_paper_stated_20k"  # the experiment's name when it ran
    # the budget in the row's name: 10k + 5k (or 20k) of the paper's 100k + 200k steps
    budgets = {path: ("keyin_paper_stated_10k_5k", 5000) for path in seeds} | {longer: ("keyin_paper_stated_10k_20k", 20_000)}
    for path, (name, steps) in budgets.items():
        job = OmegaConf.load(path)
        assert (job.model.name, job.scale.stage2_steps, job.stage) == (name, steps, "keyframes"), path


def test_our_frame_model_keeps_what_the_keyin_paper_rows_ran():
    # Table 1's keyin_paper rows ran on backbone=ours when model=keyin froze all of stage 1 and fed it the soft δ (their
    # committed job configs predate both keys): backbone=ours must compose the same pair, backbone=paper the paper's
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        ours = resolve("train", ["experiment=brownian_table1", "model=keyin_paper"])["model"]["keyframes"]
        paper = resolve("train", ["experiment=brownian_table1", "model=keyin_paper", "backbone=paper"])["model"]["keyframes"]
    assert OmegaConf.load(ROOT / "docs/results/brownian_table1/jobs/keyin_paper_seed1/config.yaml").backbone.name == "ours"
    assert (ours["frozen"], ours["delta_input"]) == ("stage1", "soft")
    assert (paper["frozen"], paper["delta_input"]) == ("lstm_inter", "argmax")

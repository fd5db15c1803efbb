"""Every model's steps, every discovery rule, keyin-discover's video path, the one-stage models' test
scores and keyin-plan's renderers on a GPU that CI does not have (tests/fake_gpu.py).

A tensor made on the CPU (``torch.zeros(n)``, ``torch.arange(n)``, ``torch.tensor(values)``, a CPU
``torch.Generator``) and mixed with the model's tensors only fails on a GPU. Here the module's
parameters and buffers, and the batch where the Trainer moves it, are :class:`tests.fake_gpu.OnGPU`
tensors: real CPU values that say ``cuda:0``, checked op by op by :class:`tests.fake_gpu.GPUCheck`,
which raises where CUDA would. Values stay real, so data-dependent code (``.item()``, ``nonzero``,
the segmentation's DP on the host) runs unchanged; the meta device would need a shim for each such
call. ``self.log`` is replaced by a check that what ``sync_dist`` reduces is on the GPU (NCCL
reduces no CPU tensor). Every rule must find the keyframes it finds on the CPU. The positive
controls put back CPU tensors of the kind the GPU fixes removed and expect the check to raise.
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import numpy as np
import pytest
import torch

import keyin.data.segments
import keyin.lit.frame_autoencoder
import keyin.lit.interpolator
from keyin.data.imports import ImportSpec, read_videos
from keyin.decode.registry import RULES, rule_named
from keyin.decode.rules import SegmentationDiscoverer
from keyin.decode.trained import KeyframeReader
from keyin.envs.segmentation import PUCK_RGB
from keyin.lit.frame_autoencoder import FrameAutoencoderModule
from keyin.pipelines.discover import discover_video
from keyin.planning.latent_cem import PriorKeyframes
from keyin.planning.surprise_cem import SurpriseRollouts
from tests.fake_gpu import DeviceMismatch, GPUCheck, batch_on_gpu, on_gpu, to_gpu
from tests.lit.tiny_models import CONV, KEYFRAMES, MODELS, N_COND, N_FUTURE, batch

STAGE2 = ("keyin_paper", "keyin_plus", "jumpy", "static")


def rgb_frame_autoencoder() -> FrameAutoencoderModule:
    """The frame autoencoder on colour frames, which also scores where it draws the puck and pusher."""
    torch.manual_seed(0)
    return FrameAutoencoderModule(**{**CONV, "channels": 3}, coord_channels=True, norm="group", n_cond=N_COND, lr=1e-3,
                                  frames_per_clip=2)


STEPPED = {**MODELS, "frame_autoencoder_rgb": rgb_frame_autoencoder}


def rgb_batch(seed: int = 0) -> dict[str, torch.Tensor]:
    """:func:`tests.lit.tiny_models.batch` in colour: its lit pixels puck-coloured, so that the
    placement scores have a puck to place."""
    clips = batch(seed=seed)
    return {**clips, "frames": clips["frames"] * torch.tensor(PUCK_RGB)[:, None, None]}


def check_logs(module: torch.nn.Module) -> list[str]:
    """Replace ``module.log``/``log_dict`` by a check that every value ``sync_dist`` reduces is on the
    GPU (a Python number is fine: Lightning makes it on the module's device); returns the logged names."""
    names = []

    def log(name: str, value: Any, *args, sync_dist: bool = False, **kwargs) -> None:
        if sync_dist and isinstance(value, torch.Tensor) and not on_gpu(value):
            raise DeviceMismatch(f"{name} is logged with sync_dist from the CPU; NCCL reduces only GPU tensors")
        names.append(name)

    module.log = log
    module.log_dict = lambda values, *args, **kwargs: [log(name, value, **kwargs) for name, value in values.items()]
    return names


def clips_of(module: torch.nn.Module, seed: int = 0) -> dict[str, torch.Tensor]:
    return rgb_batch(seed) if module.hparams.get("channels") == 3 else batch(seed=seed)


def steps_on_gpu(module: torch.nn.Module) -> tuple[torch.Tensor, list[str]]:
    """A training step and a validation step of ``module`` on the GPU, as the Trainer runs them:
    the loss and the logged names."""
    logged = check_logs(module)
    with GPUCheck():
        to_gpu(module).train()
        if hasattr(module, "on_train_batch_start"):
            module.on_train_batch_start(None, 0)
        torch.manual_seed(0)
        loss = module.training_step(batch_on_gpu(clips_of(module)), 0)
        with torch.no_grad():
            module.eval().validation_step(batch_on_gpu(clips_of(module, seed=1)), 0)
    return loss, logged


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("name", STEPPED)
def test_training_and_validation_steps_run_on_the_gpu(name):
    module = STEPPED[name]()
    loss, logged = steps_on_gpu(module)
    assert on_gpu(loss) and loss.requires_grad and torch.isfinite(loss)
    assert any(key.startswith("train/") for key in logged) and any(key.startswith("val/") for key in logged)
    assert name != "frame_autoencoder_rgb" or "val/puck_iou" in logged
    if hasattr(module, "validation_pictures"):  # the callback hands it the loader's CPU batch, plots the result
        with GPUCheck():
            shown = module.validation_pictures(batch(seed=1), 2)
        assert not any(on_gpu(value) for value in shown.values())


@pytest.mark.parametrize("name", ["tap", "frame_autoencoder", "frame_autoencoder_rgb"])
def test_keyin_train_scores_the_test_split_on_the_gpu(tmp_path, name):
    """keyin-train scores the one-stage models that find no keyframes by their ``test_metrics`` on
    ``device=``, from the test split's CPU clips."""
    module = STEPPED[name]()
    clips = clips_of(module, seed=3)
    split = [{key: value[row] for key, value in clips.items()} for row in range(len(clips["frames"]))]
    on_cpu = module.test_metrics(split, tmp_path / "cpu")
    with GPUCheck():
        on_gpu_metrics = to_gpu(module).test_metrics(split, tmp_path / "gpu")
    # the same CPU arithmetic, so equal to the bit (NaN where no object is drawn)
    assert repr(sorted(on_gpu_metrics.items())) == repr(sorted(on_cpu.items()))


def rule_discoverers() -> dict[str, tuple[str, Callable]]:
    """Test id -> (model, discoverer of a module): every rule of the registry on each stage 2 that
    has what it reads, map at the knee price, Surprise at both shifts, and stage 1's exact segmentation."""
    found = {}
    for name in STAGE2:
        evidence = name == "keyin_plus"
        for rule, decoding in RULES.items():
            if decoding.runs_on(evidence):
                found[f"{name}-{rule}"] = (name, lambda m, rule=rule: functools.partial(m.reader().discover, discovery=rule))
    found["keyin_plus-map-knee"] = ("keyin_plus", lambda m: functools.partial(m.reader().discover, discovery="map",
                                                                               keyframe_cost="knee"))
    found["surprise"] = ("surprise", lambda m: m.discover)
    found["surprise-shift0"] = ("surprise", lambda m: functools.partial(m.discover, shift=0))
    for name in ("stage1_paper", "stage1_ours"):
        found[f"{name}-segmentation"] = (name, lambda m: SegmentationDiscoverer(m, KEYFRAMES))
    return found


RULES = rule_discoverers()


@pytest.mark.parametrize("rule", RULES)
def test_every_discovery_rule_runs_on_the_gpu_and_finds_the_keyframes_it_finds_on_the_cpu(rule):
    name, discoverer = RULES[rule]
    module = MODELS[name]().eval()
    clips = batch(seed=2)
    on_cpu = discoverer(module)(clips["frames"], clips["future_length"])
    with GPUCheck():
        find = discoverer(to_gpu(module))
        assert find(clips["frames"], clips["future_length"]) == on_cpu  # the CPU batch of keyin-eval
        gpu_clips = batch_on_gpu(clips)
        assert find(gpu_clips["frames"], gpu_clips["future_length"]) == on_cpu  # the batch of a validation step
    assert any(on_cpu)


@pytest.mark.parametrize("rule", ["map", "map_pruned", "boundaries"])
def test_keyin_discover_finds_a_videos_keyframes_on_the_gpu_without_lightning(tmp_path, rule):
    """keyin-discover's path: a checkpoint's :class:`KeyframeReader` on the GPU, the video's shared
    segment costs (map), its pruned segments (map_pruned), the keyframe probabilities as scores."""
    trained = MODELS["keyin_plus"]()
    model = KeyframeReader.from_hparams(**trained.hparams)
    model.load_state_dict(trained.state_dict())
    np.save(tmp_path / "noise.npy", np.random.default_rng(0).integers(0, 256, (20, 8, 8, 1), dtype=np.uint8))
    windows = ImportSpec(image_size=8, channels=1, n_cond=N_COND, n_future=N_FUTURE, frame_stride=1, window_stride=3)
    (video,), _, _ = read_videos(tmp_path / "noise.npy", windows, None, None, progress=False)

    def keyframes() -> list:
        return discover_video(
            video, functools.partial(model.discover, discovery=rule, keyframe_cost=5.0), model.keyframe_probabilities,
            N_COND, N_FUTURE, 1, batch_size=4, video_costs=model.video_costs if rule_named(rule).reads_segment_costs else None,
            segments=functools.partial(model.kept_segments, discovery=rule) if rule_named(rule).prunes_segments else None,
        )

    on_cpu = keyframes()
    with GPUCheck():
        to_gpu(model.eval())
        assert model.device.type == "cuda"
        assert keyframes() == on_cpu
    assert on_cpu


@pytest.mark.parametrize("name", ["keyin_paper", "surprise"])
def test_keyin_plan_renders_the_planners_subgoals_on_the_gpu(name):
    """keyin-plan's latent CEM renders latents into subgoal images with the model on ``device=``:
    KEYIN's prior keyframes and Surprise's rollouts at their KL peaks, numpy in and out."""
    model = MODELS[name]().eval().model
    start = np.random.default_rng(0).integers(0, 256, (8, 8, 1), dtype=np.uint8)
    latents = np.random.default_rng(1).standard_normal((3, KEYFRAMES if name == "keyin_paper" else 4, 2))

    def renderer():
        return PriorKeyframes(model, start) if name == "keyin_paper" else SurpriseRollouts(model, start, KEYFRAMES, -1)

    on_cpu = renderer()(latents, False)
    with GPUCheck():
        to_gpu(model)
        render = renderer()
        on_gpu_images = render(latents, False), render(latents, True)
    np.testing.assert_array_equal(on_gpu_images[0], on_cpu)
    assert on_gpu_images[1].shape[:2] == (3, 1)


def test_the_check_raises_where_cuda_raises_and_only_there():
    with GPUCheck():
        weights, frames = torch.ones(3, device="cuda"), torch.zeros(2, 3)
        assert weights.device.type == "cuda" and on_gpu(weights * 2) and not on_gpu(weights.cpu())
        assert on_gpu(frames.to(weights.device) + weights) and on_gpu(weights + torch.tensor(2.0))  # a CPU scalar
        assert on_gpu(weights[torch.tensor([0, 2])]) and on_gpu(weights[torch.tensor([True, False, True])])
        weights[0:2] = torch.tensor([1.0, 2.0])  # a copy across devices
        for wrong in (
            lambda: weights + frames[0],  # a CPU vector
            lambda: torch.stack([weights[0], torch.tensor(1.0)]),
            lambda: frames[:, torch.tensor([0, 1], device="cuda")],  # a GPU index into a CPU tensor
            lambda: weights.numpy(),
            lambda: torch.rand(3, device="cuda", generator=torch.Generator()),
        ):
            with pytest.raises(DeviceMismatch):
                wrong()


class TorchForgetting:
    """The ``torch`` a keyin module imports, except that ``factory`` ignores ``device=``: the bug the
    GPU fixes removed, put back for the positive controls."""

    def __init__(self, factory: str) -> None:
        real = getattr(torch, factory)
        setattr(self, factory, lambda *args, device=None, **kwargs: real(*args, **kwargs))

    def __getattr__(self, name: str) -> Any:
        return getattr(torch, name)


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_the_check_fails_stage_1s_validation_that_logs_its_table_from_the_cpu(monkeypatch):
    monkeypatch.setattr(keyin.lit.interpolator, "torch", TorchForgetting("tensor"))
    with pytest.raises(DeviceMismatch, match="val/bce_per_frame is logged with sync_dist from the CPU"):
        steps_on_gpu(MODELS["stage1_ours"]())


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_the_check_fails_the_frame_autoencoders_draws_made_on_the_cpu(monkeypatch):
    monkeypatch.setattr(keyin.lit.frame_autoencoder, "torch", TorchForgetting("rand"))
    with pytest.raises(DeviceMismatch, match="Expected all tensors to be on the same device"):
        steps_on_gpu(MODELS["frame_autoencoder"]())


def test_the_check_fails_map_whose_segment_steps_are_made_on_the_cpu(monkeypatch):
    monkeypatch.setattr(keyin.data.segments, "torch", TorchForgetting("arange"))  # the segments' output steps
    module = MODELS["keyin_plus"]().eval()
    clips = batch(seed=2)
    with GPUCheck(), pytest.raises(DeviceMismatch, match="Expected all tensors to be on the same device"):
        to_gpu(module).reader().discover(clips["frames"], clips["future_length"], discovery="map")

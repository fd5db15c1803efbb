"""Stage-1 and stage-2 training-step time of KEYIN at a scale preset, with a profile.

    python benchmarks/train_step.py --scale cpu --steps 5
    python benchmarks/train_step.py --scale paper --steps 3
    python benchmarks/train_step.py --scale paper --dataset pushing --device cuda
    python benchmarks/train_step.py --scale cpu --model keyin_plus --precision bf16   # the forward under bf16 autocast

Builds both LightningModules from the Hydra config exactly as keyin-train does, feeds random
binary clips of the dataset's shape, and times ``training_step`` + backward + Adam (after one
warm-up step); then profiles one step of each stage and prints the top operators by self CPU time.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time
from datetime import date

import torch
from hydra import compose, initialize_config_module
from hydra.utils import instantiate
from torch.profiler import profile

from keyin.cli.app import CONFIG_MODULE


def random_batch(dataset, batch_size: int, device: torch.device) -> dict[str, torch.Tensor]:
    length = dataset.n_cond + dataset.n_future
    shape = (batch_size, length, dataset.channels, dataset.image_size, dataset.image_size)
    batch = {
        "frames": (torch.rand(shape) > 0.95).float(),
        "future_length": torch.full((batch_size,), dataset.n_future),
        "keyframes": torch.zeros(batch_size, dataset.n_future, dtype=torch.bool),
    }
    return {name: value.to(device) for name, value in batch.items()}


def synchronize(device: torch.device) -> None:
    """Wait for the GPU's queued work, so that a timer measures it."""
    if device.type == "cuda":
        torch.cuda.synchronize(device)


def one_step(module, optimizer, batch, bf16: bool = False) -> None:
    with torch.autocast(next(module.parameters()).device.type, dtype=torch.bfloat16, enabled=bf16):
        loss = module.training_step(batch, 0)
    optimizer.zero_grad()
    loss.backward()
    optimizer.step()


def time_stage(module, batch, steps: int, device: torch.device, bf16: bool = False) -> tuple[list[float], str]:
    module.log_dict = lambda *args, **kwargs: None  # no trainer attached
    module.train()
    if hasattr(module, "freeze_stage1"):
        module.freeze_stage1()
    optimizer = module.configure_optimizers()
    one_step(module, optimizer, batch, bf16)  # warm-up
    times = []
    for _ in range(steps):
        synchronize(device)
        start = time.perf_counter()
        one_step(module, optimizer, batch, bf16)
        synchronize(device)
        times.append(time.perf_counter() - start)
    with profile() as profiler:
        one_step(module, optimizer, batch, bf16)
        synchronize(device)
    sort = "self_cuda_time_total" if device.type == "cuda" else "self_cpu_time_total"
    table = profiler.key_averages().table(sort_by=sort, row_limit=8)
    return times, table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scale", default="cpu")
    parser.add_argument("--dataset", default="brownian")
    parser.add_argument("--model", default=None, help="model= override, e.g. keyin_plus (its teacher included)")
    parser.add_argument("--steps", type=int, default=5)
    parser.add_argument("--device", default="cpu", help="cpu or cuda")
    parser.add_argument("--precision", choices=("32", "bf16"), default="32",
                        help="bf16: each step's forward under bf16 autocast (as trainer.precision=bf16-mixed)")
    args = parser.parse_args()
    device = torch.device(args.device)
    torch.manual_seed(0)
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        overrides = [f"scale={args.scale}", f"dataset={args.dataset}"] + ([f"model={args.model}"] if args.model else [])
        cfg = compose("train", overrides=overrides)
    stage1 = instantiate(cfg.model.interpolator)
    stage2 = instantiate(cfg.model.keyframes, stage1=dict(stage1.hparams))
    stage2.load_stage1(stage1.state_dict())
    stage1.to(device)
    stage2.to(device)
    model = f" --model {args.model}" if args.model else ""
    print(f"## Training-step time, scale={args.scale}, dataset={args.dataset}, model={cfg.model.name}\n")
    print(f"- command: `python benchmarks/train_step.py --scale {args.scale} --dataset {args.dataset}{model} "
          f"--steps {args.steps} --device {args.device} --precision {args.precision}`")
    gpu = f", {torch.cuda.get_device_name(device)}" if device.type == "cuda" else ""
    print(f"- machine: {platform.processor() or platform.machine()}{gpu}, {torch.get_num_threads()} threads, "
          f"torch {torch.__version__}, {date.today()}; random binary clips, Adam, after 1 warm-up step\n")
    print("| stage | clips/step | median s/step | min s/step |")
    print("|---|---|---|---|")
    profiles = []
    for name, module, batch_size in (
        ("1 (interpolator)", stage1, cfg.scale.stage1_batch_size),
        ("2 (keyframes)", stage2, cfg.scale.batch_size),
    ):
        times, table = time_stage(module, random_batch(cfg.dataset, batch_size, device), args.steps, device,
                                  args.precision == "bf16")
        print(f"| {name} | {batch_size} | {statistics.median(times):.3f} | {min(times):.3f} |")
        profiles.append((name, table))
    for name, table in profiles:
        print(f"\nProfile of one stage-{name} step (self {device.type.upper()} time):\n\n```\n{table}```")


if __name__ == "__main__":
    main()

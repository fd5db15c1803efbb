"""Benchmark: vectorised soft keyframe loss vs. a per-element Python loop (paper Alg. 2).

Run from the repository root:

    PYTHONPATH=. python benchmarks/soft_loss.py

Prints a Markdown block and writes it to ``benchmarks/results/soft_loss.md``.
"""

import datetime
import os
import platform
import statistics
import subprocess
import time
from pathlib import Path

import torch

from keyin.losses.soft_keyframe import keyin_loss

SIZES = {"B": 30, "M": 6, "S": 10, "N": 30, "E": 128, "D": 32 * 32}
BETAS = {"beta_ke": 1.0, "beta_ki": 0.0, "beta_kl": 0.05}
RESULT_PATH = Path(__file__).parent / "results" / "soft_loss.md"
COMMAND = "PYTHONPATH=. python benchmarks/soft_loss.py"


def loop_loss(inputs: dict) -> dict:
    """The same loss with one Python iteration per (b, t, i, j); pixel rows stay tensors.

    Probabilities are plain Python floats, so this is forward-only.
    """
    offset_probs = inputs["offset_probs"].tolist()
    n_batch, n_keys, max_offset = inputs["offset_probs"].shape
    n_future = inputs["future_frames"].shape[1]
    n_ext = n_keys * max_offset + 1
    losses, mixed_all, c_all = [], [], []
    for b in range(n_batch):
        n_valid = int(inputs["lengths"][b])
        # D^t[k] = Σ_a δ^t[a] D^{t-1}[k - a - 1], D^0 = onehot(0).
        keyframe_pos = [[1.0] + [0.0] * (n_ext - 1)]
        for t in range(n_keys):
            keyframe_pos.append([
                sum(offset_probs[b][t][a] * keyframe_pos[t][k - a - 1]
                    for a in range(max_offset) if k - a - 1 >= 0)
                for k in range(n_ext)
            ])
        c = [sum(keyframe_pos[t + 1][1:n_valid + 1]) for t in range(n_keys)]
        key_loss = 0.0
        for t in range(n_keys):
            target = torch.zeros_like(inputs["future_emb"][b, 0])
            for j in range(n_valid):
                target = target + keyframe_pos[t + 1][j + 1] * inputs["future_emb"][b, j]
            target = target / max(c[t], 1e-6)
            key_error = float(((inputs["key_emb_pred"][b, t] - target) ** 2).sum())
            key_term = BETAS["beta_ke"] * key_error
            key_loss += c[t] * (key_term + BETAS["beta_kl"] * float(inputs["kl_per_key"][b, t]))
        key_loss /= max(sum(c), 1e-6)
        mixed = torch.zeros_like(inputs["future_frames"][b])
        coverage = [0.0] * n_future
        for t in range(n_keys):
            exists = [sum(offset_probs[b][t][i:]) for i in range(max_offset)]
            for i in range(max_offset):
                for j in range(n_future):
                    source = j - i  # extended index of p^{t-1}: (j + 1) - i - 1
                    weight = keyframe_pos[t][source] * exists[i] if source >= 0 else 0.0
                    coverage[j] += weight
                    mixed[j] += weight * inputs["inter_frames_pred"][b, t, i]
        inter_loss = 0.0
        for j in range(n_future):
            mixed[j] /= max(coverage[j], 1e-6)
            if j < n_valid:
                prob = mixed[j].clamp(1e-6, 1 - 1e-6)
                frame = inputs["future_frames"][b, j]
                inter_loss += float(-(frame * prob.log() + (1 - frame) * (1 - prob).log()).sum())
        losses.append(key_loss + inter_loss)
        mixed_all.append(mixed)
        c_all.append(c)
    return {
        "loss": sum(losses) / n_batch,
        "soft_frames": torch.stack(mixed_all),
        "c": torch.tensor(c_all, dtype=inputs["offset_probs"].dtype),
    }


def make_inputs(dtype: torch.dtype, seed: int = 0) -> dict:
    gen = torch.Generator().manual_seed(seed)
    B, M, S, N, E, D = (SIZES[k] for k in ("B", "M", "S", "N", "E", "D"))
    # Model outputs need gradients; the data (future frames and their frozen embeddings) does not.
    model_outputs = {
        "offset_logits": torch.randn(B, M, S, generator=gen, dtype=dtype),
        "key_emb_pred": torch.randn(B, M, E, generator=gen, dtype=dtype),
        "inter_frames_pred": torch.rand(B, M, S, D, generator=gen, dtype=dtype),
        "kl_per_key": torch.rand(B, M, generator=gen, dtype=dtype),
    }
    for tensor in model_outputs.values():
        tensor.requires_grad_()
    lengths = torch.full((B,), N)
    lengths[::3] = torch.randint(N // 2, N, (len(lengths[::3]),), generator=gen)
    return {
        **model_outputs,
        "future_emb": torch.randn(B, N, E, generator=gen, dtype=dtype),
        "future_frames": (torch.rand(B, N, D, generator=gen, dtype=dtype) > 0.8).to(dtype),
        "lengths": lengths,
    }


def vectorised_loss(inputs: dict) -> dict:
    args = {k: v for k, v in inputs.items() if k != "offset_logits"}
    return keyin_loss(torch.softmax(inputs["offset_logits"], -1), **args, **BETAS)


def timings(fn, repeats: int) -> tuple[float, float]:
    """(median, min) wall time in seconds; the min is the less load-sensitive of the two."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times)


def max_abs_diffs(dtype: torch.dtype) -> dict[str, float]:
    inputs = make_inputs(dtype)
    fast = vectorised_loss(inputs)
    with torch.no_grad():
        slow = loop_loss({**inputs, "offset_probs": torch.softmax(inputs["offset_logits"], -1)})
    return {
        "loss": abs(float(fast["loss"].detach()) - slow["loss"]),
        "loss_relative": abs(float(fast["loss"].detach()) - slow["loss"]) / abs(slow["loss"]),
        "soft_frames": float((fast["soft_frames"] - slow["soft_frames"]).abs().max()),
        "c": float((fast["c"] - slow["c"]).abs().max()),
    }


def machine() -> str:
    lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    model = next((line.split(":", 1)[1].strip() for line in lscpu.splitlines()
                  if line.startswith("Model name")), platform.processor())
    return f"{model}, {os.cpu_count()} logical cores (benchmark uses torch.set_num_threads(1))"


def main() -> None:
    torch.set_num_threads(1)
    diffs = {dtype: max_abs_diffs(dtype) for dtype in (torch.float64, torch.float32)}
    if max(diffs[torch.float64].values()) > 1e-9:
        raise RuntimeError(f"vectorised and loop implementations disagree: {diffs}")

    inputs = make_inputs(torch.float32)
    leaves = [v for v in inputs.values() if v.requires_grad]
    probs = torch.softmax(inputs["offset_logits"], -1).detach()

    def forward():
        with torch.no_grad():
            vectorised_loss(inputs)

    def forward_backward():
        torch.autograd.grad(vectorised_loss(inputs)["loss"], leaves)

    for _ in range(3):  # warm-up
        forward_backward()
    # Other processes share the cores: interleave the two implementations so that each round sees
    # the same load, and take the speed-up per round.
    slow_times, fast_times, speed_ups = [], [], []
    for _ in range(3):
        with torch.no_grad():
            slow_time = timings(lambda: loop_loss({**inputs, "offset_probs": probs}), 1)[1]
        fast_time = timings(forward, 10)[1]
        slow_times.append(slow_time)
        fast_times.append(fast_time)
        speed_ups.append(slow_time / fast_time)
    fast_forward_backward = timings(forward_backward, 30)
    load = Path("/proc/loadavg").read_text().split()[0] if Path("/proc/loadavg").exists() else "?"

    sizes = ", ".join(f"{k}={v}" for k, v in SIZES.items())
    lines = [
        "## Soft keyframe loss: vectorised vs. per-element loop",
        "",
        f"- command: `{COMMAND}` (from the repo root)",
        f"- machine: {machine()}; 1-min load average after the run: {load}",
        f"- torch {torch.__version__}, Python {platform.python_version()}, "
        f"{datetime.date.today().isoformat()}",
        f"- sizes: {sizes}; float32; β_ke=1, β_ki=0, β_KL=0.05; every third clip shorter than N",
        "",
        "| quantity | median | min |",
        "|---|---|---|",
        f"| loop forward (Python loops over b, t, i, j), 1 call per round "
        f"| {statistics.median(slow_times) * 1e3:.0f} ms | {min(slow_times) * 1e3:.0f} ms |",
        f"| vectorised forward, best of 10 calls per round "
        f"| {statistics.median(fast_times) * 1e3:.1f} ms | {min(fast_times) * 1e3:.1f} ms |",
        f"| **speed-up (forward), per round, 3 rounds** | **{statistics.median(speed_ups):.0f}x** "
        f"| {min(speed_ups):.0f}x (worst round) |",
        f"| vectorised forward + backward (grads of the model outputs), 30 calls "
        f"| {fast_forward_backward[0] * 1e3:.1f} ms | {fast_forward_backward[1] * 1e3:.1f} ms |",
        "",
        "| max abs diff, vectorised vs. loop | loss | soft frames | c |",
        "|---|---|---|---|",
    ]
    for dtype, diff in diffs.items():
        name = str(dtype).removeprefix("torch.")
        lines.append(
            f"| {name} | {diff['loss']:.1e} (relative {diff['loss_relative']:.1e}) "
            f"| {diff['soft_frames']:.1e} | {diff['c']:.1e} |"
        )
    report = "\n".join(lines) + "\n"
    print(report)
    RESULT_PATH.parent.mkdir(parents=True, exist_ok=True)
    RESULT_PATH.write_text(report)


if __name__ == "__main__":
    main()

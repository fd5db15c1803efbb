"""Can the paper's keyframe predictor learn each clip's true offsets when it is told them? (issue 62)

    python studies/supervised_offsets.py pretrained:brownian --arms paper evidence --steps 2000 --every 250 \
        --out docs/results/supervised_offsets/pretrained_brownian.md

A fresh stage 2 (``--overrides``; default the Table 1 rows' ``model=keyin_paper backbone=ours scale=cpu``) on the
checkpoint's stage 1 trains on the labels alone: the cross-entropy of δ^t at the labelled offsets
(``warm_start_arms.placement_loss``; no interpolator, no L_ke, no KL), Adam at ``--lr``, batch 30. Every ``--every`` steps
it scores the argmax offsets on ``--clips`` validation clips and logs the validation cross-entropy and the gradient norm
that reaches each part of the keyframe predictor (the conditioning LSTM, the inference network and its attention, LSTM_key,
the offset head). If the arm cannot fit the labels, no loss that rewards them can either. Arms:

- ``paper``: the paper's predictor: δ^t from LSTM_key's state, the clip reaching it only through z^t, the attention
  average of LSTM_inf's Gaussian parameters (eq. 1-2);
- ``unscaled``: the same with eq. 1's plain inner product (no 1/√E, no learned temperature);
- ``evidence``: ours (``keyin_plus``'s offset evidence): LSTM_inf's per-frame boundary scores added to the offset logits.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from datetime import date
from pathlib import Path

import torch
from hydra.utils import instantiate
from torch.utils.data import DataLoader

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import clip_arguments, cpu_model, publish, split_batch  # noqa: E402
from warm_start_arms import offset_scores, placement_loss, scratch_module  # noqa: E402

from keyin.checkpoints import load_checkpoint  # noqa: E402
from keyin.data.datamodule import split_clips  # noqa: E402
from keyin.lit.registry import run_config  # noqa: E402

ARMS = {  # arm → keyin-train overrides added to --overrides
    "paper": [],
    "unscaled": ["model.keyframes.attn_scale=false"],
    "evidence": ["model.keyframes.offset_evidence=true"],
}
OVERRIDES = ["model=keyin_paper", "backbone=ours", "scale=cpu"]
PARTS = {  # a column of the gradient table → the predictor's parameter-name prefixes
    "LSTM_cond": ("cond_lstm",),
    "LSTM_inf + attention": ("inference_", "attention_inv_temperature", "boundary_head"),
    "LSTM_key + K̂ head": ("key_lstm", "key_head"),
    "offset head": ("offset_head",),
}


def gradient_norms(predictor: torch.nn.Module) -> dict[str, float]:
    """The L2 norm of the current gradient over each part of :data:`PARTS` (0 where none reached it)."""
    squares = dict.fromkeys(PARTS, 0.0)
    for name, parameter in predictor.named_parameters():
        part = next((part for part, prefixes in PARTS.items() if name.startswith(prefixes)), None)
        if part is not None and parameter.grad is not None:
            squares[part] += float(parameter.grad.pow(2).sum())
    return {part: value**0.5 for part, value in squares.items()}


@torch.no_grad()
def validate(module, batch: dict) -> dict[str, float]:
    """Argmax-offset F1 (keyin-eval's ``offsets``), keyframes per clip, distinct patterns and the labels' cross-entropy
    (z at its mean)."""
    module.eval()
    out = module.model(batch["frames"], batch["future_length"], sample=False)
    return {**offset_scores(module, batch),
            "cross_entropy": placement_loss(out["offset_probs"], batch["keyframes"], batch["future_length"]).item()}


def run_arm(ckpt: str, overrides: list[str], train, val_batch: dict, steps: int, every: int, lr: float,
            batch_size: int, seed: int) -> list[dict]:
    """Train a fresh predictor on the labels alone; a row per validation (step 0 first)."""
    torch.manual_seed(seed)
    module = scratch_module(ckpt, overrides)
    optimizer = torch.optim.Adam([p for p in module.parameters() if p.requires_grad], lr=lr)
    loader = iter(DataLoader(train, batch_size=batch_size, shuffle=True, drop_last=True,
                             generator=torch.Generator().manual_seed(seed)))
    rows = []
    for step in range(steps + 1):
        module.train()
        batch = next(loader)
        out = module.model(batch["frames"], batch["future_length"], sample=True)
        loss = placement_loss(out["offset_probs"], batch["keyframes"], batch["future_length"])
        optimizer.zero_grad()
        loss.backward()
        if step % every == 0:  # measured before the step: step 0 is the untrained predictor
            rows.append({"step": step, "train_cross_entropy": loss.item(), **validate(module, val_batch),
                         "gradients": gradient_norms(module.model.predictor)})
            print(rows[-1], flush=True)
        if step < steps:
            optimizer.step()
    return rows


def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=200)
    parser.add_argument("ckpt", help="a checkpoint whose stage 1 the fresh predictors train on (e.g. pretrained:brownian)")
    parser.add_argument("--arms", nargs="+", default=list(ARMS), choices=list(ARMS))
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--every", type=int, default=250)
    parser.add_argument("--lr", type=float, default=1e-3)
    parser.add_argument("--batch-size", type=int, default=30)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--overrides", nargs="+", default=OVERRIDES,
                        help="keyin-train overrides of the fresh predictor (e.g. experiment=brownian_keyin_stated)")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    config = run_config(load_checkpoint(args.ckpt, None))
    dataset, val_batch = split_batch(config["dataset"]["name"], args.split, args.clips, args.data_dir)
    train = split_clips(dataset, instantiate(dataset.generator), "train", 100_000, args.data_dir)
    command = (f"python studies/supervised_offsets.py {args.ckpt} --arms {' '.join(args.arms)} --steps {args.steps} "
               f"--every {args.every} --lr {args.lr:g} --clips {args.clips} --seed {args.seed}"
               + (f" --overrides {' '.join(args.overrides)}" if args.overrides != OVERRIDES else ""))
    started, results = time.perf_counter(), {}
    for arm in args.arms:
        results[arm] = run_arm(args.ckpt, args.overrides + ARMS[arm], train, val_batch, args.steps, args.every, args.lr,
                               args.batch_size, args.seed)
        if args.json:  # after each arm: a stopped run keeps what it measured
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps({"command": command, "date": str(date.today()), **results}, indent=1))
    minutes = (time.perf_counter() - started) / 60
    lines = [
        f"# The keyframe predictor on the labels alone: `{args.ckpt}`",
        "",
        f"`{command}` ({len(val_batch['frames'])} {args.split} clips; {cpu_model()}, {torch.get_num_threads()} thread(s), "
        f"{date.today()}, {minutes:.0f} min). Argmax-offset F1, distinct patterns among the clips and the labels' "
        "cross-entropy (nats per clip, Σ over keyframes; z at its mean) on the validation clips; the training batch's "
        "cross-entropy and the gradient norm reaching each part of the predictor at that step.",
        "",
        "| arm | step | F1 | patterns | val CE | train CE | " + " | ".join(f"∇ {part}" for part in PARTS) + " |",
        "|---|---|---|---|---|---|" + "---|" * len(PARTS),
    ]
    for arm, rows in results.items():
        lines += [f"| {arm} | {r['step']} | {r['f1']:.3f} | {r['patterns']:.0f} | {r['cross_entropy']:.2f} | "
                  f"{r['train_cross_entropy']:.2f} | " + " | ".join(f"{r['gradients'][part]:.1e}" for part in PARTS) + " |"
                  for r in rows]
    publish("\n".join(lines) + "\n", args.out)


if __name__ == "__main__":
    main()

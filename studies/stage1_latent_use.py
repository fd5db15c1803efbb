"""How much does a stochastic stage 1 interpolate through its latent, and what is left when stage 2 draws it from the
prior? (issue 62)

    python studies/stage1_latent_use.py <stage-1 checkpoint> --clips 30 \
        --out docs/results/stated_stage1_latent/step4500.md
    python studies/stage1_latent_use.py <stage-1 checkpoint> --kl-weight 1.024 --steps 1000 --every 250 ...

The paper trains the interpolator "in a stochastic manner, similarly to a seq2seq VAE" with a KL weight of 1e-3, and
samples its latent "from the prior when training the keyframe predictor". It does not say what the 1e-3 weighs against.
keyin sums the image BCE over pixels and frames; against a BCE averaged per pixel (SVG's convention for its image
term) the same weight is C·H·W times stronger. This study scores stage 1 on validation clips, cut into segments as stage 1
trains (offsets ``offset_min``..``offset_max``): the BCE per frame with the latent from the posterior (what stage 1
trains on), from the prior (what stage 2 reads) and at the prior's mean, in train mode (batch statistics), eval mode
(BatchNorm's running statistics) and eval mode with the decoder alone in train mode, and the KL per segment. With
``--steps`` it first goes on training stage 1 from the checkpoint with another KL weight (Adam at the checkpoint's lr,
fresh moments) and scores it every ``--every`` steps.
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
from common import clip_arguments, cpu_model, publish, split_batch  # noqa: E402

from keyin.data.datamodule import split_clips  # noqa: E402
from keyin.data.segments import partition_segments  # noqa: E402
from keyin.lit.registry import load_trained_module  # noqa: E402

LATENTS = ("posterior", "prior", "mean")
# train: batch statistics everywhere; eval: BatchNorm's running statistics everywhere; decoder_train: eval mode but the
# decoder's batch statistics (its running statistics are what it saw most, which need not be interpolated frames)
MODES = ("train", "eval", "decoder_train")


@torch.no_grad()
def latent_use(module, batch: dict) -> dict[str, float]:
    """BCE per frame for every (mode, latent) of :data:`MODES` × :data:`LATENTS`, and the posterior's KL per segment,
    on ``batch``'s clips cut into stage-1 segments (the same cut, seed 0, for every entry)."""
    clips, hp, was = batch["frames"], module.hparams, module.training
    lengths = hp.n_cond + batch["future_length"]
    segments = partition_segments(lengths, hp.offset_min, hp.offset_max, torch.Generator().manual_seed(0))
    weights = module.pixel_weights(clips)
    running = {name: buffer.clone() for name, buffer in module.named_buffers()}  # train mode would update BatchNorm's
    row = {}
    for mode in MODES:
        module.train(mode == "train")
        module.decoder.train(mode != "eval")
        embeddings = module.encoder(clips)
        for latent in LATENTS:
            torch.manual_seed(0)
            bce, count, kl = module.segment_bce(clips, weights, embeddings, segments, latent)
            row[f"{mode}_{latent}"] = (bce.sum() / count.sum()).item()
            if latent == "posterior":
                row[f"{mode}_kl"] = kl.mean().item()
        for name, buffer in module.named_buffers():
            buffer.copy_(running[name])
    module.train(was)
    return row


def go_on_training(module, train, batch: dict, kl_weight: float, steps: int, every: int, batch_size: int) -> list[dict]:
    """Stage 1 trained ``steps`` more steps with ``kl_weight`` (the checkpoint's loss otherwise), scored every ``every``."""
    module.hparams.kl_weight = kl_weight
    module.log_dict = lambda *args, **kwargs: None  # no trainer here: training_step's logging goes nowhere
    optimizer = torch.optim.Adam([p for p in module.parameters() if p.requires_grad], lr=module.hparams.lr, betas=(0.9, 0.999))
    loader = iter(DataLoader(train, batch_size=batch_size, shuffle=True, generator=torch.Generator().manual_seed(0), drop_last=True))
    rows = [{"step": 0, **latent_use(module, batch)}]
    print(rows[-1], flush=True)
    module.train()
    for step in range(1, steps + 1):
        loss = module.training_step(next(loader), step)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        if step % every == 0:
            rows.append({"step": step, **latent_use(module, batch)})
            print(rows[-1], flush=True)
    return rows


def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=30)
    parser.add_argument("ckpt", help="a stage-1 checkpoint")
    parser.add_argument("--kl-weight", type=float, help="go on training with this KL weight (default: only score)")
    parser.add_argument("--steps", type=int, default=0)
    parser.add_argument("--every", type=int, default=250)
    parser.add_argument("--batch-size", type=int, default=30)
    parser.add_argument("--json", type=Path)
    parser.add_argument("--save", type=Path, help="with --steps: write the trained-on stage 1 here, as a stage-1 checkpoint")
    args = parser.parse_args()
    if args.steps and args.kl_weight is None:
        parser.error("--steps trains stage 1 on: give the KL weight it trains with, --kl-weight W")
    torch.manual_seed(0)
    module, config = load_trained_module(args.ckpt, "interpolator")
    dataset, batch = split_batch(config["dataset"]["name"], args.split, args.clips, args.data_dir)
    started, trained_at = time.perf_counter(), module.hparams.kl_weight
    if args.steps:
        train = split_clips(dataset, instantiate(dataset.generator), "train", 100_000, args.data_dir)
        rows = go_on_training(module, train, batch, args.kl_weight, args.steps, args.every, args.batch_size)
        if args.save:  # the checkpoint's own format, its weights and KL weight replaced (studies/paper_loss_truth.py reads it)
            checkpoint = torch.load(args.ckpt, map_location="cpu", weights_only=False)
            checkpoint["state_dict"] = module.state_dict()
            checkpoint["hyper_parameters"]["kl_weight"] = args.kl_weight
            checkpoint["global_step"] += args.steps
            checkpoint.pop("optimizer_states", None)
            args.save.parent.mkdir(parents=True, exist_ok=True)
            torch.save(checkpoint, args.save)
    else:
        rows = [{"step": 0, **latent_use(module, batch)}]
    minutes = (time.perf_counter() - started) / 60
    command = f"python studies/stage1_latent_use.py {args.ckpt} --clips {args.clips}" + (
        f" --kl-weight {args.kl_weight} --steps {args.steps} --every {args.every}" if args.steps else "")
    lines = [
        f"# How much stage 1 interpolates through its latent: `{args.ckpt}`",
        "",
        f"`{command}` ({len(batch['frames'])} {args.split} clips cut into stage-1 segments of {module.hparams.offset_min}-"
        f"{module.hparams.offset_max} frames; trained with KL weight {trained_at:g}"
        + (f", then {args.steps} steps at {args.kl_weight:g}" if args.steps else "")
        + f"; {cpu_model()}, {torch.get_num_threads()} thread(s), {date.today()}, {minutes:.0f} min). BCE per frame "
        "(nats, summed over pixels) with the interpolator's latent from the posterior, the prior, the prior's mean; "
        "train mode (batch statistics), eval mode (BatchNorm's running statistics) and eval mode but the decoder's batch "
        "statistics; the posterior's KL per segment.",
        "",
        "| step | train: posterior | prior | mean | KL | eval: posterior | prior | mean | KL | eval, decoder train: posterior | prior | mean | KL |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    lines += [f"| {r['step']} | " + " | ".join(f"{r[f'{m}_{k}']:.1f}" for m in MODES for k in (*LATENTS, "kl")) + " |"
              for r in rows]
    publish("\n".join(lines) + "\n", args.out)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"command": command, "date": str(date.today()), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()

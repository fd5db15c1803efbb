"""Why a stage 2 finds (or misses) the keyframes: its interpolation loss under other offsets, its gradient, its keyframes.

    python studies/stage2_diagnostics.py runs/<run>/checkpoints/keyframes/last.ckpt --clips 200 \
        --out docs/results/paper_stage2_grid/diagnostics/<arm>.md

On the first ``--clips`` clips of a split (default: validation), with the posterior mean of the keyframe
latents, reports:

* ``L_inter`` (nats per clip, the loss's own reduction "sum") of four offset patterns, each once with
  the model's keyframe embeddings K̂ and once with the embeddings of the true frames at the pattern's
  keyframe positions: the model's soft δ (as the interpolator reads it in training, ``delta_input``),
  its argmax one-hot, the Constant pattern (every ``--constant`` frames) and the true offsets (the
  labelled keyframes, then the keyframe that leaves the clip, then offsets of S);
* the fraction of clips whose own loss gradient on keyframe 1's offset logits raises the probability
  of its true offset (chance: 1/S), at the model's training loss;
* ``‖K̂ − e(frame)‖²`` between each keyframe embedding and the embedding of the frame its argmax offsets
  place it at (beside the mean distance of two neighbouring frames' embeddings);
* the keyframe KL (summed over Zk, mean over keyframes), δ's entropy, the distinct argmax patterns
  and the argmax-offset F1 of these clips.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from datetime import date
from pathlib import Path

import torch
import torch.nn.functional as F

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
from common import clip_arguments, cpu_model, publish, split_batch  # noqa: E402
from keyin.decode.offsets import offset_keyframes  # noqa: E402
from keyin.decode.segmentation import segmentation_offsets  # noqa: E402
from keyin.eval.f1 import keyframe_lists, keyframe_scores  # noqa: E402
from keyin.lit.registry import load_training_module  # noqa: E402
from keyin.losses.image import future_pixel_weights  # noqa: E402
from keyin.losses.soft_keyframe import interpolation_loss, offset_entropy  # noqa: E402
from keyin.models.distributions import gaussian_kl  # noqa: E402
from keyin.models.positions import argmax_positions, position_distributions  # noqa: E402


def true_offsets(keyframes: torch.Tensor, lengths: torch.Tensor, n_keyframes: int, max_offset: int) -> torch.Tensor:
    """(B, M) offsets of the labelled keyframes, then of the one leaving the clip, the rest S."""
    offsets = segmentation_offsets(keyframe_lists(keyframes), lengths.tolist(), n_keyframes, max_offset, leave=True)
    return torch.where(offsets > 0, offsets, torch.full_like(offsets, max_offset))


def frame_embeddings_at(boundary_emb: torch.Tensor, offsets: torch.Tensor) -> torch.Tensor:
    """(B, M, E) embeddings of the frames that (B, M) offsets place the keyframes at (the last frame
    for positions past the clip), from (B, N + 1, E) embeddings on the extended index."""
    extended = offsets.cumsum(-1).clamp(max=boundary_emb.shape[1] - 1)  # (B, M) extended index of each keyframe
    return boundary_emb.gather(1, extended[..., None].expand(-1, -1, boundary_emb.shape[-1]))


def pattern_losses(model, batch: dict, out: dict, offsets: torch.Tensor, pixel_weights, n_cond: int) -> dict[str, float]:
    """Mean L_inter of hard ``offsets`` (B, M) with the model's K̂ and with the true frames' embeddings."""
    clips, lengths = batch["frames"], batch["future_length"]
    onehot = F.one_hot(offsets - 1, out["offset_probs"].shape[-1]).float()  # (B, M, S)
    _, frame_pos = position_distributions(onehot)
    first = out["boundary_emb"][:, 0]
    result = {}
    for name, key_emb in (("model K̂", out["key_emb"]), ("true frames", frame_embeddings_at(out["boundary_emb"], offsets))):
        frames = model.interpolate(first, key_emb, onehot)
        loss, _, _ = interpolation_loss(frame_pos, frames, clips[:, n_cond:].flatten(2), lengths, pixel_weights)
        result[name] = loss.mean().item()
    return result


def gradient_raises_true_offset(module, batch: dict, first_offset: torch.Tensor) -> float:
    """Fraction of clips whose own training loss, differentiated by keyframe 1's offset logits, raises
    the log-probability of its true offset (a step against the gradient g raises log p_a by
    η (Σ_b p_b g_b − g_a))."""
    clips, lengths = batch["frames"], batch["future_length"]
    out = module.model(clips, lengths, sample=False)
    out["offset_logits"].retain_grad()
    (module.soft_loss(clips, lengths, out)["loss"] * clips.shape[0]).backward()  # the mean's gradient × B: each clip's own loss gradient
    grad, probs = out["offset_logits"].grad[:, 0], out["offset_probs"][:, 0].detach()  # (B, S)
    rise = (probs * grad).sum(-1) - grad.gather(1, first_offset[:, None] - 1).squeeze(1)
    return (rise > 0).float().mean().item()


def diagnose(module, batch: dict, constant: int) -> dict[str, float]:
    model, config = module.model, module.config
    n_cond, n_keys, max_offset = model.n_cond, config.predictor.n_keyframes, config.max_offset
    clips, lengths = batch["frames"], batch["future_length"]
    pixel_weights = future_pixel_weights(module.reader().pixel_weights(clips), n_cond)
    truth = true_offsets(batch["keyframes"], lengths, n_keys, max_offset)
    result: dict[str, float] = {}
    with torch.no_grad():
        out = model(clips, lengths, sample=False)
        probs = out["offset_probs"]
        _, frame_pos = position_distributions(probs)  # out["frames"]: interpolated as training reads δ (delta_input)
        loss, _, _ = interpolation_loss(frame_pos, out["frames"], clips[:, n_cond:].flatten(2), lengths, pixel_weights)
        result["L_inter soft δ"] = loss.mean().item()
        patterns = {
            "argmax δ": probs.argmax(-1) + 1,
            f"Constant-{constant}": torch.full_like(truth, constant),
            "true offsets": truth,
        }
        for name, offsets in patterns.items():
            for embeddings, value in pattern_losses(model, batch, out, offsets, pixel_weights, n_cond).items():
                result[f"L_inter {name}, {embeddings}"] = value
        inside = argmax_positions(probs) < lengths[:, None]
        placed = frame_embeddings_at(out["boundary_emb"], probs.argmax(-1) + 1)
        distance = ((out["key_emb"] - placed) ** 2).sum(-1)  # (B, M)
        result["‖K̂ − e(frame)‖², keyframes inside"] = distance[inside].mean().item()
        neighbours = ((out["future_emb"][:, 1:] - out["future_emb"][:, :-1]) ** 2).sum(-1)  # (B, N - 1)
        result["‖e(I_j+1) − e(I_j)‖², neighbours"] = neighbours.mean().item()
        result["keyframe KL (nats, Σ over Zk)"] = gaussian_kl(out["mu"], out["log_sigma"]).mean().item()
        result["δ entropy (nats)"] = offset_entropy(probs).mean().item()
        found = offset_keyframes(probs, lengths)
        result["distinct argmax patterns"] = float(len({tuple(row) for row in found}))
        result["argmax-offset F1"] = keyframe_scores(found, keyframe_lists(batch["keyframes"]), clips.shape[1] - n_cond)["f1"]
    with torch.enable_grad():
        result["clips whose gradient raises keyframe 1's true offset"] = gradient_raises_true_offset(module, batch, truth[:, 0])
    result["chance (1/S)"] = 1.0 / max_offset
    return result


def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=200)
    parser.add_argument("ckpt", help="a stage-2 (keyframes) checkpoint")
    parser.add_argument("--constant", type=int, default=None, help="Constant's spacing (default: the dataset's)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    torch.manual_seed(args.seed)
    module, config = load_training_module(args.ckpt)
    dataset, batch = split_batch(config["dataset"]["name"], args.split, args.clips, args.data_dir)
    constant = args.constant or dataset.tuned.constant_offset
    started = time.perf_counter()
    result = diagnose(module, batch, constant)
    seconds = time.perf_counter() - started
    hp = module.hparams  # typed since issue 59: net, loss, optimizer
    options = {"delta_input": hp.net["delta_input"], "loss_reduction": hp.loss["reduction"],
               "attn_scale": hp.net["predictor"]["attn_scale"], "normalize_key_targets": hp.loss["normalize_key_targets"],
               "entropy_bonus": hp.loss["entropy_bonus"], "lr": hp.optimizer.get("lr")}
    lines = [
        f"# Stage-2 diagnostics: {args.ckpt}",
        "",
        f"`python studies/stage2_diagnostics.py {args.ckpt} --clips {args.clips} --split {args.split}` "
        f"({len(batch['frames'])} {args.split} clips of {dataset.name}; {cpu_model()}, {torch.get_num_threads()} thread(s), "
        f"{date.today()}, {seconds:.1f} s). Options: {json.dumps(options)}.",
        "",
        "| measure | value |",
        "|---|---|",
        *(f"| {name} | {value:.4g} |" for name, value in result.items()),
        "",
        "```json",
        json.dumps({"ckpt": str(args.ckpt), "options": options, **result}, ensure_ascii=False),
        "```",
    ]
    publish("\n".join(lines) + "\n", args.out)


if __name__ == "__main__":
    main()

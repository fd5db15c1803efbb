"""Does the paper's stage-2 loss (eq. 3-5) hold the true keyframes, reading by reading? (issue 62)

    python studies/paper_loss_truth.py pretrained:brownian --clips 64 --steps 300 \
        --out docs/results/paper_loss_truth/pretrained_brownian.md

The keyframe predictor is replaced by free parameters per clip, the offset logits θ (B, M, S) and the
keyframe embeddings K̂ (B, M, E), so that only the objective and the frozen stage 1 of ``ckpt`` are
left (a stage-1 or stage-2 checkpoint, or ``pretrained:<name>``). For each reading of eq. 3-5:

1. hard corners: each term at the true offsets and at the collapsed pattern (every ``--constant``
   frames), K̂ the embeddings of the true frames at the pattern's keyframes;
2. the gradient of each term on θ at the softened truth (p = 0.9 on each true offset): the share of
   the labelled keyframes whose descent step raises its true offset's log-probability;
3. descent: Adam on (θ, K̂) from the truth and from the collapsed pattern; the argmax offsets' F1,
   interior keyframes per clip, distinct patterns and each term along the way. K̂ is either free
   ("free", as the predictor's embedding head is) or tied to its soft target K̃^e(δ) ("tied": the
   keyframes follow δ exactly and L_ke = 0).

With ``--exact-slots``, also (issue 62 item 3d) the descents with M equal to each clip's labelled keyframes plus the
one leaving the clip, clips grouped by their count: no spare keyframe slot, so L_inter cannot buy extra keyframes.

Also stage 1's interpolation cost per frame of straight segments (no turn inside) by their length. The frame networks
normalise by their running statistics (eval mode), or with ``--batch-statistics`` by each call's batch, as in a stage 2
that trains them (the stated configuration freezes only LSTM_inter; its stage 1 decoded in two calls a step, so its
running statistics fit neither: docs/decisions.md, "One decoder batch a step").
The keyframe KL of eq. 3 is left out: without a predictor there is no posterior.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import asdict, dataclass, replace
from datetime import date
from pathlib import Path
from typing import Any

import torch
import torch.nn.functional as F
from torch import Tensor

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
from common import clip_arguments, cpu_model, publish, split_batch  # noqa: E402
from stage2_diagnostics import frame_embeddings_at, true_offsets  # noqa: E402

from keyin.decode.offsets import offset_keyframes  # noqa: E402
from keyin.decode.segment_costs import interpolation_costs  # noqa: E402
from keyin.eval.f1 import keyframe_lists, keyframe_scores  # noqa: E402
from keyin.lit.registry import load_trained_module  # noqa: E402
from keyin.losses.soft_keyframe import bce_sum, in_sequence_probs  # noqa: E402
from keyin.models.keyin import interpolator_offsets  # noqa: E402
from keyin.models.positions import (  # noqa: E402
    PROB_EPS, future_window, position_distributions, soft_keyframe_targets, valid_frame_mask,
)


@dataclass(frozen=True)
class Reading:
    """One reading of eq. 3-5 (the paper's sentence it follows in ``text``)."""

    name: str
    text: str
    delta_input: str = "soft"  # what the interpolator reads of δ: soft | argmax | straight_through
    mixture: str = "normalized"  # Ĩ_j: normalized (eq. 4's text) | unnormalized (Alg. 2) | expected (E[error], ours)
    error: str = "bce"  # bce | squared (Alg. 2: ‖I_j − Ĩ_j‖²)
    reduction: str = "sum"  # sum over pixels and frames | mean: every term a mean per scalar
    normalize_key_targets: bool = True  # K̃ divided by c^t


READINGS = (
    Reading("implemented", "keyin's keyin_paper row: soft δ to the interpolator, Ĩ_j / Σ δ̃, BCE summed, K̃ / c^t"),
    Reading("argmax_delta", "Init_inter reads δ̂ = argmax δ (section 3.1)", delta_input="argmax"),
    Reading("straight_through", "δ̂ forward, δ's gradient backward", delta_input="straight_through"),
    Reading("unnormalized_mixture", "Alg. 2: Ĩ_j = Σ δ̃_ij Î_i, no division", mixture="unnormalized"),
    Reading("unnormalized_targets", "Alg. 2: K̃ = Σ δ̃_j I_j, no division by c^t", normalize_key_targets=False),
    Reading("squared_error", "Alg. 2: ‖I_j − Ĩ_j‖², summed", error="squared"),
    Reading("squared_error_mean", "‖I_j − Ĩ_j‖² as a mean per pixel (every term a mean)", error="squared", reduction="mean"),
    Reading("bce_mean", "BCE as a mean per pixel (every term a mean)", reduction="mean"),
    Reading("expected_bce", "not the paper's: Σ δ̃ BCE(I_j, Î_i) instead of BCE(I_j, Σ δ̃ Î_i)", mixture="expected"),
    Reading("expected_bce_argmax", "not the paper's: expected BCE, δ̂ to the interpolator", delta_input="argmax", mixture="expected"),
)


@dataclass
class Clips:
    """What every loss evaluation needs of the clips (fixed: stage 1 is frozen)."""

    first: Tensor  # (B, E) K^{e,0}
    boundary_emb: Tensor  # (B, N + 1, E) embeddings on the extended index
    future_emb: Tensor  # (B, N, E)
    future: Tensor  # (B, N, D) frames in [0, 1]
    lengths: Tensor  # (B,)
    truth: list[list[int]]  # labelled keyframes per clip


def subset(clips: Clips, index: list[int]) -> Clips:
    """The clips at ``index``."""
    rows = torch.tensor(index)
    tensors = {name: getattr(clips, name)[rows] for name in ("first", "boundary_emb", "future_emb", "future", "lengths")}
    return replace(clips, **tensors, truth=[clips.truth[i] for i in index])


class Stage1:
    """The frozen encoder, decoder and interpolator of a checkpoint (stage 1 or stage 2)."""

    def __init__(self, module: Any, batch_statistics: bool = False) -> None:
        holder = getattr(module, "model", module)
        self.encoder, self.decoder, self.interpolator = holder.encoder, holder.decoder, holder.interpolator
        config = getattr(module, "config", None)  # a stage-2 reader's KEYINConfig; a stage-1 module's hparams
        sizes = {"n_cond": config.n_cond, "max_offset": config.max_offset} if config is not None else module.hparams
        self.n_cond, self.max_offset = sizes["n_cond"], sizes["max_offset"]
        for network in (self.encoder, self.decoder, self.interpolator):
            network.eval().requires_grad_(False)
        if batch_statistics:  # as in a stage 2 that trains the frame networks (only LSTM_inter frozen): train mode
            self.encoder.train()
            self.decoder.train()

    def clips(self, batch: dict[str, Tensor]) -> Clips:
        with torch.no_grad():
            embeddings = self.encoder(batch["frames"])
        return Clips(
            embeddings[:, self.n_cond - 1], embeddings[:, self.n_cond - 1 :], embeddings[:, self.n_cond :],
            batch["frames"][:, self.n_cond :].flatten(2), batch["future_length"], keyframe_lists(batch["keyframes"]),
        )

    def interpolate(self, first: Tensor, key_emb: Tensor, offsets: Tensor) -> Tensor:
        """(B, M, S, D) frames between consecutive keyframes, the latent drawn from the prior."""
        starts = torch.cat([first[:, None], key_emb[:, :-1]], dim=1)
        batch, n_keys, max_offset = offsets.shape
        latent = torch.randn(batch * n_keys, self.interpolator.latent_dim)
        inter = self.interpolator(starts.flatten(0, 1), key_emb.flatten(0, 1), offsets.flatten(0, 1), latent)
        return torch.sigmoid(self.decoder(inter.flatten(0, 1))).reshape(batch, n_keys, max_offset, -1)


def frame_errors(predicted: Tensor, target: Tensor, error: str) -> Tensor:
    """(B, P, N) error of each of P predicted frames (B, P, D) against each of N targets (B, N, D)."""
    if error == "bce":
        predicted = predicted.clamp(PROB_EPS, 1 - PROB_EPS)
        log_p, log_not_p = predicted.log(), torch.log1p(-predicted)
        return -(torch.bmm(log_p - log_not_p, target.transpose(1, 2)) + log_not_p.sum(-1, keepdim=True))
    cross = torch.bmm(predicted, target.transpose(1, 2))
    return (predicted**2).sum(-1, keepdim=True) - 2 * cross + (target**2).sum(-1)[:, None, :]


def interpolation_term(reading: Reading, frame_pos: Tensor, frames: Tensor, clips: Clips) -> Tensor:
    """(B,) L_inter of one reading (eq. 4 / Alg. 2)."""
    batch, n_keys, max_offset, n_pixels = frames.shape
    n_future = clips.future.shape[1]
    weights = future_window(frame_pos, n_future).reshape(batch, n_keys * max_offset, n_future)  # (B, P, N)
    coverage = weights.sum(1)  # (B, N)
    mask = valid_frame_mask(clips.lengths, n_future)
    flat = frames.reshape(batch, n_keys * max_offset, n_pixels)
    if reading.mixture == "expected":
        errors = frame_errors(flat, clips.future, reading.error)  # (B, P, N)
        per_frame = (weights * errors).sum(1) / coverage.clamp_min(PROB_EPS)
    else:
        if reading.mixture == "normalized":
            weights = weights / coverage.clamp_min(PROB_EPS)[:, None, :]
        mixed = torch.bmm(weights.transpose(1, 2), flat)  # (B, N, D)
        if reading.error == "bce":
            per_frame = bce_sum(mixed, clips.future)
        else:
            per_frame = ((mixed - clips.future) ** 2).sum(-1)
    per_frame = per_frame * mask
    if reading.reduction == "mean":
        return per_frame.sum(-1) / (clips.lengths.clamp_min(1) * n_pixels)
    return per_frame.sum(-1)


def reading_terms(
    reading: Reading, stage1: Stage1, probs: Tensor, key_emb: Tensor | None, clips: Clips
) -> dict[str, Tensor]:
    """Per clip (B,) ``inter``, ``key_emb`` (β_ke = 1, c-weighted as eq. 3) and ``total`` of offset
    probabilities (B, M, S) and keyframe embeddings (B, M, E); ``key_emb=None`` ties K̂ to K̃^e(δ)."""
    keyframe_pos, frame_pos = position_distributions(probs)
    inside = in_sequence_probs(keyframe_pos, clips.lengths)
    key_weights = inside / inside.sum(-1, keepdim=True).clamp_min(PROB_EPS)
    targets = soft_keyframe_targets(keyframe_pos, clips.lengths, clips.future_emb, reading.normalize_key_targets)
    key_emb = targets if key_emb is None else key_emb
    distance = ((key_emb - targets) ** 2).sum(-1)
    if reading.reduction == "mean":
        distance = distance / key_emb.shape[-1]
    key_term = (key_weights * distance).sum(-1)
    frames = stage1.interpolate(clips.first, key_emb, interpolator_offsets(probs, reading.delta_input))
    inter = interpolation_term(reading, frame_pos, frames, clips)
    return {"inter": inter, "key_emb": key_term, "total": inter + key_term}


def onehot(offsets: Tensor, max_offset: int) -> Tensor:
    return F.one_hot(offsets - 1, max_offset).float()


def corner_terms(reading: Reading, stage1: Stage1, offsets: Tensor, clips: Clips) -> dict[str, Tensor]:
    """Terms at hard offsets (B, M), K̂ the true frames' embeddings at their keyframes."""
    with torch.no_grad():
        key_emb = frame_embeddings_at(clips.boundary_emb, offsets)
        return reading_terms(reading, stage1, onehot(offsets, stage1.max_offset), key_emb, clips)


def softened_logits(offsets: Tensor, max_offset: int, p_true: float = 0.9) -> Tensor:
    """Logits (B, M, S) that put ``p_true`` on each offset and spread the rest evenly."""
    return onehot(offsets, max_offset) * math.log(p_true * (max_offset - 1) / (1 - p_true))


def gradient_toward_truth(
    reading: Reading, stage1: Stage1, truth: Tensor, clips: Clips, tied: bool
) -> dict[str, float]:
    """Per term, the share of labelled keyframes whose descent step on θ raises the true offset's
    log-probability, at the softened truth (a step against g raises log p_a by η (Σ_b p_b g_b − g_a))."""
    labelled = torch.zeros_like(truth, dtype=torch.bool)
    for clip, keys in enumerate(clips.truth):
        labelled[clip, : len(keys)] = True
    result = {}
    for term in ("inter", "key_emb", "total"):
        logits = softened_logits(truth, stage1.max_offset).requires_grad_(True)
        key_emb = None if tied else frame_embeddings_at(clips.boundary_emb, truth)
        torch.manual_seed(0)
        terms = reading_terms(reading, stage1, logits.softmax(-1), key_emb, clips)
        (grad,) = torch.autograd.grad(terms[term].sum(), logits, allow_unused=True)
        if grad is None or not bool(grad.abs().sum() > 0):
            result[term] = float("nan")
            continue
        probs = logits.softmax(-1).detach()
        rise = (probs * grad).sum(-1) - grad.gather(-1, truth[..., None] - 1).squeeze(-1)
        result[term] = (rise[labelled] > 0).float().mean().item()
    return result


def summary(probs: Tensor, clips: Clips) -> dict[str, float]:
    """Argmax-offset F1, interior keyframes per clip and distinct patterns of offset probabilities."""
    found = offset_keyframes(probs, clips.lengths)
    scores = keyframe_scores(found, clips.truth, clips.future.shape[1])
    return {"f1": scores["f1"], "keys": scores["n_predicted"], "patterns": float(len({tuple(row) for row in found}))}


def descend(
    reading: Reading, stage1: Stage1, start: Tensor | None, clips: Clips, tied: bool, steps: int, lr: float, every: list[int],
    n_keyframes: int = 6,
) -> list[dict[str, float]]:
    """Adam on (θ, K̂) from hard offsets ``start`` (B, M) softened to p = 0.9, or from uniform offsets (``start=None``,
    K̂ at its soft target there); a row at each step in ``every``."""
    torch.manual_seed(0)
    if start is None:
        logits = torch.zeros(len(clips.truth), n_keyframes, stage1.max_offset, requires_grad=True)
    else:
        logits = softened_logits(start, stage1.max_offset).requires_grad_(True)
    params = [logits]
    key_emb = None
    if not tied:
        if start is None:
            keyframe_pos, _ = position_distributions(logits.detach().softmax(-1))
            key_emb = soft_keyframe_targets(keyframe_pos, clips.lengths, clips.future_emb, reading.normalize_key_targets)
        else:
            key_emb = frame_embeddings_at(clips.boundary_emb, start)
        key_emb = key_emb.clone().requires_grad_(True)
        params.append(key_emb)
    optimizer = torch.optim.Adam(params, lr=lr)
    rows = []
    for step in range(steps + 1):
        terms = reading_terms(reading, stage1, logits.softmax(-1), key_emb, clips)
        if step in every:
            rows.append({"step": step, **summary(logits.softmax(-1).detach(), clips),
                         **{name: value.mean().item() for name, value in terms.items()}})
        if step == steps:
            break
        optimizer.zero_grad()
        terms["total"].sum().backward()
        optimizer.step()
    return rows


EXACT_SLOT_RUNS = ("from_truth_free", "from_truth_tied", "from_uniform_free", "from_uniform_tied")


def exact_slot_descents(
    reading: Reading, stage1: Stage1, clips: Clips, keyframes: Tensor, steps: int, lr: float, every: list[int]
) -> dict[str, Any]:
    """Descents from the truth and from uniform offsets (free and tied K̂) with M = K + 1 for the clips with K labelled
    keyframes, group by group; ``by_count``: each group's rows, ``end``: the last rows' F1 and keyframes per clip
    averaged over the clips."""
    groups: dict[int, list[int]] = {}
    for clip, keys in enumerate(clips.truth):
        groups.setdefault(len(keys), []).append(clip)
    by_count: dict[int, dict[str, Any]] = {}
    for count, index in sorted(groups.items()):
        group = subset(clips, index)
        truth = true_offsets(keyframes[torch.tensor(index)], group.lengths, count + 1, stage1.max_offset)
        runs: dict[str, Any] = {"clips": len(index)}
        for tied in (False, True):
            mode = "tied" if tied else "free"
            runs[f"from_truth_{mode}"] = descend(reading, stage1, truth, group, tied, steps, lr, every)
            runs[f"from_uniform_{mode}"] = descend(reading, stage1, None, group, tied, steps, lr, every, count + 1)
        by_count[count] = runs
    n_clips = len(clips.truth)
    end = {run: {key: sum(runs["clips"] * runs[run][-1][key] for runs in by_count.values()) / n_clips for key in ("f1", "keys")}
           for run in EXACT_SLOT_RUNS}
    return {"by_count": by_count, "end": end}


def straight_segment_costs(stage1: Stage1, clips: Clips) -> dict[int, float]:
    """Stage 1's interpolation BCE per frame of straight segments (no labelled keyframe before their
    end), by segment length, z = 0."""
    with torch.no_grad():
        costs = interpolation_costs(stage1.interpolator, stage1.decoder, clips.boundary_emb, clips.future)  # (B, N, S)
    sums: dict[int, list[float]] = {}
    for clip, keys in enumerate(clips.truth):
        turns = set(keys)
        for start in range(costs.shape[1]):
            for length in range(1, costs.shape[2] + 1):
                cost = costs[clip, start, length - 1].item()
                if math.isinf(cost) or any(start <= k <= start + length - 2 for k in turns):
                    continue
                sums.setdefault(length, []).append(cost / length)
    return {length: sum(values) / len(values) for length, values in sorted(sums.items())}


def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=64)
    parser.add_argument("ckpt", help="a stage-1 or stage-2 checkpoint, or pretrained:<name>")
    parser.add_argument("--stage", default="keyframes", help="the checkpoint's stage: keyframes | interpolator")
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--lr", type=float, default=0.05)
    parser.add_argument("--constant", type=int, default=None, help="the collapsed pattern's spacing (default: the dataset's Constant)")
    parser.add_argument("--readings", nargs="*", default=[r.name for r in READINGS], choices=[r.name for r in READINGS])
    parser.add_argument("--json", type=Path, help="also write every number as JSON here")
    parser.add_argument("--uniform", action="store_true", help="also descend from uniform offsets (free and tied K̂)")
    parser.add_argument("--exact-slots", action="store_true",
                        help="also descend with M = each clip's labelled keyframes + 1, from the truth and from uniform")
    parser.add_argument("--batch-statistics", action="store_true",
                        help="the frame encoder and decoder normalise each call by its own batch (train mode), as in the "
                             "stated stage 2, which trains them; default: their running statistics (eval mode)")
    args = parser.parse_args()
    torch.manual_seed(0)
    module, config = load_trained_module(args.ckpt, args.stage)
    stage1 = Stage1(module, args.batch_statistics)
    dataset, batch = split_batch(config["dataset"]["name"], args.split, args.clips, args.data_dir)
    clips = stage1.clips(batch)
    n_keys = dataset.n_keyframes
    truth = true_offsets(batch["keyframes"], batch["future_length"], n_keys, stage1.max_offset)
    constant = args.constant or dataset.tuned.constant_offset
    collapsed = torch.full_like(truth, constant)
    every = sorted({0, 10, 25, 50, 100, 200, args.steps} & set(range(args.steps + 1)))
    by_name = {r.name: r for r in READINGS}
    readings = [by_name[name] for name in args.readings]  # in the order asked
    started = time.perf_counter()
    results: dict[str, Any] = {"straight_cost_per_frame": straight_segment_costs(stage1, clips)}
    for reading in readings:
        corners = {name: corner_terms(reading, stage1, offsets, clips) for name, offsets in (("truth", truth), ("collapsed", collapsed))}
        entry: dict[str, Any] = {"reading": asdict(reading), "corners": {}}
        for term in ("inter", "key_emb", "total"):
            t, c = corners["truth"][term], corners["collapsed"][term]
            entry["corners"][term] = {"truth": t.mean().item(), "collapsed": c.mean().item(),
                                      "truth_lower": (t < c).float().mean().item()}
        for tied in (False, True):
            mode = "tied" if tied else "free"
            entry[f"gradient_{mode}"] = gradient_toward_truth(reading, stage1, truth, clips, tied)
            entry[f"from_truth_{mode}"] = descend(reading, stage1, truth, clips, tied, args.steps, args.lr, every)
        entry["from_collapsed_free"] = descend(reading, stage1, collapsed, clips, False, args.steps, args.lr, every)
        if args.uniform:  # no information about the clip at the start, as a stage 2 trained from scratch
            for tied in (False, True):
                entry[f"from_uniform_{'tied' if tied else 'free'}"] = descend(
                    reading, stage1, None, clips, tied, args.steps, args.lr, every, n_keys)
        if args.exact_slots:
            entry["exact_slots"] = exact_slot_descents(reading, stage1, clips, batch["keyframes"], args.steps, args.lr, every)
        results[reading.name] = entry
        print(reading.name, json.dumps({k: v for k, v in entry.items() if k != "reading"})[:600], flush=True)
        if args.json:  # after each reading: a stopped run keeps what it measured
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps({"clips": len(clips.truth), "date": str(date.today()), **results}, indent=1))
    seconds = time.perf_counter() - started
    command = (f"python studies/paper_loss_truth.py {args.ckpt}" + (f" --stage {args.stage}" if args.stage != "keyframes" else "")
               + f" --clips {args.clips} --steps {args.steps} --lr {args.lr}"
               + (f" --readings {' '.join(args.readings)}" if len(args.readings) < len(READINGS) else "")
               + (" --uniform" if args.uniform else "") + (" --exact-slots" if args.exact_slots else "")
               + (" --batch-statistics" if args.batch_statistics else ""))
    lines = [
        f"# Does the paper's loss hold the true keyframes? Stage 1 of `{args.ckpt}`",
        "",
        f"`{command}` ({len(clips.truth)} {args.split} clips of {dataset.name}; collapsed pattern: every {constant} frames; "
        f"{cpu_model()}, {torch.get_num_threads()} thread(s), {date.today()}, {seconds / 60:.1f} min). "
        "Free per-clip offset logits θ and keyframe embeddings K̂ in place of the predictor (studies/paper_loss_truth.py); "
        + ("the frame encoder and decoder normalise by each call's batch (train mode)." if args.batch_statistics
           else "the frame networks normalise by their running statistics (eval mode)."),
        "",
        "Stage 1's interpolation BCE per frame of straight segments, by length (nats): "
        + ", ".join(f"{k}: {v:.1f}" for k, v in results["straight_cost_per_frame"].items()),
        "",
        "| reading | L_inter truth / collapsed (hard, true frames) | clips truth lower | gradient → truth (L_inter, L_ke; free K̂) | "
        f"from truth, free K̂: F1 step 0 → {args.steps} (keys/clip) | total at end | from collapsed, free K̂: F1 → {args.steps} | total at end | "
        f"from truth, tied K̂: F1 → {args.steps} (keys/clip) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for reading in readings:
        e = results[reading.name]
        truth_free, coll_free, truth_tied = e["from_truth_free"], e["from_collapsed_free"], e["from_truth_tied"]
        lines.append(
            f"| {reading.name} | {e['corners']['inter']['truth']:.4g} / {e['corners']['inter']['collapsed']:.4g} | "
            f"{e['corners']['total']['truth_lower']:.2f} | {e['gradient_free']['inter']:.2f}, {e['gradient_free']['key_emb']:.2f} | "
            f"{truth_free[0]['f1']:.3f} → {truth_free[-1]['f1']:.3f} ({truth_free[-1]['keys']:.2f}) | {truth_free[-1]['total']:.4g} | "
            f"{coll_free[0]['f1']:.3f} → {coll_free[-1]['f1']:.3f} | {coll_free[-1]['total']:.4g} | "
            f"{truth_tied[0]['f1']:.3f} → {truth_tied[-1]['f1']:.3f} ({truth_tied[-1]['keys']:.2f}) |"
        )
    if args.exact_slots:
        lines += ["", f"M = each clip's labelled keyframes + 1 (no spare slot), clips grouped by their count; F1 (interior "
                  f"keyframes per clip) after {args.steps} steps, averaged over the clips; with M = {n_keys} above for comparison:", "",
                  "| reading | from truth, free K̂ | from truth, tied K̂ | from uniform, free K̂ | from uniform, tied K̂ | clips by count |",
                  "|---|---|---|---|---|---|"]
        for reading in readings:
            exact = results[reading.name]["exact_slots"]
            cells = [f"{exact['end'][run]['f1']:.3f} ({exact['end'][run]['keys']:.2f})" for run in EXACT_SLOT_RUNS]
            counts = ", ".join(f"{count}: {runs['clips']}" for count, runs in exact["by_count"].items())
            lines.append(f"| {reading.name} | {' | '.join(cells)} | {counts} |")
    lines += ["", "Readings:", "", *(f"- `{r.name}`: {r.text}" for r in readings), "",
              "Every number (descent rows at steps " + ", ".join(map(str, every)) + "): the JSON file beside this one."]
    publish("\n".join(lines) + "\n", args.out)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"command": command, "clips": len(clips.truth), "date": str(date.today()), **results}, indent=1))


if __name__ == "__main__":
    main()

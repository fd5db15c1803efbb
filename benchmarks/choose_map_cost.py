"""Choose discovery 'map''s keyframe price λ and boundary weight α on validation clips, beside the
label-free price "knee" (each clip's count at the knee of its cost curve, no λ); with
``--candidate-logits``, also ``map_pruned``'s least boundary logit τ of a keyframe at the model's α
(at its λ and at the knee): the share of segment frames it renders, its F1, how often it keeps map's keyframes.

    python benchmarks/choose_map_cost.py runs/<run>/checkpoints/keyframes/last.ckpt --clips 300 \
        --costs 0 50 100 200 400 knee --weights 0 5 10 20 --out benchmarks/results/choose_map_cost_<dataset>.md
    python benchmarks/choose_map_cost.py pretrained:brownian --clips 300 --costs 120 --weights 10 \
        --candidate-logits -6 -5 -4 -3 -2 --out benchmarks/results/choose_map_pruning_brownian.md

λ is in nats of the decoder's pixel BCE, so it depends on the frame size and content and is chosen
again for each dataset (docs/decisions.md). The interpolation costs of every in-clip segment are
computed once per clip length; each (λ, α) is then one exact DP per clip. Validation clips only:
the test split stays for the reported F1.
"""

from __future__ import annotations

import argparse
import time
from datetime import date
from pathlib import Path

import torch
from torch.utils.data import DataLoader, Subset

from common import clip_arguments, cpu_model, publish
from keyin.data.clips import ShardClips
from keyin.data.hdf5 import split_files
from keyin.decode.rules import with_sequence_ends
from keyin.decode.segment_costs import boundary_segment_costs, candidate_segments, interpolation_costs
from keyin.decode.segmentation import KNEE, decode_by_length
from keyin.eval.f1 import column_scores, keyframe_lists, keyframe_scores
from keyin.lit.registry import load_trained_module
from keyin.losses.image import future_pixel_weights


def price(text: str) -> float | str:
    """A λ in nats, or the word knee."""
    return text if text == KNEE else float(text)


@torch.no_grad()
def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=300)
    parser.add_argument("ckpt", help="a stage-2 (keyframes) checkpoint")
    parser.add_argument("--costs", type=price, nargs="+", default=[0, 50, 100, 200, 400, KNEE])
    parser.add_argument("--weights", type=float, nargs="+", default=[0, 5, 10, 20])
    parser.add_argument("--candidate-logits", type=float, nargs="*", default=[],
                        help="map_pruned's least boundary logit of a keyframe, each scored at the model's α")
    args = parser.parse_args()
    module, config = load_trained_module(args.ckpt, "keyframes")
    dataset, stage1 = config["dataset"], module.config.stage1_hparams()
    image = (stage1["image_size"], stage1["image_size"], stage1["channels"])
    clips = ShardClips(split_files(Path(args.data_dir) / dataset["name"], args.split), image, stage1["n_cond"], stage1["n_future"])
    clips = Subset(clips, range(min(args.clips, len(clips))))
    batch = next(iter(DataLoader(clips, batch_size=len(clips))))
    started = time.perf_counter()
    n_cond, lengths, model = stage1["n_cond"], batch["future_length"], module.model
    embeddings, keys = model.keyframes(batch["frames"], lengths, mode="posterior", sample=False, chain="argmax")  # as discover reads them
    boundary_emb, future = embeddings[:, n_cond - 1 :], batch["frames"][:, n_cond:].flatten(2)
    weights = future_pixel_weights(module.pixel_weights(batch["frames"]), n_cond)
    pixel_costs = {  # per clip length: (clips of that length, their segment costs)
        length: interpolation_costs(
            model.interpolator, model.decoder, boundary_emb[rows, : length + 1], future[rows, :length],
            None if weights is None else weights[rows, :length],
        )
        for length in lengths.unique().tolist()
        for rows in [(lengths == length).nonzero().flatten()]
    }
    seconds = time.perf_counter() - started
    max_offset, n_keys = model.predictor.max_offset, module.config.predictor.n_keyframes
    truth, n_future = keyframe_lists(batch["keyframes"]), stage1["n_future"]

    def decode(cost: float | str, weight: float, candidate_logit: float | None = None) -> list[list[int]]:
        """Keyframes by map at (λ, α), among the frames whose boundary logit is ≥ candidate_logit where given."""
        scores = keys.boundary_scores

        def segment_costs(clip_rows: torch.Tensor, length: int) -> torch.Tensor:
            total = pixel_costs[length]
            if weight:
                total = total + weight * boundary_segment_costs(scores[clip_rows, :length].float(), max_offset)
            if candidate_logit is not None:
                keep = candidate_segments(scores[clip_rows, :length] >= candidate_logit, lengths[clip_rows], max_offset, n_keys)
                total = total.masked_fill(~keep, float("inf"))
            return total

        return with_sequence_ends(decode_by_length(segment_costs, lengths, n_keys, max_offset, cost), lengths, n_future)

    def columns(predicted: list[list[int]]) -> str:
        s = keyframe_scores(predicted, truth, n_future)
        f1_interior = column_scores(predicted, truth, lengths.tolist(), n_future)["f1_interior"]
        per_clip = sum(map(len, predicted)) / len(predicted)
        return (f"{s['f1']:.3f} | {f1_interior:.3f} | {s['f1_tol1']:.3f} | {s['precision']:.3f} | {s['recall']:.3f} | "
                f"{per_clip:.2f} |")

    label = lambda cost: cost if cost == KNEE else f"{cost:g}"  # noqa: E731
    rows = ["| λ (nats) | α | F1 | F1 interior | ±1 F1 | precision | recall | keyframes/clip |", "|---|---|---|---|---|---|---|---|"]
    for cost in args.costs:
        for weight in args.weights:
            if weight and keys.boundary_scores is None:
                continue
            rows.append(f"| {label(cost)} | {weight:g} | {columns(decode(cost, weight))}")
    if args.candidate_logits:
        if keys.boundary_scores is None:
            raise SystemExit(f"{args.ckpt} has no boundary scores (offset_evidence): map_pruned needs them")
        weight, offsets = module.prices().boundary_weight, torch.arange(1, max_offset + 1)
        rows += ["", f"map_pruned at the model's α = {weight:g}: *rendered*, the share of the segment frames map renders "
                 "that map_pruned renders; *same*, the share of clips with map's keyframes at the same λ.", "",
                 "| λ (nats) | τ (least boundary logit) | rendered | same | F1 | F1 interior | ±1 F1 | precision | recall | keyframes/clip |",
                 "|---|---|---|---|---|---|---|---|---|---|"]
        for cost in (module.prices().keyframe_cost, KNEE):
            exact = decode(cost, weight)
            for logit in args.candidate_logits:
                rendered = all_frames = 0.0
                for length, costs in pixel_costs.items():
                    clip_rows = (lengths == length).nonzero().flatten()
                    keep = candidate_segments(keys.boundary_scores[clip_rows, :length] >= logit, lengths[clip_rows], max_offset,
                                              n_keys)
                    inside = torch.isfinite(costs)
                    rendered += float(((keep & inside) * offsets).sum())
                    all_frames += float((inside * offsets).sum())
                pruned = decode(cost, weight, logit)
                same = sum(a == b for a, b in zip(pruned, exact)) / len(exact)
                rows.append(f"| {label(cost)} | {logit:g} | {rendered / all_frames:.3f} | {same:.3f} | {columns(pruned)}")
    true_per_clip = batch["keyframes"].sum().item() / len(clips)
    report = "\n".join([
        f"## Discovery 'map': keyframe price λ and boundary weight α on {len(clips)} {args.split} clips ({dataset['name']})\n",
        f"- command: `python benchmarks/choose_map_cost.py {args.ckpt} --clips {args.clips} --split {args.split} --costs "
        f"{' '.join(str(c) if c == KNEE else f'{c:g}' for c in args.costs)} --weights {' '.join(f'{w:g}' for w in args.weights)}"
        + (f" --candidate-logits {' '.join(f'{t:g}' for t in args.candidate_logits)}" if args.candidate_logits else "") + "`",
        f"- machine: {cpu_model()}, {torch.get_num_threads()} threads, torch {torch.__version__}, {date.today()}; "
        f"segment costs in {seconds:.0f} s; {true_per_clip:.2f} true keyframes per clip\n",
        *rows,
    ])
    publish(report, args.out)


if __name__ == "__main__":
    main()

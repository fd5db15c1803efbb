"""KEYIN's argmax-offset readout with the offset evidence chained softly (as trained) or along the
argmax path (each previous keyframe where the argmax offsets put it), the jointly most likely
offsets (Viterbi over the same δ), beside the boundary rule.

    python studies/readout_chain.py runs/<run>/checkpoints/keyframes/last.ckpt --clips 1000 --split val \
        --out studies/results/readout_chain_<dataset>.md

Both readouts take the argmax of every δ^t and sum the offsets (the paper's §3.9); they differ only
in where keyframe t's evidence believes keyframe t - 1 is. Without offset evidence they are the same.
"""

from __future__ import annotations

import argparse
import sys
import time
from datetime import date
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
from common import clip_arguments, cpu_model, publish, split_batch  # noqa: E402
from keyin.decode.offsets import joint_offset_keyframes, offset_keyframes  # noqa: E402
from keyin.decode.rules import boundary_keyframes, with_sequence_ends  # noqa: E402
from keyin.eval.f1 import column_scores, keyframe_lists  # noqa: E402
from keyin.lit.checkpoints import load_checkpoint  # noqa: E402
from keyin.lit.registry import load_trained_module  # noqa: E402


@torch.no_grad()
def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=1000)
    parser.add_argument("ckpt", help="a stage-2 (keyframes) checkpoint")
    args = parser.parse_args()
    module, config = load_trained_module(args.ckpt, "keyframes")
    model, name = module.model.eval(), config["dataset"]["name"]
    _, batch = split_batch(name, args.split, args.clips, args.data_dir)
    clips, lengths = batch["frames"], batch["future_length"]
    truth, n_future = keyframe_lists(batch["keyframes"]), clips.shape[1] - model.n_cond
    rows = ["| readout | F1 interior | F1 with ends | ±1 F1 interior | keyframes/clip | distinct patterns | seconds |",
            "|---|---|---|---|---|---|---|"]
    for chain in ("soft", "argmax"):
        started = time.perf_counter()
        _, keys = model.keyframes(clips, lengths, mode="posterior", sample=False, chain=chain)
        readouts = {f"argmax offsets, {chain} chain": offset_keyframes(keys.offset_probs, lengths)}
        if chain == "soft" and keys.boundary_scores is not None:
            interior = boundary_keyframes(keys.boundary_scores, lengths, model.predictor.n_keyframes, model.predictor.max_offset)
            readouts["boundaries"] = with_sequence_ends(interior, lengths, n_future)
            mask = torch.arange(n_future) < lengths[:, None]
            table = model.predictor.offset_log_probs(keys.head_logits, keys.boundary_scores, mask)
            readouts["jointly most likely offsets (Viterbi)"] = joint_offset_keyframes(table, lengths)
        seconds = time.perf_counter() - started
        for label, predicted in readouts.items():
            s = column_scores(predicted, truth, lengths.tolist(), n_future)
            per_clip = sum(map(len, predicted)) / len(predicted)
            patterns = len({tuple(row) for row in predicted})
            rows.append(f"| {label} | {s['f1_interior']:.3f} | {s['f1_with_ends']:.3f} | {s['f1_tol1_interior']:.3f} | "
                        f"{per_clip:.2f} | {patterns} | {seconds:.1f} |")
    report = "\n".join([
        f"## KEYIN's argmax readout, soft vs argmax evidence chain, {len(clips)} {args.split} clips ({name})\n",
        f"- command: `python studies/readout_chain.py {args.ckpt} --clips {args.clips} --split {args.split}`",
        f"- model: {config['model']['name']} (offset evidence: {module.hparams.offset_evidence}), "
        f"trained {load_checkpoint(args.ckpt)['global_step']} steps",
        f"- machine: {cpu_model()}, {torch.get_num_threads()} threads, torch {torch.__version__}, {date.today()}\n",
        *rows,
    ])
    publish(report, args.out)


if __name__ == "__main__":
    main()

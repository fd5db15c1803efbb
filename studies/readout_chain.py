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
import torch.nn.functional as F
from torch import Tensor

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
from common import clip_arguments, cpu_model, publish, split_batch  # noqa: E402
from keyin.decode.offsets import offset_keyframes  # noqa: E402
from keyin.decode.rules import boundary_keyframes, with_sequence_ends  # noqa: E402
from keyin.eval.f1 import column_scores, keyframe_lists  # noqa: E402
from keyin.lit.checkpoints import load_checkpoint  # noqa: E402
from keyin.lit.registry import load_trained_module  # noqa: E402
from keyin.precision import in_float32  # noqa: E402


@in_float32
def offset_log_probs(predictor, head_logits: Tensor, scores: Tensor, mask: Tensor) -> Tensor:
    """log δ^t for every place of the previous keyframe: what :meth:`_add_boundary_evidence`
    gives along one path, for all paths at once (``predictor``: a
    :class:`keyin.models.KeyframePredictor` with offset evidence).

    Args:
        head_logits: (B, M, S) the offset head's logits; scores: (B, N) boundary logits; mask: (B, N).
    Returns:
        (B, M, L_ext, S): entry [b, t, k, a] is log δ^{t+1}(offset a + 1) with keyframe t at
        extended index k (L_ext = M·S + 1; rows k that no path reaches are finite but unused).
    """
    _, n_keys, max_offset = head_logits.shape
    n_ext = n_keys * max_offset + 1
    extended, none_through = predictor._extended_scores(scores, mask, n_ext + max_offset)  # room past the last reachable index
    k = torch.arange(n_ext)[:, None]
    a = torch.arange(max_offset)[None]
    # log p[k+a+1] + Σ_{k<i≤k+a} log(1 - p[i])
    evidence = F.logsigmoid(extended[:, k + a + 1]) + none_through[:, k + a] - none_through[:, k]  # (B, L_ext, S)
    return torch.log_softmax(head_logits[:, :, None] + evidence[:, None], dim=-1)


def joint_offset_keyframes(log_offsets: Tensor, future_length: Tensor) -> list[list[int]]:
    """Keyframe positions of the jointly most likely offsets under δ (our readout, "joint").

    The paper's readout takes each δ^t's argmax in turn; this one maximises the path's
    ``Σ_t log δ^t(o_t | keyframe t - 1's place)`` exactly (Viterbi over the places), stopping at
    the first keyframe that leaves the clip (its offset counts, the ones after it do not) or at M.

    Args:
        log_offsets: (B, M, L_ext, S) log δ^{t+1}(offset a + 1 | keyframe t at extended index k)
            (:func:`offset_log_probs`); K^0 is at index 0.
        future_length: (B,) valid future frames (extended indices 1 … length are inside).
    Returns:
        Per clip, the increasing positions (extended index - 1) of the keyframes inside it.
    """
    batch, n_keys, n_ext, max_offset = log_offsets.shape
    lengths = future_length.to(log_offsets.device)
    index = torch.arange(n_ext, device=log_offsets.device)
    inside = index[None] <= lengths[:, None]  # (B, L_ext): K^0 and the valid frames
    score = torch.full((batch, n_ext), float("-inf"), device=log_offsets.device)
    score[:, 0] = 0.0
    back = torch.zeros((n_keys, batch, n_ext), dtype=torch.long, device=log_offsets.device)
    best_end = torch.full((batch,), float("-inf"), device=log_offsets.device)
    end_at = torch.zeros((batch, 2), dtype=torch.long, device=log_offsets.device)  # (t, k) of the best end
    for t in range(n_keys):
        reach = torch.full((batch, n_ext, max_offset), float("-inf"), device=log_offsets.device)
        from_live = score.masked_fill(~inside, float("-inf"))[:, :, None] + log_offsets[:, t]  # (B, L_ext(k), S)
        for a in range(max_offset):  # to k + a + 1
            reach[:, a + 1 :, a] = from_live[:, : n_ext - a - 1, a]
        score, offset = reach.max(-1)  # (B, L_ext)
        back[t] = index[None] - offset - 1
        ending = score.masked_fill(inside & (t < n_keys - 1), float("-inf"))  # left the clip, or the M-th keyframe
        value, at = ending.max(-1)
        better = value > best_end
        best_end = torch.where(better, value, best_end)
        end_at[better] = torch.stack([torch.full_like(at, t), at], -1)[better]
    positions = []
    for b in range(batch):
        t, k = end_at[b].tolist()
        places = []
        while t >= 0:
            places.append(k)
            k, t = int(back[t, b, k]), t - 1
        positions.append(sorted(place - 1 for place in places if place <= int(lengths[b])))
    return positions


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
        head = []  # the offset head's own logits, before the evidence
        hook = model.predictor.offset_head.register_forward_hook(lambda _module, _inputs, logits: head.append(logits))
        _, keys = model.keyframes(clips, lengths, mode="posterior", sample=False, chain=chain)
        hook.remove()
        readouts = {f"argmax offsets, {chain} chain": offset_keyframes(keys.offset_probs, lengths)}
        if chain == "soft" and keys.boundary_scores is not None:
            interior = boundary_keyframes(keys.boundary_scores, lengths, model.predictor.n_keyframes, model.predictor.max_offset)
            readouts["boundaries"] = with_sequence_ends(interior, lengths, n_future)
            mask = torch.arange(n_future) < lengths[:, None]
            table = offset_log_probs(model.predictor, head[0], keys.boundary_scores, mask)
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
        f"- model: {config['model']['name']} (offset evidence: {module.config.predictor.offset_evidence}), "
        f"trained {load_checkpoint(args.ckpt)['global_step']} steps",
        f"- machine: {cpu_model()}, {torch.get_num_threads()} threads, torch {torch.__version__}, {date.today()}\n",
        *rows,
    ])
    publish(report, args.out)


if __name__ == "__main__":
    main()

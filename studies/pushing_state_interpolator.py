"""KEYIN's decoding on pushing with perfect perception: a stage-1 interpolator trained on true states.

    python studies/pushing_state_interpolator.py --train data/pushing --steps 3000

The ceiling of a better pixel stage 1 on the pushing labels. KEYIN's ``map`` decoding picks the
segmentation its interpolator renders best; here the interpolator (keyin's own ``Interpolator``,
deterministic, "boundaries" steps, offsets 1-S) is trained on the true object positions instead of
frame embeddings, as if the encoder were perfect, and the segment cost is its squared error in that
state space (``keyin.decode.segment_costs.embedding_costs``). ``--pusher-weight`` scales the pusher's
coordinates (0 drops it): how much of the pusher's repositioning walk the cost should see. The price
λ per keyframe (or the label-free knee) is chosen on validation clips; test clips are scored by the
information rule's interior column. Prints Markdown.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

from keyin.data.hdf5 import load_arrays
from keyin.data.segments import partition_segments, segment_frames
from keyin.decode.segment_costs import embedding_costs
from keyin.decode.segmentation import KNEE, decode_by_length
from keyin.models.interpolator import Interpolator, interpolate_segments
from pushing_state_segmentation import score

N_KEYFRAMES, N_COND = 6, 1
PRICES: list[float | str] = [0.0, 1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, KNEE]


def states_of(arrays: dict[str, np.ndarray], pusher_weight: float) -> torch.Tensor:
    """(n, L, 2 or 4) the puck's positions, then the pusher's scaled by ``pusher_weight`` (if > 0)."""
    parts = [arrays["puck"]] + ([pusher_weight * arrays["pusher"]] if pusher_weight > 0 else [])
    return torch.from_numpy(np.concatenate(parts, axis=-1)).float()


def load_split(folder: Path, split: str, shards: int, pusher_weight: float) -> tuple[torch.Tensor, dict[str, np.ndarray]]:
    """The states and arrays of the first ``shards`` shards of a split."""
    paths = sorted(folder.glob(f"{split}-*.h5"))[:shards]
    names = ("puck", "pusher", "length", "keyframes")
    arrays = [load_arrays(path, names) for path in paths]
    merged = {name: np.concatenate([a[name] for a in arrays]) for name in names}
    return states_of(merged, pusher_weight), merged


def train(states: torch.Tensor, lengths: torch.Tensor, steps: int, batch: int, seed: int, max_offset: int) -> Interpolator:
    """Fit a deterministic interpolator to random segments of the state sequences (MSE)."""
    torch.manual_seed(seed)
    rng = torch.Generator().manual_seed(seed)
    model = Interpolator(states.shape[-1], max_offset, 0, hidden=128, layers=2, mlp_hidden=128)
    optimizer = torch.optim.Adam(model.parameters(), lr=1e-3)
    for step in range(steps):
        rows = torch.randint(0, len(states), (batch,), generator=rng)
        clips, clip_lengths = states[rows], lengths[rows]
        segments = partition_segments(clip_lengths, 1, max_offset, rng)
        predicted, valid, _ = interpolate_segments(model, None, clips, *segments, "mean")
        clip, start, offset = segments
        targets = clips[clip[:, None], segment_frames(start, offset, max_offset)[0]]  # (R, S, D)
        loss = (((predicted - targets) ** 2).sum(-1) * valid).sum() / valid.sum()
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        if step % 1000 == 0 or step == steps - 1:
            print(f"<!-- step {step}: mse per frame {loss.item():.2e} -->")
    return model.eval()


def discover(model: Interpolator, states: torch.Tensor, lengths: torch.Tensor, price: float | str) -> list[list[int]]:
    """Per clip, the interior keyframe positions of the cheapest segmentation under the model."""
    boundary = states[:, N_COND - 1 :]  # (B, N + 1, D) extended index
    future_lengths = lengths - N_COND

    def segment_costs(rows: torch.Tensor, length: int) -> torch.Tensor:
        return embedding_costs(model, boundary[rows, : length + 1])

    return decode_by_length(segment_costs, future_lengths, N_KEYFRAMES, model.max_offset, price)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--train", type=Path, default=Path("data/pushing"), help="dataset folder (train/val/test shards)")
    parser.add_argument("--train-shards", type=int, default=10)
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument("--batch", type=int, default=64)
    parser.add_argument("--pusher-weights", type=float, nargs="+", default=[0.0, 0.25, 1.0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--max-offset", type=int, default=6, help="S: the dataset's max_offset (pushing 6, pushing_irregular 11)")
    args = parser.parse_args()
    print(f"## Learned interpolator on the true states ({args.train.name})\n")
    print(
        f"- command: `python studies/pushing_state_interpolator.py --train {args.train} --train-shards "
        f"{args.train_shards} --steps {args.steps} --batch {args.batch} --pusher-weights "
        f"{' '.join(map(str, args.pusher_weights))} --seed {args.seed} --max-offset {args.max_offset}`\n"
    )
    rows = []
    for weight in args.pusher_weights:
        began = time.perf_counter()
        train_states, train_arrays = load_split(args.train, "train", args.train_shards, weight)
        model = train(train_states, torch.from_numpy(train_arrays["length"]).long(), args.steps, args.batch, args.seed, args.max_offset)
        val_states, val_arrays = load_split(args.train, "val", 1, weight)
        test_states, test_arrays = load_split(args.train, "test", 1, weight)
        val_lengths, test_lengths = (torch.from_numpy(a["length"]).long() for a in (val_arrays, test_arrays))
        with torch.no_grad():
            val_f1 = {p: score(val_arrays, discover(model, val_states, val_lengths, p))["f1_interior"] for p in PRICES}
            best = max(val_f1, key=lambda p: val_f1[p])
            result = score(test_arrays, discover(model, test_states, test_lengths, best))
        rows.append(
            f"| {weight} | {best} | {val_f1[best]:.3f} | {result['f1_interior']:.3f} | {result['f1_tol1_interior']:.3f} "
            f"| {result['f1_with_ends']:.3f} | {result['n_predicted_interior']:.2f} | {time.perf_counter() - began:.0f} |"
        )
    print("| pusher weight | λ (val) | val F1 interior | test F1 interior | test ±1 F1 interior | test F1 with ends | keyframes/clip (interior) | seconds |")
    print("|---|---|---|---|---|---|---|---|")
    print("\n".join(rows))


if __name__ == "__main__":
    main()

"""How long caching a split's frame embeddings takes: a frame autoencoder's encoder over every frame.

    python benchmarks/encode_split.py runs/frames/<run>/checkpoints/frames/last.ckpt --split val

Writes (or finds valid and reuses) ``data/<dataset>/embeddings/<split>-<fingerprint>.h5`` by
:func:`keyin.data.embeddings.cached_embeddings` and prints the clips, frames, seconds and the file's size.
"""

from __future__ import annotations

import argparse
import time
from datetime import date
from pathlib import Path

import torch

from common import cpu_model
from keyin.data.embeddings import EmbeddedClips, cached_embeddings
from keyin.lit.registry import load_trained_module


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ckpt", help="a frame autoencoder's checkpoint (checkpoints/frames/last.ckpt)")
    parser.add_argument("--split", default="val")
    parser.add_argument("--data-dir", default="data")
    parser.add_argument("--batch-size", type=int, default=32)
    args = parser.parse_args()
    module, config = load_trained_module(args.ckpt, "frames")
    dataset = config["dataset"]
    started = time.perf_counter()
    path = cached_embeddings(Path(args.data_dir) / dataset["name"], args.split, module.network.encoder, args.batch_size,
                             progress=False)
    seconds = time.perf_counter() - started
    clips = EmbeddedClips(path, dataset["n_cond"], dataset["n_future"])
    frames = clips.embeddings.shape[0] * clips.embeddings.shape[1]
    print(f"- command: `python benchmarks/encode_split.py {args.ckpt} --split {args.split}`")
    print(f"- {len(clips)} clips, {frames} frames, E = {clips.embeddings.shape[-1]}: {seconds:.1f} s "
          f"({frames / seconds:.0f} frames/s), {path.stat().st_size / 2**20:.1f} MiB in {path}")
    print(f"- machine: {cpu_model()}, {torch.get_num_threads()} threads, torch {torch.__version__}, {date.today()}")


if __name__ == "__main__":
    main()

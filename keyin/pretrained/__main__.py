"""Maintainers' commands for what keyin ships (docs/models.md):

    python -m keyin.pretrained export <checkpoint> --name brownian --command "keyin-reproduce table=..."
    python -m keyin.pretrained example     # the example video `make demo` discovers the keyframes of
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import imageio.v3 as iio

from keyin.data.brownian import BrownianGenerator
from keyin.io import atomic_write_bytes, atomic_write_text, sha256_of
from keyin.lit.checkpoints import load_checkpoint
from keyin.pretrained import FOLDER, export

EXAMPLE = "brownian_example.gif"  # 200 frames of Structured Brownian motion, 10 frames per second
EXAMPLE_LABELS = "brownian_example_labels.json"  # its direction changes, keyin-import's label format


def export_command(args: argparse.Namespace) -> None:
    checkpoint = load_checkpoint(args.checkpoint)
    config = checkpoint["keyin_config"]
    card = {"command": args.command, "source_sha256": sha256_of(args.checkpoint), "stage": checkpoint["keyin_stage"],
            "model": config["model"]["name"], "dataset": config["dataset"]["name"]}
    print(export(checkpoint, args.name, card))


def example_command(args: argparse.Namespace) -> None:
    """One long Brownian clip (seed 777, the dataset's motion) as a GIF, its turns as labels."""
    arrays, _ = BrownianGenerator(n_cond=1, n_future=199).generate(0, seed=777)
    frames = arrays["frames"][..., 0]  # (200, 32, 32) in {0, 255}
    atomic_write_bytes(FOLDER / EXAMPLE, iio.imwrite("<bytes>", frames, extension=".gif", duration=100, loop=0))
    turns = arrays["keyframes"].nonzero()[0].tolist()
    atomic_write_text(FOLDER / EXAMPLE_LABELS, json.dumps({EXAMPLE: turns}) + "\n")
    print(FOLDER / EXAMPLE, f"{len(frames)} frames, {len(turns)} turns")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(required=True)
    ship = commands.add_parser("export", help="ship a trained checkpoint as pretrained:<name>")
    ship.add_argument("checkpoint", type=Path, help="a keyin-train checkpoint (checkpoints/keyframes/last.ckpt)")
    ship.add_argument("--name", required=True, help="the name it loads by: ckpt=pretrained:<name>")
    ship.add_argument("--command", required=True, help="the command that trained it (for the model card)")
    ship.set_defaults(run=export_command)
    commands.add_parser("example", help="write the bundled example video and its labels").set_defaults(run=example_command)
    args = parser.parse_args()
    args.run(args)


if __name__ == "__main__":
    main()

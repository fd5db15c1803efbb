"""Ship a trained checkpoint as a pretrained model (maintainers; docs/models.md):

    python -m keyin.pretrained <checkpoint> --name brownian --command "keyin-reproduce table=..."
"""

from __future__ import annotations

import argparse
from pathlib import Path

from keyin.io import sha256_of
from keyin.lit.checkpoints import load_checkpoint
from keyin.pretrained import export


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("checkpoint", type=Path, help="a keyin-train checkpoint (checkpoints/keyframes/last.ckpt)")
    parser.add_argument("--name", required=True, help="the name it loads by: ckpt=pretrained:<name>")
    parser.add_argument("--command", required=True, help="the command that trained it (for the model card)")
    args = parser.parse_args()
    checkpoint = load_checkpoint(args.checkpoint)
    card = {"command": args.command, "source_sha256": sha256_of(args.checkpoint), "stage": checkpoint["keyin_stage"],
            "model": checkpoint["keyin_config"]["model"]["name"], "dataset": checkpoint["keyin_config"]["dataset"]["name"]}
    print(export(checkpoint, args.name, card))


if __name__ == "__main__":
    main()

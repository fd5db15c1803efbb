"""Maintainers' commands for what keyin ships (docs/models.md):

    python -m keyin.cli.pretrained export <checkpoint> --name brownian --command "keyin-reproduce table=..."
    python -m keyin.cli.pretrained export <run dir>/checkpoints/keyframes/last.ckpt ... --folder <dir>
        # slim copies outside the package (a table's models), each named after its run dir, its
        # command read from the run's .hydra/hydra.yaml
    python -m keyin.cli.pretrained example     # the example video `make demo` discovers the keyframes of
    python -m keyin.cli.pretrained rules <name> <keyin-eval ckpt=pretrained:<name> split=val>/metrics.json
        # record keyin-discover's default rule for it: the cheapest within 0.01 of map on validation clips
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import imageio.v3 as iio
from omegaconf import OmegaConf

from keyin.data.brownian import BrownianGenerator
from keyin.errors import CheckpointError
from keyin.io import atomic_write_bytes, atomic_write_text, sha256_of
from keyin.lit.checkpoints import load_checkpoint
from keyin.decode.registry import FAST_RULE_TOLERANCE, fastest_rule
from keyin.pretrained import FOLDER, PREFIX, annotate, export

EXAMPLE = "brownian_example.gif"  # 200 frames of Structured Brownian motion, 10 frames per second
EXAMPLE_LABELS = "brownian_example_labels.json"  # its direction changes, keyin-import's label format


def run_dir(checkpoint: Path) -> Path:
    """The keyin-train run folder of ``<run dir>/checkpoints/<stage>/last.ckpt``."""
    return checkpoint.parents[2]


def run_command(checkpoint: Path) -> str:
    """The keyin-train call that wrote ``checkpoint``, from its run's ``.hydra/hydra.yaml``.

    Raises:
        CheckpointError: the run folder has no such file (name the command with --command).
    """
    path = run_dir(checkpoint) / ".hydra" / "hydra.yaml"
    if not path.is_file():
        raise CheckpointError(f"{path} is missing, so the command that trained {checkpoint} is unknown; pass --command")
    hydra = OmegaConf.load(path).hydra
    multirun = " -m" if hydra.mode == "MULTIRUN" else ""
    return f"keyin-train{multirun} " + " ".join(hydra.overrides.task)


def export_command(args: argparse.Namespace) -> None:
    if len(args.checkpoints) > 1 and (args.name or args.command):
        raise SystemExit("--name and --command name one checkpoint; with several, each takes its run dir's")
    for path in args.checkpoints:
        checkpoint = load_checkpoint(path)
        config = checkpoint["keyin_config"]
        card = {"command": args.command or run_command(path), "source_sha256": sha256_of(path),
                "stage": checkpoint["keyin_stage"], "model": config["model"]["name"], "dataset": config["dataset"]["name"]}
        print(export(checkpoint, args.name or run_dir(path).name, card, args.folder))


def example_command(args: argparse.Namespace) -> None:
    """One long Brownian clip (seed 777, the dataset's motion) as a GIF, its turns as labels."""
    arrays, _ = BrownianGenerator(n_cond=1, n_future=199).generate(0, seed=777)
    frames = arrays["frames"][..., 0]  # (200, 32, 32) in {0, 255}
    atomic_write_bytes(FOLDER / EXAMPLE, iio.imwrite("<bytes>", frames, extension=".gif", duration=100, loop=0))
    turns = arrays["keyframes"].nonzero()[0].tolist()
    atomic_write_text(FOLDER / EXAMPLE_LABELS, json.dumps({EXAMPLE: turns}) + "\n")
    print(FOLDER / EXAMPLE, f"{len(frames)} frames, {len(turns)} turns")


def rules_command(args: argparse.Namespace) -> None:
    """Record keyin-discover's default rule for ``pretrained:<name>`` from a keyin-eval run of it on the
    validation split (its own rule's and its variants' interior F1)."""
    metrics = json.loads(args.metrics.read_text())
    asked = f"{PREFIX}{args.name}"
    if metrics.get("ckpt") != asked or metrics.get("split") != "val":
        raise SystemExit(
            f"{args.metrics} scored ckpt={metrics.get('ckpt')} on split={metrics.get('split')}; record the rule from "
            f"`keyin-eval ckpt={asked} split=val` (validation clips choose, the test set only scores)"
        )
    own = load_checkpoint(asked)["hyper_parameters"]["discovery"]
    method = metrics["method"]
    val_f1 = {own: metrics["f1_interior"]}
    val_f1.update({name[len(method) + 1:]: scores["f1_interior"] for name, scores in metrics.get("variants", {}).items()
                   if name.startswith(f"{method}_")})
    chosen = fastest_rule(val_f1)
    record = {"rule": chosen, "val_f1_interior": {rule: round(f1, 4) for rule, f1 in sorted(val_f1.items())},
              "val_clips": metrics["n_sequences"], "tolerance": FAST_RULE_TOLERANCE, "metrics": str(args.metrics)}
    annotate(args.name, {"default_rule": record}, args.folder)
    print(f"{asked}: keyin-discover's default rule is {chosen} ({record['val_f1_interior']})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(required=True)
    ship = commands.add_parser("export", help="ship a trained checkpoint as pretrained:<name> (or slim it into --folder)")
    ship.add_argument("checkpoints", type=Path, nargs="+", help="keyin-train checkpoints (checkpoints/keyframes/last.ckpt)")
    ship.add_argument("--name", help="the name it loads by: ckpt=pretrained:<name> (default: its run dir's name)")
    ship.add_argument("--command", help="the command that trained it, for the model card (default: its run's)")
    ship.add_argument("--folder", type=Path, default=FOLDER, help="where to write it and its models.json (default: the package)")
    ship.set_defaults(run=export_command)
    commands.add_parser("example", help="write the bundled example video and its labels").set_defaults(run=example_command)
    rules = commands.add_parser("rules", help="record keyin-discover's default rule of a shipped model from its validation F1")
    rules.add_argument("name", help="the shipped model: pretrained:<name>")
    rules.add_argument("metrics", type=Path, help="metrics.json of `keyin-eval ckpt=pretrained:<name> split=val`")
    rules.add_argument("--folder", type=Path, default=FOLDER, help="the folder of its models.json (default: the package)")
    rules.set_defaults(run=rules_command)
    args = parser.parse_args()
    args.run(args)


if __name__ == "__main__":
    main()


"""Write model_config.yaml into the committed Table 2 planning jobs that predate it (issue 62): the run config of the
model each one planned with, which keyin-plan now writes itself and keyin-report names a row of the paper's method by
(`keyin_paper · backbone=ours scale=cpu`). Their model files are gone; what stands for each is committed:

- `models/pushing_table2/<model>_seed<s>.ckpt` and `runs/multirun/pushing_table1/<run>/checkpoints/<stage>/last.ckpt`:
  the training job `model_jobs/<model>_seed<s>` (`<run>`), whose last.ckpt the table's export step copied to that file
  (conf/table/pushing_table2.yaml; its hash cannot be checked: the export halves the precision): its config.yaml with
  the frame model and sizes its metrics.json records as its choices;
- `pretrained:<name>`: the shipped model's own stored config, where the job's recorded hash is the shipped file's;
- anything else (TAP's `tap_fixed/models/after_seed<s>.ckpt`, a Surprise run not in model_jobs): left without one,
  and said.

    python docs/results/pushing_table2/scripts/model_configs.py    (from the repository root; then keyin-report
                                                                       docs/results/pushing_table2/jobs --out docs/results/pushing_table2)
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from keyin import CHOICES_KEY
from keyin.checkpoints import load_checkpoint
from keyin.eval.planning import MODEL_CONFIG
from keyin.io import atomic_write_text
from keyin.lit.registry import run_config
from keyin.pretrained import registry, resolve

TABLE = Path("docs/results/pushing_table2")


def model_job(checkpoint: str, model_jobs: Path) -> Path | None:
    """The committed training job that stands for ``checkpoint``'s model, None where none does."""
    path = Path(checkpoint)
    name = path.parents[2].name if path.name == "last.ckpt" and len(path.parents) > 2 else path.stem
    return model_jobs / name if (model_jobs / name / "config.yaml").is_file() else None


def model_config(job: Path, model_jobs: Path) -> DictConfig | str:
    """The run config of the model the planning ``job`` planned with, or why there is none."""
    checkpoint = OmegaConf.select(OmegaConf.load(job / "config.yaml"), "planner.checkpoint", default=None)
    if checkpoint is None:
        return "plans with no model"
    if checkpoint.startswith("pretrained:"):
        recorded = json.loads((job / "checkpoints.json").read_text()).get(checkpoint)
        if recorded != registry()[checkpoint.removeprefix("pretrained:")]["sha256"]:
            return f"{checkpoint} is no longer the file it planned with"
        return OmegaConf.create(run_config(load_checkpoint(resolve(checkpoint))))
    trained = model_job(checkpoint, model_jobs)
    if trained is None:
        return f"no committed training job stands for {checkpoint}"
    metrics = json.loads((trained / "metrics.json").read_text())
    config = OmegaConf.load(trained / "config.yaml")
    config[CHOICES_KEY] = {group: metrics[group] for group in ("backbone", "scale")}
    return config


def main(table: Path = TABLE) -> None:
    for job in sorted(path for path in (table / "jobs").iterdir() if (path / "metrics.json").is_file()):
        config = model_config(job, table / "model_jobs")
        if isinstance(config, str):
            print(f"{job.name}: {config}; none written")
            continue
        atomic_write_text(job / MODEL_CONFIG, OmegaConf.to_yaml(config))
        print(f"{job.name}: {MODEL_CONFIG} of model={config.model.name} ({dict(config.get(CHOICES_KEY) or {})})")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else TABLE)

"""Write model_config.yaml into the committed Table 2 planning jobs that predate it (issue 62): the run config stored in
the checkpoint each one planned with, as keyin-plan now writes it itself, which keyin-report names a row of the paper's
method by (`keyin_paper · backbone=ours scale=cpu`). Each job's checkpoints.json records the SHA-256 of the file it
planned with; the file is found by that hash among the committed models (models/manifest.json: models/pushing_table2/,
models/tap_fixed/) or the shipped ones (`pretrained:<name>`). A job that records no hash (Surprise's, which planned with
a run dir's checkpoint) or whose file is not committed is left without one, and said; a job that has one keeps it.

    python docs/results/pushing_table2/scripts/model_configs.py    (from the repository root; then keyin-report
                                                                       docs/results/pushing_table2/jobs --out docs/results/pushing_table2)
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from keyin.cli.plan import write_model_config
from keyin.eval.planning import MODEL_CONFIG
from keyin.pretrained import registry

TABLE = Path("docs/results/pushing_table2")
MANIFEST = Path("models/manifest.json")


def committed_models(manifest: Path = MANIFEST) -> dict[str, str]:
    """SHA-256 → the committed file (a path, or ``pretrained:<name>``) of every committed and shipped model."""
    files = {entry["sha256"]: entry["path"] for entry in json.loads(manifest.read_text())["models"]}
    return files | {entry["sha256"]: f"pretrained:{name}" for name, entry in registry().items()}


def back_fill(job: Path, models: dict[str, str]) -> str:
    """Write ``job``'s model config from the committed file its recorded hash names; what was done, in words."""
    if (job / MODEL_CONFIG).is_file():
        return f"has its {MODEL_CONFIG}; kept"
    recorded = json.loads((job / "checkpoints.json").read_text()) if (job / "checkpoints.json").is_file() else {}
    if not recorded:
        return "records no checkpoint hash; none written"
    (planned, sha256), = recorded.items()
    if sha256 not in models:
        return f"planned with {planned} (sha256 {sha256[:12]}), not committed; none written"
    config = write_model_config(models[sha256], job)
    return f"{MODEL_CONFIG} from {models[sha256]} (model={config.model.name})"


def main(table: Path = TABLE) -> None:
    models = committed_models()
    for job in sorted(path for path in (table / "jobs").iterdir() if (path / "metrics.json").is_file()):
        print(f"{job.name}: {back_fill(job, models)}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else TABLE)

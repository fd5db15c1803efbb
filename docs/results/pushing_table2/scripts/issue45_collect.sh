#!/bin/sh
# Issue 45: the finished TAP and Surprise planning jobs of issue45_seeds.sh (frozen checkout /work/run-tree5)
# into docs/results/pushing_table2/jobs (keyin-reproduce's collect, finished jobs only), then Table 2's report.
cd /work/main
.venv/bin/python - <<'PY'
import tempfile
from pathlib import Path
from keyin.cli.reproduce import collect
sweep = Path("/work/run-tree5/runs/multirun/pushing_table2")
with tempfile.TemporaryDirectory() as tmp:
    for job in sweep.iterdir():
        if (job / "metrics.json").is_file():
            (Path(tmp) / job.name).symlink_to(job)
    print(collect(Path(tmp), Path("docs/results/pushing_table2/jobs")))
PY
.venv/bin/python -m keyin.cli.report docs/results/pushing_table2/jobs --out docs/results/pushing_table2

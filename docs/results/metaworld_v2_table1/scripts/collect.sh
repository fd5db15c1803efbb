#!/bin/sh
# Issue 46: the finished jobs of the Meta-World v2 Table 1 sweep (frozen checkout /work/run-tree9) into
# docs/results/metaworld_v2_table1/jobs (keyin-reproduce's collect, finished jobs only), then its report.
cd /work/main
.venv/bin/python - <<'PY'
import shutil, tempfile
from pathlib import Path
from keyin.cli.reproduce import collect
sweep = Path("/work/run-tree9/runs/multirun/metaworld_v2_table1")
with tempfile.TemporaryDirectory() as tmp:
    for job in sweep.iterdir():
        if (job / "metrics.json").is_file() or job.name.startswith("stage1_") and (sweep / job.name.replace("stage1_ours", "keyin_plus") / "metrics.json").is_file():
            (Path(tmp) / job.name).symlink_to(job)
    print(collect(Path(tmp), Path("docs/results/metaworld_v2_table1/jobs")))
PY
.venv/bin/python -m keyin.cli.report docs/results/metaworld_v2_table1/jobs --out docs/results/metaworld_v2_table1

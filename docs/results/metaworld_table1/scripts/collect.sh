#!/bin/sh
# Issue 46: the finished jobs of a Meta-World Table 1 sweep into <table folder>/jobs (keyin-reproduce's
# collect, finished jobs only, a seed's shared stage 1 with its keyin_plus), then its report.
#   sh collect.sh [<sweep folder> <table folder>]   (default: version 1's, frozen checkout /work/run-tree7)
SWEEP=${1:-/work/run-tree7/runs/multirun/metaworld_table1}
TABLE=${2:-docs/results/metaworld_table1}
cd /work/main
SWEEP=$SWEEP TABLE=$TABLE .venv/bin/python - <<'PY'
import os, tempfile
from pathlib import Path
from keyin.cli.reproduce import collect
sweep, table = Path(os.environ["SWEEP"]), Path(os.environ["TABLE"])
with tempfile.TemporaryDirectory() as tmp:
    for job in sweep.iterdir():
        if (job / "metrics.json").is_file() or job.name.startswith("stage1_") and (sweep / job.name.replace("stage1_ours", "keyin_plus") / "metrics.json").is_file():
            (Path(tmp) / job.name).symlink_to(job)
    print(collect(Path(tmp), table / "jobs"))
PY
.venv/bin/python -m keyin.cli.report $TABLE/jobs --out $TABLE

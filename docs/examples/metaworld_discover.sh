#!/bin/sh
# docs/metaworld.md, "Keyframes of a Meta-World video": the shipped Meta-World model on one unseen expert
# episode per task (docs/examples/metaworld/, written by metaworld_episodes.py), the expert's switches as labels.
# From the repository root, with keyin installed:  sh docs/examples/metaworld_discover.sh [/tmp/metaworld_discover]
set -e
OUT=${1:-/tmp/metaworld_discover}
keyin-discover ckpt=pretrained:metaworld input=docs/examples/metaworld labels=docs/examples/metaworld/labels.csv \
  progress=false hydra.run.dir="$OUT"
python - "$OUT" <<'PY'
import json, sys
from pathlib import Path
from PIL import Image
out = Path(sys.argv[1])
videos = sorted(p for p in out.iterdir() if (p / "keyframes.json").is_file())
print("| video | found | expert's switches + success | exact hits | within ±1 |\n|---|---|---|---|---|")
for video in videos:
    record = json.loads((video / "keyframes.json").read_text())
    found, labels = [k["frame"] for k in record["keyframes"]], record["labels"]
    near = sum(any(abs(f - l) <= 1 for f in found) for l in labels)
    print(f"| {video.name} | {found} | {labels} | {len(set(found) & set(labels))}/{len(labels)} | {near}/{len(labels)} |")
timelines = [Image.open(video / "timeline.png").convert("RGB") for video in videos]
sheet = Image.new("RGB", (max(t.width for t in timelines), sum(t.height for t in timelines)), "white")
for row, timeline in enumerate(timelines):
    sheet.paste(timeline, (0, sum(t.height for t in timelines[:row])))
sheet.save(out / "timelines.png")
PY

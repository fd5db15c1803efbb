#!/bin/sh
# docs/discover.md, "Your own videos": import, train, discover, look, score, on ten mp4s that PyAV writes (not keyin).
# From the repository root, with keyin installed:  sh docs/examples/own_videos.sh [/tmp/own_videos]
set -e
DIR=${1:-/tmp/own_videos}
python docs/examples/make_videos.py "$DIR"            # my_videos/run00.mp4 ... run09.mp4 (128x128, 240 frames, 20 fps), labels.csv
cd "$DIR"
SIZES="dataset.image_size=32 dataset.channels=1 dataset.n_cond=5 dataset.n_future=30"   # the pretrained Brownian model's sizes
echo "+ keyin-import"; keyin-import source=my_videos labels=labels.csv $SIZES progress=false hydra.run.dir=runs/import
echo "+ keyin-train";  keyin-train dataset=custom $SIZES scale=smoke logger=none trainer.enable_progress_bar=false hydra.run.dir=runs/train
echo "+ keyin-discover"; keyin-discover ckpt=pretrained:brownian input=my_videos labels=labels.csv progress=false hydra.run.dir=runs/discover
echo "+ look";         ls runs/discover/run00.mp4; python -c "import json; k = json.load(open('runs/discover/run00.mp4/keyframes.json')); print([(e['frame'], e['time']) for e in k['keyframes']][:8], k['labels'][:8])"
echo "+ keyin-eval";   keyin-eval ckpt=pretrained:brownian data=data/custom/test-00000.h5 'tolerances=[1,2]' progress=false hydra.run.dir=runs/score

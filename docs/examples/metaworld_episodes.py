"""One Meta-World expert episode per task of `keyin-generate dataset=metaworld`, as the mp4s a user would
bring (256×256, 10 frames per second, running on 8 frames after the first success), and the expert's
phase switches and first success as a labels CSV: the input of `keyin-discover ckpt=pretrained:metaworld`
in docs/metaworld.md ("Keyframes of a Meta-World video").

    MUJOCO_GL=egl python docs/examples/metaworld_episodes.py docs/examples/metaworld

The episodes come from the dataset's own generator and timing (hand start, speed cap, pauses), at seeds
no split draws (train, val and test start at 0, 1e8 and 2e8, named splits at 3e8): none was trained on.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import imageio.v3 as iio

from keyin.data.metaworld import DEFAULT_TASKS, MetaWorldGenerator

SEED = 900_000_000
FPS = 10           # a saved frame every 8 env steps of 12.5 ms: real time
N_FUTURE = 39      # long enough for the slowest expert plus the tail (a clip of the dataset holds 25)
TAIL_FRAMES = 8    # frames kept after the first success (the dataset keeps 2)


def main(folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    generator = MetaWorldGenerator(image_size=256, n_future=N_FUTURE, tail_frames=TAIL_FRAMES)
    remaining, index = list(DEFAULT_TASKS), 0
    with open(folder / "labels.csv", "w", newline="") as out:
        labels = csv.writer(out)
        labels.writerow(["video", "frame"])
        while remaining:  # the generator draws each episode's task from its seed: the first of each task
            arrays, _ = generator.generate(index, SEED)
            task = DEFAULT_TASKS[int(arrays["task"])]
            index += 1
            if task not in remaining:
                continue
            remaining.remove(task)
            name = f"{task.removesuffix('-v3')}.mp4"
            length = int(arrays["length"])
            iio.imwrite(folder / name, arrays["frames"][:length], plugin="pyav", codec="libx264", fps=FPS)
            labels.writerows([name, int(frame)] for frame in arrays["keyframes"][:length].nonzero()[0])
            print(f"{name}: {length} frames, keyframes {arrays['keyframes'][:length].nonzero()[0].tolist()}")


if __name__ == "__main__":
    main(Path(sys.argv[1]))

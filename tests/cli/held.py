"""``python -m tests.cli.held <point> <command> [overrides...]``: run ``keyin-<command>`` and stop it
(asleep) at ``<point>``, so that a test can kill -9 it exactly there.

Points:

* ``rename:<file name>``: the file is written under its temporary name, not yet renamed;
* ``checkpoint``: right after the first checkpoint is saved;
* ``journal:<n>``: keyin-plan has appended n task lines to ``tasks.jsonl`` and written half of the next;
* ``none``: not held (the test kills it when it sees fit).
"""

from __future__ import annotations

import importlib
import json
import os
import sys
import time
from pathlib import Path


def hang() -> None:
    time.sleep(3600)  # the test kills the process here


def hold_before_rename(name: str) -> None:
    real_replace = os.replace

    def replace(src, dst, **kwargs):
        if Path(dst).name == name:
            hang()
        real_replace(src, dst, **kwargs)

    os.replace = replace


def hold_after_checkpoint() -> None:
    from keyin.lit.checkpoints import AtomicCheckpointIO

    real_save = AtomicCheckpointIO.save_checkpoint

    def save(self, checkpoint, path, storage_options=None):
        real_save(self, checkpoint, path, storage_options)
        hang()

    AtomicCheckpointIO.save_checkpoint = save


def hold_mid_journal_line(finished: int) -> None:
    from keyin.planning import runner

    real_append, appended = runner.append_json_line, []

    def append(path, record):
        if len(appended) == finished:
            line = json.dumps(dict(record), sort_keys=True)
            with open(path, "a", encoding="utf-8") as handle:
                handle.write(line[: len(line) // 2])
            hang()
        real_append(path, record)
        appended.append(record)

    runner.append_json_line = append


def main(argv: list[str]) -> None:
    point, command, *overrides = argv
    if point.startswith("rename:"):
        hold_before_rename(point.partition(":")[2])
    elif point == "checkpoint":
        hold_after_checkpoint()
    elif point.startswith("journal:"):
        hold_mid_journal_line(int(point.partition(":")[2]))
    elif point != "none":
        raise SystemExit(f"unknown hold point {point!r}")
    sys.argv = [f"keyin-{command}", *overrides]
    importlib.import_module(f"keyin.cli.{command}").main()


if __name__ == "__main__":
    main(sys.argv[1:])

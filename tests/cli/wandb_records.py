"""The records of a wandb offline run file (``run-<id>.wandb``), read without wandb's service.

wandb writes its offline runs as a LevelDB-style log (``:W&B`` header, 32 KiB blocks of chunks with a
7-byte header: CRC, length, kind) of ``wandb_internal_pb2.Record`` messages; this wandb writes no
``files/config.yaml`` or ``wandb-summary.json`` offline, so the tests read the log itself.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Iterator

from wandb.proto import wandb_internal_pb2

BLOCK, HEADER = 32768, 7
WHOLE, LAST = 1, 4  # chunk kinds that end a record


def records(path: Path) -> Iterator[Any]:
    """Every record of the file, in order."""
    data, position, pending = Path(path).read_bytes(), HEADER, b""
    while position + HEADER <= len(data):
        if BLOCK - position % BLOCK < HEADER:  # a block's tail too short for a chunk header is padding
            position += BLOCK - position % BLOCK
            continue
        length, kind = int.from_bytes(data[position + 4:position + 6], "little"), data[position + 6]
        pending += data[position + HEADER:position + HEADER + length]
        position += HEADER + length
        if kind in (WHOLE, LAST):
            record = wandb_internal_pb2.Record()
            record.ParseFromString(pending)
            pending = b""
            yield record


def offline_run(path: Path) -> dict[str, Any]:
    """A run's name, group, config (top-level keys → values) and summary (key → value) from its file."""
    run: dict[str, Any] = {"config": {}, "summary": {}}
    for record in records(path):
        kind = record.WhichOneof("record_type")
        if kind == "run":
            run.update(name=record.run.display_name, group=record.run.run_group)
        elif kind == "config":
            run["config"] |= {item.key: json.loads(item.value_json) for item in record.config.update if item.key}
        elif kind == "summary":
            run["summary"] |= {item.key: json.loads(item.value_json) for item in record.summary.update if item.key}
    return run

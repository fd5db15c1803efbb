"""Write a generated dataset as HDF5 shards with a manifest: parallel, resumable, with progress.

Any generator with ``n_cond`` and ``generate(index, seed) -> (arrays of one clip, attempts)`` plugs
in (``BrownianGenerator``, ``PushingGenerator``). Clip ``i`` of a split is generated from
``split_seed + i`` so the result does not depend on the worker count. Each shard is written to a
temporary file and renamed, then recorded with its checksum in the manifest; a re-run skips every
shard whose file matches the manifest and regenerates the rest.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Protocol

import numpy as np
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from keyin.data.hdf5 import MANIFEST_NAME, inspect_shard, read_manifest, write_manifest, write_shard
from keyin.errors import DatasetFormatError
from keyin.io import remove_stale_temporaries, sha256_of
from keyin.paths import inside
from keyin.workers import exit_with_parent

# Splits draw from disjoint seed ranges: clip i of split s uses seed + SPLIT_OFFSETS[s] + i.
SPLIT_OFFSETS = {"train": 0, "val": 100_000_000, "test": 200_000_000}


ClipMaker = Callable[[int, int], tuple[dict[str, np.ndarray], int]]


class ClipGenerator(Protocol):
    """``generate(index, seed)``: one clip's arrays and the attempts it took. A generator may also
    have ``split_makers``, split name -> such a function for splits that are not demos (pushing's
    ``planning`` tasks)."""

    n_cond: int

    def generate(self, index: int, seed: int) -> tuple[dict[str, np.ndarray], int]: ...


def clip_maker(generator: ClipGenerator, split: str) -> ClipMaker:
    """The function that makes the clips of ``split``: the generator's own for it, else ``generate``."""
    return getattr(generator, "split_makers", {}).get(split, generator.generate)


@dataclass(frozen=True)
class ShardJob:
    split: str
    shard: int
    start: int
    count: int

    @property
    def file(self) -> str:
        return f"{self.split}-{self.shard:05d}.h5"


def plan_shards(splits: Mapping[str, int], shard_size: int) -> list[ShardJob]:
    """Cut every split into shards of at most ``shard_size`` clips."""
    jobs = []
    for split, total in splits.items():
        for shard, start in enumerate(range(0, total, shard_size)):
            jobs.append(ShardJob(split, shard, start, min(shard_size, total - start)))
    return jobs


def split_seed(seed: int, split: str) -> int:
    """The base seed of a split; unknown split names get their own range from a stable hash."""
    if split in SPLIT_OFFSETS:
        return seed + SPLIT_OFFSETS[split]
    return seed + 300_000_000 + sum(ord(ch) * 7919**i for i, ch in enumerate(split)) % 10_000_000


def write_shard_job(
    generator: ClipGenerator, job: ShardJob, folder: Path, seed: int, meta: Mapping[str, Any]
) -> tuple[ShardJob, str, int]:
    """Generate and write one shard; returns the job, its checksum and the attempts it took."""
    base, make = split_seed(seed, job.split), clip_maker(generator, job.split)
    clips, attempts = [], 0
    for index in range(job.start, job.start + job.count):
        arrays, tries = make(index, base)
        clips.append(arrays)
        attempts += tries
    stacked = {name: np.stack([clip[name] for clip in clips]) for name in clips[0]}
    attrs = dict(meta, seed=base, split=job.split, n_cond=generator.n_cond, first_index=job.start)
    checksum = write_shard(folder / job.file, stacked, attrs)
    return job, checksum, attempts


def finished_shards(folder: Path, config: Mapping[str, Any]) -> dict[str, dict[str, dict]]:
    """Manifest entries whose shard file is present and matches its checksum.

    Raises:
        DatasetFormatError: the folder holds a dataset generated with another config.
    """
    if not (folder / MANIFEST_NAME).is_file():
        return {}
    manifest = read_manifest(folder)
    if manifest.get("config") != json.loads(json.dumps(dict(config))):
        raise DatasetFormatError(
            f"{folder} holds a dataset generated with another generator config; choose another "
            f"data_dir or delete the folder to regenerate it"
        )
    done: dict[str, dict[str, dict]] = {}
    for split, entries in manifest["splits"].items():
        for entry in entries:
            path = inside(folder, entry["file"], str(folder / MANIFEST_NAME))
            if path.is_file() and sha256_of(path) == entry["sha256"]:
                done.setdefault(split, {})[entry["file"]] = entry
    return done


def recorded_splits(folder: Path) -> dict[str, list[dict]]:
    """The manifest's shard entries per split as recorded, unchecked ({} without a manifest)."""
    return read_manifest(folder)["splits"] if (folder / MANIFEST_NAME).is_file() else {}


def unrecorded_shard(folder: Path, job: ShardJob, seed: int, meta: Mapping[str, Any]) -> dict | None:
    """The manifest entry of a shard that a killed run finished but had not recorded yet, if the
    file is exactly the one ``job`` would write (a shard gets its name only once complete)."""
    path = folder / job.file
    if not path.is_file():
        return None
    try:
        info = inspect_shard(path)
    except DatasetFormatError:
        return None
    config = json.loads(json.dumps(dict(meta["config"])))
    expected = (job.count, job.split, job.start, split_seed(seed, job.split), meta["generator"], config)
    if (info.n, info.split, info.first_index, info.seed, info.generator, info.config) != expected:
        return None
    return {"file": job.file, "n": job.count, "sha256": sha256_of(path)}


def generate_dataset(
    generator: ClipGenerator,
    folder: Path,
    dataset: str,
    splits: Mapping[str, int],
    shard_size: int,
    seed: int,
    workers: int = 1,
    config: Mapping[str, Any] | None = None,
    progress: bool = True,
) -> dict[str, Any]:
    """Generate (or finish generating) a dataset folder.

    Returns:
        Statistics: clips written, shards skipped (of them, recovered: finished by a killed run but
        not yet in its manifest), partial shards of a killed run removed, seconds, clips/s,
        rejection rate.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    stale = remove_stale_temporaries(folder)  # partial shards of a killed run
    meta = {"generator": type(generator).__name__, "config": dict(config or asdict(generator))}
    done = finished_shards(folder, meta["config"])
    jobs = plan_shards(splits, shard_size)
    recovered = 0
    for job in jobs:  # finished by a killed run after its last manifest write
        entry = None if job.file in done.get(job.split, {}) else unrecorded_shard(folder, job, seed, meta)
        if entry is not None:
            done.setdefault(job.split, {})[job.file] = entry
            recovered += 1
    todo = [job for job in jobs if done.get(job.split, {}).get(job.file, {}).get("n") != job.count]  # new or resized
    entries = {split: dict(done.get(split, {})) for split in splits}
    others = {split: shards for split, shards in recorded_splits(folder).items() if split not in splits}
    start_time, clips, attempts = time.perf_counter(), 0, 0

    def save_manifest() -> None:
        ordered = {s: [entries[s][name] for name in sorted(entries[s])] for s in entries}
        write_manifest(folder, dataset, {**others, **ordered}, meta["config"])

    columns = (
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total} clips"),
        TextColumn("{task.fields[rate]:.1f} clips/s, rejected {task.fields[rejected]:.0%}"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    )
    with Progress(*columns, disable=not progress) as bar:
        task = bar.add_task(
            f"{dataset} -> {folder}", total=sum(j.count for j in todo), rate=0.0, rejected=0.0
        )

        def advance(job: ShardJob, checksum: str, tries: int) -> None:
            nonlocal clips, attempts
            entries[job.split][job.file] = {"file": job.file, "n": job.count, "sha256": checksum}
            save_manifest()
            clips, attempts = clips + job.count, attempts + tries
            rate = clips / max(time.perf_counter() - start_time, 1e-9)
            bar.update(task, advance=job.count, rate=rate, rejected=1 - clips / max(attempts, 1))

        if workers <= 1:
            for job in todo:
                advance(*write_shard_job(generator, job, folder, seed, meta))
        else:
            # spawn: a forked worker of a parent that has rendered with EGL can hang.
            context = multiprocessing.get_context("spawn")
            pool = ProcessPoolExecutor(
                workers, mp_context=context, initializer=exit_with_parent, initargs=(os.getpid(),)
            )
            with pool:
                futures = [
                    pool.submit(write_shard_job, generator, job, folder, seed, meta) for job in todo
                ]
                for future in as_completed(futures):
                    advance(*future.result())
    save_manifest()
    seconds = time.perf_counter() - start_time
    return {
        "clips": clips,
        "shards_skipped": len(jobs) - len(todo),
        "shards_recovered": recovered,
        "stale_temporaries_removed": len(stale),
        "seconds": seconds,
        "clips_per_s": clips / seconds if clips else 0.0,
        "rejection_rate": 1 - clips / attempts if attempts else 0.0,
    }

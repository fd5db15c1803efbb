"""Training under DDP on 2 CPU processes (gloo), as ``trainer=ddp trainer.accelerator=cpu trainer.devices=2``
runs it: every model trains a step and validates through :func:`keyin.lit.run.fit_stage`; one step of
2 ranks x B clips gives the weights of one step of 1 process x 2B; the ranks draw different noise
from seed + rank. One spawn of two processes runs it all (the imports are most of its time)."""

from __future__ import annotations

import os
import socket
from pathlib import Path

import lightning as L
import pytest
import torch
import torch.multiprocessing as mp
from torch.utils.data import Dataset

from keyin.data.datamodule import ClipDataModule, rank_batch_size
from keyin.errors import ConfigError
from keyin.lit.ranks import is_rank_zero
from keyin.lit.run import fit_stage
from tests.lit.tiny_models import MODELS, batch, stage1

CLIPS = 8  # the global batch: 4 clips per rank


class Clips(Dataset):
    def __init__(self, seed: int = 0) -> None:
        self.items = batch(CLIPS, seed)

    def __len__(self) -> int:
        return CLIPS

    def __getitem__(self, index: int) -> dict[str, torch.Tensor]:
        return {key: value[index] for key, value in self.items.items()}


def deterministic_stage1() -> L.LightningModule:
    """A stage 1 whose step draws nothing (offsets of 1, every frame auto-encoded, no latent), so
    that one process and two can be compared weight for weight; plain SGD, whose step is the mean
    gradient itself (Adam's first step is lr · sign(gradient), blind to its scale)."""
    module = stage1("ours", latent_dim=0, offset_min=1, offset_max=1, ae_frames=0)
    module.configure_optimizers = lambda: torch.optim.SGD(module.parameters(), lr=0.1)
    return module


def record_first_draw(module: L.LightningModule) -> dict[str, float]:
    """The first number the rank's torch generator gives in training, recorded by a hook of ``module``."""
    drawn = {}
    module.on_train_batch_start = lambda batch, batch_idx: drawn.setdefault("draw", float(torch.rand(())))
    return drawn


def fit(module: L.LightningModule, folder: Path, devices: int) -> None:
    """One step of ``module`` on :class:`Clips` (global batch ``CLIPS``) and a validation, into ``folder``."""
    trainer_kwargs = dict(accelerator="cpu", devices=devices, strategy="ddp" if devices > 1 else "auto",
                          enable_progress_bar=False, enable_model_summary=False, num_sanity_val_steps=0)
    datamodule = ClipDataModule(Clips(), Clips(seed=1), CLIPS, num_workers=0)
    fit_stage(module, datamodule, folder, max_steps=1, val_every=1, checkpoint_every=1,
              trainer_kwargs=trainer_kwargs, logger=False, config={"seed": 7})


def rank_main(rank: int, port: int, folder: str) -> None:
    """One of two ranks: every model, then the deterministic stage 1 and the ranks' draws."""
    os.environ.update(MASTER_ADDR="127.0.0.1", MASTER_PORT=str(port), WORLD_SIZE="2", RANK=str(rank),
                      LOCAL_RANK=str(rank), NODE_RANK="0")
    torch.set_num_threads(1)
    for name, build in MODELS.items():
        fit(build(), Path(folder) / name, devices=2)
    module = deterministic_stage1()
    drawn = record_first_draw(module)
    fit(module, Path(folder) / "equivalence", devices=2)
    if rank == 0:
        torch.save(module.state_dict(), Path(folder) / "ddp_weights.pt")
    torch.save({"draw": drawn["draw"], "segment_seed": module.segment_rng.initial_seed(), "rank_zero": is_rank_zero()},
               Path(folder) / f"rank{rank}.pt")


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.mark.skipif(not torch.distributed.is_available(), reason="torch built without torch.distributed")
@pytest.mark.filterwarnings("ignore::UserWarning")
def test_two_cpu_ranks_train_every_model_and_one_step_equals_one_process_on_the_whole_batch(tmp_path):
    mp.spawn(rank_main, args=(free_port(), str(tmp_path)), nprocs=2, join=True)
    for name in MODELS:  # trained, validated and checkpointed once (rank 0 writes)
        stage = MODELS[name]().stage
        assert (tmp_path / name / "checkpoints" / stage / "last.ckpt").is_file(), name
    single = deterministic_stage1()
    fit(single, tmp_path / "single", devices=1)
    distributed = torch.load(tmp_path / "ddp_weights.pt")
    for key, value in single.state_dict().items():
        torch.testing.assert_close(distributed[key], value, rtol=1e-4, atol=1e-6, msg=key)
    ranks = [torch.load(tmp_path / f"rank{rank}.pt") for rank in (0, 1)]
    assert ranks[0]["draw"] != ranks[1]["draw"]  # seed 7 + rank: each rank its own noise
    assert [r["segment_seed"] for r in ranks] == [0, 1] and [r["rank_zero"] for r in ranks] == [True, False]


def test_the_global_batch_splits_evenly_over_the_ranks():
    assert rank_batch_size(30, 1) == 30 and rank_batch_size(32, 4) == 8
    with pytest.raises(ConfigError, match="multiple of 4"):
        rank_batch_size(30, 4)

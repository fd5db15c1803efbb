"""Two-process DDP on CPU (gloo) validates to the same loss as one process on the same clips."""

import lightning as L
import pytest
import torch
from torch.utils.data import DataLoader, Dataset

from keyin.lit.surprise import SurpriseModule


class RandomClips(Dataset):
    """8 fixed random binary clips of 2 + 6 frames of 8x8 with two labelled keyframes."""

    def __init__(self) -> None:
        generator = torch.Generator().manual_seed(0)
        self.frames = (torch.rand(8, 8, 1, 8, 8, generator=generator) > 0.7).float()
        self.keyframes = torch.zeros(8, 6, dtype=torch.bool)
        self.keyframes[:, [1, 4]] = True

    def __len__(self) -> int:
        return len(self.frames)

    def __getitem__(self, index: int) -> dict[str, torch.Tensor]:
        return {"frames": self.frames[index], "future_length": torch.tensor(6), "keyframes": self.keyframes[index]}


def surprise_module() -> SurpriseModule:
    torch.manual_seed(0)
    return SurpriseModule(
        image_size=8, channels=1, n_cond=2, n_future=6, n_keyframes=2, embed_dim=8, conv_width=4,
        coord_channels=True, norm="group", latent_dim=3, lstm_hidden=16, predictor_layers=1,
        posterior_layers=1, beta=0.1, lr=1e-3, ae_weight=1.0,
    )


def validate(devices: int, clips: Dataset | None = None) -> dict[str, float]:
    trainer = L.Trainer(
        accelerator="cpu", devices=devices, strategy="ddp_spawn" if devices > 1 else "auto", logger=False,
        enable_progress_bar=False, enable_model_summary=False,
    )
    (metrics,) = trainer.validate(surprise_module(), DataLoader(clips or RandomClips(), batch_size=8), verbose=False)
    return metrics


def validate_on_two_processes(attempts: int = 3) -> dict[str, float]:
    """`validate(2)`, retried when a worker aborts (SIGABRT) while gloo tears down its threads after the
    validation: a rare race at process exit (seen once in CI, never in 12 runs under full load here) that
    loses the results but says nothing about the metric reduction under test."""
    for _ in range(attempts - 1):
        try:
            return validate(2)
        except torch.multiprocessing.ProcessExitedException as crash:
            if crash.signal_name != "SIGABRT":
                raise
    return validate(2)


@pytest.mark.skipif(not torch.distributed.is_available(), reason="torch built without torch.distributed")
def test_two_cpu_processes_validate_to_the_loss_of_one():
    single, distributed = validate(1), validate_on_two_processes()
    rank0_clips = validate(1, torch.utils.data.Subset(RandomClips(), [0, 2, 4, 6]))  # what rank 0 sees
    assert rank0_clips["val/loss"] != pytest.approx(single["val/loss"], rel=1e-3)  # so the ranks were averaged
    for key in ("val/loss", "val/bce_per_frame", "val/kl_per_step"):
        assert distributed[key] == pytest.approx(single[key], rel=1e-5), key

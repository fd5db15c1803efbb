"""fit_stage's checkpoints: the final one, the full state at the last step, saved while the fit's own
loader runs; the best by the module's monitored validation metric; and the stage's training time over its runs."""

import shutil
import time

import lightning as L
import torch
from torch.utils.data import Dataset
from torchdata.stateful_dataloader import StatefulDataLoader

from keyin.data.datamodule import ClipDataModule
from keyin.lit.checkpoints import load_checkpoint
from keyin.lit.run import TrainingTime, fit_stage, training_seconds


class Numbers(Dataset):
    def __len__(self) -> int:
        return 40

    def __getitem__(self, index: int) -> torch.Tensor:
        return torch.tensor([float(index)])


class Line(L.LightningModule):
    stage = "line"
    monitor = ("val_loss", "min")  # what fit_stage keeps best.ckpt by

    def __init__(self) -> None:
        super().__init__()
        self.weight = torch.nn.Parameter(torch.zeros(1))

    def training_step(self, batch: torch.Tensor, batch_idx: int) -> torch.Tensor:
        return ((self.weight - batch) ** 2).mean()

    def validation_step(self, batch: torch.Tensor, batch_idx: int) -> None:
        self.log("val_loss", ((self.weight - batch) ** 2).mean())

    def configure_optimizers(self) -> torch.optim.Optimizer:
        return torch.optim.Adam(self.parameters(), lr=0.1)


TRAINER = dict(accelerator="cpu", devices=1, enable_progress_bar=False, enable_model_summary=False, num_sanity_val_steps=0)


def test_the_training_time_adds_a_resumed_run_to_the_runs_before_it():
    now = [100.0]
    timer = TrainingTime(clock=lambda: now[0])
    timer.load_state_dict({"seconds": 10.0})  # the runs before, from the checkpoint resumed
    timer.on_train_start(None, None)
    now[0] = 103.5
    assert timer.seconds == 13.5 and timer.state_dict() == {"seconds": 13.5}  # a checkpoint saved mid-run
    timer.on_train_end(None, None)
    now[0] = 200.0  # stopped: later reads do not grow
    assert timer.seconds == 13.5 and timer.state_dict() == {"seconds": 13.5}
    assert training_seconds({"callbacks": {}}) == 0.0  # a checkpoint older than the count


def test_a_resumed_stage_reports_its_time_over_both_runs_and_a_finished_one_reloaded_the_same(tmp_path):
    torch.manual_seed(0)
    data = ClipDataModule(Numbers(), Numbers(), batch_size=4, num_workers=0)
    fit = lambda steps: fit_stage(Line(), data, tmp_path, max_steps=steps, val_every=2, checkpoint_every=2,  # noqa: E731
                                  trainer_kwargs=TRAINER, logger=False, config={})
    first = fit(3)
    assert first.trained and first.seconds > 0
    assert training_seconds(load_checkpoint(first.last, "line")) == first.seconds
    started = time.perf_counter()
    second = fit(6)  # resumes at step 3
    wall = time.perf_counter() - started
    assert second.trained and first.seconds < second.seconds <= first.seconds + wall
    assert training_seconds(load_checkpoint(second.last, "line")) == second.seconds
    again = fit(6)  # has its steps: loaded, not trained
    assert again == (second.last, second.seconds, False)


def test_the_last_checkpoint_holds_the_final_step_and_starts_no_extra_loader_worker(tmp_path, monkeypatch):
    started = []
    get_iterator = StatefulDataLoader._get_iterator
    monkeypatch.setattr(StatefulDataLoader, "_get_iterator", lambda self: started.append(self) or get_iterator(self))
    torch.manual_seed(0)
    data = ClipDataModule(Numbers(), Numbers(), batch_size=4, num_workers=1)
    last, _, _ = fit_stage(Line(), data, tmp_path, max_steps=5, val_every=4, checkpoint_every=4,
                           trainer_kwargs=TRAINER, logger=False, config={})
    saved = load_checkpoint(last, "line")
    assert saved["global_step"] == 5 and saved["optimizer_states"]  # the last step, off the cadence of 4
    assert len(started) == 1  # the fit's loader only: the final state is read from its worker
    assert saved["loops"]["fit_loop"]["state_dict"]["combined_loader"][0]["_snapshot"]["_snapshot_step"] == 5  # where it stopped
    assert load_checkpoint(tmp_path / "checkpoints" / "line" / "best.ckpt")["global_step"] == 4  # its one validation


def test_a_run_resumed_from_a_last_checkpoint_another_folder_wrote_saves_over_it_not_beside_it(tmp_path):
    torch.manual_seed(0)
    data = ClipDataModule(Numbers(), Numbers(), batch_size=4, num_workers=0)
    fit = lambda folder, steps: fit_stage(Line(), data, folder, max_steps=steps, val_every=8,  # noqa: E731
                                          checkpoint_every=2, trainer_kwargs=TRAINER, logger=False, config={})
    first = fit(tmp_path / "first", 4)
    copied = tmp_path / "longer" / "checkpoints" / "line" / "last.ckpt"
    copied.parent.mkdir(parents=True)
    shutil.copy(first.last, copied)  # its callbacks' state names the first folder
    longer = fit(tmp_path / "longer", 7)  # saves at steps 6 and 7
    assert longer.last == copied and load_checkpoint(copied, "line")["global_step"] == 7
    assert sorted(path.name for path in copied.parent.glob("last*")) == ["last.ckpt"]

"""Training progress: a bar on a terminal, plain lines in a log file."""

import io

import lightning as L
import torch

from keyin.lit.progress import StepLogLines, StepProgressBar, duration, step_progress


class Tiny(L.LightningModule):
    stage = "keyframes"

    def __init__(self) -> None:
        super().__init__()
        self.net = torch.nn.Linear(2, 1)

    def training_step(self, batch, batch_idx):
        loss = self.net(batch[0]).pow(2).mean()
        self.log("train/loss", loss, prog_bar=True)
        return loss

    def train_dataloader(self):
        return torch.utils.data.DataLoader(torch.utils.data.TensorDataset(torch.randn(8, 2)), batch_size=2)

    def configure_optimizers(self):
        return torch.optim.SGD(self.parameters(), lr=0.1)


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_terminal_gets_the_bar_and_a_log_file_the_lines():
    assert isinstance(step_progress(Terminal()), StepProgressBar)
    log = io.StringIO()
    lines = step_progress(log)
    assert isinstance(lines, StepLogLines) and lines.stream is log  # its lines go where it looked


def test_the_lines_name_the_stage_its_step_of_max_steps_the_pace_and_the_metrics_with_no_carriage_return():
    log = io.StringIO()
    progress = StepLogLines(every_seconds=0.0, stream=log)
    trainer = L.Trainer(max_steps=3, callbacks=[progress], logger=False, enable_checkpointing=False,
                        enable_model_summary=False, accelerator="cpu")
    trainer.fit(Tiny())
    lines = log.getvalue().splitlines()
    assert trainer.progress_bar_callback is progress  # Lightning added no bar of its own beside it
    assert [line.split(" · ")[0] for line in lines] == ["keyframes: step 1/3", "keyframes: step 2/3", "keyframes: step 3/3"]
    assert all(" s/step · " in line and " left · train/loss=" in line for line in lines)
    assert "\r" not in log.getvalue()


def test_a_line_waits_for_its_interval_but_the_last_step_always_has_one():
    log = io.StringIO()
    trainer = L.Trainer(max_steps=4, callbacks=[StepLogLines(every_seconds=3600.0, stream=log)], logger=False,
                        enable_checkpointing=False, enable_model_summary=False, accelerator="cpu")
    trainer.fit(Tiny())
    assert [line.split(" · ")[0] for line in log.getvalue().splitlines()] == ["keyframes: step 4/4"]


def test_durations_read_in_hours_minutes_or_seconds():
    assert [duration(s) for s in (12.4, 245, 8160, 0)] == ["12s", "4m05s", "2h16m", "0s"]

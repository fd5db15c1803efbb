"""device=auto|cpu|cuda|cuda:N: what each names, one error line for a GPU the machine lacks, and the
commands that find keyframes with a trained model start without Lightning."""

import subprocess
import sys

import pytest
import torch

from keyin.devices import batch_size_on, choose_device
from keyin.errors import ConfigError


def test_auto_is_the_gpu_where_there_is_one_and_cpu_is_the_cpu():
    assert choose_device("auto") == torch.device("cuda:0" if torch.cuda.is_available() else "cpu")
    assert choose_device("cpu") == torch.device("cpu")
    assert batch_size_on(torch.device("cpu"), None, cpu=32, gpu=256) == 32
    assert batch_size_on(torch.device("cpu"), 7, cpu=32, gpu=256) == 7


@pytest.mark.skipif(torch.cuda.is_available(), reason="a machine with a GPU has cuda")
def test_a_gpu_this_machine_lacks_names_the_choices_that_run(monkeypatch):
    with pytest.raises(ConfigError, match=r"device=cuda: this machine has no GPU .*device=auto or device=cpu"):
        choose_device("cuda")
    with pytest.raises(ConfigError, match="device=tpu is not a device; choose device=auto|cpu|cuda|cuda:N"):
        choose_device("tpu")


@pytest.mark.skipif(torch.cuda.is_available(), reason="a machine with a GPU has cuda")
def test_keyin_eval_device_cuda_without_a_gpu_is_one_error_line(tmp_path):
    result = subprocess.run([sys.executable, "-m", "keyin.cli.eval", "model=random", "device=cuda",
                             f"hydra.run.dir={tmp_path}"], capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr.strip().splitlines()[-1].startswith("error: device=cuda: this machine has no GPU")


@pytest.mark.parametrize("command", ["keyin.cli.discover", "keyin.cli.eval", "keyin.cli.train", "keyin.cli.plan",
                                     "keyin.cli.report", "keyin.cli.reproduce"])
def test_the_commands_import_neither_lightning_nor_torch_before_they_run(command):
    probe = f"import sys, {command}; print(sorted({{'lightning', 'torch', 'matplotlib'}} & set(sys.modules)))"
    assert subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout.strip() == "[]"


def test_a_stage_2_checkpoint_loads_and_discovers_without_lightning():
    probe = ("import sys, torch; from keyin.lit.registry import load_trained_module; "
             "m, _ = load_trained_module('pretrained:brownian'); "
             "m.discover(torch.zeros(1, 15, 1, 32, 32), torch.tensor([10]), 'offsets'); print('lightning' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout.strip() == "False"

"""A checkpoint carrying a pickled payload is refused before anything in it runs."""

import os

import pytest
import torch

from keyin.errors import CheckpointError
from keyin.lit.checkpoints import STAGE_KEY, load_checkpoint
from tests.cli.runner import run


class Payload:
    """Unpickling this calls os.makedirs(marker): code execution, if anything unpickles it."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return (os.makedirs, (self.marker,))


def malicious_checkpoint(path, marker):
    path.parent.mkdir(parents=True, exist_ok=True)
    torch.save({STAGE_KEY: "interpolator", "state_dict": {}, "payload": Payload(marker)}, path)
    return path


def test_loading_a_checkpoint_with_a_payload_is_refused(tmp_path):
    marker = tmp_path / "pwned"
    path = malicious_checkpoint(tmp_path / "evil.ckpt", marker)
    with pytest.raises(CheckpointError, match="carry code"):
        load_checkpoint(path)
    assert not marker.exists()


def test_resuming_from_a_checkpoint_with_a_payload_stops_with_one_error(tmp_path):
    marker = tmp_path / "pwned"
    malicious_checkpoint(tmp_path / "run" / "checkpoints" / "interpolator" / "last.ckpt", marker)
    result = run("train", "scale=smoke", "stage=interpolator", "logger=none", "hydra.run.dir=run", cwd=tmp_path)
    assert result.returncode == 2
    assert "carry code" in result.stderr and "Traceback" not in result.stderr
    assert not marker.exists()

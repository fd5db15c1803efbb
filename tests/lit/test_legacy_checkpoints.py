"""Checkpoints of keyin 0.1 (no version entry) name KEYIN with our additions ``keyin``; they load
under today's name, ``keyin_plus``, while today's checkpoints keep the name they were saved with."""

from keyin import __version__
from keyin.lit.checkpoints import CONFIG_KEY, VERSION_KEY, saved_model_name


def checkpoint(name: str, version: str | None) -> dict:
    saved = {CONFIG_KEY: {"model": {"name": name}}}
    return saved if version is None else {**saved, VERSION_KEY: version}


def test_a_keyin_0_1_checkpoint_of_keyin_is_keyin_plus():
    assert saved_model_name(checkpoint("keyin", None)) == "keyin_plus"
    assert saved_model_name(checkpoint("jumpy", None)) == "jumpy"


def test_a_checkpoint_with_a_version_keeps_its_name():
    assert saved_model_name(checkpoint("keyin_paper", __version__)) == "keyin_paper"
    assert saved_model_name(checkpoint("keyin", __version__)) == "keyin"

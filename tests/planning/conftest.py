"""A pixel-free pushing environment with a hand-made layout: the wall far above, the puck at
(0, -0.3) and the pusher 0.12 below it, so a push straight up (+y) moves the puck at once."""

import numpy as np
import pytest

import keyin.envs
from keyin.envs.layout import Layout

LAYOUT = Layout(
    wall=np.array([0.0, 0.55, 0.35, 0.03, 0.1]),
    start=np.array([0.0, -0.3]),
    goal=np.array([0.0, 0.2]),
    home=np.array([0.0, -0.42]),
)


@pytest.fixture()
def env():
    env = keyin.envs.load("pushing", seed=0, pixels=False)
    env.task.pin_layout(LAYOUT)
    env.reset()
    return env

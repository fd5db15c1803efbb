"""Neural-network modules of KEYIN and its baselines (paper §3.1); nn.Modules only, no losses."""

from keyin.models.attention import attention_posterior
from keyin.models.conv import ConvDecoder, ConvEncoder
from keyin.models.frame_autoencoder import FrameAutoencoder
from keyin.models.interpolator import Interpolator, InterpolatorPosterior
from keyin.models.keyframe_predictor import KeyframeOutput, KeyframePredictor
from keyin.models.keyin import KEYIN
from keyin.models.recurrent import MLP, LSTMBlock, LSTMState, state_from_vector
from keyin.models.svg import SVG, SVGCore, SVGOutput
from keyin.models.tap import TAPNetwork

__all__ = [
    "ConvDecoder",
    "ConvEncoder",
    "FrameAutoencoder",
    "Interpolator",
    "KEYIN",
    "InterpolatorPosterior",
    "KeyframeOutput",
    "KeyframePredictor",
    "LSTMBlock",
    "LSTMState",
    "MLP",
    "SVG",
    "SVGCore",
    "SVGOutput",
    "TAPNetwork",
    "attention_posterior",
    "state_from_vector",
]

"""keyin: keyframe discovery and planning with keyframe-based stochastic video prediction."""

__version__ = "0.2.0"

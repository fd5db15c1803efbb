"""Pipelines: a trained model run over data into files (keyframes of whole videos, video
diagnostics, the paper's figures). They sit between ``cli/`` (which parses and checks a command) and
``lit/``, ``eval/`` (which load models and score): imports run cli -> pipelines -> lit/planning ->
eval -> decode -> models/losses -> data/envs (docs/architecture.md)."""

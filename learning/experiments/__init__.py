"""Experiments: the study's setups (RL and IL), checkpoints, run logs and the training loops."""

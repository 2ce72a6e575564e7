"""Imitation learning: expert demonstrations, their preprocessing into expert data, GAIL."""

"""Learning algorithms and their parts: networks, distributions, normalisation, rollouts, GAE,
TRPO.
"""

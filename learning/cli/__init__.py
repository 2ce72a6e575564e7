"""The learning commands: ``usvsim train`` and ``usvsim evaluate``."""

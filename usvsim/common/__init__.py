"""Shared helpers of every layer: angle wrapping (``ssa`` for numbers and CasADi), atomic files,
the matplotlib backend choice.
"""

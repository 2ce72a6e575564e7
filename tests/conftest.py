"""Test-wide settings: Hypothesis draws its examples from a fixed seed.

The project's rule is that every random draw flows from a seed, and CI must not pass or fail by
chance: the default profile ``usvsim`` derandomises Hypothesis (the same examples every run).
``HYPOTHESIS_PROFILE=explore python -m pytest ...`` searches with fresh random examples (and
more of them) when a property is being worked on.
"""

from __future__ import annotations

import os

try:
    from hypothesis import settings
except ImportError:  # the test extra is not installed: no property tests to configure
    pass
else:
    settings.register_profile("usvsim", derandomize=True)
    settings.register_profile("explore", derandomize=False, max_examples=500)
    settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "usvsim"))

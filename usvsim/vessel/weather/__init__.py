"""Environmental forces beyond the steady current: wind with gusts, waves, a heading wave filter.

Pure, vectorised building blocks over N boats (NumPy), seeded per episode; not yet wired into the
compiled plant kernel (issue 38). See docs/guide/weather.md.

============  =========================================================================
module        contents
============  =========================================================================
``wind``      :class:`Windage` (areas, coefficients), :class:`WindState`, gusts
              (first-order Gauss–Markov), wind forces and yaw moment (Fossen 2021 §10.1)
``waves``     sea-state table, JONSWAP spectrum, first-order wave motion filter, mean drift
``filters``   heading notch wave filter design (Fossen 2021 §13)
============  =========================================================================
"""

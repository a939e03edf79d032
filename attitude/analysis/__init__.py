"""Analyses of a body, a state or an ephemeris: they read, and propagate only when asked.

- :mod:`.diagnostics`: nutation, precession, Euler angles, measured periods, drift;
- :mod:`.classification`: the regime of an ephemeris (windows, margins, confidence);
- :mod:`.lyapunov`: finite-time Lyapunov exponents (the chaos test);
- :mod:`.spindown`: the spin period of a run and its trend;
- :mod:`.statistics`: statistics of populations.

The package imports nothing itself.
"""

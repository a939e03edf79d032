"""The application layer: scenario files (:mod:`.scenario_spec`, :mod:`.scenario`), the
``attitude`` command (:mod:`.cli`) and figures (:mod:`.plot`).

The package imports nothing itself.
"""

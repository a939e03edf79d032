"""Foundations: what every other layer builds on, and which imports nothing of the package
above it.

- :mod:`.errors`: every exception and warning;
- :mod:`.quantities`: the one reader of numbers with units and of epochs;
- :mod:`.spec`: declarative table specs (validation, JSON Schema, key reference);
- :mod:`.quaternion`: quaternion algebra, scalar-last ``(x, y, z, w)``;
- :mod:`.elliptic`: Landen transformations, Bulirsch's ``cel``, double-double arithmetic.
- :mod:`.constants`: the physical constants, each with its source;
- :mod:`.earth_rotation`: the Earth rotation angle (UT1 from the bundled IERS tables).

The package imports nothing itself.
"""

"""The model layer: mass properties, shapes, states, orbits, torques, ephemerides and
populations, each a value that the propagation and the analyses take.

- :mod:`.body`: :class:`MassProperties`, :class:`RigidBody`; :mod:`.shape`:
  :class:`Polyhedron`; :mod:`.surface`, :mod:`.raycast`: optical properties per facet and
  rays against triangles;
- :mod:`.state`: :class:`AttitudeState`; :mod:`.freebody`: the free rigid body (invariants,
  branches, ``diagnose``); :mod:`.regimes`: the regime vocabulary and thresholds;
- :mod:`.orbit`: :class:`KeplerOrbit` and paths; :mod:`.torques`: the torque protocol and
  the built-in models;
- :mod:`.ephemeris`: :class:`Ephemeris` (the dataset schema, netCDF);
- :mod:`.population`, :mod:`.sampling`, :mod:`.tables`: ensembles of bodies and states.

The package imports nothing itself.
"""

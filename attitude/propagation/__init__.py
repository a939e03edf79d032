"""Propagation: from a body and a state at an epoch to an ephemeris.

One entry point, :func:`attitude.propagate` (:mod:`.propagator`), and the methods behind
it, one module each:

- :mod:`.torquefree`: the exact Euler–Poinsot solution (Jacobi elliptic functions),
  vectorised over bodies and times, on :mod:`attitude.model.freebody` (the free-body
  algebra) and :mod:`attitude.foundations.elliptic` (Landen transformations, Bulirsch's ``cel``,
  double-double arithmetic);
- :mod:`.splitting`: the splitting integrator with torques (exact free flow composed with
  torque kicks, orders 2, 4 and 6), on :mod:`.freeflow` (the exact free flow over one
  step), :mod:`.schemes` (the compositions), :mod:`.kicks` (bodies, torques, kicks) and
  :mod:`.stepsize` (the default step);
- :mod:`.reference`: the DOP853 reference integrator of Euler's equations (scipy's, or
  the same method compiled: :mod:`.compiled_dop853`);
- :mod:`.compiled`, :mod:`.compiled_torques`, :mod:`.compiled_loop`: the numba kernels
  (elliptic functions and the free flow, the torque models, the splitting loop);
- :mod:`.events`: events located on any method's solution;
- :mod:`.batch`: populations in chunks, in this process or as dask tasks, and
  :mod:`.cluster` for dask clusters.

The package imports nothing itself, so that a model module may use one kernel
(``attitude.propagation.torquefree``) without loading the whole wing.
"""

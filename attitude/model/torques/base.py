"""The torque protocol: :class:`TorqueModel` (call, broadcasting, ``+``, and the hooks the
integrators use), sums, plain functions as models, and the kinematics of internal torques
(:func:`internal_rate`).  The protocol itself is described in :mod:`attitude.model.torques`."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...foundations import quaternion as quat
from .common import dot, inertia_of, matvec, unit_quaternion

__all__ = ["TorqueModel", "SumTorque", "FunctionTorque", "as_torque_model", "internal_rate"]


class TorqueModel:
    """Base class of torque models: call protocol, broadcasting, ``+`` and the hooks the
    integrators use (time scale, time shift, internal or external).

    Subclasses implement :meth:`evaluate`, which receives numpy arrays (``t`` as an
    array, a unit quaternion, ``omega_body``) and returns body-frame torques that
    broadcast over the leading axes; :meth:`__call__` does the conversions.  The
    integrators and the Lyapunov test use nothing but this protocol: a user's own
    subclass gets the same treatment as the built-in models (override
    :meth:`characteristic_rate` and :meth:`shifted` when the defaults are too generic).

    Attributes
    ----------
    velocity_dependent : bool
        Whether the torque depends on ``omega_body`` (dissipative models do; gravity
        gradient, constant and pivot torques do not).
    internal : bool
        Whether the torque is exerted by one part of the body on another (a damper, an
        inelastic body): it can only turn ``L`` in the body frame and must keep the
        inertial angular momentum.  Integrators then move the attitude with the body
        frame, ``dq/dt = q (omega + (M x L)/L^2) / 2``, so that ``R L_body`` stays fixed
        (:class:`EnergyDissipation`, docs/torques.md).  The torque must be normal to
        ``L``.

    Examples
    --------
    A user model: only :meth:`evaluate` is required; the defaults of
    :meth:`characteristic_rate` and :meth:`shifted` work from it.

    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import TorqueModel
    >>> class Wobble(TorqueModel):
    ...     velocity_dependent = False
    ...     def evaluate(self, t, quaternion, omega_body, body):
    ...         return np.stack(np.broadcast_arrays(1e-3 * np.cos(t), 0.0, 0.0), axis=-1)
    >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> model = Wobble()
    >>> model.shifted(np.pi)(0.0, [0, 0, 0, 1], [0.0, 0.0, 0.0], body)
    array([-0.001,  0.   ,  0.   ])
    >>> round(float(model.characteristic_rate(0.0, [0, 0, 0, 1], [0.0, 0.0, 0.0], body)), 4)
    0.0316
    """

    velocity_dependent: bool = True
    internal: bool = False

    def __call__(self, t, quaternion, omega_body, body) -> np.ndarray:
        """Body-frame torque, N m, shape ``broadcast(t, quaternion[..., 0],
        omega_body[..., 0]) + (3,)``."""
        t = np.asarray(t, dtype=float)
        q = unit_quaternion(quaternion)
        w = np.asarray(omega_body, dtype=float)
        out = np.asarray(self.evaluate(t, q, w, body), dtype=float)
        if out.shape == (3,) and t.ndim == 0 and q.ndim == 1 and w.ndim == 1:
            return out
        lead = np.broadcast_shapes(t.shape, q.shape[:-1], w.shape[:-1], out.shape[:-1])
        return out if out.shape[:-1] == lead else np.broadcast_to(out, lead + (3,)).copy()

    def evaluate(self, t: np.ndarray, quaternion: np.ndarray, omega_body: np.ndarray,
                 body) -> np.ndarray:
        """The torque on numpy arrays: ``t`` (float array), ``quaternion`` (unit,
        scalar-last, body -> inertial), ``omega_body`` (rad/s); body-frame N m, broadcast
        over the leading axes.  Subclasses implement this."""
        raise NotImplementedError(f"{type(self).__name__} must implement evaluate()")

    def characteristic_rate(self, t, quaternion, omega_body, body) -> np.ndarray | float:
        """The torque's own time scale: the fastest rate (rad/s) at which it changes the
        motion, per body (leading axes of the state), or one float.

        The default is measured from the torque at the given state:
        ``min(|M| / |L|, sqrt(|I^-1 M|))``: the rate at which it turns ``L`` (a fast
        spinner), or, when that is faster, the rate at which it turns a body from rest
        (a slow or resting body, whose small ``L`` the torque builds up rather than
        turns).  Built-in models return rates
        from their parameters (orbital motion, damping time, pendulum frequency...),
        which do not vanish at an equilibrium; a user model with a time dependence of
        its own (a forcing period) should override this and include it.  The splitting
        integrator adds how fast the torque varies along the free motion itself
        (:func:`attitude.propagation.splitting.choose_step`).

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import ConstantTorque
        >>> body = RigidBody.from_principal_moments([2.0, 3.0, 4.0])
        >>> float(ConstantTorque([0.0, 0.0, 0.04]).characteristic_rate(
        ...     0.0, [0, 0, 0, 1], [0.0, 0.0, 0.0], body))          # sqrt(0.04 / 4)
        0.1
        """
        q = unit_quaternion(quaternion)
        w = np.asarray(omega_body, dtype=float)
        m = np.asarray(self(t, q, w, body), dtype=float)
        inertia = inertia_of(body)
        L = matvec(inertia, w)
        m_norm = np.sqrt(dot(m, m))
        L_norm = np.sqrt(dot(L, L))
        accel = np.linalg.solve(inertia, m[..., None])[..., 0] if inertia.ndim > 2 else \
            m @ np.linalg.inv(inertia).T
        from_rest = np.sqrt(np.sqrt(dot(accel, accel)))
        with np.errstate(divide="ignore", invalid="ignore"):
            turn = np.where(L_norm > 0, m_norm / np.where(L_norm > 0, L_norm, 1.0), np.inf)
        rate = np.minimum(turn, from_rest)
        return float(rate) if np.ndim(rate) == 0 else rate

    def shifted(self, dt: float) -> TorqueModel:
        """The same model with its time origin moved by ``dt`` seconds: the result at
        ``t`` is this model's at ``t + dt`` (what a propagation restarted ``dt`` after
        the epoch needs).  The default wraps the model; built-in models return a model
        of their own class (a Keplerian orbit with its mean anomaly advanced...), or
        themselves when they do not depend on time.

        Examples
        --------
        >>> from attitude.model.torques import ConstantTorque
        >>> m = ConstantTorque([0.0, 0.0, 1e-3])
        >>> m.shifted(60.0) is m                  # no time dependence
        True
        """
        dt = float(dt)
        if dt == 0.0:
            return self
        return _ShiftedTorque(self, dt)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """The model as numbers for a compiled torque kernel, or None when it has no
        compiled form (the default: a user's model runs in Python).

        A list of ``(kind, values)`` terms, one per elementary model, whose sum is this
        model's torque on ``body`` (one body): ``kind`` names the formula, ``values``
        holds its SI parameters and the paths or fields it reads (objects with their own
        ``compiled_parameters``), and optionally ``time_shift`` (s: the term is read at
        ``t + time_shift``, what :meth:`shifted` wraps).
        :func:`attitude.propagation.compiled_torques.compile_torques` lays them out in
        flat arrays; ``t_span = (t0, t1)`` (s) is the time the run covers, which a
        tabulated path needs.

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import ConstantTorque, FunctionTorque
        >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
        >>> ConstantTorque([0.0, 0.0, 1e-3]).compiled_parameters(body)
        [('constant_body', {'torque': array([0.   , 0.   , 0.001])})]
        >>> FunctionTorque(lambda t, q, w, b: w).compiled_parameters(body) is None
        True
        """
        return None

    def __add__(self, other):
        try:
            other = as_torque_model(other)
        except TypeError:
            return NotImplemented
        return SumTorque(self, other)

    def __radd__(self, other):
        if isinstance(other, (int, float)) and other == 0:  # sum([gg, damping])
            return self
        try:
            other = as_torque_model(other)
        except TypeError:
            return NotImplemented
        return SumTorque(other, self)


class SumTorque(TorqueModel):
    """The sum of several torque models (what ``a + b`` returns).

    Parameters
    ----------
    *terms : torque models or plain functions
        Nested sums are flattened.

    Examples
    --------
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import ConstantTorque
    >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> both = ConstantTorque([1e-3, 0, 0]) + ConstantTorque([0, 2e-3, 0])
    >>> type(both).__name__, both(0.0, [0, 0, 0, 1], [0.0, 0.0, 0.1], body)
    ('SumTorque', array([0.001, 0.002, 0.   ]))
    """

    def __init__(self, *terms):
        flat = []
        for term in terms:
            term = as_torque_model(term)
            flat.extend(term.terms if isinstance(term, SumTorque) else [term])
        self.terms = tuple(flat)
        self.velocity_dependent = any(t.velocity_dependent for t in self.terms)
        # a sum is internal only if every term is (integrators take sums apart anyway)
        self.internal = bool(self.terms) and all(t.internal for t in self.terms)

    def characteristic_rate(self, t, quaternion, omega_body, body):
        """The fastest of the terms' rates."""
        rate = 0.0
        for term in self.terms:
            rate = np.maximum(rate, term.characteristic_rate(t, quaternion, omega_body, body))
        return float(rate) if np.ndim(rate) == 0 else rate

    def shifted(self, dt: float) -> SumTorque:
        """The sum of the shifted terms (itself for ``dt = 0``)."""
        if float(dt) == 0.0:
            return self
        return SumTorque(*[term.shifted(dt) for term in self.terms])

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """The terms' compiled forms, concatenated; None if any term has none.

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import ConstantTorque
        >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
        >>> both = ConstantTorque([1e-3, 0, 0]) + ConstantTorque([0, 1e-3, 0], frame="inertial")
        >>> [kind for kind, _ in both.compiled_parameters(body)]
        ['constant_body', 'constant_inertial']
        """
        out = []
        for term in self.terms:
            part = term.compiled_parameters(body, t_span)
            if part is None:
                return None
            out.extend(part)
        return out

    def __call__(self, t, quaternion, omega_body, body) -> np.ndarray:
        total = None
        for term in self.terms:
            out = np.asarray(term(t, quaternion, omega_body, body), dtype=float)
            total = out if total is None else total + out
        if total is None:
            lead = np.broadcast_shapes(np.shape(t), np.shape(omega_body)[:-1])
            return np.zeros(lead + (3,))
        return total

    def __len__(self) -> int:
        return len(self.terms)

    def __iter__(self):
        return iter(self.terms)

    def __repr__(self) -> str:
        return " + ".join(repr(t) for t in self.terms) if self.terms else "SumTorque()"


class FunctionTorque(TorqueModel):
    """A plain function ``f(t, quaternion, omega_body, body) -> torque`` as a model.

    The function receives the arguments exactly as the caller passes them (no
    conversion), so it must itself handle the shapes it is called with.

    Parameters
    ----------
    function : callable
    velocity_dependent : bool
        Declare ``False`` if the torque does not depend on ``omega_body`` (it lets a
        splitting integrator treat it as a conservative kick).
    internal : bool
        Declare ``True`` for a torque between parts of the body (normal to ``L``): the
        integrators then keep the inertial angular momentum (:attr:`TorqueModel.internal`).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import FunctionTorque
    >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> drag = FunctionTorque(lambda t, q, w, b: -1e-3 * np.asarray(w))   # rate damping
    >>> drag(0.0, [0, 0, 0, 1], [0.0, 0.0, 2.0], body)
    array([-0.   , -0.   , -0.002])
    """

    def __init__(self, function: Callable, *, velocity_dependent: bool = True,
                 internal: bool = False):
        if not callable(function):
            raise TypeError(f"expected a callable torque(t, quaternion, omega_body, body), "
                            f"got {type(function).__name__}")
        self.function = function
        self.velocity_dependent = bool(velocity_dependent)
        self.internal = bool(internal)

    def __call__(self, t, quaternion, omega_body, body) -> np.ndarray:
        return np.asarray(self.function(t, quaternion, omega_body, body), dtype=float)

    def __repr__(self) -> str:
        return f"FunctionTorque({getattr(self.function, '__name__', repr(self.function))})"


class _ShiftedTorque(TorqueModel):
    """A model evaluated at ``t + dt`` (the default of :meth:`TorqueModel.shifted`)."""

    def __init__(self, inner: TorqueModel, dt: float):
        self.inner, self.dt = inner, float(dt)
        self.velocity_dependent = inner.velocity_dependent
        self.internal = inner.internal

    def __call__(self, t, quaternion, omega_body, body) -> np.ndarray:
        return self.inner(np.asarray(t, dtype=float) + self.dt, quaternion, omega_body, body)

    def characteristic_rate(self, t, quaternion, omega_body, body):
        return self.inner.characteristic_rate(np.asarray(t, dtype=float) + self.dt,
                                              quaternion, omega_body, body)

    def shifted(self, dt: float) -> TorqueModel:
        dt = float(dt)
        return self if dt == 0.0 else _ShiftedTorque(self.inner, self.dt + dt)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """The inner model's terms, each read at ``t + dt`` (``time_shift``), its paths
        over the shifted span; None if the inner model has no compiled form.

        Examples
        --------
        >>> import numpy as np
        >>> from attitude import RigidBody
        >>> from attitude.model.orbit import TabulatedPath
        >>> from attitude.model.torques import GravityGradient
        >>> t = np.linspace(0.0, 100.0, 11)
        >>> gg = GravityGradient(3.986e14, TabulatedPath(t, np.stack([7e6 + t, 0 * t, 0 * t],
        ...                                                          axis=-1)))
        >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
        >>> gg.shifted(5.0).compiled_parameters(body, (0.0, 90.0))[0][1]["time_shift"]
        5.0
        """
        span = None if t_span is None else (t_span[0] + self.dt, t_span[1] + self.dt)
        parts = self.inner.compiled_parameters(body, span)
        if parts is None:
            return None
        return [(kind, {**values, "time_shift": values.get("time_shift", 0.0) + self.dt})
                for kind, values in parts]

    def __repr__(self) -> str:
        return f"{self.inner!r} at t + {self.dt:.9g} s"


def as_torque_model(obj, *, velocity_dependent: bool | None = None,
                    internal: bool | None = None) -> TorqueModel:
    """Return ``obj`` if it is a :class:`TorqueModel`, else wrap a callable in a
    :class:`FunctionTorque` (so that ``+`` works on it, and the integrators can ask it
    for its time scale and shift its time origin).

    ``velocity_dependent`` and ``internal`` default to the callable's attributes of
    those names if it has them, else ``True`` and ``False``.

    Raises
    ------
    TypeError
        If ``obj`` is not callable.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.model.torques import ConstantTorque, as_torque_model
    >>> def spin_up(t, quaternion, omega_body, body):
    ...     return np.broadcast_to([0.0, 0.0, 1e-3], np.shape(omega_body))
    >>> model = as_torque_model(spin_up) + ConstantTorque([1e-3, 0.0, 0.0])
    >>> model(0.0, [0, 0, 0, 1], [0.0, 0.0, 0.1], None)
    array([0.001, 0.   , 0.001])
    """
    if isinstance(obj, TorqueModel):
        return obj
    if velocity_dependent is None:
        velocity_dependent = getattr(obj, "velocity_dependent", True) is not False
    if internal is None:
        internal = getattr(obj, "internal", False) is True
    return FunctionTorque(obj, velocity_dependent=velocity_dependent, internal=internal)


def internal_rate(torque, omega_body, body) -> np.ndarray:
    r"""Extra body-frame rate of the attitude under an internal torque, rad/s.

    ``(M x L) / L^2`` with ``L = I omega``: added to ``omega`` in the attitude
    kinematics it keeps the inertial ``L`` fixed while ``M`` turns ``L`` in the body
    frame (:class:`EnergyDissipation`).  Zero where ``L = 0``.

    Parameters
    ----------
    torque : (..., 3) array
        Internal torque (normal to ``L``), body frame, N m.
    omega_body : (..., 3) array
        rad/s.
    body : RigidBody, sequence of them, or inertia array (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import EnergyDissipation, internal_rate
    >>> body = RigidBody.from_principal_moments([1.0, 1.5, 2.0])
    >>> w = np.array([0.3, 0.1, 0.2])
    >>> M = EnergyDissipation(60.0)(0.0, [0, 0, 0, 1], w, body)
    >>> L = body.inertia @ w
    >>> bool(np.allclose(np.cross(internal_rate(M, w, body), L), -M, atol=1e-17))
    True
    """
    M = np.asarray(torque, dtype=float)
    L = matvec(inertia_of(body), np.asarray(omega_body, dtype=float))
    L2 = dot(L, L)
    safe = np.where(L2 > 0, L2, 1.0)
    out = quat.cross(M, L) / np.asarray(safe)[..., None]
    return np.where(np.asarray(L2)[..., None] > 0, out, 0.0)

"""A constant torque, in body or inertial axes."""

from __future__ import annotations

import difflib

from ...foundations import quaternion as quat
from ...foundations.errors import TorqueConfigError
from .base import TorqueModel
from .common import si_value

__all__ = ["ConstantTorque"]


class ConstantTorque(TorqueModel):
    """A torque fixed in body axes (a thruster misalignment, a stuck wheel) or in
    inertial axes (rotated into the body frame by the attitude: ``M_b = q^{-1} M q``).

    Parameters
    ----------
    torque : (3,) array-like, Quantity or ``{value, unit}``
        N m.
    frame : {"body", "inertial"}

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import ConstantTorque
    >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> half_turn_z = [0, 0, 1.0, 0]                     # body x along inertial -x
    >>> ConstantTorque([1e-3, 0, 0], frame="inertial")(0.0, half_turn_z, [0, 0, 0], body)
    array([-0.001,  0.   ,  0.   ])
    """

    velocity_dependent = False
    FRAMES = ("body", "inertial")

    def __init__(self, torque, frame: str = "body"):
        self.torque = si_value(torque, "N m", "torque", shape=(3,))
        if frame not in self.FRAMES:
            near = difflib.get_close_matches(str(frame), self.FRAMES, n=1)
            did = f"did you mean {near[0]!r}? " if near else ""
            raise TorqueConfigError(f"unknown frame {frame!r}; {did}choose 'body' "
                                    "or 'inertial'", key="frame")
        self.frame = frame

    def evaluate(self, t, quaternion, omega_body, body):
        if self.frame == "body":
            return self.torque.copy()
        return quat.rotate(quaternion, self.torque, inverse=True)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]]:
        """``[("constant_body" or "constant_inertial", {torque})]``
        (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude.model.torques import ConstantTorque
        >>> ConstantTorque([1.0, 0, 0], frame="inertial").compiled_parameters(None)[0][0]
        'constant_inertial'
        """
        return [(f"constant_{self.frame}", {"torque": self.torque.copy()})]

    def shifted(self, dt: float) -> ConstantTorque:
        """Itself (no time dependence)."""
        return self

    def __repr__(self) -> str:
        return f"ConstantTorque({self.torque.tolist()} N m, frame={self.frame!r})"

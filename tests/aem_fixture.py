"""The ephemeris behind ``tests/data/written_by_attitude_0_3.*``: AEM files written by
``attitude`` before ``write_aem`` was split into steps, kept to check that its output stays
byte for byte the same.

Every number is chosen so that the written text does not depend on the machine: the
quaternions have norms of exactly 1 in binary (components 0, +-0.5, 1), so the
normalisation of ``Ephemeris.from_arrays`` leaves them unchanged, and the rates, with
many digits, go through one correctly rounded multiplication (rad -> deg) or the
quaternion product of ``QUATERNION/DERIVATIVE`` (exact in these components).
"""

import numpy as np
from astropy.time import Time

import attitude as att

#: write_aem options of each fixture file (the ``CREATION_DATE`` line is not compared).
CASES = {
    "written_by_attitude_0_3.aem": {"attitude_type": "QUATERNION/ANGVEL",
                                    "comments": ["frozen output", "second line"],
                                    "message_id": "FIXTURE-1", "center_name": "earth",
                                    "interpolation_method": "LAGRANGE",
                                    "interpolation_degree": 7},
    "written_by_attitude_0_3.xml": {"attitude_type": "QUATERNION/DERIVATIVE",
                                    "object_id": "2029-001A", "originator": "tests"},
    "written_by_attitude_0_3_q.aem": {"attitude_type": "QUATERNION", "time_system": "TAI"},
}


def frozen_ephemeris() -> att.Ephemeris:
    q = np.array([[0.0, 0.0, 0.0, 1.0], [0.5, 0.5, 0.5, 0.5], [0.5, -0.5, 0.5, 0.5],
                  [1.0, 0.0, 0.0, 0.0], [-0.5, 0.5, 0.5, 0.5], [0.0, 1.0, 0.0, 0.0],
                  [0.5, 0.5, -0.5, 0.5]])
    w = np.array([[0.0123456789012345, -0.002, 0.3], [1e-7, 2.5e-5, -0.0625],
                  [0.1, 0.2, 0.3], [-1.0, 0.0, 1e-12], [0.03125, -0.015625, 0.0078125],
                  [3.14159265358979, 2.71828182845905, -1.41421356237310],
                  [0.0, 0.0, 0.0]])
    t = np.array([0.0, 0.5, 1.25, 60.0, 61.000000001, 3600.125, 86400.0])
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0], name="fixture-sat")
    eph = att.Ephemeris.from_arrays(
        t, q, w, body=body, frame="EME2000",
        epoch=Time("2029-04-13T21:46:00.123456789", scale="utc"))
    ds = eph.dataset
    ds["aem_segment"] = ("time", np.array([0, 0, 0, 1, 1, 2, 2], dtype=np.int32))
    return att.Ephemeris(ds)

"""CCSDS Attitude Ephemeris Messages (AEM): read and write, KVN and XML forms.

The Attitude Ephemeris Message is the attitude-history exchange format of the CCSDS
Attitude Data Messages standard (CCSDS 504.0-B-2, January 2024, section 4; XML in
section 7).  :func:`write_aem` writes version 2.0; :func:`read_aem` reads versions 1.0
(CCSDS 504.0-B-1) and 2.0, in either form (detected from the content).

Conventions (CCSDS 504.0-B-2 annex F, and how they meet ours)
--------------------------------------------------------------
* **Quaternion.** The AEM quaternion "from frame A to frame B" is the rotation that
  carries the basis vectors of A onto those of B; the coordinates transform as
  ``X_B = M_BA X_A`` with ``M_BA`` the *transpose* of the rotation matrix of
  ``(Q1, Q2, Q3, QC)``, i.e. ``X_A = R(q) X_B`` (annex F2).  With A the inertial frame
  and B the body frame that is exactly our attitude quaternion, which maps body-frame
  vectors into the inertial frame (``v_inertial = R(q) v_body``): the components are
  written unchanged, ``Q1 Q2 Q3 QC = x y z w`` (version 2 puts the scalar ``QC`` last).
  :func:`write_aem` always writes ``REF_FRAME_A`` = the inertial frame and
  ``REF_FRAME_B`` = the body frame.  :func:`read_aem` accepts either order (it inverts
  the rotation when ``REF_FRAME_A`` is the body frame) and, for version 1 files, the
  ``QUATERNION_TYPE = FIRST | LAST`` and ``ATTITUDE_DIR = A2B | B2A`` choices.
* **Euler angles** (annex F3): three successive *intrinsic* rotations carrying A onto
  B, in the order of ``EULER_ROT_SEQ`` (``ZXZ``; version 1 spelled it ``313``), in
  degrees.  In scipy terms ``R(q) = Rotation.from_euler("ZXZ", angles, degrees=True)``
  (upper case = intrinsic).
* **Angular velocity** (annex F4): the angular velocity of B relative to A, in deg/s,
  with components in the frame named by ``ANGVEL_FRAME`` (A or B).  Ours is the body
  rate relative to inertial space in body components, rad/s: written with
  ``ANGVEL_FRAME`` = the body frame (``REF_FRAME_B``) unless asked otherwise.
  ``.../DERIVATIVE`` types carry time derivatives of the quaternion (1/s) or of the
  Euler angles (deg/s) instead, converted exactly (``q_dot = q omega / 2``).
* **Time**: ``TIME_SYSTEM`` maps to an astropy scale (:data:`AEM_TIME_SYSTEMS`); GPS,
  Galileo (GST) and BeiDou (BDT) time are stored as TAI (``TAI = GPS + 19 s``,
  ``TAI = BDT + 33 s``).  Epochs are written with 9 decimals of seconds from astropy's
  two-double representation (``epoch + TimeDelta``), so they are exact to 0.5 ns.
* **Numbers** are written with the shortest decimal that reads back to the same
  double, capped at the 16 significant digits the standard allows (6.8.4): a quaternion
  component comes back within 5e-17.

What is checked on reading (each failure raises :class:`~attitude.EphemerisFormatError`
naming the file, the line and the keyword): the version line and version (1.0 or 2.0;
version-1 keywords in a version-2 file), every mandatory header and metadata keyword,
unknown or repeated keywords, ``ATTITUDE_TYPE`` (and the keywords each type needs:
``EULER_ROT_SEQ``, ``ANGVEL_FRAME``, ``QUATERNION_TYPE``, ``ATTITUDE_DIR``),
``TIME_SYSTEM``, the frames (exactly one of ``REF_FRAME_A``/``REF_FRAME_B`` must be an
inertial frame of :data:`attitude.INERTIAL_FRAMES`), malformed epochs and numbers,
data lines with the wrong number of fields, non-finite values, quaternions whose norm
is off by more than :data:`AEM_QUATERNION_NORM_TOL`, time not increasing within a
segment or going backwards between segments, and XML units attributes that differ
from the standard's units.

An AEM carries no mass properties.  :func:`read_aem` takes the body as ``body=``;
without it the ephemeris has no ``inertia`` attribute, ``inertia_known = 0``, and its
``angular_momentum`` and ``kinetic_energy`` are NaN (unknown) rather than computed for
an invented body.

The implementation, one concept per module: :mod:`.aem_message` (the message as data,
shared by both encodings), :mod:`.aem_kvn` and :mod:`.aem_xml` (the encodings),
:mod:`.aem_kinematics` (attitudes and rates at the file boundary), :mod:`.aem_read`
and :mod:`.aem_write` (the entry points, re-exported here) and :mod:`.conversion`
(``attitude convert``).
"""

from __future__ import annotations

from .aem_message import (
    AEM_ATTITUDE_TYPES,
    AEM_QUATERNION_NORM_TOL,
    AEM_TIME_SYSTEMS,
    AEM_WRITE_TYPES,
    CCSDS_AEM_VERS,
)
from .aem_read import read_aem
from .aem_write import write_aem
from .conversion import convert

__all__ = [
    "read_aem",
    "write_aem",
    "convert",
    "CCSDS_AEM_VERS",
    "AEM_ATTITUDE_TYPES",
    "AEM_WRITE_TYPES",
    "AEM_TIME_SYSTEMS",
    "AEM_QUATERNION_NORM_TOL",
]

"""File formats other tools read and write, beside the ephemeris's own CF netCDF
(:meth:`attitude.Ephemeris.to_netcdf`):

- :mod:`.aem`: CCSDS Attitude Ephemeris Messages, KVN and XML (read and write:
  :func:`read_aem`, :func:`write_aem`); the encodings and conversions behind them are
  in :mod:`.aem_message`, :mod:`.aem_kvn`, :mod:`.aem_xml`, :mod:`.aem_kinematics`,
  :mod:`.aem_read` and :mod:`.aem_write`;
- :mod:`.spice`: SPICE C-kernels (type 3), with spiceypy
  (``pip install "attitude-dynamics[spice]"``, imported only when a kernel is written or
  read); :mod:`.spice_read` reads them (:func:`read_ck`, with the kernels found beside
  the CK; :meth:`attitude.Ephemeris.from_spice` underneath);
- :mod:`.streaming`: netCDF written epoch block by epoch block, for runs longer than memory;
- :mod:`.conversion`: :func:`convert`, the engine of ``attitude convert IN OUT``.

The public names are in ``__all__``; like ``import attitude``, each is imported on first
use (PEP 562), so that ``import attitude.formats`` loads neither the propagators that
:mod:`.streaming` runs (nor numba) nor spiceypy.
"""

from __future__ import annotations

from ..foundations.lazy import owned_attribute

#: Public name -> the module of this wing that owns it.
_OWNERS = {
    **dict.fromkeys(("read_aem", "write_aem", "CCSDS_AEM_VERS", "AEM_ATTITUDE_TYPES",
                     "AEM_WRITE_TYPES", "AEM_TIME_SYSTEMS", "AEM_QUATERNION_NORM_TOL"), "aem"),
    "convert": "conversion",
    **dict.fromkeys(("read_ck", "is_ck"), "spice_read"),
    **dict.fromkeys(("write_ck", "convert_to_ck", "CKFiles", "leapseconds_kernel_text",
                     "SPICE_FRAMES", "TICKS_PER_SECOND"), "spice"),
    **dict.fromkeys(("EphemerisWriter", "UniformTimes", "propagate_to_netcdf"), "streaming"),
}

__all__ = list(_OWNERS)


def __getattr__(name):
    return owned_attribute(__name__, _OWNERS, name, globals())


def __dir__():
    return sorted(set(globals()) | set(__all__))

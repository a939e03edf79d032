"""File formats other tools read and write, beside the ephemeris's own CF netCDF
(:meth:`attitude.Ephemeris.to_netcdf`):

- :mod:`.aem`: CCSDS Attitude Ephemeris Messages, KVN and XML (read and write);
- :mod:`.spice`: SPICE C-kernels (type 3), with spiceypy
  (``pip install "attitude-dynamics[spice]"``);
- :mod:`.streaming`: netCDF written epoch block by epoch block, for runs longer than memory.

:func:`attitude.formats.aem.convert` is the engine of ``attitude convert IN OUT``.
"""

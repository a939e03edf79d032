"""``attitude view``: an interactive 3D view of an ephemeris file, one self-contained
HTML page (no server, no network)."""

from __future__ import annotations

from ...foundations.errors import WriterError
from ...model.ephemeris import Ephemeris
from ...pictures.viewer import view
from .common import EXIT_OK

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (tested in
#: tests/pictures/test_cli_pictures.py).
__all__ = []


def command(args) -> int:
    if not args.output.lower().endswith((".html", ".htm")):
        raise WriterError("unknown suffix for the view (use .html)", path=args.output)
    eph = Ephemeris.from_netcdf(args.ephemeris)
    out = view(eph, args.output, max_frames=args.frames, body_index=args.body).path
    if not args.quiet:
        print(f"wrote {out}")
    return EXIT_OK

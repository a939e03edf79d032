"""``attitude animate``: a movie of an ephemeris file (the body, Poinsot's construction,
the rates and nutation against time), MP4 or GIF."""

from __future__ import annotations

import sys

from ...foundations.errors import WriterError
from ...model.ephemeris import Ephemeris
from ...pictures.animation import MOVIE_SUFFIXES, animate, terminal_progress
from .common import EXIT_OK

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (tested in
#: tests/pictures/test_cli_pictures.py).
__all__ = []


def command(args) -> int:
    if not args.output.lower().endswith(MOVIE_SUFFIXES):
        raise WriterError(f"unknown movie suffix (use {' or '.join(MOVIE_SUFFIXES)})",
                          path=args.output)
    eph = Ephemeris.from_netcdf(args.ephemeris)
    progress = None if args.quiet else terminal_progress(sys.stderr)
    out = animate(eph, args.output, poinsot=not args.no_poinsot, fps=args.fps,
                  duration=args.duration, dpi=args.dpi, body_index=args.body,
                  progress=progress)
    if not args.quiet:
        print(f"wrote {out}")
    return EXIT_OK

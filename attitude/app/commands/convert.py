"""``attitude convert``: an ephemeris between netCDF, CCSDS AEM and SPICE."""

from __future__ import annotations

from pathlib import Path

from ...formats.aem import convert
from ...formats.spice import convert_to_ck
from .common import EXIT_OK

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (the command line
#: is the interface, tested in tests/app/test_cli.py).
__all__ = []


def command(args) -> int:
    if Path(args.output).suffix.lower() == ".bc":
        out = convert_to_ck(args.input, args.output, object_id=args.object_id,
                            object_name=args.object_name, body_frame=args.body_frame,
                            frame=args.frame, attitude_type=args.attitude_type)
    else:
        options = {k: v for k, v in (("object_name", args.object_name),
                                     ("object_id", args.object_id),
                                     ("ref_frame_a", args.frame),
                                     ("ref_frame_b", args.body_frame),
                                     ("attitude_type", args.attitude_type)) if v is not None}
        out = convert(args.input, args.output, **options)
    print(f"Wrote      {out}")
    return EXIT_OK

"""``attitude convert``: an ephemeris between netCDF, CCSDS AEM and SPICE."""

from __future__ import annotations

from pathlib import Path

from ...formats.conversion import convert
from ...formats.spice import convert_to_ck
from ...formats.spice_read import is_ck
from ...foundations.errors import EphemerisFormatError
from .common import EXIT_OK

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (the command line
#: is the interface, tested in tests/app/test_cli.py).
__all__ = []

#: ``convert`` options that read a SPICE C-kernel (argparse dest -> read_ck keyword).
_CK_READ = {"sclk": "sclk", "lsk": "lsk", "instrument": "instrument", "start": "start",
            "stop": "stop", "step": "step", "kernel": "kernels"}


def command(args) -> int:
    ck_options = {key: getattr(args, dest, None) for dest, key in _CK_READ.items()}
    ck_options = {k: v for k, v in ck_options.items() if v}
    reading_ck = is_ck(args.input)
    if ck_options and not reading_ck:
        flags = ", ".join("--" + d for d, k in _CK_READ.items() if k in ck_options)
        raise EphemerisFormatError(f"{flags}: options for reading a SPICE C-kernel (.bc), "
                                   f"not {Path(args.input).name}")
    if Path(args.output).suffix.lower() == ".bc":
        if reading_ck:
            raise EphemerisFormatError("a SPICE C-kernel is written from .nc, .aem or .xml, "
                                       "not from another C-kernel")
        out = convert_to_ck(args.input, args.output, object_id=args.object_id,
                            object_name=args.object_name, body_frame=args.body_frame,
                            frame=args.frame, attitude_type=args.attitude_type,
                            member=args.body)
    else:
        options = {k: v for k, v in (("object_name", args.object_name),
                                     ("object_id", args.object_id),
                                     ("ref_frame_b", args.body_frame),
                                     ("attitude_type", args.attitude_type),
                                     ("member", args.body)) if v is not None}
        if reading_ck:              # --frame: the SPICE frame the CK is read in
            options.update(ck_options, frame=args.frame)
        elif args.frame is not None:
            options["ref_frame_a"] = args.frame
        out = convert(args.input, args.output, **options)
    print(f"Wrote      {out}")
    return EXIT_OK

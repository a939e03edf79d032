"""The subcommands of ``attitude``, one module each, with a ``command(args) -> int``:
:mod:`attitude.app.cli` builds the parser alone and imports the module of the command it
runs (``attitude --help`` loads no numpy).  :mod:`.common` holds the exit codes and the
text they share.

The package imports nothing itself.
"""

"""Test-suite settings shared by every test file.

Hypothesis profiles: ``ci`` is derandomised (the same examples on every run, so a
failure in CI is reproducible and not a lottery), keeps no example database in the work
tree, prints the blob to reproduce a failure and has no deadline (shared CI machines are
slow).  It is loaded when the environment variable ``CI`` is set (as CI services do,
and ``.ci/run``) or ``HYPOTHESIS_PROFILE=ci``; a local run keeps hypothesis' default
random exploration, without writing a database either.  Failing examples found once
are kept in the tests with ``@example(...)``.
"""

import os

try:
    from hypothesis import settings
except ImportError:          # the test extra is not installed: hypothesis tests skip
    settings = None

if settings is not None:
    settings.register_profile("ci", derandomize=True, print_blob=True, deadline=None,
                              database=None)
    settings.register_profile("dev", database=None)
    settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE")
                          or ("ci" if os.environ.get("CI") else "dev"))

"""dask clusters for propagating populations: a LocalCluster, or a scheduler's address.

:func:`local_cluster` starts a ``LocalCluster`` of worker processes (without dask's
``MALLOC_TRIM_THRESHOLD_``, which halves the kernels' throughput) and a ``Client`` to it;
:func:`shared_local_client` keeps one for the session (``client="local"``);
:func:`client_for` connects to a scheduler address.  dask and distributed are optional
(``pip install "attitude-dynamics[dask]"``): they are imported where they are used.
"""

from __future__ import annotations

import atexit
import contextlib
import os

from ..foundations.errors import AttitudeError

__all__ = ["local_cluster", "shared_local_client", "client_for", "resolve_client"]

#: The LocalCluster of ``client="local"``, kept for the session.
_SHARED: dict = {}


def shared_local_client():
    """``client="local"``: one LocalCluster for this process (a worker per available
    core), started on first use and closed at exit; it is the default dask client, so
    the lazy ephemerides are computed there.

    Examples
    --------
    >>> from attitude.propagation.cluster import shared_local_client
    >>> callable(shared_local_client)     # started by propagate(..., client="local")
    True
    """
    if "client" not in _SHARED:
        cm = local_cluster(max(1, len(os.sched_getaffinity(0))))
        _SHARED["client"] = cm.__enter__()
        atexit.register(cm.__exit__, None, None, None)
    return _SHARED["client"]


def resolve_client(client):
    """The dask client a ``client=`` argument names: ``True`` or ``"local"`` the shared
    LocalCluster (:func:`shared_local_client`), an address string its scheduler
    (:func:`client_for`), anything else (a ``Client``, or None) as it is.

    Examples
    --------
    >>> from attitude.propagation.cluster import resolve_client
    >>> resolve_client(None) is None
    True
    """
    if client is True or client == "local":
        return shared_local_client()
    if isinstance(client, str):
        return client_for(client)
    return client


def client_for(address: str):
    """The current dask client if it is connected to ``address``, else a new one (which
    becomes the default, so the lazy ephemeris is computed there).

    Examples
    --------
    >>> from attitude.propagation.cluster import client_for, local_cluster
    >>> with local_cluster(1, processes=False) as client:
    ...     client_for(client.scheduler.address) is client
    True
    """
    try:
        from distributed import Client, default_client  # optional ('attitude-dynamics[dask]')
    except ImportError:
        raise AttitudeError("client: a scheduler address needs the optional 'distributed' "
                            "package: pip install 'attitude-dynamics[dask]'") from None
    try:
        current = default_client()
        if current.scheduler.address == address:
            return current
    except ValueError:
        pass
    try:
        return Client(address, timeout="10s")
    except OSError as exc:
        raise AttitudeError(f"client: cannot reach the dask scheduler at {address} "
                            f"({exc})") from None


@contextlib.contextmanager
def local_cluster(n_workers: int = 2, *, threads_per_worker: int = 1, **kwargs):
    """A dask ``LocalCluster`` of ``n_workers`` processes and a ``Client`` to it, for
    ``propagate(..., client=...)``; both are closed on exit::

        with att.ensemble.local_cluster(2) as client:
            eph = att.propagate(ensemble, times, client=client)
            eph.to_netcdf("cloud.nc")

    Examples
    --------
    >>> from attitude.propagation.cluster import local_cluster
    >>> with local_cluster(1, processes=False) as client:   # threads: no process start-up
    ...     len(client.scheduler_info()["workers"])
    1
    """
    try:
        from distributed import Client, LocalCluster  # optional ('attitude-dynamics[dask]')
    except ImportError:
        raise AttitudeError("dask scale-out needs the optional 'distributed' package: "
                            "pip install 'attitude-dynamics[dask]'") from None
    kwargs.setdefault("dashboard_address", ":0")     # any free port: no clash, no warning
    kwargs.setdefault("processes", True)
    with _glibc_mmap_threshold():
        try:
            cluster = LocalCluster(n_workers=n_workers, threads_per_worker=threads_per_worker,
                                   **kwargs)
        except RuntimeError as exc:
            raise AttitudeError(
                f"the dask LocalCluster did not start ({exc}): its worker processes died "
                "starting (a worker's traceback is printed above). Each worker re-imports "
                "the script that started it and runs its top level: either the cluster is "
                "started there (start it under 'if __name__ == \"__main__\":'), or code "
                "outside that guard fails or takes long when a worker runs it (reading a "
                "missing file, a propagation: move it under the guard too), or "
                "this machine cannot start the workers (memory, processes: fewer workers, "
                "or processes=False)") from exc
        with cluster, Client(cluster) as client:     # restarted workers: same environment
            yield client


#: dask's default ``MALLOC_TRIM_THRESHOLD_`` for its worker processes.
_DASK_TRIM = "65536"


@contextlib.contextmanager
def _glibc_mmap_threshold():
    """Start workers without dask's default ``MALLOC_TRIM_THRESHOLD_=65536``.

    Setting it turns off glibc's dynamic mmap threshold, so every large numpy temporary
    of the propagation kernel (8-32 MB per 1000-body chunk) is mmapped and page-faulted
    afresh: measured, more than half of a worker's CPU time in the kernel and half the
    throughput of one plain process (``benchmarks/ensemble.py``).  A value the user set
    (other than dask's default) is kept."""
    import dask  # optional dependency ('attitude-dynamics[dask]')

    key = "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"
    if str(dask.config.get(key, None)) != _DASK_TRIM:
        yield
        return
    # a previous dask cluster in this process leaves the variable in os.environ
    inherited = os.environ.get("MALLOC_TRIM_THRESHOLD_")
    if inherited == _DASK_TRIM:
        del os.environ["MALLOC_TRIM_THRESHOLD_"]
    try:
        with dask.config.set({key: None}):
            yield
    finally:
        if inherited == _DASK_TRIM:
            os.environ["MALLOC_TRIM_THRESHOLD_"] = inherited

"""Batches of bodies propagated in chunks, in this process or as dask tasks.

The engine behind ``propagate(ensemble, times)`` and ``propagate(bodies, states, times,
client=..., chunks=...)``: the bodies of an :class:`~attitude.Ensemble` are cut into
chunks that run the same vectorised numpy kernels (the exact solution, the splitting
integrator or DOP853) and are written in place into the output, or become the tasks of
a dask graph whose ephemeris is backed by dask arrays.  A row whose input is invalid
gets ``status = 1`` and NaN; a body whose propagation fails, ``status = 2``; neither
stops the others.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..foundations import quaternion as quat
from ..foundations.errors import AttitudeError, InvalidStateError
from ..model.body import RigidBody
from ..model.ephemeris import Ephemeris, build_dataset, momentum_and_energy
from ..model.population import Ensemble
from ..model.sampling import MODELS
from .cluster import resolve_client
from .reference import integrate_reference_batch
from .splitting import integrate_splitting
from .torquefree import exact_arrays

__all__ = ["propagate_ensemble", "STATUS_OK", "STATUS_INVALID", "STATUS_FAILED",
           "MODEL_UNITS"]

#: ``status`` values of an ensemble ephemeris (CF ``flag_values``).
STATUS_OK, STATUS_INVALID, STATUS_FAILED = 0, 1, 2
_STATUS_MEANINGS = "ok invalid_input propagation_failed"

#: Epochs per dask chunk when ``chunks=`` is not given (about 90 MB of float64 output).
_EPOCHS_PER_CHUNK = 1_000_000


def _propagate_chunk(inertia, mass, moments, b2p, q0, w0, status, t, method, torques,
                     options):
    """The numpy kernel of one chunk of bodies: ``{"q", "w", "L", "E", "status"}``.

    Invalid rows come back NaN with their status; if the vectorised run fails, the
    bodies are run one by one and those that fail get :data:`STATUS_FAILED`."""
    n, T = inertia.shape[0], t.size
    out = {"q": np.full((n, T, 4), np.nan), "w": np.full((n, T, 3), np.nan),
           "L": np.full((n, T, 3), np.nan), "E": np.full((n, T), np.nan),
           "status": np.asarray(status, dtype=np.int8).copy()}
    ok = out["status"] == STATUS_OK

    def run(rows):
        q, w = _kernel(inertia[rows], mass[rows], moments[rows], b2p[rows], q0[rows],
                       w0[rows], t, method, torques, options)
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(w))):
            raise FloatingPointError("non-finite result")
        return q, w

    idx = np.nonzero(ok)[0]
    if idx.size:
        try:
            results = [(idx, run(idx))]
        except (AttitudeError, FloatingPointError, ArithmeticError):
            results = []
            for i in idx:
                try:
                    results.append((np.array([i]), run(np.array([i]))))
                except (AttitudeError, FloatingPointError, ArithmeticError):
                    out["status"][i] = STATUS_FAILED
        for rows, (q, w) in results:
            q = quat.canonical(q)
            L, E = momentum_and_energy(inertia[rows], q, w)
            out["q"][rows], out["w"][rows], out["L"][rows], out["E"][rows] = q, w, L, E
    return out


def _kernel(inertia, mass, moments, b2p, q0, w0, t, method, torques, options):
    if method == "exact":
        return exact_arrays(moments, b2p, q0, w0, t)
    bodies = [RigidBody(i, mass=m if np.isfinite(m) else None) for i, m in zip(inertia, mass)]
    if method == "splitting":
        return integrate_splitting(bodies, q0, w0, t, torques=torques, **options)
    return integrate_reference_batch(bodies, q0, w0, t, torques=torques, **options)



def _default_chunk(n: int, T: int) -> int:
    return int(max(1, min(n, _EPOCHS_PER_CHUNK // max(T, 1))))


def propagate_ensemble(ensemble: Ensemble, t: np.ndarray, *, method: str = "exact",
                       torques=(), options: Mapping | None = None, client=None,
                       chunks: int | None = None, title: str = "", source: str = ""):
    """Propagate an ensemble to ``t`` (s since its epoch); the engine of
    :func:`attitude.propagate` for ensembles.

    Without ``client`` and ``chunks`` the bodies run in this process, in chunks of
    about :data:`_EPOCHS_PER_CHUNK` epochs, into numpy arrays.  With ``chunks`` (bodies
    per chunk) or ``client`` (a ``dask.distributed.Client`` or a scheduler address) the
    chunks become tasks of a dask graph and the ephemeris is backed by dask arrays: it
    is computed when written (:meth:`~attitude.Ephemeris.to_netcdf`, chunk by chunk,
    never gathered in one process) or loaded.  A worker that dies is replaced and its
    tasks rerun by the dask scheduler; a body whose input is invalid gets
    ``status = 1`` and NaN, one whose propagation fails ``status = 2``.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ens = att.Ensemble.from_arrays(
    ...     principal_moments=[[0.61, 0.965, 1.0], [1.0, 2.0, 3.0]],
    ...     omega_body=[[0.02, 0.0, 0.1], [0.1, 0.0, 0.3]], epoch="2024-01-01")
    >>> eph = propagate_ensemble(ens, np.linspace(0.0, 100.0, 11))
    >>> eph.dataset.quaternion.shape, eph.dataset.status.values.tolist()
    ((2, 11, 4), [0, 0])
    >>> one = att.propagate(ens.body_at(1), ens.state_at(1), np.linspace(0.0, 100.0, 11))
    >>> q = eph.dataset.quaternion.values[1]                  # the same body alone
    >>> bool(np.allclose(np.abs(np.sum(q * one.dataset.quaternion.values, axis=1)), 1.0,
    ...                  rtol=0, atol=1e-14))
    True
    """
    options = dict(options or {})
    n, T = len(ensemble), t.size
    status = np.where(ensemble.valid, STATUS_OK, STATUS_INVALID).astype(np.int8)
    size = _default_chunk(n, T) if chunks is None else int(chunks)
    if size < 1:
        raise InvalidStateError(f"chunks: expected a positive number of bodies per chunk, "
                                f"got {chunks!r}")
    bounds = [(a, min(a + size, n)) for a in range(0, n, size)]

    def args(a, b):
        return (ensemble.inertia[a:b], ensemble.mass[a:b], ensemble.principal_moments[a:b],
                ensemble.body_to_principal[a:b], ensemble.quaternion[a:b],
                ensemble.omega_body[a:b], status[a:b], t, method, list(torques), options)

    if client is None and chunks is None:         # in place: the output and one chunk
        arrays = {"q": np.empty((n, T, 4)), "w": np.empty((n, T, 3)),
                  "L": np.empty((n, T, 3)), "E": np.empty((n, T)),
                  "status": np.empty(n, dtype=np.int8)}
        for a, b in bounds:
            for k, v in _propagate_chunk(*args(a, b)).items():
                arrays[k][a:b] = v
    else:
        arrays = _dask_arrays(bounds, args, T, client)
    extra = {"status": ("body", arrays.pop("status"), {
        "long_name": "propagation status of the body", "flag_values": np.array(
            [STATUS_OK, STATUS_INVALID, STATUS_FAILED], dtype=np.int8),
        "flag_meanings": _STATUS_MEANINGS})}
    attrs = {"ensemble_size": n}
    if ensemble.nominal is not None:
        attrs["nominal_body"] = ensemble.nominal
    if ensemble.invalid:
        attrs["invalid_bodies"] = "; ".join(f"{i}: {why}" for i, why in
                                            list(ensemble.invalid.items())[:100])
    for k, v in ensemble.parameters.items():
        extra[f"parameter_{k}"] = ("body", v, {"long_name": f"sampled parameter {k}",
                                               "units": MODEL_UNITS.get(k, "1")})
    ds = build_dataset(t, arrays["q"], arrays["w"], arrays["L"], arrays["E"],
                       inertia=ensemble.inertia, moments=ensemble.principal_moments,
                       names=ensemble.names, single=None, epoch=ensemble.epoch,
                       frame=ensemble.frame, title=title or "attitude ensemble ephemeris",
                       source=source, extra_attrs=attrs, extra_vars=extra)
    return Ephemeris(ds)


#: CF units of the sampled parameters stored with an ensemble ephemeris.
MODEL_UNITS = {k: {"rad/s": "rad s-1", "": "1"}.get(v, v)
               for spec in MODELS.values() for k, v in spec.items()}


def _dask_arrays(bounds, args, T, client):
    """The chunk tasks as dask arrays ``q w L E status`` along ``body``."""
    try:
        import dask  # optional dependency ('attitude-dynamics[dask]')
        import dask.array as da  # optional
    except ImportError:
        raise AttitudeError("client=/chunks= need the optional 'dask' package: pip install "
                            "'attitude-dynamics[dask]'") from None

    client = resolve_client(client)
    shapes = {"q": (T, 4), "w": (T, 3), "L": (T, 3), "E": (T,), "status": ()}
    dtypes = {"status": np.int8}
    pieces = {k: [] for k in shapes}
    held: dict[int, object] = {}
    for a, b in bounds:
        chunk_args = args(a, b)
        if client is not None:          # chunks= alone: dask's current scheduler, as is
            chunk_args = _inputs_on_workers(client, chunk_args, held)
        part = dask.delayed(_propagate_chunk, pure=True)(*chunk_args)
        for k, shape in shapes.items():
            pieces[k].append(da.from_delayed(part[k], shape=(b - a,) + shape,
                                             dtype=dtypes.get(k, np.float64)))
    return {k: da.concatenate(v, axis=0) for k, v in pieces.items()}


def _held(x):
    """A task whose result is its argument: an input array held on the workers."""
    return x


def _inputs_on_workers(client, chunk_args, held: dict):
    """``chunk_args`` with its numpy arrays replaced by futures of them held on the
    workers, so that the graph holds keys, not the ensemble (17.7 MiB of inputs at 1e5
    bodies, issue 14); an array shared by every chunk (the times) is sent once
    (``held``, by id).

    Not ``client.scatter``: scattered data has no task that could recompute it, so a
    worker that dies takes its chunk's inputs with it and the run fails ("lost scattered
    data, which can't be recovered"; ``client.replicate`` is undone by the active memory
    manager's ReduceReplicas policy).  Each array is the result of a small task instead
    (``client.submit``, sent to one worker), which the scheduler reruns on another
    worker when the one holding it dies, so the chunks that need it rerun too."""
    out = []
    for x in chunk_args:
        if isinstance(x, np.ndarray):
            key = id(x)
            if key not in held:
                held[key] = (client.submit(_held, x, pure=False), x)
            x = held[key][0]
        out.append(x)
    return tuple(out)

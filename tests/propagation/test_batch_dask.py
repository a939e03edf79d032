"""Ensembles on a dask LocalCluster: same results as one process, netCDF written from
the workers, worker deaths retried, invalid bodies isolated.

A small two-worker cluster (processes) is started once for the module (~3 s).
"""

import os
import pickle

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude import ensemble as en

from ..tolerances import EXACT_SOLUTION, FEW_OPS, SPLITTING_STEP, assert_agree, ulps

distributed = pytest.importorskip("distributed")

EPOCH = "2030-01-01T00:00:00"


@pytest.fixture(scope="module")
def client():
    with en.local_cluster(2) as c:
        yield c


def population(n, seed=0):
    rng = np.random.default_rng(seed)
    m = np.sort(rng.uniform(1.0, 2.0, (n, 3)), axis=1)
    q = Rotation.random(n, random_state=rng).as_quat()
    w = rng.normal(scale=0.02, size=(n, 3))
    return att.Ensemble.from_arrays(principal_moments=m, quaternion=q, omega_body=w,
                                    epoch=EPOCH, names=[f"deb-{i}" for i in range(n)])


def test_cluster_result_equals_the_single_process_result(client, tmp_path):
    ens = population(250)
    t = np.linspace(0.0, 3 * 86400.0, 60)
    ref = att.propagate(ens, t)
    eph = att.propagate(ens, t, client=client, chunks=40)
    ds = eph.dataset
    assert type(ds.quaternion.data).__module__.startswith("dask")
    assert ds.quaternion.data.numblocks[0] == 7                  # ceil(250 / 40) chunks
    # the exact solution in chunks of 40 on the workers against one process: a few ulps
    assert_agree(ds.quaternion.values, ref.dataset.quaternion.values, ulps=EXACT_SOLUTION,
                 magnitude=1.0, what="quaternion")
    # written chunk by chunk from the workers, read back whole
    path = eph.to_netcdf(tmp_path / "cloud.nc")
    back = att.Ephemeris.from_netcdf(path)
    assert back.dataset.sizes["body"] == 250
    L = ref.dataset.angular_momentum.values
    assert_agree(back.dataset.angular_momentum.values, L, ulps=EXACT_SOLUTION + FEW_OPS,
                 magnitude=np.linalg.norm(L, axis=-1, keepdims=True), what="L")
    assert back.dataset.status.values.tolist() == [0] * 250
    assert back.dataset.body_name.values[3] == "deb-3"
    # statistics of the lazy ephemeris run on the cluster too
    sq = en.spread_quantiles(eph, q=[0.5])
    np.testing.assert_allclose(sq.values, en.spread_quantiles(ref, q=[0.5]).values,
                               atol=1e-9)


def test_scheduler_address_and_invalid_bodies(client):
    ens = population(30, seed=1)
    inertia = np.array(ens.inertia)
    inertia[17] = np.diag([1.0, 1.0, 2.5])
    with pytest.warns(en.InvalidBodiesWarning, match="body 17"):
        bad = att.Ensemble(inertia, ens.quaternion, ens.omega_body, epoch=EPOCH)
    t = np.linspace(0.0, 600.0, 7)
    eph = att.propagate(bad, t, client=client.scheduler.address, chunks=8)
    status = eph.dataset.status.values
    assert status[17] == en.STATUS_INVALID and (np.delete(status, 17) == 0).all()
    ref = att.propagate(ens, t)
    keep = np.arange(30) != 17
    assert_agree(eph.dataset.quaternion.values[keep], ref.dataset.quaternion.values[keep],
                 ulps=EXACT_SOLUTION, magnitude=1.0, what="quaternion")
    assert np.isnan(eph.dataset.quaternion.values[17]).all()


class KillWorkerOnce:
    """A torque that kills the worker process the first time it runs (a marker file
    records it): the scheduler must rerun the lost task on a fresh worker."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __call__(self, t, q, w, body):
        if not os.path.exists(self.marker):
            with open(self.marker, "w") as f:
                f.write(str(os.getpid()))
            os._exit(1)
        return np.zeros_like(w)


def test_a_worker_that_dies_mid_run_is_retried(client, tmp_path):
    ens = population(12, seed=2)
    t = np.linspace(0.0, 100.0, 5)
    marker = tmp_path / "killed"
    eph = att.propagate(ens, t, torques=[KillWorkerOnce(marker)], step=5.0,
                        client=client, chunks=6)
    q = eph.dataset.quaternion.values                      # computed on the cluster
    assert marker.exists()                                 # a worker did die
    ref = att.propagate(ens, t, torques=[lambda t, q, w, body: np.zeros_like(w)], step=5.0)
    # 20 splitting steps of a zero torque, on a worker and here
    assert_agree(q, ref.dataset.quaternion.values, ulps=20 * SPLITTING_STEP, magnitude=1.0,
                 what="quaternion")
    assert (eph.dataset.status.values == 0).all()


def test_client_local_starts_a_shared_local_cluster(tmp_path):
    import subprocess
    import sys

    script = tmp_path / "local.py"
    script.write_text(
        "import numpy as np, attitude as att, distributed\n"
        "if __name__ == '__main__':\n"
        "    ens = att.Ensemble.from_arrays(principal_moments=[[1, 2, 2.5]] * 30,\n"
        "        omega_body=np.random.default_rng(0).normal(size=(30, 3)), epoch='2030-01-01')\n"
        "    t = np.linspace(0, 10, 5)\n"
        "    e = att.propagate(ens, t, client='local', chunks=10)\n"
        "    f = att.propagate(ens, t, client='local', chunks=10)\n"
        "    ref = att.propagate(ens, t)\n"
        "    c = distributed.default_client()\n"
        "    print(len(c.scheduler_info()['workers']))\n"
        "    print(float(abs(e.dataset.quaternion - ref.dataset.quaternion).max()))\n"
        "    print(float(abs(f.dataset.quaternion - ref.dataset.quaternion).max()))\n")
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         timeout=180)
    assert out.returncode == 0, out.stderr
    workers, d1, d2 = out.stdout.split()
    assert int(workers) == len(os.sched_getaffinity(0))
    assert float(d1) <= ulps(1.0, EXACT_SOLUTION) and float(d2) <= ulps(1.0, EXACT_SOLUTION)


def test_ensemble_inputs_travel_ahead_of_the_graph_not_in_it(client):
    """The graph of an ensemble run on a cluster holds the keys of inputs held on the
    workers: its size does not grow with the number of bodies (it held the whole
    ensemble before, 17.7 MiB at 1e5 bodies), and the result is the one of a single
    process."""
    t = np.linspace(0.0, 600.0, 5)
    size = {}
    for n in (200, 4000):                  # the same 4 chunks, 20 times the bodies
        eph = att.propagate(population(n, seed=3), t, client=client, chunks=n // 4)
        graph = dict(eph.dataset.quaternion.data.__dask_graph__())
        size[n] = len(pickle.dumps(graph))
    inputs = 4000 * (9 + 1 + 3 + 9 + 4 + 3 + 1) * 8    # the float inputs of 4000 bodies
    assert size[4000] < 1.2 * size[200] and size[4000] < inputs / 10, (size, inputs)
    ens = population(200, seed=3)
    ref = att.propagate(ens, t)
    eph = att.propagate(ens, t, client=client, chunks=50)
    assert_agree(eph.dataset.quaternion.values, ref.dataset.quaternion.values,
                 ulps=EXACT_SOLUTION, magnitude=1.0, what="quaternion")

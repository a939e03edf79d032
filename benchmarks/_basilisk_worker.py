"""The Basilisk side of ``benchmarks/perturbed.py``, run with a Python that has Basilisk.

Basilisk (``pip install bsk``) and ``attitude`` need not share a virtual environment, so
``perturbed.py`` runs this script as a subprocess with the Basilisk venv's Python and
exchanges arrays through ``.npz`` files::

    /path/to/bskvenv/bin/python benchmarks/_basilisk_worker.py request.npz result.npz

It imports only numpy and Basilisk.  The request holds the orbit (``mu``, ``r0``, ``v0``
inertial, m and m/s), the bodies (``inertia`` (N, 3, 3) kg m^2 about the centre of mass,
``sigma0`` (N, 3) MRPs sigma_BN, ``omega0`` (N, 3) rad/s body frame), ``t_end`` and
``out_step`` (s), the integration steps to run (``dts``, s), ``gravity_gradient``
(whether to attach the GravityGradientEffector) and ``repeats``.  The simulation is a
``spacecraft.Spacecraft`` hub (centre of mass at the body point) in the point-mass field
of the Earth (``gravityEffector`` through ``gravBodyFactory``, ``mu`` overridden to the
request's), with ``GravityGradientEffector.GravityGradientEffector`` and the default
integrator (``svIntegratorRK4``); ``scStateOutMsg`` is recorded every ``out_step``.

Mode ``"scan"`` (one body, every dt): a warm-up run, then ``repeats`` timed runs of the
whole thing; per dt the result has the recorded ``sigma_BN``, ``omega_BN_B`` and
``r_BN_N`` and the best times of the execution alone (``ExecuteSimulation``) and of the
total (building the modules, ``InitializeSimulation`` and executing).  Mode ``"batch"``
(N bodies, the first dt): a warm-up run, then the N bodies one after the other, each
built and run, the whole loop timed ``repeats`` times (best kept).
"""

from __future__ import annotations

import sys
import time

import numpy as np
from Basilisk import __version__ as BSK_VERSION
from Basilisk.simulation import GravityGradientEffector, spacecraft
from Basilisk.utilities import SimulationBaseClass, macros, simIncludeGravBody


def build(mu, r0, v0, inertia, sigma0, omega0, dt, t_end, out_step, gravity_gradient):
    """One Basilisk simulation, initialised; returns ``(sim, recorder)``."""
    sim = SimulationBaseClass.SimBaseClass()
    process = sim.CreateNewProcess("dynamics")
    process.addTask(sim.CreateNewTask("dyn", macros.sec2nano(dt)))
    sc = spacecraft.Spacecraft()
    sc.ModelTag = "sat"
    sc.hub.mHub = 100.0
    sc.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    sc.hub.IHubPntBc_B = [[float(x) for x in row] for row in inertia]
    sc.hub.r_CN_NInit = [[float(x)] for x in r0]
    sc.hub.v_CN_NInit = [[float(x)] for x in v0]
    sc.hub.sigma_BNInit = [[float(x)] for x in sigma0]
    sc.hub.omega_BN_BInit = [[float(x)] for x in omega0]
    sim.AddModelToTask("dyn", sc)
    factory = simIncludeGravBody.gravBodyFactory()
    earth = factory.createEarth()
    earth.isCentralBody = True
    earth.mu = float(mu)
    factory.addBodiesTo(sc)
    if gravity_gradient:
        gg = GravityGradientEffector.GravityGradientEffector()
        gg.ModelTag = "gravityGradient"
        gg.addPlanetName(earth.planetName)
        sc.addDynamicEffector(gg)
        sim.AddModelToTask("dyn", gg)
    rec = sc.scStateOutMsg.recorder(macros.sec2nano(out_step))
    sim.AddModelToTask("dyn", rec)
    sim.InitializeSimulation()
    sim.ConfigureStopTime(macros.sec2nano(t_end))
    return sim, rec


def run_one(req, k, dt):
    """Build and run body ``k`` at step ``dt``: ``(rec, t_exec, t_total)``."""
    t0 = time.perf_counter()
    sim, rec = build(req["mu"], req["r0"], req["v0"], req["inertia"][k], req["sigma0"][k],
                     req["omega0"][k], dt, float(req["t_end"]), float(req["out_step"]),
                     bool(req["gravity_gradient"]))
    t1 = time.perf_counter()
    sim.ExecuteSimulation()
    t2 = time.perf_counter()
    return rec, t2 - t1, t2 - t0


def main(request: str, result: str) -> None:
    req = dict(np.load(request))
    mode = str(req["mode"])
    repeats = int(req["repeats"])
    out = {"basilisk_version": np.array(BSK_VERSION)}
    if mode == "scan":
        run_one(req, 0, float(req["dts"][0]))                     # warm-up
        for j, dt in enumerate(np.asarray(req["dts"], dtype=float)):
            execs, totals = [], []
            for _ in range(max(repeats, 1)):
                rec, t_exec, t_total = run_one(req, 0, dt)
                execs.append(t_exec)
                totals.append(t_total)
            out[f"times_{j}"] = rec.times() * 1e-9
            out[f"sigma_{j}"] = np.array(rec.sigma_BN)
            out[f"omega_{j}"] = np.array(rec.omega_BN_B)
            out[f"r_{j}"] = np.array(rec.r_BN_N)
            out[f"t_exec_{j}"] = np.array(min(execs))
            out[f"t_total_{j}"] = np.array(min(totals))
    elif mode == "batch":
        dt = float(req["dts"][0])
        n = len(req["sigma0"])
        run_one(req, 0, dt)                                       # warm-up
        best_total, best_exec = np.inf, np.inf
        for _ in range(max(repeats, 1)):
            sigmas, exec_sum = [], 0.0
            t0 = time.perf_counter()
            for k in range(n):
                rec, t_exec, _ = run_one(req, k, dt)
                exec_sum += t_exec
                sigmas.append(np.array(rec.sigma_BN))
            best_total = min(best_total, time.perf_counter() - t0)
            best_exec = min(best_exec, exec_sum)
        out["times"] = rec.times() * 1e-9
        out["sigma"] = np.array(sigmas)
        out["t_exec"] = np.array(best_exec)
        out["t_total"] = np.array(best_total)
    else:
        raise SystemExit(f"unknown mode {mode!r}")
    np.savez(result, **out)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])

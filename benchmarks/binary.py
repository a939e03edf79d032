"""The full two-body problem (issue 28): one day of a Didymos-like binary asteroid with the
Lie-group variational integrator (``method="lgvi"``, 30 s steps) and with DOP853
(``method="integrator"``, rtol 1e-12).

The system: a primary ellipsoid 425 x 410 x 390 m of 5.2e11 kg spinning in 2.26 h, a
secondary ellipsoid 103.16 x 79.35 x 66.13 m of 4.3e9 kg on a circular orbit of 1190 m,
synchronous, both attitudes aligned with the orbit frame; the mutual potential to order 4.
Each method's CPU time (process time, after a warm-up on a short run), the largest
relative energy and angular momentum errors over the day (outputs every 30 s), and the
two methods' difference in position and attitudes after the day (the LGVI's error: DOP853
at 1e-12 is 10^4 closer to the truth).

``--gubas DIR``: the same against GUBAS (github.com/meyeralexj/gubas, the C++ code of
Davis & Scheeres 2020) on its own Didymos example, from a run of it in ``DIR``
(``didymos_inputs.json``: the inputs in SI; ``didymos_lgvi.csv`` and ``didymos_rk.csv``:
its LGVI at 30 s and its RK7(8) at 1e-12, one row per output, rotation matrices body ->
inertial row-major; ``gubas_summary.json``: its CPU times): the primary polyhedron (the
example's vertex and facet files, read through ``RigidBody.from_obj``), the secondary
ellipsoid, the same G and initial state.  Reported: our LGVI's position and attitude
difference from GUBAS's LGVI after the day (the same discrete map: round-off and the
implicit solve's tolerance), our DOP853's from GUBAS's RK7(8) (two accurate methods: the
difference bounds either's error and any difference in the physics), and both timings.

    python benchmarks/binary.py [--gubas /work/peers/gubas_runs] [--days 1]

The issue's longer figures, each kept in the same results file:

    python benchmarks/binary.py --only --kepler         # two spheres, 100 orbits, DOP853
    python benchmarks/binary.py --only --dart-libration # Dimorphos's free libration
    python benchmarks/binary.py --only --long 10000     # the LGVI over 1e4 orbits
    python benchmarks/binary.py --only --variants 1000 --workers 2 --numpy
                                    # post-impact Dimorphos variants (compiled LGVI; one
                                    # process, 2 dask workers, and the numpy path)
    python benchmarks/binary.py --only --flyby 100      # Apophis 2029 as an ensemble
    python benchmarks/binary.py --only --shapes         # does Dimorphos tumble, by a/b

Writes ``benchmarks/results/binary.json`` atomically.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

# one BLAS thread per process: the LGVI's arrays are small, and with --workers the dask
# workers are the parallelism (set before numpy loads; the caller's setting wins)
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from _machine import cpu_name  # noqa: E402

import attitude as att  # noqa: E402
from attitude.model.ephemeris import write_atomically  # noqa: E402

HERE = Path(__file__).resolve().parent
DAY = 86400.0
ELLIPSOID = att.MassProperties.solid_ellipsoid


def didymos_like(order: int = 4) -> tuple[att.BinarySystem, att.BinaryState]:
    system = att.BinarySystem(
        att.RigidBody.from_mass_properties(ELLIPSOID(5.2e11, [425.0, 410.0, 390.0])),
        att.RigidBody.from_mass_properties(ELLIPSOID(4.3e9, [103.16, 79.35, 66.13])),
        order=order)
    n = np.sqrt(system.mu / 1190.0**3)
    state = att.BinaryState("2022-09-26", [1190.0, 0, 0], [0, n * 1190.0, 0],
                            Rotation.identity(), [0, 0, 2 * np.pi / (2.26 * 3600.0)],
                            Rotation.identity(), [0, 0, n])
    return system, state


def timed(system, state, times, **options) -> tuple[att.Ephemeris, dict]:
    """One propagation after a warm-up of a few steps: the ephemeris and its figures."""
    att.propagate(system, state, times[:3], **options)
    t0 = time.process_time()
    eph = att.propagate(system, state, times, **options)
    cpu = time.process_time() - t0
    ds = eph.dataset
    E, L = ds.total_energy.values, ds.total_angular_momentum.values
    return eph, {**{k: v for k, v in options.items()}, "cpu_s": cpu,
                 "max_abs_dE_over_E": float(np.abs(E / E[0] - 1.0).max()),
                 "max_abs_dH_over_H": float((np.linalg.norm(L - L[0], axis=-1)
                                             / np.linalg.norm(L[0])).max())}


def matrices(eph, body: int) -> np.ndarray:
    return Rotation.from_quat(eph.dataset.quaternion.values[body]).as_matrix()


def angle_between(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Rotation angle of ``A^T B`` (rad), for stacks of rotation matrices."""
    return Rotation.from_matrix(np.einsum("...ji,...jk->...ik", A, B)).magnitude()


def differences(eph, R, A1, A2) -> dict:
    """Position (m) and both attitudes (rad) of ``eph`` at its last time against another
    run's ``R`` (3,) and matrices ``A1``, ``A2`` (3, 3)."""
    return {"position_m": float(np.linalg.norm(eph.dataset.relative_position.values[-1] - R)),
            "primary_attitude_rad": float(angle_between(matrices(eph, 0)[-1], A1)),
            "secondary_attitude_rad": float(angle_between(matrices(eph, 1)[-1], A2))}


def didymos_like_runs(days: float) -> dict:
    system, state = didymos_like()
    times = np.arange(0.0, days * DAY + 15.0, 30.0)
    lgvi, a = timed(system, state, times, method="lgvi", step=30.0)
    dop, b = timed(system, state, times, method="integrator", rtol=1e-12)
    last = dop.dataset
    a["difference_from_dop853"] = differences(
        lgvi, last.relative_position.values[-1], matrices(dop, 0)[-1], matrices(dop, 1)[-1])
    return {"system": "Didymos-like ellipsoids, order 4, 1190 m circular, synchronous "
                      "secondary, primary period 2.26 h", "days": days,
            "lgvi": a, "dop853": b}


def gubas_case(folder: Path) -> tuple[att.BinarySystem, att.BinaryState, dict]:
    """GUBAS's Didymos example from its inputs: the primary polyhedron through an OBJ
    written from the example's vertex and facet files."""
    inputs = json.loads((folder / "didymos_inputs.json").read_text())
    primary, secondary, ic = inputs["primary"], inputs["secondary"], inputs["initial_state"]
    vertices = np.loadtxt(primary["shape_vertex_file"], delimiter=",")[:, 1:]
    facets = np.genfromtxt(primary["shape_facet_file"], delimiter=",", usecols=(0, 1, 2),
                           dtype=int)
    with tempfile.TemporaryDirectory() as tmp:
        obj = Path(tmp) / "didymos.obj"
        obj.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in vertices.tolist())
                       + "".join(f"f {a} {b} {c}\n" for a, b, c in facets.tolist()))
        body1 = att.RigidBody.from_obj(obj, density=primary["density_kg_m3"])
    body2 = att.RigidBody.from_mass_properties(
        ELLIPSOID(secondary["mass_kg"], secondary["semi_axes_m"]))
    system = att.BinarySystem(body1, body2, order=inputs["mutual_potential_order"],
                              G=inputs["G_m3_per_kg_s2"])
    state = att.BinaryState(
        "2022-09-26", ic["r_rel_inertial_m"], ic["v_rel_inertial_mps"],
        Rotation.from_matrix(ic["R_primary_body_to_inertial"]), ic["w_primary_body_radps"],
        Rotation.from_matrix(ic["R_secondary_body_to_inertial"]),
        ic["w_secondary_body_radps"])
    return system, state, inputs


def gubas_run(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Times, positions and both attitude matrices of a GUBAS run's CSV."""
    rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return (rows[:, 0], rows[:, 1:4], rows[:, 7:16].reshape(-1, 3, 3),
            rows[:, 19:28].reshape(-1, 3, 3))


def gubas_comparison(folder: Path) -> dict:
    system, state, inputs = gubas_case(folder)
    summary = json.loads((folder / "gubas_summary.json").read_text())
    t, R, A1, A2 = gubas_run(folder / "didymos_lgvi.csv")
    step = inputs["integration"]["lgvi_step_s"]
    lgvi, a = timed(system, state, t, method="lgvi", step=step)
    a["difference_from_gubas_lgvi"] = differences(lgvi, R[-1], A1[-1], A2[-1])
    a["largest_position_difference_over_the_run_m"] = float(np.linalg.norm(
        lgvi.dataset.relative_position.values - R, axis=-1).max())
    t_rk, R_rk, A1_rk, A2_rk = gubas_run(folder / "didymos_rk.csv")
    rtol = inputs["integration"]["rk78_tolerance"]
    dop, b = timed(system, state, t_rk, method="integrator", rtol=rtol)
    b["difference_from_gubas_rk78"] = differences(dop, R_rk[-1], A1_rk[-1], A2_rk[-1])
    gubas = {name: {"cpu_s": summary[name]["cpu_cpp"]["cpu_s"],
                    "max_abs_dE_over_E": summary[name]["gubas_max_abs_dE_over_E"],
                    "max_abs_dH_over_H": summary[name]["gubas_max_abs_dH_over_H"]}
             for name in ("lgvi", "rk")}
    gubas["lgvi"]["step"] = step
    gubas["rk"]["rtol"] = rtol
    gubas["lgvi_minus_rk78_position_m"] = float(np.linalg.norm(R[-1] - R_rk[-1]))
    return {"source": inputs["source"], "days": float(t[-1]) / DAY, "lgvi": a, "dop853": b,
            "gubas": gubas}


def kepler_run(orbits: int = 100, rtol: float = 2.5e-14, e: float = 0.5) -> dict:
    """Two spheres (order 2) on an eccentric orbit, DOP853 (Encke's form,
    attitude.binary.dynamics.integrate_dop853) at rtol 2.5e-14 (near the smallest scipy
    takes, 2.2e-14) against the Kepler solution (KeplerOrbit with mu = G (m1 + m2)), 20
    samples an orbit: the largest position error over ``orbits`` orbits, relative to the
    semi-major axis (tests/binary/test_kepler.py asserts the issue's 1e-10)."""
    ball = lambda m, r: att.RigidBody.from_mass_properties(  # noqa: E731
        att.MassProperties.solid_sphere(m, r))
    system = att.BinarySystem(ball(5.2e11, 400.0), ball(4.3e9, 90.0))
    orbit = att.KeplerOrbit(system.mu, 1190.0, e, i=0.3, raan=1.0, argp=-0.4)
    R0, V0 = orbit.state(0.0)
    state = att.BinaryState("2026-12-01", R0, V0, Rotation.identity(), [0, 0, 0],
                            Rotation.identity(), [0, 0, 0])
    times = np.linspace(0.0, orbits * orbit.period, 20 * orbits + 1)
    t0 = time.process_time()
    eph = att.propagate(system, state, times, method="integrator", rtol=rtol)
    cpu = time.process_time() - t0
    error = np.linalg.norm(eph.dataset.relative_position.values - orbit.position(times),
                           axis=-1) / orbit.a
    return {"orbits": orbits, "e": e, "rtol": rtol, "form": "Encke", "cpu_s": cpu,
            "max_position_error_over_a": float(error.max()),
            "position_error_over_a_at_end": float(error[-1])}


def dart_libration_run(days: float = 10.0) -> dict:
    """The free libration of Dimorphos after DART, on the system of docs/binary.md's DART
    section (order 4, Didymos an oblate spheroid, the pre-impact Dimorphos ellipsoid, the
    head-on kick of beta = 3.6 scaled to Cheng et al.'s along-track -2.70 mm/s): DOP853
    at rtol 1e-10 over ``days`` after the impact, sampled every 10 minutes; the free and
    forced libration (att.binary.diagnostics.free_libration) against the formula
    ``n sqrt(3 (B - A) / C)`` with the measured post-impact orbit period."""
    from attitude.binary.diagnostics import free_libration

    G = att.binary.G
    separation = 1190.0
    mu = 4 * np.pi**2 * separation**3 / (11.921473 * 3600) ** 2
    axes = np.array([179.0, 169.0, 115.0]) / 2
    m2 = 2400.0 * 4 / 3 * np.pi * np.prod(axes)
    system = att.BinarySystem(
        att.RigidBody.from_mass_properties(ELLIPSOID(mu / G - m2, [394.0, 394.0, 290.0])),
        att.RigidBody.from_mass_properties(ELLIPSOID(m2, axes)), order=4)
    R = np.array([separation, 0.0, 0.0])
    v = np.sqrt(-system.gravity.forces(R, *system.integrals).force[0] * separation
                / system.reduced_mass)
    n = v / separation
    state = att.BinaryState("2022-09-26T10:00:00", R, [0.0, v, 0.0], Rotation.identity(),
                            [0, 0, 2 * np.pi / (2.26 * 3600)], Rotation.identity(),
                            [0, 0, n])
    t_impact = 3600.0
    along = np.array([-np.sin(n * t_impact), np.cos(n * t_impact), 0.0])
    dart = att.Impulse(t_impact, body="secondary", delta_v=-2.70e-3 * along)
    times = np.union1d(np.arange(0.0, t_impact + days * DAY, 600.0), [t_impact])
    t0 = time.process_time()
    eph = att.propagate(system, state, times, method="integrator", rtol=1e-10,
                        events=[dart])
    cpu = time.process_time() - t0
    fl = free_libration(eph, after=t_impact)
    b = att.binary.diagnose(eph, impulses=[t_impact])
    A, B, C = system.secondary.principal_moments
    formula = 2 * np.pi / b.orbit_period * np.sqrt(3 * (B - A) / C)
    return {"days_after_impact": days, "along_track_dv_mm_s": -2.70, "order": 4,
            "rtol": 1e-10, "cpu_s": cpu, "orbit_period_after_h": b.orbit_period / 3600,
            "free_libration_period_h": fl.period / 3600,
            "free_libration_amplitude_deg": float(np.degrees(fl.amplitude)),
            "forced_libration_period_h": fl.forced_period / 3600,
            "forced_libration_amplitude_deg": float(np.degrees(fl.forced_amplitude)),
            "fit_residual_deg": float(np.degrees(fl.residual)),
            "zero_crossing_libration_period_h": b.libration_period / 3600,
            "formula_period_h": 2 * np.pi / formula / 3600,
            "free_over_formula_frequency": float(2 * np.pi / fl.period / formula)}


def long_lgvi_run(orbits: int = 10_000, steps_per_orbit: int = 40) -> dict:
    """The LGVI over ``orbits`` orbits of an ellipsoidal secondary (librating) about a
    spherical primary, order 2, ``steps_per_orbit`` steps per orbit, sampled once per
    orbit: the total angular momentum's largest relative change, and the energy's linear
    trend over the run against its scatter (a drift shows as a trend far above the
    scatter; a bounded error as a trend far below it)."""
    system = att.BinarySystem(
        att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(5.2e11, 400.0)),
        att.RigidBody.from_mass_properties(ELLIPSOID(4.3e9, [103.16, 79.35, 66.13])))
    n = np.sqrt(system.mu / 1190.0**3)
    period = 2 * np.pi / n
    state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
                            Rotation.identity(), [0, 0, 0],
                            Rotation.from_euler("z", 10.0, degrees=True), [0, 0, n])
    times = np.arange(orbits + 1) * period
    t0 = time.process_time()
    eph = att.propagate(system, state, times, method="lgvi", step=period / steps_per_orbit)
    cpu = time.process_time() - t0
    ds = eph.dataset
    E, L = ds.total_energy.values, ds.total_angular_momentum.values
    dL = np.linalg.norm(L - L[0], axis=-1).max() / np.linalg.norm(L[0])
    x = times / times[-1]
    slope, intercept = np.polyfit(x, E / E[0] - 1.0, 1)
    scatter = float(np.std(E / E[0] - 1.0 - (slope * x + intercept)))
    return {"orbits": orbits, "steps_per_orbit": steps_per_orbit, "cpu_s": cpu,
            "max_abs_dH_over_H": float(dL),
            "max_abs_dE_over_E": float(np.abs(E / E[0] - 1.0).max()),
            "energy_trend_over_the_run": float(slope), "energy_scatter": scatter}


def _variants(count: int, seed: int = 1):
    """``count`` post-impact Dimorphos variants about a spherical-ish Didymos: the
    secondary's axes (a/b from 1.0 to 1.6, b/c 1.2-1.6, the volume kept), the impact's
    along-track dv (-2.70 +- 0.10 mm/s) applied at t = 0 to a synchronous start."""
    rng = np.random.default_rng(seed)
    primary = att.RigidBody.from_mass_properties(ELLIPSOID(5.282e11, [394.0, 394.0, 290.0]))
    volume = 89.5 * 84.5 * 57.5
    systems, states = [], []
    for _ in range(count):
        ab, bc = rng.uniform(1.0, 1.6), rng.uniform(1.2, 1.6)
        c = (volume / (ab * bc * bc)) ** (1 / 3)
        b, a = bc * c, ab * bc * c
        system = att.BinarySystem(primary, att.RigidBody.from_mass_properties(
            ELLIPSOID(4.3e9, [a, b, c])))
        n = np.sqrt(system.mu / 1190.0**3)
        dv = rng.normal(-2.70e-3, 0.10e-3)
        states.append(att.BinaryState(
            "2022-09-26T23:15:09.184", [1190.0, 0, 0], [0, n * 1190.0 + dv, 0],
            Rotation.identity(), [0, 0, 2 * np.pi / (2.26 * 3600.0)],
            Rotation.identity(), [0, 0, n]))
        systems.append(system)
    return systems, states


def _run_variants(systems, states, times, step, compiled=None) -> dict:
    """The members all at once (integrate_lgvi_batch: each member's step loop compiled,
    or with ``compiled=False`` the numpy path vectorised over them), then each one's
    regime by att.binary.diagnose: only the regimes and this process's CPU times travel
    back from a dask worker."""
    from attitude.binary.diagnostics import diagnose
    from attitude.binary.lgvi import integrate_lgvi_batch
    from attitude.binary.propagate import binary_ephemeris, initial_vector

    t0, w0, c0 = time.process_time(), time.perf_counter(), time.thread_time()
    y0 = np.array([initial_vector(s) for s in states])
    y = integrate_lgvi_batch(systems, y0, times, step, compiled=compiled)
    t1 = time.process_time()
    regimes = [diagnose(binary_ephemeris(s, st, times, yy, method="lgvi")).secondary_regime
               for s, st, yy in zip(systems, states, y)]
    return {"regimes": regimes, "lgvi_cpu_s": t1 - t0,
            "diagnose_cpu_s": time.process_time() - t1, "wall_s": time.perf_counter() - w0,
            "thread_cpu_s": time.thread_time() - c0}


def variants_run(count: int = 1000, days: float = 30.0, step: float = 60.0,
                 workers: int = 0, numpy_path: bool = False) -> dict:
    """``count`` post-impact variants over ``days`` with the LGVI (integrate_lgvi_batch,
    each member's step loop compiled), sampled every hour, each member's regime by
    att.binary.diagnose; with ``workers``, the same members split over a dask
    LocalCluster of that many single-threaded workers, one chunk each, and the scaling
    (the serial wall time over ``workers`` times the parallel one; and in CPU time, the
    serial over ``workers`` times the slowest worker's).  Every process runs
    two members first (numba loads its compiled code, or compiles it: not timed).  With
    ``numpy_path``, the LGVI also on the numpy path (vectorised over the members) for
    the speed-up.  The machine's load average is kept with the times: on a shared
    machine the wall times (and so the scaling) carry the other work's share."""
    systems, states = _variants(count)
    times = np.arange(0.0, days * DAY + 1.0, 3600.0)
    _run_variants(systems[:2], states[:2], times[:2], step)          # warm-up
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    serial = _run_variants(systems, states, times, step)
    wall = time.perf_counter() - t0
    regimes = serial["regimes"]
    counts = {r: regimes.count(r) for r in sorted(set(regimes))}
    out = {"members": count, "days": days, "step_s": step, "wall_s": wall,
           "lgvi_cpu_s": serial["lgvi_cpu_s"], "diagnose_cpu_s": serial["diagnose_cpu_s"],
           "load_average_at_start": load,
           "regime_fractions": {k: v / count for k, v in counts.items()}}
    print(f"  serial: {out}", flush=True)
    if workers:
        from attitude.propagation.cluster import local_cluster

        # the package's LocalCluster: worker processes without dask's malloc trimming
        with local_cluster(workers) as client:
            client.run(_run_variants, systems[:2], states[:2], times[:2], step)  # warm-up
            chunks = np.array_split(np.arange(count), workers)
            load = os.getloadavg()[0]
            t0 = time.perf_counter()
            futures = [client.submit(_run_variants, [systems[i] for i in ix],
                                     [states[i] for i in ix], times, step) for ix in chunks]
            parts = client.gather(futures)
            parallel = time.perf_counter() - t0
        out.update(workers=workers, parallel_wall_s=parallel,
                   scaling=wall / (workers * parallel),
                   # the same without the other work's share of a shared machine: the
                   # serial CPU time over workers x the slowest worker's
                   cpu_scaling=(serial["lgvi_cpu_s"] + serial["diagnose_cpu_s"]) / (
                       workers * max(p["lgvi_cpu_s"] + p["diagnose_cpu_s"] for p in parts)),
                   worker_cpu_s=[p["lgvi_cpu_s"] + p["diagnose_cpu_s"] for p in parts],
                   worker_wall_s=[p["wall_s"] for p in parts],
                   worker_thread_cpu_s=[p["thread_cpu_s"] for p in parts],
                   # and the tasks' own threads only (not dask's in the same process)
                   thread_cpu_scaling=serial["thread_cpu_s"] / (
                       workers * max(p["thread_cpu_s"] for p in parts)),
                   load_average_at_parallel_start=load,
                   same_regimes_as_serial=[r for p in parts for r in p["regimes"]] == regimes)
        print(f"  with {workers} workers: {out}", flush=True)
    if numpy_path:
        t0 = time.perf_counter()
        plain = _run_variants(systems, states, times, step, compiled=False)
        out.update(numpy_wall_s=time.perf_counter() - t0, numpy_lgvi_cpu_s=plain["lgvi_cpu_s"],
                   lgvi_speedup_over_numpy=plain["lgvi_cpu_s"] / serial["lgvi_cpu_s"],
                   numpy_same_regimes=plain["regimes"] == regimes)
    return out


def flyby_run(count: int = 100, seed: int = 1, step: float = 300.0,
              check: int = 4) -> dict:
    """Apophis past the Earth in 2029 as an ensemble (att.binary.sample_encounter: Pravec
    et al. 2014's state and uncertainties, both phases uniform), from 12 h before perigee
    to 12 h after, with the LGVI at ``step`` s; the first ``check`` members again with
    DOP853 at rtol 1e-10, whose largest difference in the period changes bounds the
    LGVI's error.  The quantiles of the changes of E/E0, P_phi and P_psi and of
    ``|dH|/|H|``, the regime fractions after, and the share of members whose P_phi
    changes by more than its published 3-sigma uncertainty (0.07 h)."""
    members = att.binary.sample_encounter(count, rng=seed)
    times = np.array([0.0, 86400.0])
    t0 = time.perf_counter()
    ds = att.binary.encounter_ensemble(members, times, step=step)
    wall = time.perf_counter() - t0
    ref = att.binary.encounter_ensemble(members[:check], times, rtol=1e-10)
    ok = ds.status.values == 0

    def quantiles(values, scale=1.0):
        q = np.percentile(np.asarray(values)[ok] / scale, [5, 50, 95])
        return {"p05": float(q[0]), "p50": float(q[1]), "p95": float(q[2])}

    dphi = ds.precession_change.values
    return {"members": count, "seed": seed, "step_s": step, "wall_s": wall,
            "ran": int(ok.sum()),
            "regime_fractions_before": ds.attrs["regime_fractions_before"],
            "regime_fractions_after": ds.attrs["regime_fractions"],
            "energy_ratio_change": quantiles(ds.energy_ratio_change.values),
            "precession_change_h": quantiles(dphi, 3600.0),
            "rotation_change_h": quantiles(ds.rotation_change.values, 3600.0),
            "spin_momentum_change": quantiles(ds.spin_momentum_change.values),
            "abs_precession_change_h_max": float(np.abs(dphi[ok]).max() / 3600.0),
            "share_precession_change_above_0.07h": float(np.mean(np.abs(dphi[ok]) > 252.0)),
            "max_angular_momentum_drift": float(ds.angular_momentum_drift.values[ok].max()),
            "lgvi_minus_dop853_precession_change_h": float(np.abs(
                dphi[:check] - ref.precession_change.values).max() / 3600.0)}


#: Dimorphos's shape family for --shapes: the volume and b/c (84.5/57.5, the pre-impact
#: model's) kept, a/b swept.
SHAPE_VOLUME, SHAPE_BC = 89.5 * 84.5 * 57.5, 84.5 / 57.5


def shape_members(elongation: float, betas, impact_time: float):
    """DART members with Dimorphos of long-to-intermediate ratio ``elongation``:
    att.binary.sample_dart's system and impact (circular at 1190 m in the mutual force,
    Dimorphos locked, 580 kg at the scenario's velocity) with its axes replaced, the
    impact at the same ``impact_time`` for every member (so that they run as one family)."""
    from attitude.binary.dynamics import mutual_forces
    from attitude.binary.ensembles import DART
    from attitude.binary.system import impact_delta_v

    c = (SHAPE_VOLUME / (elongation * SHAPE_BC**2)) ** (1 / 3)
    axes = [elongation * SHAPE_BC * c, SHAPE_BC * c, c]
    primary = att.RigidBody.from_mass_properties(ELLIPSOID(5.282e11, DART["primary_axes"]))
    system = att.BinarySystem(primary, att.RigidBody.from_mass_properties(
        ELLIPSOID(DART["secondary_mass"], axes)))
    r = DART["separation"]
    force = mutual_forces(system, np.array([r, 0.0, 0.0]), np.eye(3), np.eye(3)).force
    speed = np.sqrt(-float(force[0]) * r / system.reduced_mass)
    rate = speed / r
    state = att.BinaryState("2022-09-26", [r, 0.0, 0.0], [0.0, speed, 0.0],
                            Rotation.identity(), [0, 0, 2 * np.pi / DART["primary_spin_period"]],
                            Rotation.identity(), [0.0, 0.0, rate])
    U = Rotation.from_rotvec([0.0, 0.0, rate * impact_time]).apply(DART["impactor_velocity"])
    return [(system, state, [att.Impulse(impact_time, body="secondary",
                                         delta_v=impact_delta_v(DART["impactor_mass"], U, b,
                                                                DART["secondary_mass"]))],
             {"elongation": elongation, "beta": float(b)}) for b in betas]


def shapes_run(elongations=(1.05, 1.1, 1.2, 1.3, 1.4, 1.5), per_shape: int = 3,
               days: float = 30.0, step: float = 120.0, seed: int = 1) -> dict:
    """Whether Dimorphos tumbles after DART, shape by shape: ``per_shape`` members each
    (beta 3.61 +- 0.2) over ``days`` after the impact (1.5 orbits in), sampled every 10
    min, the LGVI at ``step`` s, order 2, each member's regime by att.binary.ensemble
    (att.binary.diagnose after the impact).  Beside each shape: its planar libration
    frequency ``omega_0 / n = sqrt(3 (B - A) / C)`` (the lock's strength)."""
    rng = np.random.default_rng(seed)
    betas = rng.normal(3.61, 0.2, size=per_shape)
    impact = 1.5 * 11.92 * 3600.0
    members = [m for e in elongations for m in shape_members(e, betas, impact)]
    times = np.arange(0.0, impact + days * DAY + 1.0, 600.0)
    t0 = time.perf_counter()
    ds = att.binary.ensemble(members, times, step=step)
    wall = time.perf_counter() - t0
    rows = []
    for e in elongations:
        sel = np.isclose(ds.elongation.values, e) & (ds.status.values == 0)
        A, B, C = shape_members(e, [3.61], impact)[0][0].secondary.principal_moments
        regimes = list(ds.secondary_regime.values[sel])
        amp = ds.libration_amplitude.values[sel]
        rows.append({"elongation": e, "omega0_over_n": float(np.sqrt(3 * (B - A) / C)),
                     "members": int(sel.sum()),
                     "regimes": {r: regimes.count(r) / len(regimes) for r in sorted(set(regimes))},
                     "libration_amplitude_deg": [float(np.degrees(a)) for a in amp]})
    return {"days": days, "step_s": step, "per_shape": per_shape, "wall_s": wall,
            "betas": [float(b) for b in betas], "shapes": rows}


def report(name: str, run: dict) -> None:
    setting = f"step {run['step']:g} s" if "step" in run else f"rtol {run['rtol']:g}"
    print(f"  {name:8s} {setting:14s} CPU {run['cpu_s']:6.2f} s   max |dE/E| "
          f"{run['max_abs_dE_over_E']:.2e}   max |dH/H| {run['max_abs_dH_over_H']:.2e}")


def print_difference(what: str, d: dict) -> None:
    print(f"    {what}: position {d['position_m']:.3g} m, primary attitude "
          f"{d['primary_attitude_rad']:.3g} rad, secondary {d['secondary_attitude_rad']:.3g} "
          "rad")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--days", type=float, default=1.0, help="length of the Didymos-like run")
    ap.add_argument("--gubas", type=Path, default=None, metavar="DIR",
                    help="compare with a GUBAS run of its Didymos example in DIR")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "binary.json")
    ap.add_argument("--kepler", action="store_true",
                    help="two spheres, 100 orbits of DOP853 (rtol 2.5e-14) against Kepler")
    ap.add_argument("--dart-libration", action="store_true",
                    help="Dimorphos's free libration over 10 days after DART")
    ap.add_argument("--long", type=int, default=0, metavar="ORBITS",
                    help="the LGVI over ORBITS orbits (the issue's 10000)")
    ap.add_argument("--variants", type=int, default=0, metavar="N",
                    help="N post-impact Dimorphos variants over a month, all at once")
    ap.add_argument("--workers", type=int, default=0, metavar="W",
                    help="with --variants: also on a dask LocalCluster of W workers")
    ap.add_argument("--flyby", type=int, default=0, metavar="N",
                    help="N Apophis flybys of 2029 over the uncertainty of its state")
    ap.add_argument("--shapes", action="store_true",
                    help="Dimorphos's regime a month after DART, shape by shape (a/b)")
    ap.add_argument("--variant-days", type=float, default=30.0, metavar="DAYS",
                    help="with --variants: the length of the run (default a month)")
    ap.add_argument("--numpy", action="store_true",
                    help="with --variants: also the numpy path, for the speed-up")
    ap.add_argument("--only", action="store_true",
                    help="run only the parts asked (--kepler, --long, --variants), not "
                         "the Didymos-like day; keep the other results in the file")
    args = ap.parse_args(argv)
    if args.only:
        result = json.loads(args.out.read_text()) if args.out.is_file() else {}
        if args.kepler:
            k = result["kepler_100_orbits"] = kepler_run()
            print(f"two spheres, {k['orbits']} orbits (e {k['e']:g}), DOP853 {k['rtol']:g} "
                  f"(Encke): largest position error {k['max_position_error_over_a']:.2e} "
                  f"of a, CPU {k['cpu_s']:.1f} s")
        if args.dart_libration:
            d = result["dart_libration"] = dart_libration_run()
            print(f"Dimorphos after DART ({d['days_after_impact']:g} days): free libration "
                  f"{d['free_libration_period_h']:.2f} h ({d['free_libration_amplitude_deg']:.2f}"
                  f" deg), forced {d['forced_libration_period_h']:.2f} h "
                  f"({d['forced_libration_amplitude_deg']:.2f} deg); orbit "
                  f"{d['orbit_period_after_h']:.3f} h, n sqrt(3 (B - A) / C) gives "
                  f"{d['formula_period_h']:.2f} h; zero crossings "
                  f"{d['zero_crossing_libration_period_h']:.2f} h; CPU {d['cpu_s']:.0f} s")
        if args.long:
            g = result["lgvi_long"] = long_lgvi_run(args.long)
            print(f"LGVI over {g['orbits']} orbits ({g['steps_per_orbit']} steps each): "
                  f"max |dH/H| {g['max_abs_dH_over_H']:.2e}, energy trend "
                  f"{g['energy_trend_over_the_run']:.2e} against scatter "
                  f"{g['energy_scatter']:.2e}, CPU {g['cpu_s']:.0f} s")
        if args.variants:
            v = result["variants"] = variants_run(args.variants, days=args.variant_days,
                                                  workers=args.workers, numpy_path=args.numpy)
            print(f"{v['members']} post-impact variants over {v['days']:g} days: "
                  f"{v['wall_s']:.0f} s (LGVI {v['lgvi_cpu_s']:.0f} s CPU); regimes "
                  f"{v['regime_fractions']}"
                  + (f"; numpy path LGVI {v['numpy_lgvi_cpu_s']:.0f} s CPU, "
                     f"{v['lgvi_speedup_over_numpy']:.1f}x" if "numpy_wall_s" in v else "")
                  + (f"; {v['workers']} dask workers {v['parallel_wall_s']:.0f} s, scaling "
                     f"{100 * v['scaling']:.0f} % (in CPU time {100 * v['cpu_scaling']:.0f} "
                     "%)" if "scaling" in v else ""))
        if args.flyby:
            f = result["apophis_flyby"] = flyby_run(args.flyby)
            print(f"Apophis 2029, {f['ran']} of {f['members']} members ({f['wall_s']:.0f} s): "
                  f"regimes after {f['regime_fractions_after']}; dP_phi (5, 50, 95 %) "
                  + ", ".join(f"{v:+.2f}" for v in f["precession_change_h"].values())
                  + " h; dP_psi " + ", ".join(f"{v:+.1f}" for v in f["rotation_change_h"].values())
                  + " h; d(E/E0) "
                  + ", ".join(f"{v:+.4f}" for v in f["energy_ratio_change"].values())
                  + f"; |dP_phi| > 0.07 h in {100 * f['share_precession_change_above_0.07h']:.0f} %"
                  f"; LGVI - DOP853 {f['lgvi_minus_dop853_precession_change_h']:.1e} h")
        if args.shapes:
            s = result["dimorphos_shapes"] = shapes_run()
            print(f"Dimorphos after DART, {s['days']:g} days, {s['per_shape']} members a shape "
                  f"({s['wall_s']:.0f} s):")
            for row in s["shapes"]:
                amp = ", ".join(f"{a:.0f}" for a in row["libration_amplitude_deg"])
                print(f"  a/b {row['elongation']:.2f}  omega0/n {row['omega0_over_n']:.2f}  "
                      f"{row['regimes']}  libration amplitude {amp} deg")
        text = json.dumps(result, indent=1)
        path = write_atomically(args.out, lambda tmp: tmp.write_text(text))
        print(f"results: {path}")
        return

    print(f"{cpu_name()}: one Didymos-like day, order 4, outputs every 30 s")
    result = {"benchmark": "binary", "cpu": cpu_name(), "cores": os.cpu_count(),
              "didymos_like": didymos_like_runs(args.days)}
    runs = result["didymos_like"]
    report("lgvi", runs["lgvi"])
    report("dop853", runs["dop853"])
    print_difference("lgvi - dop853 after the run", runs["lgvi"]["difference_from_dop853"])
    if args.gubas is not None:
        g = result["gubas"] = gubas_comparison(args.gubas)
        print(f"GUBAS's Didymos example (polyhedron primary, {g['days']:g} day): "
              f"{g['source']}")
        report("lgvi", g["lgvi"])
        print_difference("ours - GUBAS's LGVI", g["lgvi"]["difference_from_gubas_lgvi"])
        report("dop853", g["dop853"])
        print_difference("ours - GUBAS's RK7(8)", g["dop853"]["difference_from_gubas_rk78"])
        for name, label in (("lgvi", "GUBAS lgvi"), ("rk", "GUBAS rk78")):
            s = g["gubas"][name]
            print(f"  {label}: CPU {s['cpu_s']:.2f} s (C++), max |dE/E| "
                  f"{s['max_abs_dE_over_E']:.2e}, max |dH/H| {s['max_abs_dH_over_H']:.2e}")
    text = json.dumps(result, indent=1)
    path = write_atomically(args.out, lambda tmp: tmp.write_text(text))
    print(f"results: {path}")


if __name__ == "__main__":
    main()

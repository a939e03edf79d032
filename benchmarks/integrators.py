"""Accuracy and speed of the integrators with torques (issue 6, section 2).

Prints, for one process on this machine, Markdown tables of wall time and achieved
accuracy against DOP853 at ``rtol = 1e-13`` (the reference, :mod:`attitude.propagation.reference`):

1. a Hyperion-like moon (``(B - A)/C = 0.265``) tumbling in Saturn's gravity gradient on
   an ``e = 0.1`` orbit, two orbits: Strang, the 4th-order splittings (RKN and S6) and
   the 6th-order one at several steps and at their default step, DOP853 at rtol 1e-8,
   1e-10 and 1e-12;
2. a fast spinner (a 0.5 x 1 x 2 m box at 10 deg/s) in low Earth orbit, 3 hours: the
   regime where the exact free flow pays most;
3. a batch of 1000 Hyperion-like bodies (Monte Carlo over the initial spin), one orbit:
   one vectorised splitting run against DOP853 body by body (extrapolated from a measured
   subset) and against the one-body splitting path, body by body;
4. a long run in a conservative field (gravity gradient of a fixed primary): the energy
   error of DOP853 drifts, that of the symplectic splittings does not.

Accuracy is the largest attitude error (rotation angle, rad) over the output times, and
the largest error of the body rates relative to ``|omega|``.

Run from the repository root::

    python benchmarks/integrators.py            # ~4 minutes
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time

import numpy as np
import scipy
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from _machine import cpu_name  # noqa: E402  (benchmarks/_machine.py)

import attitude as att  # noqa: E402
from attitude.model.orbit import KeplerOrbit  # noqa: E402
from attitude.propagation.reference import integrate_reference as _reference  # noqa: E402


def integrate_reference(*args, **kwargs):
    """scipy's DOP853 (``compiled=False``): the tables of docs/integrators.md compare the
    splitting with scipy's integrator; the compiled DOP853 is measured by
    benchmarks/perturbed.py."""
    return _reference(*args, compiled=False, **kwargs)
from attitude.model.torques import EARTH_MU, GravityGradient  # noqa: E402
from attitude.propagation.splitting import choose_step, integrate_splitting  # noqa: E402

SATURN_MU = 3.7931187e16          # m^3/s^2 (JPL)
HYPERION_A = 1.481e9              # m


def timed(fn, repeat=1):
    """(best wall time over ``repeat`` runs, result of the last run)."""
    best, out = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def errors(q, w, q_ref, w_ref):
    angle = (Rotation.from_quat(q.reshape(-1, 4))
             * Rotation.from_quat(q_ref.reshape(-1, 4)).inv()).magnitude()
    scale = np.linalg.norm(w_ref, axis=-1, keepdims=True)
    return float(angle.max()), float(np.max(np.abs(w - w_ref) / scale))


def row(label, step, seconds, err, ref_seconds):
    h = "" if step is None else (f"{step:.4g}" if math.isfinite(step) else "-")
    return (f"| {label} | {h} | {seconds:.3f} | {ref_seconds / seconds:.1f} | "
            f"{err[0]:.1e} | {err[1]:.1e} |")


def header(title):
    print(f"\n### {title}\n")
    print("| method | step (s) | time (s) | speed-up vs ref. | attitude error (rad) | "
          "rate error (rel.) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")


def compare(title, body, q0, w0, t, torques, splitting_steps, rtols):
    """One table: the reference, DOP853 at ``rtols``, splittings at ``steps``."""
    ref_time, (q_ref, w_ref) = timed(lambda: integrate_reference(body, q0, w0, t,
                                                                 torques=torques, rtol=1e-13))
    header(title)
    print(row("DOP853 rtol 1e-13 (reference)", None, ref_time, (0.0, 0.0), ref_time))
    for rtol in rtols:
        sec, (q, w) = timed(lambda r=rtol: integrate_reference(body, q0, w0, t,
                                                               torques=torques, rtol=r))
        print(row(f"DOP853 rtol {rtol:.0e}", None, sec, errors(q, w, q_ref, w_ref), ref_time))
    for label, scheme, order, steps in splitting_steps:
        for h in steps:
            default = h is None
            if default:
                h = choose_step(body, q0, w0, torques, order=order)
            sec, (q, w) = timed(lambda s=h, sc=scheme, o=order: integrate_splitting(
                body, q0, w0, t, torques=torques, step=s, scheme=sc,
                order=o if sc is None else None), repeat=1 if h < 1e-3 * t[-1] else 2)
            name = f"{label} (default step)" if default else label
            print(row(name, h, sec, errors(q, w, q_ref, w_ref), ref_time))
    return ref_time


def hyperion():
    orbit = KeplerOrbit(SATURN_MU, HYPERION_A, 0.1)
    gg = GravityGradient(SATURN_MU, orbit)
    body = att.RigidBody.from_principal_moments([0.6, 0.865, 1.0])    # (B - A)/C = 0.265
    n = orbit.mean_motion
    q0 = Rotation.from_euler("zxz", [0.2, 0.3, 0.1]).as_quat()
    w0 = n * np.array([0.1, 0.2, 2.0])
    return orbit, gg, body, q0, w0


def main() -> None:
    print(f"# integrators with torques: {cpu_name()}, {os.cpu_count()} cores; "
          f"Python {platform.python_version()}, numpy {np.__version__}, scipy "
          f"{scipy.__version__}; one process")

    # --- 1. Hyperion-like -----------------------------------------------------------
    orbit, gg, body, q0, w0 = hyperion()
    P = orbit.period
    t = np.linspace(0.0, 2 * P, 401)
    steps = [
        ("Strang (order 2)", "strang", 2, [P / 1000, P / 4000, P / 16000, None]),
        ("splitting order 4, RKN", None, 4, [P / 250, P / 1000, P / 4000, None]),
        ("splitting order 4, S6", "blanes-moan", 4, [P / 1000, P / 4000]),
        ("splitting order 4, Yoshida", "yoshida4", 4, [P / 2000, P / 8000]),
        ("splitting order 6, Yoshida", None, 6, [P / 250, P / 1000, None]),
    ]
    compare(f"Hyperion-like: (B-A)/C = 0.265, e = 0.1, a = {HYPERION_A / 1e9:.3f} Gm about "
            f"Saturn, 2 orbits ({2 * P / 86400:.1f} d), 401 outputs; |omega0| = "
            f"{np.linalg.norm(w0) / orbit.mean_motion:.2f} n", body, q0, w0, t, [gg], steps,
            [1e-8, 1e-10, 1e-12])

    # --- 2. fast spinner in LEO -------------------------------------------------------
    leo = KeplerOrbit(EARTH_MU, 7.0e6, 0.001)
    box = att.RigidBody.from_parts([att.MassProperties.solid_box(100.0, [0.5, 1.0, 2.0])])
    gg_leo = GravityGradient(EARTH_MU, leo)
    q0_leo = Rotation.from_euler("xyz", [0.4, -0.2, 0.3]).as_quat()
    w0_leo = np.radians(10.0) * np.array([0.2, 0.3, 0.93]) / np.linalg.norm([0.2, 0.3, 0.93])
    t_leo = np.linspace(0.0, 3 * 3600.0, 181)
    steps_leo = [
        ("Strang (order 2)", "strang", 2, [0.5, None]),
        ("splitting order 4, RKN", None, 4, [5.0, 2.0, None]),
        ("splitting order 6, Yoshida", None, 6, [5.0, None]),
    ]
    compare("Fast spinner in LEO: 100 kg box 0.5 x 1 x 2 m, 10 deg/s, 7000 km, 3 h, "
            "181 outputs", box, q0_leo, w0_leo, t_leo, [gg_leo], steps_leo, [1e-8, 1e-10])

    # --- 3. batch of 1000 ------------------------------------------------------------
    rng = np.random.default_rng(1)
    N, n_sub = 1000, 20
    t1 = np.linspace(0.0, P, 101)
    ws = w0 * (1.0 + 0.05 * rng.normal(size=(N, 3)))
    qs = (Rotation.from_rotvec(0.1 * rng.normal(size=(N, 3))) * Rotation.from_quat(q0)
          ).as_quat()
    bodies = [body] * N
    refs = [integrate_reference(body, qs[i], ws[i], t1, torques=[gg], rtol=1e-13)
            for i in range(n_sub)]
    sec_dop, dop = timed(lambda: [integrate_reference(body, qs[i], ws[i], t1, torques=[gg],
                                                      rtol=1e-10) for i in range(n_sub)])
    err_dop = max(errors(*dop[i], *refs[i])[0] for i in range(n_sub))
    dop_all = sec_dop * N / n_sub
    print(f"\n### Batch: {N} Hyperion-like bodies (spins +-5 %, attitudes +-0.1 rad), one "
          f"orbit, 101 outputs\n")
    print(f"| method | step (s) | time for {N} bodies (s) | speed-up vs DOP853 | attitude "
          f"error (rad, {n_sub} bodies) |")
    print("| --- | ---: | ---: | ---: | ---: |")
    print(f"| DOP853 rtol 1e-10, body by body (x{N // n_sub} from {n_sub} bodies) |  | "
          f"{dop_all:.1f} | 1.0 | {err_dop:.1e} |")
    for label, h in (("default step", choose_step(bodies, qs, ws, [gg], order=4)),
                     ("P / 200", P / 200)):
        sec_one, _ = timed(lambda s=h: [integrate_splitting(body, qs[i], ws[i], t1,
                                                            torques=[gg], step=s)
                                        for i in range(n_sub)])
        sec_batch, (qb, wb) = timed(lambda s=h: integrate_splitting(bodies, qs, ws, t1,
                                                                    torques=[gg], step=s))
        err = max(errors(qb[i], wb[i], *refs[i])[0] for i in range(n_sub))
        one_all = sec_one * N / n_sub
        print(f"| splitting order 4 ({label}), body by body (x{N // n_sub} from {n_sub}) | "
              f"{h:.4g} | {one_all:.1f} | {dop_all / one_all:.1f} | {err:.1e} |")
        print(f"| splitting order 4 ({label}), one vectorised batch | {h:.4g} | "
              f"{sec_batch:.1f} | {dop_all / sec_batch:.1f} | {err:.1e} |")

    # --- 4. long-run energy error --------------------------------------------------------
    static = GravityGradient(EARTH_MU, [7.0e6, 0.0, 0.0])        # fixed primary: E + V kept
    moments = np.array([2.0, 3.0, 4.5])
    sat = att.RigidBody.from_principal_moments(moments)
    q0s = Rotation.from_euler("xyz", [0.4, -0.3, 0.2]).as_quat()
    w0s = np.array([3e-4, -2e-4, 1e-3])
    t_long = np.linspace(0.0, 2.0e6, 1001)                     # 23 days, ~300 librations

    def energy(q, w):
        return 0.5 * np.sum(moments * w * w, axis=1) + static.potential(t_long, q, sat)

    print("\n### Long run: energy error, gravity gradient of a fixed primary (E + V "
          "conserved), 23 days, 1001 outputs\n")
    print("| method | step (s) | time (s) | max rel. energy error, first tenth | last tenth |")
    print("| --- | ---: | ---: | ---: | ---: |")
    runs = [("DOP853 rtol 1e-8", lambda: integrate_reference(sat, q0s, w0s, t_long,
                                                              torques=[static], rtol=1e-8), None),
            ("DOP853 rtol 1e-10", lambda: integrate_reference(sat, q0s, w0s, t_long,
                                                               torques=[static], rtol=1e-10),
             None),
            ("Strang (order 2)", lambda: integrate_splitting(sat, q0s, w0s, t_long,
                                                             torques=[static], step=20.0,
                                                             order=2), 20.0),
            ("splitting order 4, RKN", lambda: integrate_splitting(sat, q0s, w0s, t_long,
                                                                   torques=[static],
                                                                   step=200.0), 200.0),
            ("splitting order 4, RKN", lambda: integrate_splitting(sat, q0s, w0s, t_long,
                                                                   torques=[static],
                                                                   step=100.0), 100.0)]
    for label, fn, h in runs:
        sec, (q, w) = timed(fn)
        E = energy(q, w)
        err = np.abs(E / E[0] - 1.0)
        tenth = len(E) // 10
        print(f"| {label} | {'' if h is None else h} | {sec:.2f} | {err[1:tenth].max():.1e} | "
              f"{err[-tenth:].max():.1e} |")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__,   # --help: what it measures, then exit
                            formatter_class=argparse.RawDescriptionHelpFormatter
                            ).parse_args()
    main()

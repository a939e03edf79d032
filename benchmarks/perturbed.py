"""Perturbed propagation at matched accuracy: our default (splitting) integrator vs scipy
DOP853 vs a classical fixed-step RK4 (issue 6, section 3).

Case: a 1 m^3 satellite (100 kg box, 0.5 x 1 x 2 m) tumbling slowly under the gravity
gradient of the Earth on a circular 7000 km orbit, for one day, output every minute.
Reference: DOP853 at rtol = 1e-13.  For each method the cheapest setting whose attitude
error stays <= 1e-6 rad over the day is found by scanning, then timed (best of 3).

    python benchmarks/perturbed.py
"""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.orbit import KeplerOrbit
from attitude.propagation.reference import _rhs
from attitude.torques import GravityGradient

TARGET = 1e-6          # rad
DAY = 86400.0
T_OUT = np.arange(0.0, DAY + 1.0, 60.0)


def case():
    body = att.RigidBody.from_parts([att.MassProperties.solid_box(100.0, [0.5, 1.0, 2.0])])
    orbit = KeplerOrbit.from_elements(mu="3.986004418e14 m3/s2", a="7000 km", e=0.0,
                                      i="51.6 deg", raan="0 deg", argp="0 deg",
                                      mean_anomaly="0 deg")
    state = att.AttitudeState("2030-01-01T00:00:00", Rotation.from_euler("ZXZ", [0.3, 1.0, 0.2]),
                              [0.004, -0.003, 0.006])
    return body, state, [GravityGradient(orbit=orbit)]


def best_of(fn, n=3):
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def attitude_error(q, q_ref):
    return float(np.max((Rotation.from_quat(q) * Rotation.from_quat(q_ref).inv()).magnitude()))


def rk4(body, state, torques, h):
    """Classical fixed-step RK4 on Euler's equations + quaternion kinematics (the same
    right-hand side as the reference integrator), quaternion renormalised each step,
    outputs every 60 s (h divides 60 s)."""
    rhs = _rhs(body, torques)
    y = np.concatenate([state.attitude.as_quat(), state.omega_body])
    per_out = int(round(60.0 / h))
    out = [y.copy()]
    t = 0.0
    for _ in range(len(T_OUT) - 1):
        for _ in range(per_out):
            k1 = rhs(t, y)
            k2 = rhs(t + h / 2, y + h / 2 * k1)
            k3 = rhs(t + h / 2, y + h / 2 * k2)
            k4 = rhs(t + h, y + h * k3)
            y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            y[:4] /= np.linalg.norm(y[:4])
            t += h
        out.append(y.copy())
    return np.array(out)[:, :4]


def main():
    body, state, torques = case()
    print("reference: DOP853 rtol 1e-13 ...", flush=True)
    ref = att.propagate(body, state, T_OUT, torques=torques, method="integrator", rtol=1e-13)
    q_ref = ref.dataset.quaternion.values
    rows = []

    for step in (600.0, 300.0, 120.0, 60.0, 30.0, 15.0, 10.0, 5.0):
        eph = att.propagate(body, state, T_OUT, torques=torques, method="splitting", step=step)
        err = attitude_error(eph.dataset.quaternion.values, q_ref)
        if err <= TARGET:
            t, _ = best_of(lambda s=step: att.propagate(body, state, T_OUT, torques=torques,
                                                        method="splitting", step=s))
            rows.append(("splitting, order 4 (default)", f"step {step:g} s", err, t))
            break
    for rtol in (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12):
        eph = att.propagate(body, state, T_OUT, torques=torques, method="integrator", rtol=rtol)
        err = attitude_error(eph.dataset.quaternion.values, q_ref)
        if err <= TARGET:
            t, _ = best_of(lambda r=rtol: att.propagate(body, state, T_OUT, torques=torques,
                                                        method="integrator", rtol=r))
            rows.append(("scipy DOP853", f"rtol {rtol:g}", err, t))
            break
    for h in (60.0, 30.0, 20.0, 10.0, 5.0, 2.0, 1.0):
        err = attitude_error(rk4(body, state, torques, h), q_ref)
        if err <= TARGET:
            t, _ = best_of(lambda s=h: rk4(body, state, torques, s), n=1)
            rows.append(("classical RK4 (fixed step)", f"step {h:g} s", err, t))
            break

    print(f"\n1 day, gravity gradient, 7000 km orbit; attitude error <= {TARGET:g} rad vs "
          "DOP853 rtol 1e-13\n")
    print("| method | setting | max attitude error (rad) | wall time (s) |")
    print("| --- | --- | ---: | ---: |")
    for name, setting, err, t in rows:
        print(f"| {name} | {setting} | {err:.2e} | {t:.3f} |")
    ours = rows[0][3] if rows and rows[0][0].startswith("splitting") else None
    if ours:
        for name, _, _, t in rows[1:]:
            print(f"\n{name}: {t / ours:.1f}x the time of the splitting integrator", end="")
        print()


if __name__ == "__main__":
    main()

"""Figures of docs/diagnostics.md: a worked time-resolved classification (an
energy-dissipating long-axis spinner) and the chaos test of Hyperion.

Run from the repository root (needs matplotlib, not a dependency of the package)::

    python benchmarks/diagnostics_figures.py          # writes docs/figures/*.png

It also prints the numbers quoted in the docs.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.analysis.classification import classify, lyapunov_exponent
from attitude.analysis.diagnostics import add_diagnostics
from attitude.model.orbit import KeplerOrbit
from attitude.model.torques import EnergyDissipation, GravityGradient

OUT = Path(__file__).resolve().parents[1] / "docs" / "figures"
COLORS = {"PA-long": "#4c72b0", "LAM": "#55a868", "separatrix": "#c44e52", "SAM": "#8172b2",
          "PA-short": "#ccb974", "chaotic": "#64b5cd", "axisymmetric": "#999999"}


def dissipation(plt):
    body = att.RigidBody.from_principal_moments([1.0, 1.5, 2.0])
    state = att.AttitudeState("2030-01-01", Rotation.identity(), [1.0, 2e-4, 2e-4])
    t = np.linspace(0.0, 800.0, 4001)
    eph = att.propagate(body, state, t, torques=[EnergyDissipation(20.0)], rtol=1e-10)
    c = classify(eph)
    ds = add_diagnostics(eph, reference_axis=3).dataset
    print("dissipation segments:")
    for s0, s1, r in c.segments:
        print(f"  {s0:7.1f} .. {s1:7.1f} s  {r}")
    for tr in c.transitions:
        print(f"  transition {tr.epoch:7.2f} s  {tr.before} -> {tr.after}")
    fig, ax = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    ang = np.degrees(ds["momentum_axis_angle"].values)
    ax[0].plot(t, ang[:, 0], label="L to A (long axis)")
    ax[0].plot(t, ang[:, 2], label="L to C (short axis)")
    ax[0].set_ylabel("nutation angle (deg)")
    ax[0].legend(loc="center right")
    ax[1].plot(t, np.degrees(ds["precession_angle"].values) / 360.0)
    ax[1].set_ylabel("precession angle of C\nabout L (turns)")
    for s0, s1, r in c.segments:
        for a in ax:
            a.axvspan(s0, s1, color=COLORS.get(r, "#dddddd"), alpha=0.15, lw=0)
        ax[2].barh(0, s1 - s0, left=s0, color=COLORS.get(r, "#dddddd"))
        ax[2].text(0.5 * (s0 + s1), 0, r, ha="center", va="center", fontsize=8)
    ax[2].set_yticks([])
    ax[2].set_ylabel("regime")
    ax[2].set_xlabel("time (s)")
    fig.suptitle("Long-axis spinner with an energy sink (EnergyDissipation, tau = 20 s)")
    fig.tight_layout()
    fig.savefig(OUT / "dissipation_classification.png", dpi=110)


def hyperion(plt):
    MU, A = 3.7931e16, 1.4811e9
    body = att.RigidBody.from_principal_moments(np.array([0.5629, 0.8279, 1.0]) * 5.6e31)
    fig, ax = plt.subplots(2, 1, figsize=(7, 6))
    for e, tilt, label in ((0.1, 0.0, "Hyperion, planar start"),
                           (0.1, 0.1, "Hyperion, spin axis 0.1 rad off the normal"),
                           (0.0, 0.0, "synchronous moon, circular orbit")):
        orbit = KeplerOrbit(mu=MU, a=A, e=e)
        P = orbit.period
        state = att.AttitudeState("2030-01-01", Rotation.from_euler("x", tilt),
                                  [0.0, 0.0, orbit.mean_motion])
        gg = GravityGradient(orbit=orbit)
        ly = lyapunov_exponent(body, state, [gg], 100 * P, intervals=200)
        print(f"{label}: lambda = {ly.exponent * P:.3f} +/- {ly.uncertainty * P:.3f} per "
              f"orbit, Lyapunov time {ly.lyapunov_time / P:.2f} orbits "
              f"({ly.lyapunov_time / 86400:.1f} d); control {ly.control_exponent * P:.3f}; "
              f"excess {ly.excess_efolds:.1f} e-folds; chaotic {ly.chaotic}")
        ax[0].plot(ly.times / P, ly.running_exponent * P, label=label)
        if tilt == 0.0 and e == 0.1:
            ax[0].plot(ly.times / P, np.cumsum(ly.control_local_exponents) /
                       np.arange(1, ly.times.size + 1) * P, "k:",
                       label="regular control (no torque)")
        if tilt > 0:
            eph = att.propagate(body, state, np.linspace(0, 20 * P, 2001), torques=[gg],
                                rtol=1e-10)
            ds = add_diagnostics(eph).dataset
            ax[1].plot(eph.time / P, np.degrees(ds["momentum_axis_angle"].values[:, 2]))
    ax[0].set_xlabel("time (orbital periods)")
    ax[0].set_ylabel("FTLE (per orbit)")
    ax[0].legend(fontsize=8)
    ax[1].set_xlabel("time (orbital periods)")
    ax[1].set_ylabel("angle L to C (deg)")
    ax[1].set_title("Hyperion, spin axis started 0.1 rad off the orbit normal: tumbling",
                    fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "hyperion_lyapunov.png", dpi=110)


def main():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    OUT.mkdir(parents=True, exist_ok=True)
    dissipation(plt)
    hyperion(plt)


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__,   # --help: what it measures, then exit
                            formatter_class=argparse.RawDescriptionHelpFormatter
                            ).parse_args()
    main()

"""Figure of docs/ensembles.md: the attitude spread of a Monte Carlo ensemble of
Apophis's spin state (Pravec et al. 2014) from 2013 to the 2029 close approach.

Run from the repository root (needs matplotlib, not a dependency of the package)::

    python benchmarks/ensemble_figures.py      # writes docs/figures/apophis_ensemble_spread.png

It also prints the numbers quoted in the docs.  The assumptions (3-sigma errors, split
normal moment ratios, 3 deg (1 sigma) on the direction of L, epoch 2013-01-01 TDB with
known phases, the P_psi = 263 +/- 6 h cut) are those of the page and are repeated in
``pravec2014`` below.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.time import Time

import attitude as att
from attitude.ensemble import (
    diagnose_ensemble,
    period_quantiles,
    regime_fractions,
    spread_quantiles,
)

OUT = Path(__file__).resolve().parents[1] / "docs" / "figures"
EPOCH = Time("2013-01-01T00:00:00", scale="tdb")        # assumed (not Pravec's epoch)
ENCOUNTER = Time("2029-04-13T21:46:00", scale="tdb")    # Earth close approach
NOMINAL = {"angular_momentum_ra": 250 * u.deg, "angular_momentum_dec": -75 * u.deg,
           "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
           "precession_period": 27.38 * u.h}
QUANTILES = (0.5, 0.9, 0.99)


def split_normal(rng, n, mean, minus, plus):
    z = rng.standard_normal(n)
    return mean + np.where(z < 0, minus, plus) * z


def pravec2014(rng, n):
    """Independent draws: 3-sigma errors as published, 3 deg (1 sigma, assumed) on L."""
    lat = np.radians(-75.0)
    return {
        "angular_momentum_ra": np.radians(250.0)
                               + np.radians(3.0) / np.cos(lat) * rng.standard_normal(n),
        "angular_momentum_dec": lat + np.radians(3.0) * rng.standard_normal(n),
        "energy_ratio": 1.024 + 0.013 / 3 * rng.standard_normal(n),
        "ratio_a": split_normal(rng, n, 0.61, 0.08 / 3, 0.11 / 3),
        "ratio_b": split_normal(rng, n, 0.965, 0.015 / 3, 0.009 / 3),
        "precession_period": (27.38 + 0.07 / 3 * rng.standard_normal(n)) * 3600.0}


def first_crossing(t, y, level):
    above = np.nonzero(y >= level)[0]
    return t[above[0]] if above.size else np.nan


def main(n_draws: int = 100_000, n_times: int = 400):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    draws = att.Ensemble.sample(n_draws, rng=2029, epoch=EPOCH, frame="ECLIPJ2000",
                                mean=NOMINAL, sampler=pravec2014)
    p_psi = diagnose_ensemble(draws)["rotation"].values / 3600.0
    keep = np.abs(p_psi - 263.0) <= 6.0
    apophis = draws.subset(keep)
    print(f"{n_draws} draws ({len(draws.invalid)} invalid): regimes "
          f"{regime_fractions(draws)}; P_psi 5-95 % {np.nanpercentile(p_psi, [5, 95])} h")
    print(f"{len(apophis)} consistent with P_psi = 263 +/- 6 h: regimes "
          f"{regime_fractions(apophis)}")
    print("period quantiles (h), 5/50/95 %:")
    print((period_quantiles(apophis, q=(0.05, 0.5, 0.95)) / 3600).round(3).to_pandas())

    days = np.geomspace(1.0 / 24, (ENCOUNTER - EPOCH).to_value(u.d), n_times)
    times = EPOCH + days * u.d
    years = days / 365.25
    # the consistent draws, and (for comparison) as many independent draws
    spread = np.degrees(spread_quantiles(att.propagate(apophis, times), q=QUANTILES).values)
    free = np.degrees(spread_quantiles(att.propagate(draws.subset(slice(0, len(apophis))),
                                                     times), q=QUANTILES).values)
    print("spread quantiles (deg) at the epoch + 1 h:", spread[:, 0].round(1))
    print("spread quantiles (deg) at the encounter:", spread[:, -1].round(1))
    for level in (10.0, 30.0, 90.0):
        print(f"median spread reaches {level:.0f} deg after "
              f"{first_crossing(days, spread[0], level):.1f} d (consistent draws), "
              f"{first_crossing(days, free[0], level):.1f} d (independent draws)")

    fig, ax = plt.subplots(figsize=(7, 4.2))
    colors = ("#4c72b0", "#55a868", "#c44e52")
    for k, (q, c) in enumerate(zip(QUANTILES, colors)):
        ax.plot(years, spread[k], color=c, lw=2, label=f"{q:.0%} of the draws within")
        if q < 0.99:          # the top 1 % of the independent draws are LAM: off scale
            ax.plot(years, free[k], color=c, lw=0.8, ls="--")
    ax.plot([], [], color="k", lw=0.8, ls="--",
            label="independent draws, no P_psi cut (50 %, 90 %)")
    ax.axhline(90.0, color="0.5", lw=0.8, ls=":")
    ax.set_xscale("log")
    ax.set_xlim(years[0], years[-1])
    ax.set_ylim(0, 185)
    ax.set_yticks(range(0, 181, 30))
    ax.set_xlabel("years since 2013-01-01 TDB (log scale); the encounter is at the right edge")
    ax.set_ylabel("angle from the nominal attitude (deg)")
    ax.set_title(f"Apophis: {len(apophis)} spin states consistent with Pravec et al. 2014, "
                 "propagated to 2029-04-13", fontsize=9)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(0.0, 0.93))
    fig.tight_layout()
    OUT.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT / "apophis_ensemble_spread.png", dpi=110)
    print("wrote", OUT / "apophis_ensemble_spread.png")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__,   # --help: what it measures, then exit
                            formatter_class=argparse.RawDescriptionHelpFormatter
                            ).parse_args()
    main()

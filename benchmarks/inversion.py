"""Convex inversion against DAMIT's convexinv on the same lightcurves, in one run.

Both programs invert (43) Ariadne's 37 relative lightcurves (tests/data/inversion/, the
convexinv test file) from the same period, Lommel-Seeliger + 0.1 Lambert, a Gaussian image
of 8 rows per octant and harmonics of degree 6; convexinv from its own input file's pole
start (220, 0) deg with 50 iterations, attitude from its pole starts over the sphere (and
the mirror), and once from convexinv's start with 50 model evaluations (the like-for-like
timing). Reported: pole, period, rms (relative flux) and CPU time of each.

convexinv is built from source outside the repository (GPL-2; nothing of it is copied)::

    # fetch github:mkretlow/DAMIT-convex, then: cd DAMIT-convex/convexinv && make
    python benchmarks/inversion.py --convexinv /path/to/DAMIT-convex/convexinv/convexinv

Without --convexinv only attitude runs.

The synthetic suites (issue 27's numbers), each a part run on its own::

    python benchmarks/inversion.py --synthetic-pa --json benchmarks/results/inversion.json
    python benchmarks/inversion.py --synthetic-tumblers --json benchmarks/results/inversion.json

``--synthetic-pa``: ten principal-axis rotators of seeded Gaussian-random-sphere shapes (the
convex hull, so that the truth is in the model's class), random poles and periods, six
apparitions of four nights seen from the Earth on the orbit of (135) Hertha (elements
rounded from JPL's), Lommel-Seeliger + 0.1 Lambert, 0.01 mag noise; inverted by
``att.invert`` from a period range of +-1.3 scan steps around the truth.  Reported per
case: the pole's distance from the truth and from its mirror (both solutions), the
period's relative error and the inertia ratios at uniform density against the truth's.

``--synthetic-tumblers``: Apophis-like SAMs and Toutatis-like LAMs (ellipsoids of the
published moment ratios with random lumps, the convex hull), 40 days at 30 min, 0.01 mag,
inverted from the data alone (no start); the stages' CPU times are measured.

A JSON file given with --json is updated (the parts run replace their keys; the others
are kept).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
from astropy.time import Time
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.inversion import (
    ConvexModel,
    GaussianImage,
    ObservedLightcurve,
    fit_convex,
    invert,
    read_damit_lightcurves,
)
from attitude.inversion import tumbler as tb
from attitude.inversion.gaussian_image import real_harmonics, sphere_triangulation
from attitude.model.freebody import diagnose_many
from attitude.model.orbit import KeplerOrbit
from attitude.model.sampling import tumbling_state
from attitude.model.state import AttitudeState
from attitude.photometry.geometry import Geometry

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "inversion" / "ariadne_lcs_rel.txt"
PERIOD_H = 5.76198

HERTHA = ROOT / "tests" / "data" / "inversion" / "hertha_135_rel.txt"
#: The start of ADAM's own Hertha example (135_oct.ini: beta, lambda 52, 272 deg, P 8.40060 h).
HERTHA_POLE, HERTHA_PERIOD_H = (272.0, 52.0), 8.40060

CONVEXINV_INPUT = """{lon} 1 inital lambda [deg] (0/1 - fixed/free)
{lat} 1 initial beta [deg] (0/1 - fixed/free)
{period} 1 inital period [hours] (0/1 - fixed/free)
0 zero time [JD]
0 initial rotation angle [deg]
0.1 convexity regularization
6 6 degree and order of spherical harmonics expansion
8 number of rows
0.5 0 phase funct. param. 'a' (0/1 - fixed/free)
0.1 0 phase funct. param. 'd' (0/1 - fixed/free)
-0.5 0 phase funct. param. 'k' (0/1 - fixed/free)
0.1 0 Lambert coefficient 'c' (0/1 - fixed/free)
50 iteration stop condition
"""


def run_attitude(poles: int, data=DATA, period_h=PERIOD_H) -> dict:
    start = time.process_time()
    res = invert(read_damit_lightcurves(data), "principal", period=period_h * 3600,
                 poles=poles, max_iterations=60)
    return {"pole_deg": list(res.pole), "period_h": res.period / 3600, "rms": res.rms,
            "dark_facet": res.dark_facet, "cpu_s": time.process_time() - start,
            "mirror": res.alternatives[0][1], "poles": poles}


def run_attitude_single(data=DATA, period_h=PERIOD_H, pole=(220.0, 0.0)) -> dict:
    """One fit from convexinv's start, as convexinv runs: the like-for-like timing."""
    start = time.process_time()
    model = ConvexModel(read_damit_lightcurves(data), GaussianImage(8, 6))
    fit = fit_convex(model, *np.radians(pole), period_h * 3600, max_iterations=50)
    return {"pole_deg": list(fit.pole), "period_h": fit.period / 3600, "rms": fit.rms,
            "dark_facet": fit.dark_facet, "cpu_s": time.process_time() - start,
            "evaluations": fit.n_evaluations}


def run_convexinv(exe: Path, data_path=DATA, period_h=PERIOD_H, pole=(220.0, 0.0)) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "input").write_text(CONVEXINV_INPUT.format(period=period_h, lon=pole[0],
                                                          lat=pole[1]))
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        with open(data_path) as data:
            proc = subprocess.run([str(exe), "-v", "-o", "areas", "-p", "par", "input",
                                   "out_lcs"], stdin=data, cwd=tmp, capture_output=True,
                                  text=True, check=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        lon, lat, period = map(float, (tmp / "par").read_text().split()[:3])
        model = np.loadtxt(tmp / "out_lcs")
    # the rms of the relative residuals, as attitude computes it (each curve over its mean)
    observations = read_damit_lightcurves(data_path)
    resid, start = [], 0
    for obs in observations:
        m = model[start:start + len(obs)]
        start += len(obs)
        resid.append(obs.brightness / obs.brightness.mean() - m / m.mean())
    rms = float(np.sqrt(np.mean(np.concatenate(resid) ** 2)))
    return {"pole_deg": [lon, lat], "period_h": period, "rms": rms,
            "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
            "log_tail": proc.stdout.strip().splitlines()[-3:]}


# --- synthetic suites --------------------------------------------------------------------

SUN_MU = "1.32712440018e20 m3/s2"
PA_EPOCH = Time("2024-01-01", scale="tdb")
#: (135) Hertha's orbit, elements rounded (JPL SBDB); the mean anomaly at the epoch is
#: chosen, not Hertha's: only a realistic main-belt geometry is wanted.
HERTHA_ORBIT = dict(a="2.4288 AU", e=0.2073, i="2.306 deg", raan="343.7 deg",
                    argp="340.3 deg", mean_anomaly="120 deg")


def _hull(points) -> att.Polyhedron:
    """The convex hull of points around the origin as an outward-oriented Polyhedron."""
    faces = ConvexHull(points).simplices.copy()
    a, b, c = points[faces[:, 0]], points[faces[:, 1]], points[faces[:, 2]]
    flip = np.einsum("ij,ij->i", np.cross(b - a, c - a), a + b + c) < 0.0
    faces[flip] = faces[flip][:, ::-1]
    used = np.unique(faces)
    index = np.full(points.shape[0], -1)
    index[used] = np.arange(used.size)
    return att.Polyhedron(points[used], index[faces])


def _principal(shape: att.Polyhedron) -> tuple[att.Polyhedron, np.ndarray]:
    """The shape at unit volume in its principal axes (x smallest moment, z largest) and
    its principal moments at unit density."""
    _, com, inertia = shape.mass_properties(1.0)
    _, axes = np.linalg.eigh(inertia)
    if np.linalg.det(axes) < 0:
        axes[:, 0] *= -1.0
    out = att.Polyhedron((shape.vertices - com) @ axes * shape.volume ** (-1 / 3), shape.faces)
    return out, np.diag(out.mass_properties(1.0)[2])


def gaussian_random_sphere(rng, axes=(1.0, 1.0, 1.0), sigma=0.25, nu=4.0, degree=10,
                           rows=12):
    """A Gaussian random sphere (Muinonen 1998: log radius a Gaussian field of harmonic
    variances ~ l^-nu from degree 2, standard deviation ``sigma``) stretched by ``axes``,
    as its convex hull in principal axes, and its principal moments."""
    v, _ = sphere_triangulation(rows)
    ell = np.concatenate([[k] * (2 * k + 1) for k in range(degree + 1)])
    c_l = np.where(ell >= 2, np.maximum(ell, 1) ** -nu, 0.0)
    c_l *= sigma ** 2 / np.sum(c_l / (4.0 * np.pi))
    s = real_harmonics(degree, v) @ (rng.standard_normal(ell.size) * np.sqrt(c_l))
    return _principal(_hull(v * np.asarray(axes) * np.exp(s - 0.5 * sigma ** 2)[:, None]))


def _relative_lightcurves(t, flux, geometry, block, noise, rng, epoch):
    """Relative lightcurves (one per block) of ``flux`` with ``noise`` mag of Gaussian
    noise, weighted as 0.01 mag at least."""
    mag = -2.5 * np.log10(flux) + noise * rng.standard_normal(t.size)
    y = 10.0 ** (-0.4 * mag)
    sigma = y * max(noise, 0.01) * np.log(10.0) / 2.5
    return [ObservedLightcurve(epoch, t[block == k], y[block == k],
                               Geometry(sun=geometry.sun[block == k],
                                        observer=geometry.observer[block == k]),
                               sigma=sigma[block == k], name=f"lightcurve {k}")
            for k in np.unique(block)]


def opposition_times(orbit, years=8.0, epoch=PA_EPOCH) -> np.ndarray:
    """Times (s after ``epoch``) of the smallest phase angle of each apparition."""
    t = np.arange(0.0, years * 365.25) * 86400.0
    g = Geometry.from_orbit(orbit, t, "earth", epoch=epoch)
    s = g.sun / np.linalg.norm(g.sun, axis=1)[:, None]
    o = g.observer / np.linalg.norm(g.observer, axis=1)[:, None]
    alpha = np.arccos(np.clip(np.einsum("ij,ij->i", s, o), -1.0, 1.0))
    k = np.nonzero((alpha[1:-1] < alpha[:-2]) & (alpha[1:-1] <= alpha[2:]))[0] + 1
    return t[k]


def pa_case(seed: int, *, apparitions=6, nights=(-30.0, -12.0, 8.0, 25.0), hours=5.0,
            cadence=600.0, noise=0.01) -> dict:
    """One synthetic principal-axis rotator: its lightcurves and its truth."""
    rng = np.random.default_rng(seed)
    shape, moments = gaussian_random_sphere(rng)
    pole = (rng.uniform(0.0, 2.0 * np.pi), float(np.arcsin(rng.uniform(-1.0, 1.0))))
    period = rng.uniform(4.0, 10.0) * 3600.0
    phi0 = rng.uniform(0.0, 2.0 * np.pi)
    orbit = KeplerOrbit.from_elements(mu=SUN_MU, **HERTHA_ORBIT)
    starts = (opposition_times(orbit)[:apparitions, None]
              + np.array(nights)[None] * 86400.0).ravel()
    night = np.arange(0.0, hours * 3600.0 + 1.0, cadence)
    t = (starts[:, None] + night[None]).ravel()
    geometry = Geometry.from_orbit(orbit, t, "earth", epoch=PA_EPOCH)
    state = AttitudeState(PA_EPOCH, Rotation.from_euler("ZYZ", [pole[0], np.pi / 2 - pole[1],
                                                                phi0]),
                          [0.0, 0.0, 2.0 * np.pi / period], frame="ECLIPJ2000")
    eph = att.propagate(att.RigidBody.from_principal_moments(moments), state, t)
    flux = np.asarray(att.lightcurve(eph, shape, geometry, law="ls-lambert").dataset["flux"])
    block = np.repeat(np.arange(starts.size), night.size)
    return {"observations": _relative_lightcurves(t, flux, geometry, block, noise, rng,
                                                  PA_EPOCH),
            "pole": pole, "period": period, "ratios": (moments[0] / moments[2],
                                                       moments[1] / moments[2]),
            "span": float(np.ptp(t))}


def _angle(a_deg, b_deg) -> float:
    """Angle (deg) between two (longitude, latitude) directions given in deg."""
    def unit(lon_lat):
        lon, lat = np.radians(lon_lat)
        return np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    a, b = unit(a_deg), unit(b_deg)
    return float(np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b)))


def _moment_ratios(body) -> list:
    m = body.principal_moments
    return [float(m[0] / m[2]), float(m[1] / m[2])]


def run_pa_case(seed: int, *, poles=6, max_iterations=50) -> dict:
    """Invert one synthetic principal-axis rotator from a period range of +-1.3 scan
    steps around the truth (its centre shifted at random by up to half a step)."""
    case = pa_case(seed)
    p = case["period"]
    step = 0.4 * p ** 2 / case["span"]
    shift = np.random.default_rng(seed + 1000).uniform(-0.5, 0.5) * step
    start = time.process_time()
    res = invert(case["observations"], period=(p + shift - 1.3 * step, p + shift + 1.3 * step),
                 poles=poles, rows=8, degree=6, max_iterations=max_iterations)
    cpu = time.process_time() - start
    truth = np.degrees(case["pole"])
    mirror_truth = [(truth[0] + 180.0) % 360.0, truth[1]]
    mirror = [float(x) for x in res.alternatives[0][1].split("(")[1].split(")")[0].split(",")]
    best = list(res.pole)
    ratios = _moment_ratios(res.body)
    # the solution near the truth (the best or its mirror) and its distance
    near = min(_angle(best, truth), _angle(mirror, truth))
    return {"seed": seed, "truth_pole_deg": truth.tolist(), "period_h": p / 3600,
            "pole_deg": best, "mirror_pole_deg": mirror, "chi2": res.chi2,
            "mirror_chi2": res.alternatives[0][0],
            "best_to_truth_deg": _angle(best, truth),
            "best_to_mirror_of_truth_deg": _angle(best, mirror_truth),
            "nearest_solution_to_truth_deg": near,
            "period_rel_error": res.period / p - 1.0,
            "truth_ratios": list(map(float, case["ratios"])), "fitted_ratios": ratios,
            "ratio_rel_errors": [r / t - 1.0 for r, t in zip(ratios, case["ratios"])],
            "rms": res.rms, "dark_facet": res.dark_facet, "cpu_s": cpu,
            "n_points": sum(len(o) for o in case["observations"]),
            "pole_ok": bool(min(_angle(best, truth), _angle(best, mirror_truth)) < 3.0),
            "period_ok": bool(abs(res.period / p - 1.0) < 1e-6),
            "ratios_ok": bool(all(abs(r / t - 1.0) < 0.03
                                  for r, t in zip(ratios, case["ratios"])))}


def run_hertha(exe: Path | None, poles: int) -> dict:
    """(135) Hertha's 30 relative lightcurves (ADAM's example data, CC BY 4.0): attitude
    and convexinv on the same file from the same period, from convexinv's default start
    (220, 0) deg and from ADAM's pole; attitude's ``invert`` from its pole starts; all
    against ADAM's start (the published model's pole and period as ADAM's example uses
    them)."""
    out = {"attitude (one start)": run_attitude_single(HERTHA, HERTHA_PERIOD_H),
           "attitude (one start at ADAM's pole)": run_attitude_single(
               HERTHA, HERTHA_PERIOD_H, HERTHA_POLE),
           "attitude (invert)": run_attitude(poles, HERTHA, HERTHA_PERIOD_H)}
    if exe:
        out["convexinv"] = run_convexinv(exe, HERTHA, HERTHA_PERIOD_H)
        out["convexinv (start at ADAM's pole)"] = run_convexinv(exe, HERTHA, HERTHA_PERIOD_H,
                                                                HERTHA_POLE)
    for name, r in out.items():
        mirror = [(r["pole_deg"][0] + 180.0) % 360.0, r["pole_deg"][1]]
        r["to_reference_pole_deg"] = min(_angle(r["pole_deg"], HERTHA_POLE),
                                         _angle(mirror, HERTHA_POLE))
        r["period_rel_to_reference"] = r["period_h"] / HERTHA_PERIOD_H - 1.0
        print(f"Hertha {name:20s} pole ({r['pole_deg'][0]:.2f}, {r['pole_deg'][1]:.2f}) deg "
              f"({r['to_reference_pole_deg']:.2f} from ADAM's) P {r['period_h']:.7f} h  rms "
              f"{r['rms']:.4f}  CPU {r['cpu_s']:.1f} s", flush=True)
    if exe:
        a, c = out["attitude (invert)"], out["convexinv (start at ADAM's pole)"]
        out["agreement"] = {"pole_deg": _angle(a["pole_deg"], c["pole_deg"]),
                            "period_rel": a["period_h"] / c["period_h"] - 1.0,
                            "rms_rel": a["rms"] / c["rms"] - 1.0}
    out["reference"] = {"pole_deg": list(HERTHA_POLE), "period_h": HERTHA_PERIOD_H,
                        "source": "ADAM 135_oct.ini (github:matvii/ADAM 25810f7)"}
    return out


def run_synthetic_pa(cases=10, progress=None) -> dict:
    rows = []
    for seed in range(cases):
        r = run_pa_case(seed)
        rows.append(r)
        if progress:
            progress({"cases": rows})
        print(f"PA {seed}: pole {r['best_to_truth_deg']:.2f} deg from the truth, "
              f"{r['best_to_mirror_of_truth_deg']:.2f} from its mirror; dP/P "
              f"{r['period_rel_error']:.1e}; ratios {r['fitted_ratios'][0]:.3f} "
              f"{r['fitted_ratios'][1]:.3f} (truth {r['truth_ratios'][0]:.3f} "
              f"{r['truth_ratios'][1]:.3f}); CPU {r['cpu_s']:.0f} s", flush=True)
    return {"cases": rows,
            "pole_ok": sum(r["pole_ok"] for r in rows),
            "period_ok": sum(r["period_ok"] for r in rows),
            "ratios_ok": sum(r["ratios_ok"] for r in rows), "n": len(rows)}


TUMBLER_EPOCH = Time("2029-01-01", scale="tdb")
#: kind: (A/C, B/C, P_phi in h, P_psi / P_phi, mode).  Apophis (Pravec et al. 2014):
#: 0.61, 0.965, 27.38 h, 264.6 h; Toutatis (Hudson & Ostro 1995): moments 1 : 3.01 :
#: 3.19, P_phi 7.35 d, P_psi 5.41 d (unverified, /work/shared/validation).
TUMBLER_KINDS = {"apophis-like SAM": (0.61, 0.965, 27.38, 264.6 / 27.38, "SAM"),
                 "toutatis-like LAM": (1 / 3.19, 3.01 / 3.19, 7.35 * 24.0, 5.41 / 7.35,
                                       "LAM"),
                 "issue SAM": (0.55, 0.9, None, None, "SAM")}


def tumbler_geometry(t):
    """Sun and observer directions changing slowly (tests/inversion/test_tumbler.py uses it too):
    the Sun 0.8 deg/day along the ecliptic, the phase angle from 25 deg growing 0.6
    deg/day, the observer's latitude from 12 deg falling 0.5 deg/day."""
    day = t / 86400.0
    lon = np.radians(30.0 + 0.8 * day)
    alpha = np.radians(25.0 + 0.6 * day)
    lat = np.radians(12.0 - 0.5 * day)
    sun = np.stack([np.cos(lon), np.sin(lon), np.zeros_like(t)], axis=1)
    seen = np.stack([np.cos(lat) * np.cos(lon + alpha), np.cos(lat) * np.sin(lon + alpha),
                     np.sin(lat)], axis=1)
    return Geometry(sun=sun, observer=seen)


def tumbler_case(kind: str, seed: int, *, days=40.0, cadence=1800.0, noise=0.01) -> dict:
    """One synthetic tumbler: a lumpy convex shape near the kind's moment ratios, a state
    of the kind's periods (the issue's case: E/E0 1.027, P_phi 10 h), L and phases at
    random; one relative lightcurve a day."""
    rng = np.random.default_rng(seed)
    a, b, p_phi_h, ratio, regime = TUMBLER_KINDS[kind]
    semi = np.sqrt(np.array([b + 1.0 - a, a + 1.0 - b, a + b - 1.0]))
    shape, moments = gaussian_random_sphere(rng, semi, sigma=0.08, nu=3.0, degree=8)
    ra, rb = moments[0] / moments[2], moments[1] / moments[2]
    if ratio is None:
        er, p_phi = 1.027, 10.0 * 3600.0
    else:
        er, p_phi = float(tb.energy_for_period_ratio(ra, rb, ratio, regime)[0]), p_phi_h * 3600
    truth = np.array([rng.uniform(0.0, 2.0 * np.pi), np.arcsin(rng.uniform(-0.9, 0.9)), er,
                      ra, rb, p_phi, rng.uniform(0.0, 2.0 * np.pi),
                      rng.uniform(0.0, 2.0 * np.pi)])
    m, q, w, _ = tumbling_state(*truth, moment_c=moments[2])
    state = AttitudeState(TUMBLER_EPOCH, Rotation.from_quat(q[0]), w[0], frame="ECLIPJ2000")
    t = np.arange(0.0, days * 86400.0, cadence)
    eph = att.propagate(att.RigidBody.from_principal_moments(m[0]), state, t)
    geometry = tumbler_geometry(t)
    flux = np.asarray(att.lightcurve(eph, shape, geometry, law="ls-lambert").dataset["flux"])
    block = np.floor(t / 86400.0).astype(int)
    return {"observations": _relative_lightcurves(t, flux, geometry, block, noise, rng,
                                                  TUMBLER_EPOCH),
            "truth": truth, "regime": regime, "faces": len(shape.faces)}


def run_tumbler_case(kind: str, seed: int, *, rows=5, degree=3) -> dict:
    """Invert one synthetic tumbler from the data alone; the stages' CPU times."""
    case = tumbler_case(kind, seed)
    truth = case["truth"]
    model = ConvexModel(case["observations"], GaussianImage(rows, degree))
    timings = {}
    start = time.process_time()
    fits = tb.search_tumbler(model, timings=timings)
    cpu = time.process_time() - start
    best = fits[0]
    p = np.array([best.parameters[k] for k in tb.PARAMETERS])
    s = np.array([best.uncertainties[k] for k in tb.PARAMETERS])
    moments, _, w, _ = tumbling_state(*truth)
    d = diagnose_many(moments, w)
    true_periods = (float(d["precession"][0]), float(d["rotation"][0]))
    fitted_periods = (best.periods["precession"], best.periods["rotation"])
    period_err = [f / t - 1.0 for f, t in zip(fitted_periods, true_periods)]
    l_err = _angle(best.pole, np.degrees(truth[:2]))
    z = [(p[i] - truth[i]) / s[i] if s[i] > 0 else float("inf") for i in (2, 3, 4)]
    ok = (best.regime == case["regime"] and max(map(abs, period_err)) < 1e-4 and l_err < 5.0
          and max(map(abs, z)) < 3.0)
    return {"kind": kind, "seed": seed, "regime": best.regime, "truth_regime": case["regime"],
            "truth": truth.tolist(), "fitted": p.tolist(), "sigma": s.tolist(),
            "periods_h": [x / 3600 for x in fitted_periods],
            "true_periods_h": [x / 3600 for x in true_periods],
            "period_rel_errors": period_err, "L_error_deg": l_err,
            "z_energy_ratio_a_ratio_b": z, "shape_ratios": list(best.shape_ratios),
            "rms": best.rms, "n_points": model.n_points, "facets": len(model.image.normals),
            "cpu_s": cpu, "stage_cpu_s": timings, "ok": bool(ok)}


def run_synthetic_tumblers(cases=5, kinds=("apophis-like SAM", "toutatis-like LAM")) -> dict:
    out = {}
    for kind in kinds:
        rows = []
        for seed in range(cases):
            r = run_tumbler_case(kind, seed)
            rows.append(r)
            print(f"{kind} {seed}: {r['regime']} periods {r['periods_h'][0]:.5f} "
                  f"{r['periods_h'][1]:.4f} h (truth {r['true_periods_h'][0]:.5f} "
                  f"{r['true_periods_h'][1]:.4f}), L {r['L_error_deg']:.2f} deg, z "
                  f"{np.round(r['z_energy_ratio_a_ratio_b'], 1)}, ok {r['ok']}, CPU "
                  f"{r['cpu_s']:.0f} s {r['stage_cpu_s']}", flush=True)
        out[kind] = {"cases": rows, "ok": sum(r["ok"] for r in rows), "n": len(rows)}
    out[ISSUE_CASE] = run_issue_case()
    return out


ISSUE_CASE = "issue SAM (A/C 0.55, B/C 0.9, E/E0 1.027), 968 facets"


def run_issue_case() -> dict:
    """The issue's first paragraph (a SAM of A/C 0.55, B/C 0.9, E/E0 1.027, here P_phi
    10 h; 40 days at 30 min, 0.01 mag; 1920 points) from the data alone on a 968-facet
    Gaussian image (11 rows, degree 6): the timing case of the issue (2000 points, a
    1000-facet model, under 10 minutes), each stage's CPU time."""
    r = run_tumbler_case("issue SAM", 0, rows=11, degree=6)
    print(f"issue case: {r['regime']} periods {r['periods_h'][0]:.5f} {r['periods_h'][1]:.4f}"
          f" h (truth {r['true_periods_h'][0]:.5f} {r['true_periods_h'][1]:.4f}), L "
          f"{r['L_error_deg']:.2f} deg, ok {r['ok']}, CPU {r['cpu_s']:.0f} s "
          f"{r['stage_cpu_s']}", flush=True)
    return r


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--convexinv", type=Path, help="path of the built convexinv")
    parser.add_argument("--poles", type=int, default=6, help="attitude's pole starts")
    parser.add_argument("--synthetic-pa", action="store_true",
                        help="the synthetic principal-axis suite only")
    parser.add_argument("--synthetic-tumblers", action="store_true",
                        help="the synthetic tumbler suite only")
    parser.add_argument("--issue-case", action="store_true",
                        help="only the issue's SAM case (the timing case), from the data alone")
    parser.add_argument("--hertha", action="store_true",
                        help="(135) Hertha's lightcurves only (with --convexinv: both)")
    parser.add_argument("--cases", type=int, default=None,
                        help="cases per suite (default 10 PA, 5 per tumbler kind)")
    parser.add_argument("--json", type=Path, help="update these results (JSON)")
    args = parser.parse_args(argv)
    results = {}

    def save(part, value):
        """Update the JSON file with one part (also while a suite runs)."""
        if args.json:
            old = json.loads(args.json.read_text()) if args.json.exists() else {}
            old[part] = value
            tmp = args.json.with_suffix(".tmp")
            tmp.write_text(json.dumps(old, indent=2) + "\n")
            tmp.replace(args.json)

    if args.synthetic_pa:
        results["synthetic principal-axis"] = run_synthetic_pa(
            args.cases or 10, lambda part: save("synthetic principal-axis", part))
    if args.synthetic_tumblers:
        results["synthetic tumblers"] = run_synthetic_tumblers(args.cases or 5)
    if args.issue_case:
        results["synthetic tumblers: " + ISSUE_CASE] = run_issue_case()
    if args.hertha:
        results["hertha"] = run_hertha(args.convexinv, args.poles)
    if not results:
        results = {"attitude (one start)": run_attitude_single(),
                   "attitude (invert)": run_attitude(args.poles)}
        if args.convexinv:
            results["convexinv"] = run_convexinv(args.convexinv)
        for name, r in results.items():
            print(f"{name:20s} pole ({r['pole_deg'][0]:.2f}, {r['pole_deg'][1]:.2f}) deg  "
                  f"P {r['period_h']:.7f} h  rms {r['rms']:.4f}  CPU {r['cpu_s']:.1f} s")
    for part, value in results.items():
        save(part, value)


if __name__ == "__main__":
    main()

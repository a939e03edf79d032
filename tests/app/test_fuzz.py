"""Mutation fuzzing of the command line: the shipped scenarios (scenarios/*.toml), the
data files they name (CSV, OBJ, quaternion samples; the NEA lightcurve also as ALCDEF)
and an ephemeris (netCDF, CCSDS AEM), each copied into a temporary folder, shortened,
and broken in one way -- lines dropped, a line cut, a field replaced by garbage or NaN,
binary bytes inserted, the file emptied -- on a fixed seed, then given to every command
that reads it (``run``, ``check``, ``lightcurve``, ``fit``, ``section``; ``classify`` and
``convert`` for the ephemeris).

Whatever the input, the command must end the way the CLI promises: exit 0, 1, 2 or 3, at
most three lines on stderr (a warning counts two), no traceback, no "internal error", no
warning of another package leaking through, every key named once; and a broken *data*
file is bad input: exit 3 (a failed propagation) is a bug of its reader.

The commands run in-process (``attitude.app.cli.main``).  The default tier fuzzes the
torque-free scenarios (two mutations of each TOML, every mutation kind of each data
file) and runs ``fit`` only where the input is refused (a fit of a still-valid file takes
seconds); ``-m slow`` (about four minutes) adds the scenarios with torques
(``check``), a third mutation of each TOML, another seed, and ``fit`` on everything.
"""

from __future__ import annotations

import re
import shutil
import tomllib
import warnings
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from attitude.app.cli import main
from attitude.app.scenario import load_scenario
from attitude.foundations.errors import AttitudeWarning

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "scenarios"
#: Output steps kept per scenario copy (the duration is cut to this many steps); a
#: lightcurve needs more points than its Fourier series has terms.
STEPS, LIGHTCURVE_STEPS = 8, 160
#: The scenario commands and the table each needs.
COMMANDS = {"run": None, "check": "expect", "lightcurve": "photometry",
            "fit": "observations", "section": "section"}
MUTATIONS = ("drop_lines", "cut_line", "garbage", "nan", "binary", "empty")
#: Replacements for one field ("garbage"): text, a subnormal, an overflow, TOML syntax,
#: a non-ASCII letter, a hex literal.
GARBAGE = (b"x#!", b"1e-320", b"-0", b"1e999", b'"', b"[", b"\xce\xbb", b"0x1F")
#: A scenario made from a shipped one: the NEA lightcurve fit reading ALCDEF.
ALCDEF = "nea_lightcurve_alcdef.toml"
#: The ephemeris files (written once by ``run`` and ``convert``) and their commands.
EPHEMERIS = {"eph.nc": (["classify", "{file}"], ["convert", "{file}", "{out}.aem"]),
             "eph.aem": (["convert", "{file}", "{out}.nc"],)}


def _alcdef_of(csv_text: str) -> str:
    """The NEA lightcurve CSV (jd, mag, session) as ALCDEF, one block per session."""
    rows = [line.split(",") for line in csv_text.splitlines()[2:] if line.strip()]
    blocks = []
    for session in dict.fromkeys(r[2] for r in rows):
        data = "".join(f"DATA={jd}|{mag}|0.015\n" for jd, mag, s in rows if s == session)
        blocks.append(f"STARTMETADATA\nOBJECTNAME=SYNTHETIC NEA\nSESSIONDATE=night {session}"
                      f"\nDELIMITER=PIPE\nLTCAPP=NONE\nENDMETADATA\n{data}ENDDATA\n")
    return "".join(blocks)


def _source(name: str) -> str:
    if name == ALCDEF:
        return (SCENARIOS / "nea_lightcurve_fit.toml").read_text().replace(
            "data/nea_lightcurve.csv", "data/nea_lightcurve.alcdef")
    return (SCENARIOS / name).read_text()


@cache
def _shipped() -> dict[str, dict]:
    """Each scenario: its tables, the data files it names (relative), its step (s)."""
    out = {}
    for name in [p.name for p in sorted(SCENARIOS.glob("*.toml"))] + [ALCDEF]:
        text = _source(name)
        data = sorted(set(re.findall(r'"([\w./-]+\.(?:csv|obj|alcdef))"', text)))
        step = load_scenario(SCENARIOS / name).step if name != ALCDEF else 600.0
        out[name] = {"tables": set(tomllib.loads(text)), "data": data, "step": step}
    return out


def _copy(name: str, folder: Path) -> Path:
    """The scenario ``name`` and its data files in ``folder``, the run cut to
    :data:`STEPS` output steps (a spin-orbit section to one orbit)."""
    info = _shipped()[name]
    steps = LIGHTCURVE_STEPS if "photometry" in info["tables"] else STEPS
    text = re.sub(r'(?m)^duration\s*=\s*"[^"]*"', f'duration = "{steps * info["step"]!r} s"',
                  _source(name), count=1)
    text = re.sub(r"(?m)^n_orbits\s*=\s*\d+", "n_orbits = 1", text)
    target = folder / name
    target.write_text(text)
    for rel in info["data"]:
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        if rel.endswith(".alcdef"):
            (folder / rel).write_text(_alcdef_of((SCENARIOS / "data/nea_lightcurve.csv")
                                                 .read_text()))
        else:
            shutil.copyfile(SCENARIOS / rel, folder / rel)
    return target


def mutate(data: bytes, kind: str, rng: np.random.Generator) -> bytes:
    """``data`` broken in one way (``kind``, one of :data:`MUTATIONS`) drawn from ``rng``."""
    lines = data.split(b"\n")
    k = int(rng.integers(len(lines)))
    if kind == "drop_lines":
        drop = rng.choice(len(lines), size=min(len(lines), int(rng.integers(1, 4))),
                          replace=False).tolist()
        lines = [ln for i, ln in enumerate(lines) if i not in drop]
    elif kind == "cut_line":
        lines[k] = lines[k][:int(rng.integers(len(lines[k]) + 1))]
    elif kind in ("garbage", "nan"):
        fields = re.split(rb"([,|=\s]+)", lines[k])
        spots = [i for i, f in enumerate(fields) if f and not re.fullmatch(rb"[,|=\s]+", f)]
        if kind == "nan":                 # a number if the line has one
            spots = [i for i in spots if re.fullmatch(rb"[-+.\d][-+.\deE]*", fields[i])] \
                or spots
        if spots:
            fields[int(rng.choice(spots))] = (b"nan" if kind == "nan" else
                                              GARBAGE[int(rng.integers(len(GARBAGE)))])
        lines[k] = b"".join(fields)
    elif kind == "binary":
        at = int(rng.integers(len(data) + 1))
        noise = rng.integers(0, 256, size=int(rng.integers(1, 64)), dtype=np.uint8)
        return data[:at] + noise.tobytes() + data[at:]
    elif kind == "empty":
        return b""
    return b"\n".join(lines)


@dataclass(frozen=True)
class Case:
    scenario: str         # a scenario, or "ephemeris"
    target: str           # the file broken: the scenario itself or one of its data files
    kind: str
    seed: int

    def __str__(self):
        return f"{self.scenario}:{self.target}:{self.kind}:{self.seed}"


def cases(seed: int, *, per_toml: int, per_data: int, torques: bool) -> list[Case]:
    """``per_toml`` mutations of each scenario file and ``per_data`` of each data file
    (kinds taken in turn from :data:`MUTATIONS`, starting at a random one), the scenarios
    that ``check`` propagates with [[torques]] only if ``torques``; seeds from ``seed``."""
    rng = np.random.default_rng(seed)
    targets = []
    for name, info in _shipped().items():
        if torques or not {"torques", "expect"} <= info["tables"]:   # check: seconds
            targets += [(name, name, per_toml)] + [(name, d, per_data) for d in info["data"]]
    targets += [("ephemeris", file, per_data) for file in EPHEMERIS]
    out = []
    for scenario, target, n in targets:
        first = int(rng.integers(len(MUTATIONS)))
        out += [Case(scenario, target, MUTATIONS[(first + j) % len(MUTATIONS)],
                     int(rng.integers(2**31))) for j in range(n)]
    return out


def _invoke(argv: list[str], capsys) -> tuple[int, str, list]:
    capsys.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main(argv)
    return code, capsys.readouterr().err, caught


def _argvs(case: Case, folder: Path, ephemeris: Path, *, fit: bool):
    """The command lines of ``case`` (after its files are in ``folder``)."""
    if case.scenario == "ephemeris":
        for argv in EPHEMERIS[case.target]:
            yield [a.format(file=folder / case.target, out=folder / "out") for a in argv]
        return
    scenario = folder / case.scenario
    for command, needs in COMMANDS.items():
        if needs is not None and needs not in _shipped()[case.scenario]["tables"]:
            continue
        if command == "fit" and not fit:
            continue
        if "torques" in _shipped()[case.scenario]["tables"] and command == "run":
            continue                       # seconds each: ``check`` runs it
        argv = [command, str(scenario)]
        if command == "check":
            argv += ["--jobs", "1"]
        elif command == "fit":
            argv += ["-o", str(folder / "fitted.toml"), "--quiet"]
        else:
            argv += ["-o", str(folder / f"{command}.nc"), "--quiet"]
        if command == "section":
            argv += ["--orbits", "1"]
        yield argv


def run_case(case: Case, folder: Path, ephemeris: Path, capsys, *, fit: bool) -> list[str]:
    """Every command applicable to ``case`` on its mutated copy: the promises broken.
    ``fit`` false runs ``fit`` only if ``run`` refused the input."""
    if case.scenario == "ephemeris":
        shutil.copyfile(ephemeris.parent / case.target, folder / case.target)
    else:
        _copy(case.scenario, folder)
    path = folder / case.target
    path.write_bytes(mutate(path.read_bytes(), case.kind, np.random.default_rng(case.seed)))
    problems, refused = [], False
    for argv in list(_argvs(case, folder, ephemeris, fit=True)):
        if argv[0] == "fit" and not (fit or refused):
            continue
        code, err, caught = _invoke(argv, capsys)
        refused |= argv[0] == "run" and code == 2
        problems += broken_promises(f"{case} {argv[0]}", code, err, caught,
                                    data=case.target != case.scenario)
    return problems


def broken_promises(where: str, code, err: str, caught, *, data: bool) -> list[str]:
    """What the CLI promises on any input, checked on one command's outcome."""
    lines = err.strip().splitlines()
    leaked = [f"{w.category.__name__}: {w.message}" for w in caught
              if not issubclass(w.category, AttitudeWarning)]
    problems = []
    if code not in (0, 1, 2, 3):
        problems.append(f"exit {code}")
    if len(lines) + 2 * len(caught) > 3:        # a warning prints two lines
        problems.append(f"{len(lines)} lines on stderr and {len(caught)} warnings")
    if "Traceback" in err or "internal error" in err:
        problems.append("traceback or internal error")
    if leaked:
        problems.append(f"leaked warnings {leaked}")
    if re.search(r"(?:^|: )([\w.\[\]]+): \1: ", err, flags=re.MULTILINE):
        problems.append("a key named twice")
    if data and code == 3:
        problems.append("exit 3 for a broken data file (bad input is exit 2)")
    return [f"{where}: {p}: {err.strip()[:300]}" for p in problems]


@pytest.fixture(scope="module")
def ephemeris(tmp_path_factory):
    """eph.nc (the Dzhanibekov scenario over 8 s: 2.4 polhode periods, so ``classify``
    has something to classify) and eph.aem, its CCSDS AEM."""
    folder = tmp_path_factory.mktemp("ephemeris")
    scenario = folder / "dzhanibekov.toml"
    scenario.write_text(re.sub(r'(?m)^duration\s*=\s*"[^"]*"', 'duration = "8 s"',
                               (SCENARIOS / "dzhanibekov.toml").read_text()))
    assert main(["run", str(scenario), "-o", str(folder / "eph.nc"), "--quiet"]) == 0
    assert main(["convert", str(folder / "eph.nc"), str(folder / "eph.aem")]) == 0
    return folder / "eph.nc"


def _fuzz(cases_, tmp_path, ephemeris, capsys, *, fit):
    problems = []
    for k, case in enumerate(cases_):
        folder = tmp_path / str(k)
        folder.mkdir()
        problems += run_case(case, folder, ephemeris, capsys, fit=fit)
    assert not problems, "\n".join(problems)


def test_mutations_are_deterministic_and_break_the_file():
    data = (SCENARIOS / "data/tumbler_quaternions.csv").read_bytes()
    for kind in MUTATIONS:
        once, again = (mutate(data, kind, np.random.default_rng(7)) for _ in range(2))
        assert once == again and once != data, kind
    assert mutate(data, "empty", np.random.default_rng(7)) == b""


def test_fuzz_torque_free_scenarios_data_and_ephemeris(tmp_path, ephemeris, capsys):
    _fuzz(cases(26, per_toml=2, per_data=len(MUTATIONS), torques=False), tmp_path,
          ephemeris, capsys, fit=False)


@pytest.mark.slow
def test_fuzz_every_scenario_every_mutation(tmp_path, ephemeris, capsys):
    _fuzz(cases(2026, per_toml=3, per_data=len(MUTATIONS), torques=True),
          tmp_path, ephemeris, capsys, fit=True)

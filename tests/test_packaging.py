"""Packaging: the distribution name, the licence, and every install hint naming them.

The name ``attitude`` on the public package index belongs to an unrelated project, so the
distribution is ``attitude-dynamics`` (the import name and the command stay ``attitude``):
a hint such as ``pip install 'attitude[plot]'`` in an error message or a page would
install the other project.  The scan below finds such hints in the package, the tests,
the docs, the README, the benchmarks and the CI script.
"""

import re
import tomllib
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement  # a dependency of pytest

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
DISTRIBUTION = "attitude-dynamics"
OLD = "attitude"

#: An install hint naming the old distribution: its extras (``attitude[plot]``, quoted or
#: not, in ``pip install`` or in a requirement list) or ``pip install attitude`` alone or
#: with a version.  Not: ``attitude-dynamics[plot]``, ``pip install .``, ``import attitude``.
OLD_HINTS = [
    re.compile(r"(?<![\w./-])" + OLD + r"\["),
    re.compile(r"pip\s+install\s+(?:-\S+\s+)*[\"']?" + OLD + r"(?![\w\-./\[])"),
]
SCANNED = ("*.py", "*.md", "*.rst", "*.toml", "*.txt", "*.cfg", "*.yml", "*.yaml")


def _canonical(name: str) -> str:
    """Distribution names compare after PEP 503 normalisation."""
    return re.sub(r"[-_.]+", "-", name).lower()


def _old_hints(text: str) -> list[str]:
    return [m.group(0) for pattern in OLD_HINTS for m in pattern.finditer(text)]


def _files():
    folders = ("attitude", "tests", "docs", "benchmarks", "scenarios", ".ci")
    for folder in folders:
        for pattern in SCANNED:
            yield from (ROOT / folder).rglob(pattern)
    yield from (ROOT / ".ci").glob("*")
    yield ROOT / "README.md"
    yield ROOT / "pyproject.toml"


@pytest.mark.parametrize(("text", "found"), [
    ("pip install 'attitude[plot]'", True),
    ('pip install "attitude[dask]"', True),
    ("Optional: ``pip install attitude[spice]``.", True),
    ("python -m pip install attitude   # pin the version", True),
    ("python -m pip install -U attitude==0.1", True),
    ('dev = ["attitude[test]"]', True),
    ("pip install 'attitude-dynamics[plot]'", False),
    ("python -m pip install attitude-dynamics", False),
    ('python -m pip install ".[test]" && attitude run scenarios/apophis.toml', False),
    ("import attitude as att; attitude.ensemble[0]", False),
])
def test_the_scan_recognises_old_install_hints(text, found):
    assert bool(_old_hints(text)) is found


def test_no_install_hint_names_the_old_distribution():
    me = Path(__file__).resolve()
    bad = []
    for path in sorted(set(_files())):
        if not path.is_file() or path.resolve() == me or "_build" in path.parts:
            continue
        for lineno, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            bad += [f"{path.relative_to(ROOT)}:{lineno}: {hint}" for hint in _old_hints(line)]
    assert not bad, ("install hints naming the distribution 'attitude' (an unrelated "
                     f"project on the index); use '{DISTRIBUTION}':\n" + "\n".join(bad))


def test_pyproject_names_the_distribution_and_the_licence():
    project = PYPROJECT["project"]
    assert project["name"] == DISTRIBUTION
    assert _canonical(project["name"]) != _canonical(OLD)
    assert project["license"] == "BSD-3-Clause"                 # an SPDX expression
    assert project["license-files"] == ["LICENSE"]
    # PEP 639: no licence classifier next to an SPDX expression
    assert not any(c.startswith("License ::") for c in project.get("classifiers", []))
    # the package and the command keep the name attitude
    assert project["scripts"] == {"attitude": "attitude.app.cli:main"}
    assert PYPROJECT["tool"]["setuptools"]["packages"]["find"]["include"] == ["attitude*"]


def test_build_backend_understands_spdx_licences():
    """setuptools reads ``license = "<SPDX>"`` and ``license-files`` from version 77."""
    requires = PYPROJECT["build-system"]["requires"]
    setuptools = [r for r in requires if re.match(r"setuptools\b", r)]
    assert len(setuptools) == 1
    minimum = re.fullmatch(r"setuptools\s*>=\s*(\d+)(?:\.\d+)*", setuptools[0])
    assert minimum and int(minimum.group(1)) >= 77, setuptools[0]


def test_extras_refer_to_the_distribution_by_its_name():
    """A self-reference (``dev = ["attitude-dynamics[test]"]``) names this distribution,
    never the old one, and names extras that exist."""
    extras = PYPROJECT["project"]["optional-dependencies"]
    for extra, requirements in extras.items():
        for requirement in requirements:
            name = re.match(r"[A-Za-z0-9][A-Za-z0-9._-]*", requirement).group(0)
            assert _canonical(name) != _canonical(OLD), (extra, requirement)
            if _canonical(name) == DISTRIBUTION:
                wanted = re.search(r"\[([^\]]*)\]", requirement).group(1).split(",")
                assert {w.strip() for w in wanted} <= extras.keys(), requirement
    assert f"{DISTRIBUTION}[test]" in extras["dev"]


def test_licence_file_is_bsd_3_clause():
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License")
    assert re.search(r"Copyright \(c\) \d{4}, the attitude developers", text)
    assert "Neither the name of the copyright holder" in text        # the third clause


def test_installed_metadata():
    """In an environment that installed this checkout (``pip install .``, as CI does)."""
    try:
        dist = metadata.distribution(DISTRIBUTION)
    except metadata.PackageNotFoundError:
        pytest.skip(f"{DISTRIBUTION} is not installed here (an older install under the "
                    "name 'attitude', or run from the source tree)")
    assert dist.metadata["License-Expression"] == "BSD-3-Clause"
    assert "LICENSE" in (dist.metadata.get_all("License-File") or [])
    scripts = {ep.name: ep.value for ep in dist.entry_points if ep.group == "console_scripts"}
    assert scripts == {"attitude": "attitude.app.cli:main"}


@pytest.mark.parametrize(("platform", "machine", "python", "installed"), [
    ("linux", "x86_64", "3.11", True),
    ("linux", "aarch64", "3.14", True),
    ("linux", "x86_64", "3.15", False),     # no wheels yet: never build LLVM from source
    ("linux", "ppc64le", "3.12", False),    # no wheels
    ("linux", "armv7l", "3.12", False),
    ("win32", "AMD64", "3.12", True),
    ("win32", "ARM64", "3.12", True),
    ("win32", "ARM64", "3.11", False),      # Windows ARM64 wheels from Python 3.12
    ("darwin", "arm64", "3.13", True),
    ("darwin", "x86_64", "3.13", True),
    ("darwin", "arm64", "3.14", False),     # only beta wheels for macOS and Python 3.14
])
def test_numba_is_a_dependency_only_where_it_has_wheels(platform, machine, python, installed):
    """numba (the compiled kernels, optional at run time) is installed by default on the
    platforms and Pythons numba and llvmlite publish wheels for, nowhere else."""
    numba = [Requirement(r) for r in PYPROJECT["project"]["dependencies"]
             if Requirement(r).name == "numba"]
    assert len(numba) == 1 and numba[0].marker is not None
    env = {"sys_platform": platform, "platform_machine": machine, "python_version": python,
           "python_full_version": python + ".0", "platform_system": platform}
    assert numba[0].marker.evaluate(env) is installed

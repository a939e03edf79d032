"""``attitude animate`` and ``attitude view``: files written, bad input -> exit 2 with one
line naming the file."""

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from scipy.spatial.transform import Rotation  # noqa: E402

import attitude as att  # noqa: E402
from attitude.app.cli import main  # noqa: E402


@pytest.fixture(scope="module")
def ephemeris_file(tmp_path_factory):
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    path = tmp_path_factory.mktemp("eph") / "spin.nc"
    att.propagate(body, state, np.linspace(0.0, 300.0, 31)).to_netcdf(path)
    return path


def test_animate_writes_a_gif(ephemeris_file, tmp_path, capsys):
    from PIL import Image

    out = tmp_path / "spin.gif"
    assert main(["animate", str(ephemeris_file), "-o", str(out), "--fps", "3",
                 "--duration", "1", "--dpi", "20", "--no-poinsot"]) == 0
    with Image.open(out) as im:
        assert im.n_frames == 3
    captured = capsys.readouterr()
    assert captured.out.strip() == f"wrote {out}"
    assert captured.err.splitlines()[-1] == "frames 3/3 (100 %)"    # progress, not a tty


def test_view_writes_one_html_file(ephemeris_file, tmp_path, capsys):
    pytest.importorskip("plotly")
    out = tmp_path / "spin.html"
    assert main(["view", str(ephemeris_file), "-o", str(out), "--frames", "4",
                 "--quiet"]) == 0
    assert capsys.readouterr().out == ""
    text = out.read_text()
    assert "plotly" in text and '<script src="http' not in text     # plotly.js embedded
    assert [p.name for p in tmp_path.iterdir()] == ["spin.html"]


@pytest.mark.parametrize("args, message", [
    (["animate", "{missing}", "-o", "{tmp}/a.gif"], "no such file"),
    (["animate", "{eph}", "-o", "{tmp}/a.avi"], "unknown movie suffix"),
    (["view", "{eph}", "-o", "{tmp}/a.png"], "unknown suffix for the view"),
    (["view", "{missing}", "-o", "{tmp}/a.html"], "no such file"),
])
def test_bad_input_exits_2_with_one_line(ephemeris_file, tmp_path, capsys, args, message):
    missing = tmp_path / "missing.nc"
    argv = [a.format(missing=missing, tmp=tmp_path, eph=ephemeris_file) for a in args]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("attitude: error: ") and message in err[0]
    assert not [p for p in tmp_path.iterdir() if p.name != "missing.nc"]

"""The HTML view in a real browser: Debian's chromium driven by playwright (its own browser
download is not reachable, so the system browser's executable is given).  The page loads
with no console error and no network request, the scene draws and changes with the time
slider, and play advances the time.  Without chromium or playwright these tests skip
with the reason (.ci/run installs chromium with apt-get when it runs as root)."""

import shutil
import time

import numpy as np
import pytest

pytest.importorskip("plotly")
sync_api = pytest.importorskip("playwright.sync_api", reason="pip install playwright")

from scipy.spatial.transform import Rotation  # noqa: E402

import attitude as att  # noqa: E402

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.fixture(scope="module")
def browser():
    if CHROMIUM is None:
        pytest.skip("no system chromium (apt-get install chromium)")
    with sync_api.sync_playwright() as p:
        try:
            b = p.chromium.launch(executable_path=CHROMIUM, args=[
                "--no-sandbox"])
        except Exception as exc:  # noqa: BLE001 - any launch failure: skip with the reason
            pytest.skip(f"chromium does not start: {str(exc).splitlines()[0]}")
        yield b
        b.close()


@pytest.fixture(scope="module")
def page_file(tmp_path_factory):
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    state = att.AttitudeState("2029-04-13", Rotation.from_euler(
        "ZXZ", [250.0, 165.0, 10.0], degrees=True), [0.02, 0.0, 0.1])
    eph = att.propagate(body, state, np.linspace(0.0, 600.0, 301))
    return att.Ephemeris.view(eph, tmp_path_factory.mktemp("view") / "view.html",
                              max_frames=40).path


@pytest.fixture(scope="module")
def binary_page(tmp_path_factory):
    ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(5e11, 400.0))
    egg = att.RigidBody.from_mass_properties(
        att.MassProperties.solid_ellipsoid(4.3e9, [103.16, 79.35, 66.13]))
    system = att.BinarySystem(ball, egg)
    n = np.sqrt(system.mu / 1190.0**3)
    state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
                            Rotation.identity(), [0, 0, 7.7e-4],
                            Rotation.from_euler("z", 15.0, degrees=True), [0, 0, n])
    eph = att.propagate(system, state, np.linspace(0.0, 43200.0, 241), method="integrator",
                        rtol=1e-9)
    return eph.view(tmp_path_factory.mktemp("binary") / "binary.html", max_frames=40).path


def _open(browser, path):
    page = browser.new_page(viewport={"width": 1200, "height": 900})
    errors, requests = [], []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("request", lambda r: requests.append(r.url))
    page.goto(path.as_uri())
    page.wait_for_function("() => { const gd = document.querySelector('.js-plotly-plot');"
                           " return gd && gd._fullLayout && gd._fullLayout.sliders; }")
    page.wait_for_timeout(500)
    return page, errors, requests


def _scene(page):
    from io import BytesIO

    from PIL import Image

    box = page.locator(".js-plotly-plot .gl-container").first.bounding_box() \
        or page.locator(".js-plotly-plot").first.bounding_box()
    shot = page.screenshot(clip={"x": box["x"], "y": box["y"], "width": 560,
                                 "height": 420})
    return np.asarray(Image.open(BytesIO(shot)).convert("RGB"), dtype=int)


def _goto_step(page, k):
    page.evaluate("""k => { const gd = document.querySelector('.js-plotly-plot');
        const s = gd.layout.sliders[0].steps[k];
        return Plotly.animate(gd, s.args[0], s.args[1]); }""", k)
    page.wait_for_timeout(400)


def test_page_loads_offline_without_errors_and_draws(browser, page_file):
    page, errors, requests = _open(browser, page_file)
    try:
        assert errors == []
        assert requests and all(u.startswith(("file:", "data:", "blob:")) for u in requests), \
            requests
        first = _scene(page)
        # drawn: the scene holds many colours, not a blank or uniform picture
        assert len(np.unique(first.reshape(-1, 3), axis=0)) > 50
        _goto_step(page, 25)
        later = _scene(page)
        changed = np.mean(np.any(first != later, axis=-1))
        assert changed > 0.002, changed            # the body turned between the steps
        assert errors == []
    finally:
        page.close()


def test_binary_page_loads_offline_and_the_secondary_moves(browser, binary_page):
    page, errors, requests = _open(browser, binary_page)
    try:
        assert errors == []
        assert all(u.startswith(("file:", "data:", "blob:")) for u in requests), requests
        first = _scene(page)
        assert len(np.unique(first.reshape(-1, 3), axis=0)) > 50
        _goto_step(page, 20)                # half an orbit later
        later = _scene(page)
        assert np.mean(np.any(first != later, axis=-1)) > 0.002
        assert errors == []
    finally:
        page.close()


def test_play_advances_the_time(browser, page_file, capsys):
    page, errors, _ = _open(browser, page_file)
    try:
        page.evaluate("""() => { const gd = document.querySelector('.js-plotly-plot');
            window.framesSeen = []; gd.on('plotly_animatingframe',
                e => window.framesSeen.push([performance.now(), e.name])); }""")
        cursor0 = page.evaluate("""() => { const gd = document.querySelector('.js-plotly-plot');
            const c = gd.data.find(d => d.name === 'now'); return c.x[0]; }""")
        page.get_by_text("play", exact=True).click()
        start = time.monotonic()
        page.wait_for_timeout(3000)
        seen = page.evaluate("() => window.framesSeen")
        elapsed = time.monotonic() - start
        cursor1 = page.evaluate("""() => { const gd = document.querySelector('.js-plotly-plot');
            const c = gd.data.find(d => d.name === 'now'); return c.x[0]; }""")
        assert len(seen) >= 2 and cursor1 > cursor0
        assert errors == []
        with capsys.disabled():
            print(f"\nbrowser: {len(seen)} frames played in {elapsed:.1f} s "
                  f"({len(seen) / elapsed:.1f} frames/s)")
    finally:
        page.close()

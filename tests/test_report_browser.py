"""The report pages in a real browser: headless Chromium loads them, every figure renders, and
no script error, console error or failed resource load is reported.

Skipped when no Chromium is installed (CI installs Debian's ``chromium`` package, see
``docs/report.md``). The probe: a copy of the page with a small script injected first in
<head> (it records errors: window ``error`` events in the capture phase, which include failed
image or resource loads, unhandled rejections and ``console.error`` calls) and last in <body>
(on ``load`` it writes, into attributes of <body>, how many images decoded with
``naturalWidth > 0`` and the errors seen); ``--dump-dom`` prints the DOM after the load, and
the test reads the attributes back. A screenshot checks that the page paints.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import struct
import subprocess
from pathlib import Path

import pytest

import rockbench as rb

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parents[1]
_CANDIDATES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable",
               "chrome")


def _chromium() -> str | None:
    env = os.environ.get("ROCKBENCH_CHROMIUM")
    if env:
        return env
    for name in _CANDIDATES:
        path = shutil.which(name)
        if path:
            return path
    return None


CHROMIUM = _chromium()
if CHROMIUM is None:
    pytest.skip("no headless Chromium installed (apt-get install chromium)",
                allow_module_level=True)

_HEAD_PROBE = """<script>
window.__rbErrors = [];
window.addEventListener('error', function (e) {
  var t = e.target;
  if (t && t !== window && (t.src || t.href)) {
    window.__rbErrors.push('resource failed: ' + String(t.src || t.href).slice(0, 60));
  } else {
    window.__rbErrors.push('error: ' + (e.message || 'unknown'));
  }
}, true);
window.addEventListener('unhandledrejection', function (e) {
  window.__rbErrors.push('rejection: ' + String(e.reason));
});
(function () {
  var orig = console.error;
  console.error = function () {
    window.__rbErrors.push('console.error: ' + Array.prototype.join.call(arguments, ' '));
    return orig.apply(console, arguments);
  };
})();
</script>"""

_BODY_PROBE = """<script>
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var ok = imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length;
  document.body.setAttribute('data-rb-images', ok + '/' + imgs.length);
  document.body.setAttribute('data-rb-errors', JSON.stringify(window.__rbErrors));
  var dec = document.getElementById('decision-section');
  document.body.setAttribute('data-rb-dectop',
                             dec ? String(dec.getBoundingClientRect().top) : '-1');
  document.body.setAttribute('data-rb-dectext',
                             dec ? dec.innerText.slice(0, 4000).replace(/"/g, "'") : '');
  var dtab = document.getElementById('decision-table');
  document.body.setAttribute('data-rb-decbottom',
                             dtab ? String(dtab.getBoundingClientRect().bottom) : '-1');
  document.body.setAttribute('data-rb-viewport', String(window.innerHeight));
  // every collapsed section opened, then: the smallest figure text as shown, and tables wider
  // than the page (none may be: a table that needs a scroll bar is not read)
  document.querySelectorAll('details').forEach(function (d) { d.open = true; });
  var minpx = 1e9, small = [];
  imgs.forEach(function (i) {
    var n = parseFloat(i.getAttribute('data-text-px'));
    if (isNaN(n) || !(i.naturalWidth > 0)) return;
    var s = n * i.getBoundingClientRect().width / i.naturalWidth;
    if (s < minpx) minpx = s;
    if (s < 10.95) small.push(((i.closest('figure') || {}).id || 'figure') + ' ' + s.toFixed(1));
  });
  document.body.setAttribute('data-rb-textpx', String(minpx));
  document.body.setAttribute('data-rb-small', JSON.stringify(small).replace(/"/g, "'"));
  var right = document.body.getBoundingClientRect().right, over = [];
  document.querySelectorAll('table').forEach(function (t) {
    if (t.getBoundingClientRect().right > right + 1)
      over.push(((t.closest('section') || {}).id || 'page') + '/' + (t.id || 'table'));
  });
  document.body.setAttribute('data-rb-overflow', JSON.stringify(over).replace(/"/g, "'"));
  document.body.setAttribute('data-rb-loaded', 'yes');
});
</script>"""

_BASE_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
               "--no-first-run", "--disable-background-networking",
               "--disable-component-update", "--disable-sync", "--disable-extensions",
               "--disable-dev-shm-usage", "--hide-scrollbars", "--mute-audio"]


def _run_chromium(tmp: Path, *args: str, timeout: float = 90.0) -> subprocess.CompletedProcess:
    cmd = [CHROMIUM, *_BASE_FLAGS, f"--user-data-dir={tmp / 'profile'}",
           "--enable-logging=stderr", "--v=0", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


#: The browser windows the pages are checked in: a small laptop's and a desktop's.
VIEWPORTS = ((1366, 657), (1920, 1080))


def _probe(page: Path, tmp: Path, size: tuple[int, int] = VIEWPORTS[0]) -> tuple[dict, str]:
    """Load a probed copy of ``page`` in a window of ``size`` (width, height) px; return the
    attributes written on <body> and stderr."""
    html = page.read_text(encoding="utf-8")
    html = html.replace("<head>", "<head>\n" + _HEAD_PROBE, 1)
    html = html.replace("</body>", _BODY_PROBE + "\n</body>", 1)
    # beside the page (its figures are relative links), named per window and process: the
    # two windows' tests run at once under xdist and must not remove each other's probe
    probe = page.parent / f"_browser_probe-{size[0]}x{size[1]}-{os.getpid()}.html"
    probe.write_text(html, encoding="utf-8")
    try:
        res = _run_chromium(tmp, "--virtual-time-budget=10000",
                            f"--window-size={size[0]},{size[1]}", "--dump-dom", probe.as_uri())
    finally:
        probe.unlink(missing_ok=True)
    assert res.returncode == 0, res.stderr[-2000:]
    body = re.search(r"<body\b([^>]*)>", res.stdout)
    assert body, "no <body> in the dumped DOM"
    attrs = dict(re.findall(r'(data-rb-[a-z]+)="([^"]*)"', body.group(1)))
    return attrs, res.stderr


def _check_page(page: Path, tmp: Path, size: tuple[int, int] = VIEWPORTS[0]) -> dict:
    n_img = len(re.findall(r"<img\b", page.read_text(encoding="utf-8")))
    assert n_img > 0
    attrs, stderr = _probe(page, tmp, size)
    assert attrs.get("data-rb-loaded") == "yes", "the load event never fired"
    assert attrs["data-rb-images"] == f"{n_img}/{n_img}", attrs["data-rb-images"]
    errors = json.loads(attrs["data-rb-errors"].replace("&quot;", '"'))
    assert errors == [], errors
    # legible at 100 % zoom: every figure's text at least 11 px as shown, and no table wider
    # than the page
    assert float(attrs["data-rb-textpx"]) >= 10.95, attrs["data-rb-small"]
    crowded = re.findall(r'id="fig-([^"]+)"><img [^>]*data-overlaps="([1-9]\d*)"',
                         page.read_text(encoding="utf-8"))
    assert crowded == [], f"figures with overlapping labels: {crowded}"
    assert attrs["data-rb-overflow"] == "[]", attrs["data-rb-overflow"]
    # Chromium's own log of the page: no uncaught error, no failed load, no console error
    for line in stderr.splitlines():
        assert "Uncaught" not in line, line
        assert "net::ERR_" not in line, line
        assert not re.search(r"CONSOLE\(\d+\).*error", line, re.IGNORECASE), line
    shot = tmp / f"page-{size[0]}x{size[1]}.png"
    res = _run_chromium(tmp, f"--screenshot={shot}", f"--window-size={size[0]},{size[1]}",
                        page.as_uri())
    assert res.returncode == 0 and shot.is_file(), res.stderr[-2000:]
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    w, h = struct.unpack(">II", data[16:24])
    assert (w, h) == size
    assert len(data) > 20_000            # a blank page compresses to a few kB
    return attrs


@pytest.fixture(scope="module")
def case_page(tmp_path_factory):
    from rockbench.comparison import compare
    from rockbench.report import write_case_report

    engines = [e for e in ("pymunk",) if e in rb.available_backends()]
    scene = rb.load_scene("paper-asymmetric")
    pulse = rb.RickerPulse.dimensionless(A=3.0, W=4.0, structure=scene.structure)
    c = compare(scene, pulse, engines=engines, duration=8.0)
    return write_case_report(c, tmp_path_factory.mktemp("case"), histories=False)


@pytest.mark.parametrize("size", VIEWPORTS, ids=lambda s: f"{s[0]}x{s[1]}")
def test_case_page_in_chromium(case_page, tmp_path, size):
    _check_page(case_page, tmp_path, size)


def test_a_broken_image_is_caught(case_page, tmp_path):
    """The probe is not blind: a page with an undecodable image fails the image count."""
    bad = case_page.parent / "broken.html"
    html = case_page.read_text(encoding="utf-8")
    bad.write_text(html.replace("data:image/png;base64,", "data:image/png;base64,AAAA", 1),
                   encoding="utf-8")
    attrs, _ = _probe(bad, tmp_path)
    n = html.count("<img")
    assert attrs["data-rb-images"] == f"{n - 1}/{n}"
    assert "resource failed" in attrs["data-rb-errors"]


@pytest.mark.parametrize("size", VIEWPORTS, ids=lambda s: f"{s[0]}x{s[1]}")
def test_campaign_page_in_chromium(tmp_path, size):
    """The campaign page: ``$ROCKBENCH_REPORT`` (CI sets it after ``make report``; it must
    exist then), else ``reports/index.html`` when it exists."""
    given = os.environ.get("ROCKBENCH_REPORT") or os.environ.get("ROCKBENCH_REPORT_PAGE")
    page = Path(given) if given else ROOT / "reports" / "index.html"
    if not page.is_absolute():
        page = (Path.cwd() / page).resolve()
    if not page.is_file():
        assert not given, f"ROCKBENCH_REPORT={given}: no such page"
        pytest.skip(f"{page} does not exist (run `make report`)")
    attrs = _check_page(page, tmp_path, size)
    # the decision is on the first screen: every engine's row of its table without scrolling,
    # and the sentence of each tolerance right under it
    assert 0 <= float(attrs["data-rb-dectop"]), attrs["data-rb-dectop"]
    assert 0 < float(attrs["data-rb-decbottom"]) <= float(attrs["data-rb-viewport"]), attrs
    assert "Within 2 %" in attrs["data-rb-dectext"], attrs["data-rb-dectext"]

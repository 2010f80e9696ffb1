"""Render the traceability report of the shipped traces in headless Chromium: check it opens
without console errors, and screenshot the matrix and one violation's timeline.

    python bench/screenshot_report.py [--out /tmp/fretc-report-shots] \
        [--violation v-r2-sif_disabled]

Steps:

1. ``fretc report -r requirements/ traces/ -o OUT/report --annotate OUT/annotated`` (runs the
   audit; exit status 1 is expected: the shipped traces hold violations);
2. ``chromium --headless --dump-dom`` of ``report.html`` with ``--enable-logging=stderr``:
   the DOM must parse and no ``CONSOLE`` line may appear (the report has no script; a
   console line would be a resource or parse error);
3. measures where the matrix and the violation section lie (a throw-away copy of the page with
   a measuring script, ``OUT/report/measure.html``; the report itself stays script-free), then
   one full-page screenshot of ``report.html`` at 1400 px width, cropped into
   ``OUT/matrix.png`` and ``OUT/violation.png`` (Pillow; without it the full page is kept).

Chromium: ``apt-get install -y chromium`` (Debian, /usr/bin/chromium); runs as root with
``--no-sandbox``. Exits 0 when all went well, 1 on a console error or an unparsable DOM, 2 when
chromium is missing.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                  "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync"]

MEASURE = """<script>//<![CDATA[
window.addEventListener('load', function () {
  function box(id) { var e = document.getElementById(id); if (!e) return null;
    var r = e.getBoundingClientRect();
    return [Math.round(r.left + window.scrollX), Math.round(r.top + window.scrollY),
            Math.round(r.width), Math.round(r.height)]; }
  var W = document.documentElement.clientWidth, wide = [];
  document.querySelectorAll('body *').forEach(function (e) {
    if (e.getBoundingClientRect().right > W + 1 && wide.length < 10) wide.push(e.tagName); });
  var out = {height: document.documentElement.scrollHeight, width: W,
             matrix: box('matrix'), violation: box(%(target)s), too_wide: wide};
  var p = document.createElement('pre'); p.id = 'fretc-measure';
  p.textContent = JSON.stringify(out); document.body.appendChild(p); });
//]]></script>"""


def chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def run_chromium(args: list, timeout: float = 120) -> subprocess.CompletedProcess:
    with tempfile.TemporaryDirectory() as profile:
        return subprocess.run([chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args],
                              capture_output=True, text=True, timeout=timeout)


def dump_dom(html: Path, width: int = 1400, height: int = 2000) -> tuple[str, list[str]]:
    """(the DOM Chromium built, the CONSOLE lines it logged)."""
    res = run_chromium(["--enable-logging=stderr", "--v=0", f"--window-size={width},{height}",
                        "--dump-dom", html.as_uri()])
    console = [l for l in res.stderr.splitlines() if ":CONSOLE" in l]
    return res.stdout, console


def screenshot(html: Path, png: Path, width: int = 1400, height: int = 2000) -> None:
    run_chromium([f"--screenshot={png}", f"--window-size={width},{height}", html.as_uri()])
    if not png.exists():
        raise RuntimeError(f"chromium wrote no screenshot of {html}")


def measure(html: Path, target: str) -> dict:
    page = html.read_text(encoding="utf-8")
    copy = html.with_name("measure.html")
    copy.write_text(page.replace("</body>", MEASURE % {"target": json.dumps(target)}
                                 + "</body>"), encoding="utf-8")
    try:
        dom, _ = dump_dom(copy)
    finally:
        copy.unlink()
    m = re.search(r'<pre id="fretc-measure">(.*?)</pre>', dom, re.S)
    if not m:
        raise RuntimeError("could not measure the page")
    return json.loads(m.group(1).replace("&quot;", '"'))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(Path(tempfile.gettempdir()) / "fretc-report-shots"))
    ap.add_argument("--violation", default="v-r2-sif_disabled",
                    help="id of the violation section to screenshot")
    args = ap.parse_args(argv)
    if chromium() is None:
        print("chromium not found (apt-get install -y chromium)", file=sys.stderr)
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    report = out / "report"
    cmd = [sys.executable, "-m", "fretc", "report", "-r", "requirements/", "traces/",
           "-o", str(report), "--annotate", str(out / "annotated")]
    print("$", " ".join(cmd))
    res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    print(res.stderr.strip())
    if res.returncode not in (0, 1):
        return res.returncode
    html = report / "report.html"

    dom, console = dump_dom(html)
    import xml.etree.ElementTree as ET
    ET.fromstring(html.read_text(encoding="utf-8"))   # the page is well-formed XHTML
    ok = "id=\"matrix\"" in dom and not console
    print(f"DOM {len(dom)} chars, {len(console)} console lines" + "".join(
        f"\n  {c}" for c in console))

    box = measure(html, args.violation)
    print(f"page {box['width']}x{box['height']} px; matrix at {box['matrix']}; "
          f"{args.violation} at {box['violation']}; wider than the window: {box['too_wide']}")
    full = out / "full.png"
    screenshot(html, full, 1400, min(box["height"] + 20, 30000))
    try:
        from PIL import Image
    except ImportError:  # pragma: no cover
        print(f"wrote {full} (no Pillow to crop)")
        return 0 if ok else 1
    im = Image.open(full)
    for name, b in (("matrix", box["matrix"]), ("violation", box["violation"])):
        if b is None:
            print(f"no section for {name}")
            ok = False
            continue
        x, y, w, h = b
        im.crop((0, max(0, y - 80 if name == "matrix" else y - 10), 1400,
                 min(im.height, y + h + 10))).save(out / f"{name}.png")
        print(f"wrote {out / f'{name}.png'}")
    return 0 if ok and not box["too_wide"] else 1


if __name__ == "__main__":
    sys.exit(main())

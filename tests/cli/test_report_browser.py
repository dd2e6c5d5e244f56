"""The report in a real browser (#18): headless Chromium opens a report.html written by rotor37_rom.viz.html from real
PNG charts and must find the summary table first, the flagged runs, and every figure loaded at its own size.

Chromium is the Debian package `chromium`, which `make test` installs when apt can; where it cannot be found the
browser tests are skipped, saying so. Each figure is checked against the PNG file itself: the browser's naturalWidth
and naturalHeight must be the width and height in the file's IHDR header (a figure that fails to load has 0)."""
import json
import re
import shutil
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest

from rotor37_rom.viz.html import Section, Table, write_report

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")

# appended to a copy of the page: what the browser loaded, written into the DOM that --dump-dom prints
_PROBE = """<script>
window.addEventListener('load', () => {
  const tables = Array.from(document.querySelectorAll('table'));
  const summary = document.getElementById('summary');
  const report = {
    images: Array.from(document.images).map(i => ({src: i.getAttribute('src'), complete: i.complete,
                                                   width: i.naturalWidth, height: i.naturalHeight})),
    first_table_id: tables.length ? tables[0].id : null,
    summary_rows: summary ? Array.from(summary.rows).map(r => Array.from(r.cells).map(c => c.textContent)) : null,
    flags: Array.from(document.querySelectorAll('#flags li')).map(li => li.textContent),
  };
  const pre = document.createElement('pre');
  pre.id = 'probe';
  pre.textContent = JSON.stringify(report);
  document.body.appendChild(pre);
});
</script>"""


def png_size(path: Path) -> tuple[int, int]:
    """(width, height) from a PNG's IHDR chunk."""
    head = Path(path).read_bytes()[:24]
    assert head[:8] == b"\x89PNG\r\n\x1a\n", path
    return struct.unpack(">II", head[16:24])


def open_in_chromium(report: Path) -> dict:
    """Load ``report`` in headless Chromium (from a copy with the probe script, in the same folder so relative paths
    hold) and return what the page loaded: images, the first table's id, the summary rows, the flags."""
    if CHROMIUM is None:
        pytest.skip("chromium not found: `make test` installs the Debian package chromium with apt; on a machine "
                    "where apt cannot, the browser test does not run")
    probe = report.with_name("browser_probe.html")
    probe.write_text(report.read_text(encoding="utf-8").replace("</body>", _PROBE + "</body>"), encoding="utf-8")
    try:
        run = subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                              "--allow-file-access-from-files", "--virtual-time-budget=10000", "--dump-dom",
                              probe.resolve().as_uri()], capture_output=True, text=True, timeout=120)
    finally:
        probe.unlink()
    found = re.search(r'<pre id="probe">(.*?)</pre>', run.stdout, re.S)
    assert found, f"chromium printed no probe (exit {run.returncode}): {run.stderr[-1500:]}"
    import html

    return json.loads(html.unescape(found.group(1)))


def check_figures_load(report: Path, page: dict) -> None:
    """Every <img> of the page loaded, at the size of its PNG file."""
    assert page["images"], "the report has no figure"
    for image in page["images"]:
        width, height = png_size(report.parent / image["src"])
        assert image["complete"] and (image["width"], image["height"]) == (width, height), image


def test_report_opens_in_chromium(tmp_path):
    """A report with charts inside its folder and one outside it (copied to figures/), a summary table, a flagged
    run, and a missing figure (listed in words, never an image that fails to load). Control: a corrupt PNG, which
    the browser must report as not loaded (size 0), so that the check would see a figure that does not load."""
    from rotor37_rom.viz.charts import plot_nfrc, plot_time_history

    out = tmp_path / "report"
    speeds = np.linspace(1200.0, 1600.0, 11)
    inside = plot_nfrc({"no GNL": (speeds, 1e-3 * np.exp(-((speeds - 1440) / 60) ** 2), "--"),
                        "GNL": (speeds, 1e-3 * np.exp(-((speeds - 1370) / 60) ** 2), "-")},
                       out / "contact_map" / "nfrc.png", 1354.0, {"zero IC, no GNL": 1446.0})
    t = np.linspace(0.0, 0.02, 400)
    outside = plot_time_history(t, {"LE": 1e-4 * np.sin(5400 * t)}, tmp_path / "elsewhere" / "history.png", "LE")
    summary = Table("Summary: this work next to the paper", ["quantity", "this work", "paper", "conditions"],
                    [["clamped 1B (rad/s)", "5414 (+2.7 %)", "5272", "ci mesh"],
                     ["max von Mises at t_max, GNL", "no stress: the run at 1600 rad/s is unbounded", "below sigma_Y",
                      "single blade"]], html_id="summary")
    flagged = ["GNL: the run at 1600 rad/s grew past the limit (a tip DOF beyond 20 mm)"]
    sections = [Section("Maps", ["text"], [Table("numbers", ["a", "b"], [[1.0, float("nan")]])],
                        [(inside, "NFRC"), (outside, "time history"), (tmp_path / "absent.png", "never drawn")])]
    path = write_report(out / "report.html", "test report", sections, {"preset": "ci"}, summary=summary,
                        flags=flagged)
    assert "missing figure" in path.read_text() and (out / "figures").is_dir()
    page = open_in_chromium(path)
    check_figures_load(path, page)
    assert [Path(i["src"]).name for i in page["images"]] == ["nfrc.png", next((out / "figures").iterdir()).name]
    corrupt = out / "corrupt.png"
    corrupt.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(64))
    sections[0].figures.append((corrupt, "corrupt"))
    control = open_in_chromium(write_report(out / "control.html", "control", sections))
    assert [(Path(i["src"]).name, i["width"]) for i in control["images"]][-1] == ("corrupt.png", 0)
    assert page["first_table_id"] == "summary"
    assert page["summary_rows"] == [list(summary.header)] + [list(r) for r in summary.rows]
    assert page["flags"] == flagged

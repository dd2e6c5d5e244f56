"""The report demo at the ci preset (inside make test): HTML with figures and numbers, stress maxima, bad input."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_report_builds_at_ci(tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    cmd = [sys.executable, str(ROOT / "demos" / "report.py"), "--preset", "ci", "--revolutions", "2",
           "--out", str(tmp_path / "report"), "--results", str(tmp_path)]
    run = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-3000:]
    html = (tmp_path / "report" / "report.html").read_text()
    for needle in ("Clamped eigenfrequencies", "5272", "Peak instant and stress", "Run parameters",
                   "stress_blade_gnl.png", "stress_disk_linear.png", "sigma_Y"):
        assert needle in html, needle
    assert "missing figure: " + str(tmp_path / "report") not in html
    summary = json.loads((tmp_path / "report" / "stress_summary.json").read_text())
    for label in ("no GNL", "GNL"):
        s = summary[label]
        assert np.isfinite(s["vm_max"]) and s["vm_max"] > 1e6                   # Pa: a loaded blade
        assert s["vm_max_tip_band"] >= 0 and s["vm_max_at_contact_nodes"] > 0
        assert 0 < s["t_max"] and abs(s["u_le"]) < 2e-3
        assert s["u_le"] <= 0.5e-3 + 1e-12                                       # never through the casing
    for name in ("stress_blade_gnl", "stress_disk_gnl", "stress_blade_linear", "stress_disk_linear"):
        info = json.loads((tmp_path / "report" / f"{name}.png.json").read_text())
        assert info["scalar_range"][1] > info["scalar_range"][0] >= 0
    for name in ("displacement_tmax_gnl.xdmf", "von_mises_tmax_gnl.xdmf"):
        assert (tmp_path / "report" / name).is_file()


def test_report_bad_input(tmp_path):
    run = subprocess.run([sys.executable, str(ROOT / "demos" / "report.py"), "--preset", "ci", "--speed", "-5",
                          "--out", str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and "--speed" in run.stderr and "Traceback" not in run.stderr


def test_stress_before_simulation(ci_blade, ci_rom):
    from rotor37_rom.analysis import stress_at_peak

    with pytest.raises(ValueError, match="run the contact simulation first"):
        stress_at_peak(ci_blade, ci_rom, None, None, nonlinear=True)

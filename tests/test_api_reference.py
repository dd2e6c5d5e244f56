"""The API reference (``make docs``: pdoc over rotor37_rom, forms and geometry) builds, pdoc's warnings being errors
(an annotation it cannot read is a UserWarning), and documents the public names: every subpackage's page exists and
every name of a module's ``__all__`` appears on its page."""
import importlib
import os
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    pytest.importorskip("pdoc", reason="pdoc is not installed (make test installs it)")
    out = tmp_path_factory.mktemp("api")
    run = subprocess.run([sys.executable, "-W", "error::UserWarning", "-m", "pdoc", "-o", str(out), "rotor37_rom",
                          "forms", "geometry"], cwd=ROOT, capture_output=True, text=True, timeout=600,
                         env=dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg"))
    assert run.returncode == 0, run.stderr[-3000:]
    return out


def test_reference_builds_without_warnings_and_names_every_public_name(reference):
    import rotor37_rom

    assert (reference / "index.html").is_file()
    pages, missing = 0, []
    for info in pkgutil.walk_packages(rotor37_rom.__path__, "rotor37_rom."):
        # a package with its own __all__ documents its modules' public names on its page (fem, periodic)
        page = reference / (info.name.replace(".", "/") + ".html")
        parent = reference / (info.name.rsplit(".", 1)[0].replace(".", "/") + ".html")
        text = page.read_text() if page.is_file() else parent.read_text()
        pages += page.is_file()
        missing += [f"{info.name}.{name}" for name in getattr(importlib.import_module(info.name), "__all__", ())
                    if f'id="{name}"' not in text]
    assert not missing, f"{len(missing)} public names on no page: {missing[:20]}"
    assert pages >= 60

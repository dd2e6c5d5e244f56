"""The demos as modules, for the benchmark scripts that still load one (the machine description and result files
are ``rotor37_rom.machine``'s)."""
from __future__ import annotations

import functools
import importlib.util
import sys
from pathlib import Path

DEMOS = Path(__file__).resolve().parents[1] / "demos"


@functools.lru_cache(maxsize=None)
def load_demo(name: str):
    """demos/<name>.py as a module (demos/ is not a package), loaded once per process; registered in sys.modules, as
    its dataclasses look their module up."""
    spec = importlib.util.spec_from_file_location(f"demo_{name}", DEMOS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module

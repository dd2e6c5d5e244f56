"""Pictures: pyvista off-screen renderings and XDMF output (pyvista and matplotlib are imported lazily)."""
from __future__ import annotations

import logging
from pathlib import Path
from typing import Sequence

import numpy as np

__all__ = ["write_xdmf", "render_mode_shapes"]

LOG = logging.getLogger(__name__)


def write_xdmf(sector, functions: Sequence, path: str | Path) -> Path:
    """Write functions (interpolated to P1, the mesh degree) to an XDMF/HDF5 pair for ParaView; one 'time' each."""
    from dolfinx import fem, io

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    V1 = fem.VectorFunctionSpace(sector.mesh, ("Lagrange", 1))
    out = fem.Function(V1, name="displacement")
    with io.XDMFFile(sector.comm, str(path), "w") as xdmf:
        xdmf.write_mesh(sector.mesh)
        for k, f in enumerate(functions):
            out.interpolate(f)
            xdmf.write_function(out, float(k))
    return path


def render_mode_shapes(sector, modes: Sequence, titles: Sequence[str], folder: str | Path, amplitude: float = 0.1
                       ) -> list[Path]:
    """One PNG per mode: the blade deformed so that the largest displacement is ``amplitude`` x blade span,
    coloured by the normalised displacement magnitude. Serial only (returns [] under MPI).

    Rendering runs in a child process without dolfinx (see rotor37_rom._render for why).
    """
    if sector.comm.size > 1:
        LOG.warning("render_mode_shapes: pyvista rendering runs serially; skipped under MPI")
        return []
    from dolfinx import plot

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    topology, cell_types, x = plot.create_vtk_mesh(sector.V)
    span = np.ptp(np.hypot(x[:, 0], x[:, 1]))
    scene = {"topology": topology, "cell_types": cell_types, "points": x, "n_frames": len(modes),
             "scalar_name": "|u| (normalised)"}
    paths = []
    for k, (f, title) in enumerate(zip(modes, titles)):
        values = f.x.array.reshape(-1, 3)
        magnitude = np.linalg.norm(values, axis=1)
        path = folder / f"mode_{k + 1}.png"
        scene.update({f"u_{k}": values, f"s_{k}": magnitude / magnitude.max(), f"title_{k}": title,
                      f"path_{k}": str(path), f"factor_{k}": amplitude * span / magnitude.max()})
        paths.append(path)
    run_render(scene, folder / "scene.npz")
    return paths


def run_render(scene: dict, scene_path: Path) -> None:
    """Save the scene and render it in a child process; raises RuntimeError with its last error line."""
    import subprocess
    import sys

    np.savez(scene_path, **scene)
    proc = subprocess.run([sys.executable, "-m", "rotor37_rom._render", str(scene_path)], capture_output=True,
                          text=True)
    scene_path.unlink(missing_ok=True)
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        raise RuntimeError(f"pyvista rendering failed: {last}")

"""Off-screen pyvista rendering in a process that never imports dolfinx.

VTK wheels crash (std::regex in vtkScalarBarActor) when Debian's dolfinx libraries were loaded first in the same
process: both define the same weak libstdc++ template instantiations with different ABIs. So plotting.py writes
the grid to an .npz and runs ``python -m rotor37_rom._render scene.npz``.

Scene file keys: topology, cell_types, points, displacement (n, 3) per frame as 'u_<k>', scalars as 's_<k>',
'title_<k>', 'path_<k>', 'scalar_name', 'amplitude', 'clim' (optional).
"""
from __future__ import annotations

import sys

import numpy as np


def render_scene(scene_path: str) -> None:
    import pyvista

    pyvista.OFF_SCREEN = True
    scene = np.load(scene_path, allow_pickle=False)
    grid0 = pyvista.UnstructuredGrid(scene["topology"], scene["cell_types"], scene["points"])
    n_frames = int(scene["n_frames"])
    scalar_name = str(scene["scalar_name"])
    for k in range(n_frames):
        grid = grid0.copy()
        grid.point_data["u"] = scene[f"u_{k}"]
        grid.point_data[scalar_name] = scene[f"s_{k}"]
        warped = grid.warp_by_vector("u", factor=float(scene[f"factor_{k}"]))
        plotter = pyvista.Plotter(off_screen=True, window_size=[900, 700])
        plotter.set_background("white")
        plotter.add_mesh(grid0, style="wireframe", color="grey", opacity=0.12)
        clim = scene["clim"] if "clim" in scene.files else None
        plotter.add_mesh(warped, scalars=scalar_name, cmap="viridis", clim=clim,
                         scalar_bar_args={"title": scalar_name, "color": "black"})
        plotter.add_text(str(scene[f"title_{k}"]), font_size=11, color="black")
        plotter.view_vector((0.35, -0.5, 0.8), viewup=(1.0, 0.0, 0.0))
        plotter.screenshot(str(scene[f"path_{k}"]))
        plotter.close()


if __name__ == "__main__":
    render_scene(sys.argv[1])

"""Off-screen pyvista rendering in a process that never imports dolfinx.

VTK wheels crash (std::regex in vtkScalarBarActor) when Debian's dolfinx libraries were loaded first in the same
process: both define the same weak libstdc++ template instantiations with different ABIs. So plotting.py writes
the grid to an .npz and runs ``python -m rotor37_rom.viz._render scene.npz``.

Scene file keys: topology, cell_types, points, displacement (n, 3) per frame as 'u_<k>', scalars as 's_<k>',
'title_<k>', 'path_<k>', 'scalar_name', 'amplitude', 'clim' (optional), 'markers' (optional (m, 3) points drawn as
red dots).
"""
from __future__ import annotations

import sys

import numpy as np


def render_scene(scene_path: str) -> None:
    import json

    import pyvista

    pyvista.OFF_SCREEN = True
    scene = np.load(scene_path, allow_pickle=False)
    grid0 = pyvista.UnstructuredGrid(scene["topology"], scene["cell_types"], scene["points"])
    n_frames = int(scene["n_frames"])
    scalar_name = str(scene["scalar_name"])
    cell_scalars = bool(scene["cell_scalars"]) if "cell_scalars" in scene.files else False
    cmap = str(scene["cmap"]) if "cmap" in scene.files else "viridis"
    for k in range(n_frames):
        grid = grid0.copy()
        grid.point_data["u"] = scene[f"u_{k}"]
        if cell_scalars:
            grid.cell_data[scalar_name] = scene[f"s_{k}"]
        else:
            grid.point_data[scalar_name] = scene[f"s_{k}"]
        warped = grid.warp_by_vector("u", factor=float(scene[f"factor_{k}"]))
        plotter = pyvista.Plotter(off_screen=True, window_size=[900, 700])
        plotter.set_background("white")
        if not bool(scene["no_ghost"]) if "no_ghost" in scene.files else True:
            plotter.add_mesh(grid0, style="wireframe", color="grey", opacity=0.12)
        clim = scene["clim"] if "clim" in scene.files else None
        plotter.add_mesh(warped, scalars=scalar_name, cmap=cmap, clim=clim,
                         scalar_bar_args={"title": scalar_name, "color": "black", "fmt": "%.3g"})
        if "markers" in scene.files and len(scene["markers"]):        # points to mark (e.g. the contact nodes)
            plotter.add_points(np.asarray(scene["markers"]), color="red", point_size=12,
                               render_points_as_spheres=True)
        plotter.add_text(str(scene[f"title_{k}"]), font_size=11, color="black")
        view = scene["view"] if "view" in scene.files else (0.35, -0.5, 0.8)
        up = scene["viewup"] if "viewup" in scene.files else (1.0, 0.0, 0.0)
        plotter.view_vector(tuple(view), viewup=tuple(up))
        path = str(scene[f"path_{k}"])
        plotter.screenshot(path)
        plotter.close()
        data = warped.cell_data[scalar_name] if cell_scalars else warped.point_data[scalar_name]
        with open(path + ".json", "w") as f:      # what was drawn, for checks
            json.dump({"scalar_range": [float(np.min(data)), float(np.max(data))],
                       "clim": None if clim is None else [float(c) for c in clim], "n_cells": int(warped.n_cells),
                       "scalar_name": scalar_name}, f)


if __name__ == "__main__":
    render_scene(sys.argv[1])

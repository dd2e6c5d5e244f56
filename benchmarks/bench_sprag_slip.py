"""What the sprag-slip onset mu* depends on (issue #23, item 1): the friction coefficient from which sustained
sliding of the tip on the casing diverges, against the modelling choices the paper leaves open.

mu* needs only the static compliance G = E^T K^-1 E at the contact nodes (``fem.static_compliance``: Craig-Bampton
keeps those DOFs with exact constraint modes, so every reduced model of the project has this G) and each node's
contact normal n and sliding direction s: one node diverges where G_nn + mu G_ns = 0, a set of nodes where
det(N G (N + mu S)^T) = 0 (``dynamics.friction.sprag_slip_friction``). Choices measured, at the ci and coarse presets:

- contact normal: the blade frame's e_x (the paper: "the radial direction is defined as axis e_x for each boundary
  node"; this geometry's stacking line lies along it), e_x turned about e_z through the root face's centroid or
  through the tip face's centroid, the true radial direction at each node, and the normal of the conical casing
  (r = 251.97 mm - 0.2737 (z - 6.32 mm), tilted 15.3 deg towards +z); sliding along -e_theta (rotor 37 turns towards
  -theta) in the casing's tangent plane;
- clamp: the blade clamped at section 1, or the 4 mm shorter blade on its disk (the bladed-disk sector, bore
  clamped) for all blades in phase (k = 0) and in antiphase (k = 18);
- tip nodes: 8 or 16 along the tip camber line; the full or the 4 mm shorter blade;
- centrifugal prestress (the paper has none): the full blade clamped at section 1 turning at 1,400 and 1,800 rad/s
  about the machine axis, G from the tangent of the rotating blade at its centrifugal equilibrium,
  K_T(u_c) - Omega^2 M_P (``fem.solve_static(spin=...)``, ``fem.assemble_tangent``). Printed beside it: the
  prestressed 1B, 1T, 2B frequencies, Southwell's coefficient S (omega_1^2 = omega_1,0^2 + S Omega^2) and the speed
  where the prestressed 1B meets engine order 4 (omega_1(Omega) = 4 Omega, by fixed point on S).

Rows: mu* of the weakest node, of the LE half of the tip (the nodes that touch first at the 1B/EO4 interaction) and
of all nodes. Results to results/bench_sprag_slip.json, printed as Markdown (docs/results.md).

    python benchmarks/bench_sprag_slip.py [--presets ci coarse]
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from rotor37_rom.machine import write_results
from rotor37_rom.dynamics.casing import contact_frames  # noqa: E402
from rotor37_rom.dynamics.friction import sprag_slip_friction  # noqa: E402

SENSES = (-1, 1)             # rotor 37 is taken to turn towards -theta (inferred from the stagger); +1 for contrast
SPINS = (1400.0, 1800.0)     # rad/s: the 1B/EO4 region and the design speed


def frames(nodes: np.ndarray, normal: str, sense: int, root: np.ndarray, tip: np.ndarray):
    """(normals, slides) (n, 3) of the contact nodes for one choice of normal (``dynamics.casing.contact_frames``;
    e_x turned about e_z through a centroid for 'root centroid' and 'tip centroid')."""
    if normal in ("root centroid", "tip centroid"):
        c = root if normal == "root centroid" else tip
        beta = np.arctan2(c[1], c[0])
        turned = np.tile([np.cos(beta), np.sin(beta), 0.0], (len(nodes), 1))
        normals, slides, _ = contact_frames(turned, "radial", sense)
        return normals, slides
    normals, slides, _ = contact_frames(nodes, {"e_x": "x", "radial": "radial", "casing cone": "cone"}[normal], sense)
    return normals, slides


NORMALS = ("e_x", "root centroid", "tip centroid", "radial", "casing cone")


def onsets(G: np.ndarray, nodes: np.ndarray, normal: str, sense: int, root, tip) -> dict:
    n_nodes = len(nodes)
    normals, slides = frames(nodes, normal, sense, root, tip)
    N, S = np.zeros((n_nodes, 3 * n_nodes)), np.zeros((n_nodes, 3 * n_nodes))
    for i in range(n_nodes):
        N[i, 3 * i:3 * i + 3], S[i, 3 * i:3 * i + 3] = normals[i], slides[i]
    K = np.linalg.inv(G)
    per_node = [sprag_slip_friction(K, N, S, [i]) for i in range(n_nodes)]
    return {"per_node": per_node, "weakest": min(per_node),
            "le_half": sprag_slip_friction(K, N, S, list(range(n_nodes // 2))), "all": sprag_slip_friction(K, N, S)}


def rotating_tangent(blade, ops, spin: float):
    """K_T(u_c) - spin^2 M_P at the blade's centrifugal equilibrium u_c (PETSc, clamped)."""
    from rotor37_rom import fem

    u = fem.solve_static(blade, spin=spin, n_steps=2, ops=ops).u.x.array
    return fem.assemble_tangent(blade, u, ops, spin)


class Turning:
    """The full blade's 1B, 1T, 2B (rad/s) at rest and turning, Southwell's S of 1B, and the EO4 crossing of the
    prestressed 1B: Omega = omega_1,0 / sqrt(16 - S(Omega)), iterated to 0.01 rad/s. The speeds of the mu* rows
    reuse those rows' tangents (one centrifugal equilibrium per speed)."""

    def __init__(self, preset: str, blade, ops):
        from rotor37_rom import fem

        self.blade, self.ops = blade, ops
        self.M = fem.assemble_mass(blade, ops)
        K = fem.assemble_stiffness(blade, ops)
        self.rest = np.asarray(fem.solve_eigenproblem(K, self.M, 3)[0])
        K.destroy()
        self.record = {"preset": preset, "rest_rad_s": self.rest.tolist(), "turning": []}

    def frequencies(self, K, spin: float):
        """Frequencies of the rotating blade's tangent K at ``spin`` and Southwell's S of 1B."""
        from rotor37_rom import fem

        w = np.asarray(fem.solve_eigenproblem(K, self.M, 3)[0])
        return w, (w[0] ** 2 - self.rest[0] ** 2) / spin**2

    def add(self, K, spin: float) -> None:
        w, S = self.frequencies(K, spin)
        self.record["turning"].append({"spin_rad_s": spin, "frequencies_rad_s": w.tolist(), "southwell": S})

    def finish(self) -> dict:
        from rotor37_rom import fem
        from rotor37_rom.studies.campbell import iterate_crossing

        crossing, _ = iterate_crossing(lambda spin: fem.rotating_modes(self.blade, spin, 3, self.ops, self.M), 4,
                                       self.rest[0] / 4, self.rest[0], lambda w, V: 0, tol=1e-2)
        S = 16 - (self.rest[0] / crossing) ** 2      # the Southwell S of the last update: crossing = w0 / sqrt(16 - S)
        self.M.destroy()
        self.record.update(eo4_crossing_rad_s=float(crossing), eo4_crossing_at_rest_rad_s=float(self.rest[0] / 4),
                           southwell=S)
        return self.record


def configurations(preset: str, turning: list):
    """(clamp, blade shortening (m), tip nodes, prestress speed (rad/s), sector, K) one at a time; K None: the
    sector's own clamped stiffness, else the rotating blade's prestressed tangent or the disk's cyclic K_k (freed
    after its rows). The full blade turning is appended to ``turning`` (a ``Turning``, finished by the caller)."""
    from rotor37_rom import fem
    from rotor37_rom.fem.cyclic import CyclicOperators

    for shorten, n_tip in ((0.0, 8), (4e-3, 8), (0.0, 16)):
        blade = fem.create_blade_sector(preset=preset, shorten=shorten, n_tip_nodes=n_tip)
        yield "section 1", shorten, n_tip, 0.0, blade, None
        if shorten or n_tip != 8:
            continue
        ops = fem.create_svk_operators(blade)
        spinning = Turning(preset, blade, ops)
        for spin in SPINS:
            K = rotating_tangent(blade, ops, spin)
            spinning.add(K, spin)
            yield "section 1", shorten, n_tip, spin, blade, K
            K.destroy()
        turning.append(spinning)                       # its EO4 crossing after the mu* rows
    disk = fem.create_disk_sector(preset=preset)
    cyclic = CyclicOperators(disk)
    for k in (0, 18):
        Kk, Mk, T = cyclic.project(k)
        yield f"disk, k = {k}", 4e-3, len(disk.tip_nodes), 0.0, disk, Kk
        for A in (Kk, Mk, T):
            A.destroy()
    cyclic.destroy()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["ci", "coarse"], help="mesh presets (ci, coarse, paper)")
    args = parser.parse_args(argv)
    from rotor37_rom import fem
    from rotor37_rom.geometry.blade import get_mesh_preset

    for preset in args.presets:
        get_mesh_preset(preset)                            # a bad name: one line before any meshing
    rows, turning = [], []
    for preset in args.presets:
        roots = {}                                         # blade shortening -> root face centroid (section 1)
        t0 = time.perf_counter()
        for clamp, shorten, n_tip, spin, sector, K in configurations(preset, turning):
            G = fem.static_compliance(sector, sector.tip_dofs, K=K)
            seconds = time.perf_counter() - t0             # meshing or prestress (in the generator) and G
            if clamp == "section 1":
                roots[shorten] = fem.facet_centroid(sector, "clamp")
            root, tip = roots[shorten], fem.facet_centroid(sector, "tip")    # the disk's blade: its own tip face
            for sense in SENSES:
                for normal in NORMALS:
                    res = onsets(G, sector.tip_nodes, normal, sense, root, tip)
                    rows.append({"preset": preset, "clamp": clamp, "shorten_mm": 1e3 * shorten, "tip_nodes": n_tip,
                                 "prestress_rad_s": spin, "sense": sense, "normal": normal, "dofs": sector.n_dofs,
                                 "seconds": seconds,
                                 "root_centroid_deg": float(np.degrees(np.arctan2(root[1], root[0]))),
                                 "tip_centroid_deg": float(np.degrees(np.arctan2(tip[1], tip[0]))), **res})
                    print(f"{preset:6s} {clamp:12s} L-{1e3 * shorten:.0f} mm {n_tip:2d} nodes spin {spin:4.0f} "
                          f"sense {sense:+d} "
                          f"{normal:14s} weakest {res['weakest']:.3f}  LE half {res['le_half']:.3f}  all "
                          f"{res['all']:.3f}", flush=True)
            t0 = time.perf_counter()
    turning = [t.finish() for t in turning]
    machine = write_results("bench_sprag_slip", [{k: _json(v) for k, v in r.items()} for r in rows],
                            prestressed_frequencies=turning)
    print(f"\nMachine: {machine}. Command: python benchmarks/bench_sprag_slip.py --presets {' '.join(args.presets)}\n")
    print("mu* of the LE half / the weakest node / all nodes ('none': friction never wedges them)\n")
    print("| preset | clamp | blade | tip nodes | prestress | sense | " + " | ".join(NORMALS) + " |")
    print("|---|---|---|---|---|---|" + "---|" * len(NORMALS))

    def key(r):
        return r["preset"], r["clamp"], r["shorten_mm"], r["tip_nodes"], r["prestress_rad_s"], r["sense"]

    for k in dict.fromkeys(key(r) for r in rows):          # configurations in the order they ran
        cells = []
        for normal in NORMALS:
            r = next(r for r in rows if key(r) == k and r["normal"] == normal)
            cells.append(f"{_fmt(r['le_half'])} / {_fmt(r['weakest'])} / {_fmt(r['all'])}")
        preset, clamp, shorten, n_tip, spin, sense = k
        print(f"| {preset} | {clamp} | {'4 mm shorter' if shorten else 'full'} | {n_tip} | "
              f"{f'{spin:,.0f} rad/s' if spin else 'none'} | {sense:+d} | "
              + " | ".join(cells) + " |")
    print("\nThe full blade turning (section 1 clamped, centrifugal equilibrium and its tangent)\n")
    print("| preset | speed (rad/s) | 1B | 1T | 2B (rad/s) | Southwell S of 1B |")
    print("|---|---|---|---|---|---|")
    for t in turning:
        print(f"| {t['preset']} | 0 | " + " | ".join(f"{w:,.0f}" for w in t["rest_rad_s"]) + " | |")
        for r in t["turning"]:
            print(f"| {t['preset']} | {r['spin_rad_s']:,.0f} | " + " | ".join(f"{w:,.0f}" for w in
                                                                            r["frequencies_rad_s"])
                  + f" | {r['southwell']:.3f} |")
    for t in turning:
        print(f"{t['preset']}: 1B meets EO4 at {t['eo4_crossing_rad_s']:,.1f} rad/s turning (S = {t['southwell']:.3f}),"
              f" {t['eo4_crossing_at_rest_rad_s']:,.1f} rad/s from the frequency at rest")
    return 0


def _json(value):
    """inf (friction never wedges the nodes) as null: JSON has no infinity."""
    if isinstance(value, list):
        return [_json(v) for v in value]
    return None if isinstance(value, float) and not np.isfinite(value) else value


def _fmt(x: float) -> str:
    return "none" if not np.isfinite(x) else f"{x:.3f}"


if __name__ == "__main__":
    from rotor37_rom.cli import run_main

    sys.exit(run_main(main))

# # Stress at the worst instant of a contact simulation, pictures, and the HTML report (paper §3.4.2, Fig. 25)
#
# Builds the reduced blade (r = 45: 24 tip DOFs, 15 fixed-interface modes, the 6 global MDs), runs the casing
# contact at one speed with GNL off and on, finds t_max where node LE reaches its largest radial displacement, and
# recovers the exact SVK Cauchy stress (linear stress with GNL off) at every quadrature point from q(t_max) without
# reassembly. Writes the von Mises fields (XDMF for ParaView, pyvista PNGs of the blade and of the 36-blade disk),
# the charts, and report.html with the numbers next to the paper's and the run parameters. Figures of the other
# demos (modes, clearance, interaction maps) found under results/ are included.
#
#     python demos/report.py --preset ci --revolutions 3          # about a minute (run by the tests)
#     python demos/report.py                                       # default preset (make demo)

# +
from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg

PAPER_OMEGA = {"1B": 5272.0, "1T": 15760.0, "2B": 19071.0}
PAPER_SPEEDS = {"linear 1B/EO4": 1317.0, "zero IC, no GNL": 1446.0, "zero IC, GNL": 1535.0,
                "continuation, no GNL": 1520.0, "continuation, GNL": 1551.0}
# -


# +
def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="stress at the worst instant of a contact run, and the report")
    parser.add_argument("--preset", default="coarse")
    parser.add_argument("--speed", type=float, default=1400.0, help="angular speed of the contact run (rad/s)")
    parser.add_argument("--revolutions", type=float, default=10.0)
    parser.add_argument("--safety", type=float, default=0.5)
    parser.add_argument("--out", default="results/report")
    parser.add_argument("--results", default="results", help="folder searched for the other demos' figures")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)
    if not args.speed > 0 or not args.revolutions > 0:
        print("error: --speed (rad/s) and --revolutions must be > 0", file=sys.stderr)
        return 2

    from rotor37_rom import fem
    from rotor37_rom.builder import ReductionConfig, build_reduced_model
    from rotor37_rom.casing import Casing
    from rotor37_rom.charts import plot_time_history
    from rotor37_rom.integrator import CentralDifference, simulate
    from rotor37_rom.modes import classify_blade_modes
    from rotor37_rom.plotting import render_stress, write_xdmf
    from rotor37_rom.report import Section, write_report
    from rotor37_rom.analysis import stress_at_peak
    from rotor37_rom.stress import StressRecovery

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    timings = {}
    t0 = time.perf_counter()
    sector = fem.create_blade_sector(preset=args.preset)
    ops = fem.create_svk_operators(sector)
    modal = fem.compute_clamped_modes(sector, 3, ops)
    labels = classify_blade_modes(modal.tip_displacements, sector.tip_nodes)
    timings["mesh + modes"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    config = ReductionConfig(r_c=15, r_md=0, global_md_modes=3, forces="intrusive")
    model, _ = build_reduced_model(sector, config, ops=ops, cache_dir=Path(args.results) / "cache")
    timings["reduced model"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    H, _, cells = fem.quadrature_gradients(sector, model.Phi.T)
    recovery = StressRecovery(H, cells, *sector.material.lame)
    timings["stress recovery data"] = time.perf_counter() - t0
    rom_omega = np.sqrt(scipy.linalg.eigh(model.K, model.M, eigvals_only=True)[:3])
    casing = Casing()
    runs = {}
    for gnl in (False, True):
        label = "GNL" if gnl else "no GNL"
        scheme = CentralDifference(model, nonlinear=gnl, safety=args.safety)
        every = max(1, int(round(5e-6 / scheme.h)))
        t0 = time.perf_counter()
        res = simulate(scheme, args.speed, casing, revolutions=args.revolutions, record_every=every, record_q=True,
                       on_blowup="flag")
        wall = time.perf_counter() - t0
        if res.diverged_step[0] >= 0:
            # with Coulomb friction the response can grow without bound (friction-driven flutter of this model,
            # independent of h); it is reported, not hidden
            t_div = res.diverged_step[0] * scheme.h
            print(f"{label:>7}: diverged at step {res.diverged_step[0]} (t = {t_div * 1e3:.2f} ms): no stress at t_max")
            runs[label] = {"scheme": scheme, "result": res, "diverged": int(res.diverged_step[0]), "t_div": t_div,
                           "wall": wall}
            continue
        peak = stress_at_peak(sector, model, recovery, res, gnl)
        runs[label] = {"scheme": scheme, "result": res, "peak": peak, "wall": wall}
        u = fem.displacement_function(sector, model.Phi, peak["q"])
        vm_dg = fem.von_mises_function(sector, u, nonlinear=gnl, degree=0)
        tag = "gnl" if gnl else "linear"
        write_xdmf(sector, [u], out / f"displacement_tmax_{tag}.xdmf")
        from dolfinx import io

        with io.XDMFFile(sector.comm, str(out / f"von_mises_tmax_{tag}.xdmf"), "w") as xdmf:
            xdmf.write_mesh(sector.mesh)
            xdmf.write_function(vm_dg)
        span = 0.074
        factor = 0.1 * span / max(np.abs(u.x.array).max(), 1e-12)
        title = (f"{label}: von Mises at t_max = {peak['t_max'] * 1e3:.2f} ms, Omega = {args.speed:.0f} rad/s "
                 f"(x{factor:.0f})")
        render_stress(sector, u, peak["cell_max"], out / f"stress_blade_{tag}.png", title, factor=factor,
                      clim=peak["clim"])
        render_stress(sector, u, peak["cell_max"], out / f"stress_disk_{tag}.png", title + ", 36 blades in phase",
                      n_sectors=36, factor=factor, clim=peak["clim"])
        plot_time_history(res.t[0], {"LE": res.u_r[0][res.row("0:LE")], "TE": res.u_r[0][res.row("0:TE")]}, out / f"time_history_{tag}.png",
                          title=f"{label}, Omega = {args.speed:.0f} rad/s, h = {scheme.h:.3g} s")
        print(f"{label:>7}: t_max = {peak['t_max'] * 1e3:.3f} ms, u_LE = {peak['u_le'] * 1e3:.3f} mm, max von Mises "
              f"{peak['vm_max'] / 1e6:.1f} MPa = {100 * peak['ratio_yield']:.1f} % of sigma_Y at "
              f"{np.round(np.array(peak['location']) * 1e3, 1)} mm; tip band {peak['vm_max_tip_band'] / 1e6:.0f} MPa "
              f"(cells at the contact nodes, singular: {peak['vm_max_at_contact_nodes'] / 1e6:.0f} MPa); "
              f"simulation {wall:.1f} s")

    # the report
    sections = []
    freq_rows = [[f"{k + 1} ({lab})", w, rw, PAPER_OMEGA.get(lab, float("nan")),
                  100 * (w / PAPER_OMEGA[lab] - 1) if lab in PAPER_OMEGA else float("nan")]
                 for k, (lab, w, rw) in enumerate(zip(labels, modal.omega, rom_omega))]
    sections.append(Section(
        "Blade and reduced model",
        [f"{args.preset} preset: {sector.n_dofs} DOF (P2 tetrahedra), mass {sector.total_mass() * 1e3:.2f} g. "
         f"Reduced model r = {model.r} ({model.sizes}).",
         "Timings (s): " + ", ".join(f"{k} {v:.1f}" for k, v in timings.items())],
        tables=[("Clamped eigenfrequencies (rad/s)", ["mode", "full order", "ROM", "paper", "full vs paper (%)"],
                 freq_rows)]))
    stress_rows = [[label, f"diverged at step {r['diverged']} (t = {r['t_div'] * 1e3:.2f} ms)", "", "", "", "", "",
                    "", r["wall"]] if "diverged" in r else
                   [label, f"{r['peak']['t_max'] * 1e3:.3f}", r["peak"]["u_le"] * 1e3, r["peak"]["vm_max"] / 1e6,
                    100 * r["peak"]["ratio_yield"], str(np.round(np.array(r["peak"]["location"]) * 1e3, 1)),
                    r["peak"]["vm_max_tip_band"] / 1e6, r["peak"]["vm_max_at_contact_nodes"] / 1e6, r["wall"]]
                   for label, r in runs.items()]
    sections.append(Section(
        "Stress at the largest radial displacement of node LE (Fig. 25 analogue)",
        [f"Contact run at Omega = {args.speed:.0f} rad/s for {args.revolutions:g} revolutions from rest, casing "
         f"c0 = {casing.c0 * 1e3:g} mm, h_b = {casing.h_b * 1e3:g} mm, mu = {casing.mu:g} (eqs. 37-38). "
         "Von Mises from the exact SVK Cauchy stress (GNL on) or the linear stress (GNL off), evaluated at the "
         f"quadrature points from q(t_max); yield stress sigma_Y = {sector.material.sigma_y / 1e9:g} GPa. The "
         "maximum is over the blade except the cells within 10 % of the span of a contact node; that tip band, "
         "where the contact impulses excite the local response, and the cells touching a contact node, where the "
         "point forces of the Lagrange multipliers make the FE stress singular (it grows under mesh refinement), "
         "are listed apart. Colour scale: 0 to the 99.5th percentile outside the tip band."],
        tables=[("Peak instant and stress", ["model", "t_max (ms)", "u_LE,r (mm)", "max von Mises (MPa)",
                                             "% of sigma_Y", "location (mm)",
                                             "tip band (MPa)", "at contact nodes (MPa, singular)",
                                             "simulation (s)"], stress_rows)],
        figures=[(out / f"stress_blade_{t}.png", f"von Mises at t_max, {lab}") for t, lab in
                 (("linear", "GNL off"), ("gnl", "GNL on"))]
        + [(out / f"stress_disk_{t}.png", f"36-blade disk, {lab}") for t, lab in (("linear", "GNL off"),
                                                                                    ("gnl", "GNL on"))]
        + [(out / f"time_history_{t}.png", f"LE/TE radial displacement, {lab}") for t, lab in
           (("linear", "GNL off"), ("gnl", "GNL on"))]))
    res_dir = Path(args.results)
    cmap = res_dir / "contact_map"
    figs = [(p, p.stem.replace("_", " ")) for p in sorted(cmap.glob("*.png"))] if cmap.is_dir() else []
    paras = []
    summary_file = cmap / "summary.json"
    if summary_file.is_file():
        s = json.loads(summary_file.read_text())
        rows = [[lab, run["peak_speed"], run["peak_amplitude"] * 1e3,
                 PAPER_SPEEDS["zero IC, GNL" if lab == "GNL" else "zero IC, no GNL"], run["h"], run["wall_s"]]
                for lab, run in s["runs"].items()]
        rows.append(["linear 1B/EO4", s["linear_resonance"], float("nan"), PAPER_SPEEDS["linear 1B/EO4"],
                     float("nan"), float("nan")])
        tables = [("Largest response speed (rad/s), zero initial conditions",
                   ["model", "this work", "amplitude (mm)", "paper", "h (s)", "wall (s)"], rows)]
        paras.append(f"Sweep {s['speeds']} rad/s, {s['revolutions']} revolutions per speed, r = {s['r']}.")
    else:
        tables = []
        paras.append("No interaction map yet: run demos/contact_map.py.")
    sections.append(Section("Interaction maps and NFRC (Figs. 6, 7, 11, 12)", paras, tables=tables, figures=figs))
    other = [(p, f"{p.parent.name}/{p.stem}") for sub in ("reduced_blade", "blade_modes/parametric_png")
             for p in sorted((res_dir / sub).glob("*.png"))]
    sections.append(Section("Mode shapes, modal-derivative weights, clearance consumption",
                            [] if other else ["Run demos/blade_modes.py and demos/reduced_blade.py for these."],
                            figures=other))
    params = {"preset": args.preset, "dofs": sector.n_dofs, "r": model.r, "config": config, "speed": args.speed,
              "revolutions": args.revolutions, "h": {k: r["scheme"].h for k, r in runs.items()},
              "h_crit (linear)": runs["no GNL"]["scheme"].h_crit, "casing": casing, "model key": model.key}
    path = write_report(out / "report.html", "rotor37_rom: blade with casing contact", sections, params)
    (out / "stress_summary.json").write_text(json.dumps(
        {k: ({kk: vv for kk, vv in r["peak"].items() if kk not in ("q", "cell_max")} if "peak" in r else
             {"diverged_step": r["diverged"], "t_diverged": r["t_div"]}) for k, r in runs.items()},
        indent=1))
    print(f"report: {path}")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
# -

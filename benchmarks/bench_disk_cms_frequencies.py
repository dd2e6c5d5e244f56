"""The bladed disk's CMS frequencies at every nodal diameter against the full-order cyclic reference (issue #20's
acceptance: the 1B, 1T and 2B families within 1 % at every k, Rayleigh-Ritz upper bounds).

The paper's r = 972 model (r_b = 3, node LE; r_c = 10; r_MD = 10 by MI 2b; r_cyclic = 144) and, with --tip-nodes all,
the contact maps' model (r_b = 24): the disk model's eigenfrequencies sorted by harmonic index
(``disk.harmonics.harmonic_frequencies``) against the sector's full-order cyclic modes at k = 0 ... 18
(``post.stress.cyclic_harmonic_frequencies``).

    python benchmarks/bench_disk_cms_frequencies.py [--preset ci] [--tip-nodes LE|all]

Results: results/bench_disk_cms_frequencies_<tip-nodes>.json (machine stated).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from rotor37_rom.machine import write_results
from rotor37_rom import fem  # noqa: E402
from rotor37_rom.post.stress import cyclic_harmonic_frequencies  # noqa: E402
from rotor37_rom.disk.harmonics import harmonic_frequencies  # noqa: E402
from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model  # noqa: E402

FAMILIES = ("1B", "1T", "2B")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="ci", choices=["ci", "coarse"])
    parser.add_argument("--tip-nodes", default="LE", choices=["LE", "all"])
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    sector = fem.create_disk_sector(preset=args.preset)
    ops = fem.create_svk_operators(sector)
    model, _ = build_disk_model(sector, DiskReductionConfig(tip_nodes=args.tip_nodes, r_c=10, r_md=10,
                                                            criterion="MI2b", r_cyclic=144), ops=ops,
                                cache_dir=Path("results/cache"))
    rom_all = harmonic_frequencies(model, 3)
    ref_all = cyclic_harmonic_frequencies(sector, 3, ops=ops)
    rows, worst, bound_ok = [], 0.0, True
    for k, (ref, rom) in enumerate(zip(ref_all, rom_all)):
        err = rom / ref - 1.0
        worst = max(worst, float(np.abs(err).max()))
        bound_ok &= bool(np.all(rom >= ref * (1 - 1e-9)))
        rows.append({"k": k, "reference_rad_s": ref.tolist(), "rom_rad_s": rom.tolist(),
                     "relative_error": err.tolist()})
        print(f"k = {k:2d}: " + "  ".join(f"{f} {r:8.1f} / {c:8.1f} ({e:+.3%})" for f, r, c, e in
                                         zip(FAMILIES, ref, rom, err)), flush=True)
    wall = time.perf_counter() - t0
    machine = write_results(f"bench_disk_cms_frequencies_{args.tip_nodes}", rows, r=model.r, sizes=model.sizes,
                            largest_relative_error=worst, rayleigh_ritz=bound_ok, wall_s=wall)
    print(f"r = {model.r}: largest relative error {worst:.3%} over k = 0 ... 18 and 1B/1T/2B; Rayleigh-Ritz upper "
          f"bounds {'hold' if bound_ok else 'FAIL'}; {wall:.0f} s ({machine})")
    return 0 if bound_ok and worst <= 0.01 else 1


if __name__ == "__main__":
    sys.exit(main())

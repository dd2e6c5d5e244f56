"""The map command's periodic orbits (#72, ``--periodic``): the blade's periodic responses to the casing, orbits of
the map's own scheme continued over the map's speeds beside its runs from rest, with their stability and where it
changes, in the summary and on a chart."""
import json

import numpy as np
import pytest

from rotor37_rom.model.reduced import save_reduced_model
from rotor37_rom.studies import contact_map
from rotor37_rom.studies.periodic_map import BLOWUP_LIMIT


def test_contact_map_draws_the_periodic_orbits(ci_rom, tmp_path):
    """2 speeds x 0.3 revolutions (GNL off, 30 kHz cap) and the periodic orbits from 1,220 to 1,250 rad/s: the
    branch reaches its end; every orbit is a fixed point of the map's scheme's period map (n steps of at most the
    map's step); its stability is its largest multiplier's modulus against 1, and a change of stability is reported
    exactly where neighbouring points differ, with a kind; the summary holds the branch and the chart is drawn."""
    out = tmp_path / "map"
    config = contact_map.ContactMapConfig.from_options(model=save_reduced_model(ci_rom, tmp_path / "rom.npz"),
                                                       speeds=(1220, 1250, 2), revolutions=0.3, gnl="off",
                                                       frequency_cap=30, periodic=0.05, quiet=True, out=out)
    result = contact_map.run_contact_map(config)
    (run,) = result.runs.values()
    branch = run.periodic
    print(branch.describe())
    assert branch.ended.startswith("reached") and branch.speeds[0] == 1220.0 and branch.speeds[-1] >= 1250.0
    assert np.pi / 1220.0 / branch.steps <= run.h
    # an orbit moving a node past the maps' blow-up limit is flagged, its amplitude left out (NaN) as a map's
    assert np.all(branch.amplitude[~branch.blown_up] > 0) and np.all(np.isfinite(branch.multiplier))
    assert np.isnan(branch.amplitude[branch.blown_up]).all()
    assert np.all((branch.largest_displacement > BLOWUP_LIMIT) == branch.blown_up)
    growth = np.exp(1e-9 * 2 * np.pi)                              # the stability test's round-off margin
    np.testing.assert_array_equal(branch.stable, branch.multiplier < growth)
    changes = np.flatnonzero(branch.stable[1:] != branch.stable[:-1]) + 1
    assert [b["index"] for b in branch.bifurcations] == changes.tolist()
    assert all(b["kind"] in ("fold", "period doubling", "Neimark-Sacker") for b in branch.bifurcations)
    summary = json.loads((out / "summary.json").read_text())
    saved = summary["runs"][run.label]["periodic"]
    assert saved.pop("file") == f"orbits_{run.tag}.npz"
    np.testing.assert_equal(saved, json.loads(json.dumps(branch.summary())))
    chart = out / f"nfrc_periodic_{run.tag}.png"
    assert chart in result.files and chart.is_file()
    # the orbits read back from their file are the branch's, and the file says how to march them: each start returns
    # to itself after one period of the map's scheme (Newton's 1e-9), the blown-up ones included
    from rotor37_rom.periodic import Shooting
    from rotor37_rom.studies.contact_scheme import time_scheme
    from rotor37_rom.studies.periodic_map import load_orbits

    orbits = load_orbits(out / f"orbits_{run.tag}.npz")
    np.testing.assert_array_equal(orbits["states"], branch.states)
    np.testing.assert_array_equal(orbits["speeds"], branch.speeds)
    assert tuple(orbits["node_labels"]) == ci_rom.nodes.labels and "[q_0, q_-1]" in str(orbits["layout"])
    shooting = Shooting(time_scheme(config.setting(False), ci_rom, False, None), config.sweep.casing,
                        steps=int(orbits["steps"]))
    for k in (0, len(branch.speeds) // 2, len(branch.speeds) - 1):
        z = orbits["states"][k].ravel()
        back = shooting.march(z, 2 * orbits["speeds"][k], tangent=False)[0]
        assert np.abs(back - z).max() <= 1e-8 * np.abs(z).max(), k
    with pytest.raises(ValueError, match="is no orbits file"):
        load_orbits(out / "summary.json")


def test_sequential_continuation_sits_on_the_stable_orbits(ci_rom, tmp_path):
    """(g) of #72: the map's sequential continuation (each speed's run from the previous one's end, §2.3.3; 100
    revolutions first, then 15 a speed) against the stable periodic orbits of the same scheme at its speeds (GNL off,
    30 kHz cap, 1,220-1,235 rad/s, below the Neimark-Sacker point). By Floquet theory a run of n periods started at
    relative distance D from a stable orbit ends within |mu|^n D of it (|mu| the orbit's largest multiplier; a
    factor 2 for the non-orthogonal Floquet modes); the record's 1e-5 s sampling of the 1B-dominated response and the
    orbits' step T / n <= h add 1e-3 at most ((omega_1 dt)^2 / 8 = 4e-4). D is the point's distance from the previous
    point's amplitude (1: from rest). Every steady point within the branch must find its stable orbit there."""
    out = tmp_path / "map"
    config = contact_map.ContactMapConfig.from_options(model=save_reduced_model(ci_rom, tmp_path / "rom.npz"),
                                                       speeds=(1220, 1235, 2), revolutions=100, gnl="off",
                                                       frequency_cap=30, periodic=0.05, continuation=5,
                                                       continuation_range=(1220, 1235), quiet=True, out=out)
    result = contact_map.run_contact_map(config)
    (run,) = result.runs.values()
    first, continued = 2 * 100, 2 * contact_map.continued_revolutions(100)       # periods: half a revolution each
    compared = 0
    for name, branch in run.branches.items():
        comparison = run.periodic.continuation[name]
        rows = {r["speed"]: r for r in comparison["compared"]}
        previous = None
        for p in branch.points:
            if p.omega in rows:
                row = rows[p.omega]
                D = 1.0 if previous is None else abs(row["orbit"] - previous) / row["orbit"]
                n = first if previous is None else continued
                bound = 2 * row["multiplier"] ** n * D + 1e-3
                print(f"{name} {p.omega:.2f} rad/s: continuation {row['continuation'] * 1e3:.4f} mm, orbit "
                      f"{row['orbit'] * 1e3:.4f} mm, |mu| {row['multiplier']:.4f}: {row['difference']:.2e} "
                      f"<= {bound:.2e}")
                assert row["difference"] <= bound
                compared += 1
            previous = p.amplitude
        assert comparison["no_stable_orbit"] == []
    assert compared >= 5

"""The map command's periodic orbits (#72, ``--periodic``): the blade's periodic responses to the casing, orbits of
the map's own scheme continued over the map's speeds beside its runs from rest, with their stability and where it
changes, in the summary and on a chart."""
import json

import numpy as np

from rotor37_rom.model.reduced import save_reduced_model
from rotor37_rom.studies import contact_map


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
    assert np.all(branch.amplitude > 0) and np.all(np.isfinite(branch.multiplier))
    growth = np.exp(1e-9 * 2 * np.pi)                              # the stability test's round-off margin
    np.testing.assert_array_equal(branch.stable, branch.multiplier < growth)
    changes = np.flatnonzero(branch.stable[1:] != branch.stable[:-1]) + 1
    assert [b["index"] for b in branch.bifurcations] == changes.tolist()
    assert all(b["kind"] in ("fold", "period doubling", "Neimark-Sacker") for b in branch.bifurcations)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["runs"][run.label]["periodic"] == json.loads(json.dumps(branch.summary()))
    chart = out / f"nfrc_periodic_{run.tag}.png"
    assert chart in result.files and chart.is_file()

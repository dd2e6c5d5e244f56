"""The impact numbers of the blade's contact nodes (``post.impact``; issue #88, item 5): for the full order and
reduced models, on 1B, under the damping ratios of the project's laws. What they say: whether the impact law (and so
a regularised or penalty harmonic balance's law) can move the steady state the damping sets."""
from __future__ import annotations

import numpy as np
import scipy.linalg

from rotor37_rom.post.impact import ImpactNumbers, impact_numbers

__all__ = ["blade_impact_numbers", "table"]


def blade_impact_numbers(sector, ops, models: dict, casing, zetas: dict) -> dict:
    """{model name: {law name: ImpactNumbers}} on 1B for the full order ('full order', ``fem.RepeatingSectors``:
    its mass on the free DOFs, the casing's contact rows) and each reduced model of ``models`` ({name:
    ReducedModel}: its M, its contact rows ``dynamics.casing.contact_matrices``), at each damping ratio of ``zetas``
    ({law name: 1B's ratio})."""
    from rotor37_rom.dynamics.casing import contact_matrices
    from rotor37_rom.fem.periodic import RepeatingSectors

    system = RepeatingSectors(sector, 1, ops)
    _, phi = system.modes(1)
    N = system.contact_operators(casing).N
    out = {"full order": {law: impact_numbers(system.M, N, phi[:, 0], z) for law, z in zetas.items()}}
    for name, model in models.items():
        _, V = scipy.linalg.eigh(model.K, model.M, subset_by_index=[0, 0])
        N_r = contact_matrices(model.nodes, model.r, casing)[0]
        out[name] = {law: impact_numbers(np.asarray(model.M), N_r, V[:, 0], z) for law, z in zetas.items()}
    return out


def table(numbers: dict[str, dict[str, ImpactNumbers]]) -> list[dict]:
    """One row per model and law: the contact nodes' smallest and largest m_eff / m_mode and Pi."""
    return [{"model": name, "law": law, "zeta": n.zeta, "ratio_min": float(n.ratio.min()),
             "ratio_max": float(n.ratio.max()), "pi_min": float(n.pi.min()), "pi_max": float(n.pi.max()),
             "m_eff_kg": n.m_eff.tolist()}
            for name, laws in numbers.items() for law, n in laws.items()]

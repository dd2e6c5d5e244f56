"""Mode identification from tip displacements (pure NumPy)."""
from __future__ import annotations

import numpy as np

__all__ = ["classify_blade_modes", "normalise_signs", "PAPER_CLAMPED_OMEGA"]

#: Clamped-blade eigenfrequencies of the paper (§2.2.1), rad/s.
PAPER_CLAMPED_OMEGA = {"1B": 5272.0, "1T": 15760.0, "2B": 19071.0}


def normalise_signs(V: np.ndarray) -> np.ndarray:
    """The columns of V, each multiplied by +-1 so that its entry of largest magnitude is positive.

    An eigen-solver returns each eigenvector up to its sign, and which sign depends on the LAPACK/BLAS kernels and
    the thread count (seen: the same 1B vector of scipy.linalg.eigh came out with opposite signs on an Intel and an
    AMD machine). Anything built from a single eigenvector (a deflected start, training states, a scaled mode)
    must first fix the sign so that it is the same on every machine. The entry of largest magnitude is chosen
    because round-off (~1e-15 relative) cannot move it unless two entries tie to that accuracy.
    Returns a new (n,) or (n, m) array."""
    V = np.asarray(V, float)
    flat = V.reshape(V.shape[0], -1)
    pick = flat[np.argmax(np.abs(flat), axis=0), np.arange(flat.shape[1])]
    return (flat * np.where(pick < 0, -1.0, 1.0)).reshape(V.shape)


def classify_blade_modes(tip_displacements: np.ndarray, tip_nodes: np.ndarray) -> list[str]:
    """Label modes 1B, 2B, ... (bending), 1T, ... (torsion), 1E, ... (edgewise) from the tip LE/TE motion.

    Args:
        tip_displacements: (n_modes, n_tip, 3) displacements of the tip nodes, LE first and TE last.
        tip_nodes: (n_tip, 3) tip node coordinates (m), z axial.

    The tip chord c runs LE -> TE and n = e_r x c is the out-of-plane direction. A mode whose LE and TE move
    mostly along c is edgewise; otherwise LE and TE moving the same way along n is bending, opposite ways torsion.
    """
    tip_displacements = np.asarray(tip_displacements, float)
    le, te = tip_nodes[0], tip_nodes[-1]
    chord = (te - le) / np.linalg.norm(te - le)
    mid = 0.5 * (le + te)
    e_r = np.array([mid[0], mid[1], 0.0]) / np.hypot(mid[0], mid[1])
    normal = np.cross(e_r, chord)
    normal /= np.linalg.norm(normal)
    counts = {"B": 0, "T": 0, "E": 0}
    labels = []
    for u in tip_displacements:
        a_le, a_te = u[0] @ normal, u[-1] @ normal
        along = abs(0.5 * (u[0] + u[-1]) @ chord)
        if along > max(abs(a_le), abs(a_te)):
            kind = "E"
        elif a_le * a_te > 0.0:
            kind = "B"
        else:
            kind = "T"
        counts[kind] += 1
        labels.append(f"{counts[kind]}{kind}")
    return labels

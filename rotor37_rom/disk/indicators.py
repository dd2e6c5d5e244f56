"""The performance indicator I of the disk's reduced models (loaded node, tip nodes, field norms) and its
histories, and the best approximation of a reference field in a basis."""
from __future__ import annotations

import numpy as np

from rotor37_rom.model.disk_basis import DiskBasis

INDICATOR_CRITERIA = ("loaded node", "tip nodes", "field", "strain energy")


def _norms(A, X: np.ndarray) -> np.ndarray:
    """The A-norms of the fields X (..., n_dofs), one per leading index, flattened."""
    X2 = X.reshape(-1, X.shape[-1])
    return np.sqrt(np.maximum(np.einsum("ij,ij->i", X2, (A @ X2.T).T), 0.0))


def best_approximation(basis: DiskBasis, field_ref: np.ndarray, K, M) -> dict:
    """The smallest errors that any state of a disk model can have against reference fields: the lower bounds of
    ``performance_indicator``'s global criteria, which tell the basis's share of a reduced model's error from the
    share of its reduced dynamics (Galerkin projection, force approximation, time integration).

    Each snapshot of sector n is projected, in the M norm ('field') and in the K norm ('strain energy'), on the
    fields that sector n can take: span[Phi_s, Psi_L Pi_n + Psi_R' Pi_(n+1)] (``DiskBasis.sector_field``'s image;
    the snapshots are treated independently, so the bound holds for every q history). Normalised as the indicator
    (max over snapshots and sectors of the error norm / max of the reference's).

    Args: field_ref (n_snap, n_s, n_dofs) snapshots of sectors 0 ... n_s - 1; K, M the sector's stiffness and mass
    (as for the indicator). Returns {'field': e_M, 'strain energy': e_K}."""
    field_ref = np.asarray(field_ref, float)
    N, nL = basis.n_sectors, basis.Psi_L.shape[1]
    if field_ref.ndim != 3 or field_ref.shape[2] != basis.Phi_s.shape[0] or not 1 <= field_ref.shape[1] <= N:
        raise ValueError(f"reference fields must be (snapshots, 1 ... {N} sectors, {basis.Phi_s.shape[0]} DOFs), got "
                         f"{field_ref.shape}")
    out = {}
    for name, A in (("field", M), ("strain energy", K)):
        worst, ref_max = 0.0, 0.0
        for n in range(field_ref.shape[1]):
            m = (n + 1) % N
            B = np.hstack([basis.Phi_s, basis.Psi_L @ basis.Pi[n * nL:(n + 1) * nL]
                           + basis.Psi_Rr @ basis.Pi[m * nL:(m + 1) * nL]])
            AB = np.asarray(A @ B)
            d = np.sqrt(np.maximum(np.einsum("ij,ij->j", B, AB), 1e-300))   # columns scaled to unit A-norm
            w, V = np.linalg.eigh(0.5 * (B.T @ AB + AB.T @ B) / np.outer(d, d))
            keep = w > 1e-14 * w.max()      # an A-orthonormal basis of the span; directions at round-off (eigh's
            #                                 1e-16 w_max) out, a field's part along them <= 1e-7 of its norm
            T = V[:, keep] / np.sqrt(w[keep]) / d[:, None]
            U = field_ref[:, n, :].T
            E = U - B @ (T @ (T.T @ (AB.T @ U)))
            E -= B @ (T @ (T.T @ (AB.T @ E)))           # once more: the projection's round-off projected out
            worst, ref_max = max(worst, _norms(A, E.T).max()), max(ref_max, _norms(A, U.T).max())
        out[name] = float(worst / max(ref_max, 1e-300))
    return out


def performance_indicator(tip_ref: np.ndarray, tip_rom: np.ndarray, field_ref: np.ndarray, field_rom: np.ndarray,
                          K, M, loaded: tuple = (0, 2)) -> dict:
    """The performance indicator I in [0, 1] of a reduced model's transient against a full-order reference, in the
    spirit of the paper's (its ref. [28]): two tip-local and two global criteria, each e_i >= 0 a relative error,
    I = mean_i max(0, 1 - e_i) (1: exact).

    - loaded node: max_t |u - u_ref| / max_t |u_ref| of the loaded DOF (``loaded`` = (tip node, component)) of
      every sector carried, the largest over sectors;
    - tip nodes: || u - u_ref || / || u_ref || over all tip nodes, components, sectors and instants (RMS);
    - field: max over snapshots of || u - u_ref ||_M / max over snapshots of || u_ref ||_M (whole sectors);
    - strain energy: the same in the K norm (the linear strain energy of the error).

    Args: tip_*: (n_t, n_s, n_tip, 3) tip histories (same instants, sectors in their frames); field_*: (n_snap, n_s,
    n_dofs) snapshots; K, M: the sector's stiffness and mass (n_dofs square, clamped rows and columns zero or
    identity-free). Returns {'I': ..., 'errors': {criterion: e}}."""
    tip_ref, tip_rom = np.asarray(tip_ref, float), np.asarray(tip_rom, float)
    field_ref, field_rom = np.asarray(field_ref, float), np.asarray(field_rom, float)
    if tip_ref.shape != tip_rom.shape or field_ref.shape != field_rom.shape:
        raise ValueError(f"reference and reduced histories must have the same shape: tips {tip_ref.shape} vs "
                         f"{tip_rom.shape}, fields {field_ref.shape} vs {field_rom.shape}")
    hist = indicator_histories(tip_ref, tip_rom, field_ref, field_rom, K, M, loaded)
    rms_tip = np.linalg.norm(tip_rom - tip_ref) / max(np.linalg.norm(tip_ref), 1e-300)   # the tip history's RMS
    errors = {name: float(rms_tip if name == "tip nodes" else hist[name].max()) for name in INDICATOR_CRITERIA}
    return {"I": float(np.mean([max(0.0, 1.0 - e) for e in errors.values()])), "errors": errors}


def indicator_histories(tip_ref: np.ndarray, tip_rom: np.ndarray, field_ref: np.ndarray, field_rom: np.ndarray,
                        K, M, loaded: tuple = (0, 2)) -> dict:
    """The error time histories behind ``performance_indicator`` (same arguments), each relative to the same
    reference scale as its criterion, so that the criterion is the history's largest value (loaded node, field,
    strain energy) or its RMS (tip nodes):

    - 'loaded node' (n_t,): |u - u_ref| of the loaded DOF, the largest over sectors of that sector's error over the
      sector's max_t |u_ref|;
    - 'tip nodes' (n_t,): || u - u_ref || over tip nodes, components and sectors at each instant over the RMS over
      instants of || u_ref ||;
    - 'field', 'strain energy' (n_snap,): the M- and K-norm of the error per snapshot (largest over sectors) over the
      largest of the reference's."""
    tip_ref, tip_rom = np.asarray(tip_ref, float), np.asarray(tip_rom, float)
    field_ref, field_rom = np.asarray(field_ref, float), np.asarray(field_rom, float)
    node, comp = loaded
    d_ref, d_rom = tip_ref[:, :, node, comp], tip_rom[:, :, node, comp]
    loaded_err = (np.abs(d_rom - d_ref) / np.maximum(np.abs(d_ref).max(axis=0), 1e-300)).max(axis=1)
    n_t = tip_ref.shape[0]
    per_instant = np.linalg.norm((tip_rom - tip_ref).reshape(n_t, -1), axis=1)
    tip_err = per_instant / max(np.linalg.norm(tip_ref) / np.sqrt(n_t), 1e-300)
    out = {"loaded node": loaded_err, "tip nodes": tip_err}
    n_snap, n_s = field_ref.shape[:2]
    for name, A in (("field", M), ("strain energy", K)):
        e = _norms(A, field_rom - field_ref).reshape(n_snap, n_s).max(axis=1)
        out[name] = e / max(_norms(A, field_ref).max(), 1e-300)
    return out

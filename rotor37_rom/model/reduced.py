"""The reduced model M~ q'' + C~ q' + K~ q + g~(q) = f~ (eq. 3): its data, its key, its file (saved
atomically, read back with its key checked), its force precision and perturbation, and its static solve."""
from __future__ import annotations

import dataclasses
import hashlib
import json
import numbers
from pathlib import Path
from typing import Sequence

import numpy as np

from rotor37_rom.checks import readable_file
from rotor37_rom.model.disk_basis import DiskBasis
from rotor37_rom.forces.protocol import NonlinearForce
from rotor37_rom.forces.sector import SectorForces
from rotor37_rom.forces.tensors import PolynomialForces, QuadratureForces
from rotor37_rom.model.nodes import NodeMap
from rotor37_rom.model.rotating import RotationTerms
from rotor37_rom.npz import save_npz


# how a model's file names its force's kind (``NonlinearForce.arrays``); a disk's sector forces prefix it 'sector_'
FORCE_KINDS = {"polynomial": PolynomialForces, "quadrature": QuadratureForces}


@dataclasses.dataclass(frozen=True)
class ReducedModel:
    """A reduced model M~ q'' + C~ q' + K~ q + g~(q) = f~ (eq. 3) with q = [u_b; eta_c; eta_MD] (eq. 22).

    Attributes:
        M, C, K: (r, r) reduced matrices.
        forces: the nonlinear force g~ (``forces.protocol.NonlinearForce``: exact tensors, a quadrature or cubature, a
            disk's sector forces), or None (linear).
        boundary_dofs: (r_b,) full-DOF indices (of one sector's mesh) kept physical in q.
        nodes: NodeMap: which entries of q are which node's displacement (the contact nodes).
        sizes: {'r_b', 'r_c', 'r_md'} per sector (a disk's also 'r_load', 'n_sectors', 'r_cyclic'); md_pairs:
            (r_md, 2).
        Phi: (n, r) basis to rebuild fields (optional).
        metadata: parameters, mesh signature, version; ``key`` hashes them.
        sectors: for a disk model, the per-sector basis that rebuilds each sector's field
        (``model.disk_basis.DiskBasis``);
            None for a blade.
        rotation: the terms of the model turning about e_z (``model.rotating.RotationTerms``: spin softening,
            centrifugal load, Coriolis, the speed range), or None (a model at rest).
    """

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    forces: NonlinearForce | None
    boundary_dofs: np.ndarray
    nodes: NodeMap
    sizes: dict
    md_pairs: np.ndarray
    Phi: np.ndarray | None
    metadata: dict
    sectors: DiskBasis | None = None
    rotation: RotationTerms | None = None

    @property
    def r(self) -> int:
        return self.K.shape[0]

    @property
    def key(self) -> str:
        return reduced_model_key(self.metadata)

    def nonlinear_force(self, Q: np.ndarray) -> np.ndarray:
        if self.forces is None:
            return np.zeros_like(np.asarray(Q, float).reshape(self.r, -1))
        return self.forces.evaluate(Q)


def with_force_precision(model: ReducedModel, precision: str) -> ReducedModel:
    """The model with its quadrature forces (exact or hyper-reduced) evaluated in ``precision``, 'double' or
    'single'; the key changes with it (single: metadata 'force_precision'), so cached sweeps are not mixed up."""
    if model.forces is None:
        raise ValueError("force precision applies to quadrature forces (exact or hyper-reduced), not to NoneType")
    forces = model.forces.with_precision(precision)           # refused by exact tensors; checks the name
    metadata = {k: v for k, v in model.metadata.items() if k != "force_precision"}
    if precision != "double":
        metadata["force_precision"] = precision
    return dataclasses.replace(model, forces=forces, metadata=metadata)


def perturbed_model(model: ReducedModel, eps: float) -> ReducedModel:
    """The model with its internal force K q + g(q) scaled by 1 + ``eps`` (|eps| < 0.01), whatever evaluates g:
    exact tensors, a quadrature or cubature (its weights), a disk's sector forces (their per-sector scales). A
    perturbation as small as any force approximation's error: the speeds whose response it moves are those no
    approximation can be judged on (the floor, docs/results.md). The key changes with it (metadata 'perturbation',
    the product of the factors applied), so cached sweeps are not mixed up."""
    if not (isinstance(eps, numbers.Real) and np.isfinite(eps) and abs(eps) < 0.01):
        raise ValueError(f"perturbation must be a number with |eps| < 0.01, got {eps!r}")
    eps = float(eps)
    if eps == 0:
        return model
    scale = 1.0 + eps
    forces = None if model.forces is None else model.forces.scaled(scale)
    prior = model.metadata.get("perturbation")
    total = eps if prior is None else (1.0 + float(prior)) * scale - 1.0
    return dataclasses.replace(model, K=model.K * scale, forces=forces,
                               metadata={**model.metadata, "perturbation": total})


def reduced_model_key(metadata: dict) -> str:
    """sha256 of the metadata (parameters, mesh signature, version) as canonical JSON."""
    return hashlib.sha256(json.dumps(metadata, sort_keys=True, default=str).encode()).hexdigest()[:24]


def save_reduced_model(model: ReducedModel, path: str | Path) -> Path:
    """Write an .npz atomically (temporary file, then rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = {"M": model.M, "C": model.C, "K": model.K, "boundary_dofs": model.boundary_dofs,
              **model.nodes.arrays(), "md_pairs": model.md_pairs,
              "meta": np.array(json.dumps({"metadata": model.metadata, "sizes": model.sizes, "key": model.key},
                                          sort_keys=True, default=str))}
    if model.Phi is not None:
        arrays["Phi"] = model.Phi
    arrays.update({"forces": "none"} if model.forces is None else model.forces.arrays())
    if model.sectors is not None:
        arrays.update({f"sectors_{name}": value for name, value in dataclasses.asdict(model.sectors).items()})
    if model.rotation is not None:
        arrays.update(model.rotation.arrays())
    return save_npz(path, **arrays)


def saved_model_key(path: str | Path) -> str:
    """The key of the reduced model saved at ``path`` (``save_reduced_model``), read from its 'meta' entry alone
    (np.load reads an .npz's arrays lazily: the matrices are not read); refuses a missing or corrupted file, or one
    whose stored key does not match its metadata, as ``load_reduced_model`` does."""
    path = Path(path)
    readable_file("reduced model file", path)
    try:
        with np.load(path, allow_pickle=False) as data:
            info = json.loads(str(data["meta"]))
        if not {"metadata", "key"} <= info.keys():          # a 'meta' without them: not a reduced model
            raise KeyError("metadata, key")
    except Exception as exc:
        raise ValueError(f"reduced model file {path} is corrupted or not a reduced model ({exc.__class__.__name__})"
                         ) from None
    return _checked_key(info, path)


def _checked_key(info: dict, path: Path) -> str:
    """The key stored in a saved model's 'meta' entry ``info``, refused if it does not match its metadata."""
    key = reduced_model_key(info["metadata"])
    if key != info["key"]:
        raise ValueError(f"reduced model file {path}: stored key does not match its metadata (corrupted)")
    return key


def load_reduced_model(path: str | Path, expected_key: str | None = None) -> ReducedModel:
    """Read a reduced model; refuse a corrupted file or one whose key differs from ``expected_key``."""
    path = Path(path)
    readable_file("reduced model file", path)
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
        info = json.loads(str(arrays["meta"]))
        nodes = NodeMap.from_arrays(arrays)
    except Exception as exc:
        raise ValueError(f"reduced model file {path} is corrupted or not a reduced model ({exc.__class__.__name__})"
                         ) from None
    key = _checked_key(info, path)
    if expected_key is not None and key != expected_key:
        raise ValueError(f"reduced model file {path} was built for other parameters or another mesh "
                         f"(key {key}, expected {expected_key}); it is stale: rebuild it")
    try:
        forces = _load_force(arrays, arrays["K"].shape[0])
    except KeyError as exc:
        raise ValueError(f"reduced model file {path} is corrupted or not a reduced model ({exc.__class__.__name__})"
                         ) from None
    sectors = None
    if "sectors_Pi" in arrays:
        sectors = DiskBasis(**{f.name: arrays[f"sectors_{f.name}"] for f in dataclasses.fields(DiskBasis)})
    return ReducedModel(M=arrays["M"], C=arrays["C"], K=arrays["K"], forces=forces,
                        boundary_dofs=arrays["boundary_dofs"], nodes=nodes,
                        sizes=info["sizes"], md_pairs=arrays["md_pairs"], Phi=arrays.get("Phi"),
                        metadata=info["metadata"], sectors=sectors, rotation=RotationTerms.from_arrays(arrays))


def _load_force(arrays, r: int) -> NonlinearForce | None:
    """The force a model's file holds (its arrays; ``NonlinearForce.arrays``), for a model of size ``r``; None for a
    linear model. KeyError for missing entries (a damaged file)."""
    kind = str(arrays["forces"])
    inner = FORCE_KINDS.get(kind.removeprefix("sector_"))
    force = None if inner is None else inner.from_arrays(arrays)
    return SectorForces.from_arrays(arrays, force, r) if kind.startswith("sector_") else force


def solve_reduced_static(model: ReducedModel, f: np.ndarray, load_factors: Sequence[float],
                         nonlinear: bool = True, rtol: float = 1e-10, max_iterations: int = 30,
                         max_bisections: int = 8) -> np.ndarray:
    """K~ q + g~(q) = lambda f for each lambda in order (continuation from q = 0).

    Newton with the exact reduced Jacobian, refreshed only when the residual stops dropping fast (ratio > 0.3);
    a load increment that does not converge is bisected (up to ``max_bisections`` times).
    Returns q (len(load_factors), r).
    """
    f = np.asarray(f, float)
    use_nl = nonlinear and model.forces is not None

    def residual(q, lam):
        res = model.K @ q - lam * f
        if use_nl:
            res += model.forces.evaluate(q)[:, 0]
        return res

    def newton(q, lam):
        scale = max(np.linalg.norm(lam * f), 1e-300)
        J, previous = None, np.inf
        for _ in range(max_iterations):
            res = residual(q, lam)
            norm = np.linalg.norm(res)
            if norm <= rtol * max(scale, np.linalg.norm(model.K @ q)):
                return q
            if J is None or norm > 0.3 * previous:
                J = model.K + (model.forces.jacobian(q) if use_nl else 0.0)
            previous = norm
            q = q - np.linalg.solve(J, res)
        return None

    q, lam_done, out = np.zeros(model.r), 0.0, []
    for target in load_factors:
        step, bisections = target - lam_done, 0
        while lam_done != target:
            lam = target if abs(target - lam_done) <= abs(step) else lam_done + step
            q_new = newton(q.copy(), lam)
            if q_new is None:
                bisections += 1
                if bisections > max_bisections:
                    raise RuntimeError(f"reduced Newton did not converge at load factor {lam:.4g} after "
                                       f"{max_bisections} bisections of the increment")
                step *= 0.5
                continue
            q, lam_done = q_new, lam
        out.append(q.copy())
    return np.array(out)

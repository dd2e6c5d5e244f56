"""What the explicit scheme's runs keep as they go: the loop state (``LoopState``, also what a checkpoint holds), the
records of each run at every ``record_every`` steps (``Recorder``), and the checkpoint file (``save_loop_state``,
``loop_state``)."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

__all__ = ["LoopState", "Recorder", "save_loop_state", "loop_state"]

# the per-run arrays of a checkpoint file, besides the records u_r<p>, lam<p> (and q_rec<p>)
_ARRAYS = ("Q", "Qp", "done", "max_pen", "min_lam", "fric_pow", "contact_steps", "diverged")


@dataclasses.dataclass
class LoopState:
    """The state of P runs integrated together, after ``n`` steps: everything a resumed run needs.

    Attributes:
        n: steps done; Q, Qp: (r, P) the last two states; done: (P,) runs ended (finished or diverged).
        u_r, lam: per run (n_m, n_rec) normal displacements of the monitored nodes and (n_c, n_rec) contact forces.
        max_pen, min_lam, fric_pow, contact_steps, diverged: (P,) the contact's extremes, steps in contact, the step a
            run blew up at (-1: none).
        energy: per run (n_rec,) discrete energies, or None; q_rec: per run (r, n_rec) states, or None.
        work: (4, P) running works (``WORK_TERMS``), or None before they are set up; work_rec: per run (4, n_rec)
            running works at the records (energy runs), or None.
        elapsed: wall time (s) the loop has run these runs for, over every sitting (a resumed run adds its own).
    """

    n: int
    Q: np.ndarray
    Qp: np.ndarray
    done: np.ndarray
    u_r: list
    lam: list
    max_pen: np.ndarray
    min_lam: np.ndarray
    fric_pow: np.ndarray
    contact_steps: np.ndarray
    diverged: np.ndarray
    energy: list | None = None
    q_rec: list | None = None
    work: np.ndarray | None = None
    work_rec: list | None = None
    elapsed: float = 0.0


class Recorder:
    """The records of P runs: the monitored nodes' normal displacements (``Nm`` q, ``labels``), the contact forces,
    and on request the full states and discrete energies, every ``record_every`` steps; ``steps`` (P,) is each run's
    length (a run's records stop at its end). ``offset`` (n_m, P): the normal displacements the records are measured
    from (a turning blade's running state, ``dynamics.turning``); None: rest. The full states are kept as they are.
    """

    def __init__(self, Nm, labels: tuple, steps: np.ndarray, h: float, record_every: int, omega: np.ndarray,
                 n_contact: int, record_q: bool, energy: bool, offset: np.ndarray | None = None):
        self.Nm, self.labels, self.steps, self.h, self.offset = Nm, labels, steps, h, offset
        self.every, self.omega, self.nc = record_every, omega, n_contact
        self.record_q, self.energy = record_q, energy

    def fresh(self, r: int, initial: tuple | None) -> LoopState:
        """The state of runs starting from ``initial`` (Q_0, Q_-1), or from rest, with step 0 recorded."""
        P = self.omega.size
        Q, Qp = np.zeros((r, P)), np.zeros((r, P))
        if initial is not None:
            Q[:] = np.asarray(initial[0], float).reshape(r, -1)
            Qp[:] = np.asarray(initial[1], float).reshape(r, -1)
        n_rec = self.steps // self.every + 1
        nm = self.Nm.shape[0]
        st = LoopState(n=0, Q=Q, Qp=Qp, done=np.zeros(P, bool),
                       u_r=[np.full((nm, n_rec[p]), np.nan) for p in range(P)],
                       lam=[np.zeros((self.nc, n_rec[p])) for p in range(P)],
                       energy=[np.full(n_rec[p], np.nan) for p in range(P)] if self.energy else None,
                       q_rec=[np.full((r, n_rec[p]), np.nan) for p in range(P)] if self.record_q else None,
                       max_pen=np.full(P, -np.inf), min_lam=np.full(P, np.inf), fric_pow=np.full(P, -np.inf),
                       contact_steps=np.zeros(P, np.int64), diverged=np.full(P, -1, np.int64))
        for p in range(P):
            st.u_r[p][:, 0] = self.Nm @ Q[:, p] - (0.0 if self.offset is None else self.offset[:, p])
            if self.record_q:
                st.q_rec[p][:, 0] = Q[:, p]
        return st

    def check_resumable(self, st: LoopState) -> LoopState:
        """``st`` if this recorder can carry it on, else ValueError."""
        if self.record_q and st.q_rec is None:
            raise ValueError("record_q=True cannot resume from a state saved without the full states (q_rec)")
        if self.energy and st.energy is None:
            raise ValueError("energy=True cannot resume from a saved state (its energies are not kept)")
        return st

    def record(self, st: LoopState, active: np.ndarray, Qn: np.ndarray, lam_now: np.ndarray, E) -> None:
        """Step ``st.n``'s record of the runs ``active`` (their states Qn, energies E or None)."""
        n = st.n
        i = n // self.every
        ur_all = self.Nm @ Qn
        if self.offset is not None:
            ur_all = ur_all - self.offset[:, active]
        for j, p in enumerate(active):
            if n <= self.steps[p]:
                st.u_r[p][:, i] = ur_all[:, j]
                st.lam[p][:, i] = lam_now[:, p]
                if self.energy:
                    st.energy[p][i] = E[j]
                    st.work_rec[p][:, i] = st.work[:, p]
                if self.record_q:
                    st.q_rec[p][:, i] = Qn[:, j]

    def record_of(self, st: LoopState, p: int) -> dict:
        """Run p's records and extremes as a dict (what ``simulate``'s ``on_finish`` receives)."""
        n_rec = self.steps[p] // self.every + 1
        return {"t": np.arange(n_rec) * self.every * self.h, "u_r": st.u_r[p], "lam": st.lam[p],
                "labels": np.array(self.labels, dtype=str),
                "energy": None if st.energy is None else st.energy[p], "q_final": st.Q[:, p].copy(),
                "q_prev": st.Qp[:, p].copy(), "omega": float(self.omega[p]), "max_penetration": float(st.max_pen[p]),
                "min_multiplier": float(st.min_lam[p]), "friction_power": float(st.fric_pow[p]),
                "contact_steps": int(st.contact_steps[p]), "diverged_step": int(st.diverged[p]),
                "work": st.work[:, p].copy(), "wall": float(st.elapsed)}


def save_loop_state(path: "str | Path", st: LoopState, speeds: np.ndarray, **extra) -> None:
    """``simulate``'s loop state ``st`` (what its ``checkpoint`` receives) to ``path`` (``save_npz``: whole or not at
    all), with the speeds it runs and the arrays ``extra`` (what identifies the runs); the full states too when the
    run records them (``record_q``)."""
    from rotor37_rom.npz import save_npz

    arrays = {**extra, "speeds": np.asarray(speeds, float), "n": st.n, "Q": st.Q, "Qp": st.Qp,
              "done": st.done, "max_pen": st.max_pen, "min_lam": st.min_lam, "fric_pow": st.fric_pow,
              "contact_steps": st.contact_steps, "diverged": st.diverged, "work": st.work, "elapsed": st.elapsed}
    for p in range(len(st.u_r)):
        arrays[f"u_r{p}"] = st.u_r[p]
        arrays[f"lam{p}"] = st.lam[p]
        if st.q_rec is not None:
            arrays[f"q_rec{p}"] = st.q_rec[p]
    save_npz(path, **arrays)


def loop_state(data, P: int) -> LoopState:
    """The loop state of ``save_loop_state``'s file (any mapping of its arrays) for ``simulate(state=...)``; P
    simulations. Energies are not kept (a run with ``energy=True`` starts over)."""
    return LoopState(n=int(data["n"]), **{k: data[k] for k in _ARRAYS},
                     work=data["work"] if "work" in data else None,   # older checkpoints: works from the resumed step
                     u_r=[data[f"u_r{p}"] for p in range(P)], lam=[data[f"lam{p}"] for p in range(P)],
                     q_rec=[data[f"q_rec{p}"] for p in range(P)] if "q_rec0" in data else None, energy=None,
                     elapsed=float(data["elapsed"]) if "elapsed" in data else 0.0)    # older checkpoints: unknown

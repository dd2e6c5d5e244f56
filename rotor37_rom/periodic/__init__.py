"""Periodic orbits and their stability (#72): harmonic balance with alternating frequency-time, Hill's method, and
arc-length continuation (``harmonic_balance``); Coulomb friction with sticking, collocated without regularisation
(``contact``); shooting of the project's explicit scheme with its casing contact, Floquet multipliers from its
monodromy (``shooting``); a tuned disk's travelling-wave response on one sector, its Hill stability per nodal
diameter (``travelling_wave``), and the full disk marched from that wave, each set of diameters' growth against Hill's
(``departure``). Pure NumPy/SciPy, on any second-order system whose nonlinear force evaluates a batch of
states with its Jacobian, as the reduced models' forces do."""
from .harmonic_balance import (Branch, Harmonics, HarmonicBalance, PeriodicProblem, PeriodicSolution, continue_branch,
    model_force, solve_periodic, time_state, backbone, bifurcation_kind, hill_eigenvalues, hill_exponents,
    harmonic_energy, square_matrices)
from .contact import CoulombFriction, ContactBalance
from .shooting import Shooting, solve_periodic_krylov
from .travelling_wave import TravellingWaveBalance, sector_turn, travelling_excitation
from .departure import SetDeparture, WaveDeparture, residue_sets, wave_departure

__all__ = ["Branch", "Harmonics", "HarmonicBalance", "PeriodicProblem", "PeriodicSolution", "continue_branch",
           "solve_periodic", "model_force", "time_state", "backbone", "bifurcation_kind", "CoulombFriction",
           "ContactBalance", "Shooting", "solve_periodic_krylov", "TravellingWaveBalance", "travelling_excitation", "wave_departure",
           "hill_eigenvalues", "hill_exponents", "harmonic_energy", "square_matrices", "sector_turn", "SetDeparture",
           "WaveDeparture", "residue_sets"]

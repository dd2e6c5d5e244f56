"""Which kernels OpenBLAS runs on this CPU, and a fix when it does not know the CPU.

Debian 12's OpenBLAS 0.3.21 (DYNAMIC_ARCH) picks its kernels from the CPU model. CPUs newer than the library (e.g.
the Xeon model 207 of the project's machines: AVX-512, AMX) are not in its table, and it falls back to 'Prescott'
(SSE3) kernels: dgemm 2000^3 ran at ~20 GFLOP/s on 2 cores instead of ~120 with the SkylakeX (AVX-512) kernels,
single-threaded 9 instead of 38. OPENBLAS_CORETYPE, read when the library loads, names the kernels to use.

``make setup`` runs this file with the system Python and no site packages (so no OPENBLAS_CORETYPE is set yet):

    python3 -S rotor37_rom/blas_check.py --pth .venv/lib/python3.11/site-packages/rotor37_openblas.pth

When OpenBLAS reports a generic core on a CPU with AVX-512 (or AVX2 + FMA), it writes a .pth file that sets
OPENBLAS_CORETYPE=SkylakeX (or Haswell) at the start of every interpreter of the virtual environment (before numpy
loads OpenBLAS; a value the user sets wins). Otherwise it removes that file. Standard library only.
"""
from __future__ import annotations

import argparse
import ctypes
import os
import sys
from pathlib import Path

GENERIC_CORES = {"prescott", "core2", "nehalem", "katmai", "coppermine", "northwood", "banias", "atom", "generic"}
AVX512 = {"avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"}


def openblas_core(library: str = "libblas.so.3") -> str | None:
    """The kernel set OpenBLAS chose ('Prescott', 'SkylakeX', ...), or None when the BLAS is not OpenBLAS."""
    try:
        lib = ctypes.CDLL(library)
        get = lib.openblas_get_corename
    except (OSError, AttributeError):
        return None
    get.restype = ctypes.c_char_p
    return get().decode()


def cpu_flags(cpuinfo: str = "/proc/cpuinfo") -> set[str]:
    try:
        for line in Path(cpuinfo).read_text().splitlines():
            if line.startswith("flags"):
                return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


def suggested_coretype(core: str | None, flags: set[str]) -> str | None:
    """The OPENBLAS_CORETYPE to force, or None when OpenBLAS already uses kernels that fit the CPU."""
    if core is None or core.lower() not in GENERIC_CORES:
        return None
    if AVX512 <= flags:
        return "SkylakeX"
    if {"avx2", "fma"} <= flags:
        return "Haswell"
    return None


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pth", type=Path, help="write (or remove) this .pth file accordingly")
    args = parser.parse_args(argv)
    if "OPENBLAS_CORETYPE" in os.environ:
        print(f"OPENBLAS_CORETYPE={os.environ['OPENBLAS_CORETYPE']} is set already: not checking", file=sys.stderr)
        return 0
    core = openblas_core()
    fix = suggested_coretype(core, cpu_flags())
    if fix is None:
        print(f"OpenBLAS kernels: {core or 'not OpenBLAS'} (fit this CPU)")
        if args.pth is not None and args.pth.exists():
            args.pth.unlink()
        return 0
    print(f"OpenBLAS kernels: {core}, generic for this CPU: using OPENBLAS_CORETYPE={fix}")
    if args.pth is not None:
        args.pth.write_text(f'import os; os.environ.setdefault("OPENBLAS_CORETYPE", "{fix}")\n')
    return 0


if __name__ == "__main__":
    sys.exit(main())

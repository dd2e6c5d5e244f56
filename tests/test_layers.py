"""Layering: only the adapter package rotor37_rom/fem/ (and the plotting modules) import dolfinx, PETSc or SLEPc;
geometry (gmsh + NumPy), forms (UFL) and every module that does not call the adapter import without them; the BLAS
under them runs kernels that fit the CPU; imports go down the layers (``RANKS``), the climbs that remain listed for
issue #87 (``CLIMBS``). The rule is a directory, checked on every file of the package."""
import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {"rotor37_rom": ROOT / "rotor37_rom", "rotor37_rom.geometry": ROOT / "geometry",
            "rotor37_rom.forms": ROOT / "forms"}
FE_LIBRARIES = ("dolfinx", "petsc4py", "slepc4py", "basix", "ffcx")
PLOTTING = {"rotor37_rom.viz.plotting", "rotor37_rom.viz._render"}         # pyvista, dolfinx.plot: rendering only


def _modules():
    """(dotted name, path) of every module of the package, its installed subpackages included."""
    for package, folder in PACKAGES.items():
        for path in sorted(folder.rglob("*.py")):
            parts = path.relative_to(folder).with_suffix("").parts
            parts = parts[:-1] if parts[-1] == "__init__" else parts
            yield ".".join((package,) + parts), path


def _imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{a.name}" for a in node.names)
    return names


def test_only_the_adapter_imports_dolfinx():
    offenders = []
    for name, path in _modules():
        if name.startswith("rotor37_rom.fem") or name in PLOTTING:
            continue
        bad = [m for m in _imports(path) if m.split(".")[0] in FE_LIBRARIES]
        if bad:
            offenders.append(f"{name}: {sorted(bad)}")
    assert not offenders, offenders


def test_pure_modules_do_not_import_dolfinx():
    """Modules that do not use the adapter (directly or through another module) load without dolfinx."""
    modules = dict(_modules())
    uses_fe = {n for n in modules if n.startswith("rotor37_rom.fem") or n in PLOTTING}
    changed = True
    while changed:                         # a module importing one that uses the adapter uses it too
        changed = False
        for name, path in modules.items():
            if name not in uses_fe and any(m in uses_fe or m.rsplit(".", 1)[0] in uses_fe and
                                           m.rsplit(".", 1)[0] != "rotor37_rom" for m in _imports(path)):
                uses_fe.add(name)
                changed = True
    pure = sorted(n for n in modules if n not in uses_fe)
    assert {"rotor37_rom.dynamics.explicit", "rotor37_rom.reduction.craig_bampton", "rotor37_rom.geometry.blade",
            "rotor37_rom.forms"} <= set(pure)
    code = ("import sys\n" + "".join(f"import {m}\n" for m in pure)
            + f"bad = [m for m in {FE_LIBRARIES + ('pyvista',)!r} if m in sys.modules]\n"
            + "assert not bad, bad\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-1500:]


def test_openblas_runs_kernels_that_fit_the_cpu():
    """make setup (rotor37_rom/blas_check.py): OpenBLAS 0.3.21 falls back to its SSE3 'Prescott' kernels on CPUs it
    does not know (dgemm 6x slower on the project's AVX-512 machines); the environment must run fitting ones."""
    import importlib

    importlib.import_module("numpy")                     # loads the BLAS with the interpreter's environment
    from rotor37_rom.blas_check import AVX512, cpu_flags, openblas_core, suggested_coretype

    assert suggested_coretype("Prescott", AVX512 | {"avx2", "fma"}) == "SkylakeX"
    assert suggested_coretype("Prescott", {"avx2", "fma", "sse3"}) == "Haswell"
    assert suggested_coretype("Prescott", {"sse3"}) is None                     # nothing better to run
    assert suggested_coretype("SkylakeX", AVX512) is None and suggested_coretype(None, AVX512) is None
    core = openblas_core()
    if core is None:
        pytest.skip("the BLAS is not OpenBLAS")
    assert suggested_coretype(core, cpu_flags()) is None, \
        f"OpenBLAS runs its generic '{core}' kernels on this CPU: run make setup (it sets OPENBLAS_CORETYPE)"


def _package_graph() -> dict[str, set[str]]:
    """The package's import graph: each module -> the modules of the package it imports (at any depth of its code,
    deferred imports included; ``from a import b`` counts as a.b where a.b is a module, else as a)."""
    modules = dict(_modules())
    graph = {}
    for name, path in modules.items():
        edges = set()
        for imported in _imports(path):
            if imported in modules:
                edges.add(imported)
            elif imported.rsplit(".", 1)[0] in modules:
                edges.add(imported.rsplit(".", 1)[0])
        graph[name] = edges - {name}
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` (a list of modules, the first repeated at the end), or None."""
    state, stack = {}, []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == "open":
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state:
                found = visit(nxt)
                if found:
                    return found
        state[node] = "closed"
        stack.pop()
        return None

    for node in sorted(graph):
        if node not in state:
            found = visit(node)
            if found:
                return found
    return None


def test_the_package_has_no_import_cycle():
    """Subpackages import one way: no module of rotor37_rom reaches itself through its imports (deferred ones too)."""
    assert _cycle(_package_graph()) is None, " -> ".join(_cycle(_package_graph()))
    # the test sees a cycle when there is one
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set(), "c": {"a", "b"}}) is None


def _subpackage(module: str) -> str:
    """The part of the package a module belongs to: its subpackage (rotor37_rom.fem, ...) or, for a module at the
    top (rotor37_rom.npz), itself."""
    return ".".join(module.split(".")[:2])


def test_subpackages_import_one_way():
    """The architecture reads from the imports: no subpackage reaches itself through another (fem uses the pure
    algebra of disk and dynamics, the builders use fem, studies use viz; never back), deferred imports included."""
    graph = {}
    for module, edges in _package_graph().items():
        graph.setdefault(_subpackage(module), set()).update(_subpackage(m) for m in edges)
    graph = {node: edges - {node, "rotor37_rom"} for node, edges in graph.items()}
    assert _cycle(graph) is None, " -> ".join(_cycle(graph))
    # a module's edges collapse onto its subpackage: a two-way import between subpackages is a cycle here
    assert _subpackage("rotor37_rom.disk.builder") == "rotor37_rom.disk" and _subpackage("rotor37_rom.npz") \
        == "rotor37_rom.npz"


def test_scripts_are_not_imported_and_do_not_touch_the_search_path():
    """The library holds the logic: no module of the package, no test, demo or benchmark imports a demo or a benchmark
    (by name or by file), and no file reads or changes the interpreter's module search path (the attribute ``path``
    of ``sys``) to find one."""
    scripts = {p.stem for folder in ("demos", "benchmarks") for p in (ROOT / folder).glob("*.py")}
    offenders = []
    for folder in ("rotor37_rom", "geometry", "forms", "tests", "demos", "benchmarks"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            text = path.read_text()
            tree = ast.parse(text)
            if any(isinstance(n, ast.Attribute) and n.attr == "path" and isinstance(n.value, ast.Name)
                   and n.value.id == "sys" for n in ast.walk(tree)):
                offenders.append(f"{path.relative_to(ROOT)}: the module search path")
            if any(isinstance(n, ast.Attribute) and n.attr == "spec_from_file_location" for n in ast.walk(tree)):
                offenders.append(f"{path.relative_to(ROOT)}: loads a file as a module")
            imported = {m.split(".")[0] for m in _imports(path)}
            if folder in ("demos", "benchmarks", "tests"):
                imported |= {n.module for n in ast.walk(tree)
                             if isinstance(n, ast.ImportFrom) and n.module and n.level == 0}
            bad = sorted(imported & scripts - {"conftest"})
            if bad:
                offenders.append(f"{path.relative_to(ROOT)}: imports {bad}")
    assert not offenders, offenders


def test_every_subpackage_is_installed():
    """pyproject.toml lists the packages setuptools installs (no discovery: forms/ and geometry/ are mapped): every
    folder of rotor37_rom with an __init__.py must be among them, or a non-editable install would lack it."""
    import tomllib

    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "rotor37_rom").rglob("__init__.py")}
    assert found <= listed, sorted(found - listed)


# The layers, lowest first (a module imports only from layers below its own, or from its own subpackage): utilities
# and the FE-free geometry and forms; the dolfinx adapter; the pure algorithms in their own order; the studies; the
# plotting and the command line. Two pure modules sit below the adapter that uses them.
RANKS = {"checks": 0, "npz": 0, "interruption": 0, "reporting": 0, "blas_check": 0, "pareto": 0, "geometry": 0, "forms": 0,
         "machine": 0.5, "disk.symmetry": 0.9, "model.modes": 0.9, "fem": 1, "forces": 2.0, "model": 2.1,
         "disk": 2.2, "dynamics": 2.3, "periodic": 2.4, "post": 2.5, "reduction": 2.6, "studies": 3, "viz": 4,
         "cli": 4}
# The imports that still climb (issue #87): the full order's time integration inside the adapter, and studies that
# draw and print themselves. The test fails on any other climb, and on a listed one that is gone (remove it here).
CLIMBS = {"rotor37_rom.fem.periodic": {"dynamics"},
          "rotor37_rom.studies.blade_modes": {"cli", "viz"}, "rotor37_rom.studies.blade_report": {"viz"},
          "rotor37_rom.studies.campbell": {"viz"}, "rotor37_rom.studies.clearance_consumption": {"cli", "viz"},
          "rotor37_rom.studies.contact_config": {"cli"}, "rotor37_rom.studies.contact_map": {"viz"},
          "rotor37_rom.studies.disk_campbell": {"viz"}, "rotor37_rom.studies.disk_modes": {"cli", "viz"},
          "rotor37_rom.studies.forced_response": {"cli"}, "rotor37_rom.studies.own_blade": {"viz"},
          "rotor37_rom.studies.rotating_disk_rom": {"viz"}, "rotor37_rom.studies.rotating_rom": {"viz"},
          "rotor37_rom.studies.speed_accuracy.charts": {"viz"}, "rotor37_rom.studies.turning_map": {"viz"}}


def _unit(dotted: str) -> str | None:
    """The layer unit of a module of the package: 'disk.symmetry' where it has its own rank, else its subpackage."""
    parts = dotted.split(".")[1:]
    if not parts:
        return None
    return ".".join(parts[:2]) if ".".join(parts[:2]) in RANKS else parts[0]


def test_imports_go_down_the_layers():
    climbs = {}
    for name, path in _modules():
        if not name.startswith("rotor37_rom.") or name.startswith(("rotor37_rom.geometry", "rotor37_rom.forms")):
            continue
        source = _unit(name)
        for target in (_unit(m) for m in _imports(path) if m.startswith("rotor37_rom.")):
            if target in RANKS and target != source and target.split(".")[0] != source.split(".")[0] \
                    and RANKS[target] >= RANKS[source]:
                climbs.setdefault(name, set()).add(target)
    assert set(RANKS) >= {_unit(n) for n, _ in _modules() if _unit(n) and "." not in _unit(n)} - {"__init__", "data"}
    assert climbs == CLIMBS


# the command line's own modules: they talk to the user; the library says (``rotor37_rom.reporting``)
PRINTING = {"rotor37_rom/cli.py", "rotor37_rom/blas_check.py"}


def test_the_library_says_and_never_prints():
    """No ``print`` call in the package below the command line (#87): the library's messages go through
    ``reporting.say``, and a caller can keep or silence them."""
    printing = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "rotor37_rom").rglob("*.py")
                      if str(p.relative_to(ROOT)) not in PRINTING
                      and any(isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "print"
                              for n in ast.walk(ast.parse(p.read_text()))))
    assert printing == []


def test_a_reporter_keeps_or_silences_what_the_library_says(capsys):
    from rotor37_rom.reporting import reporting, say

    kept = []
    with reporting(kept.append):
        say("model built:", 55, sep=" ")
        with reporting(lambda message: None):
            say("silenced")
        say("after")
    say("to stdout")
    assert kept == ["model built: 55", "after"] and capsys.readouterr().out == "to stdout\n"
    with pytest.raises(ValueError, match="reporter must be a callable"):
        with reporting("stdout"):
            pass

"""Fuzzing every entry point's every option (#70): generated bad values (nan, +-inf, 0, negative, huge, not a
number, empty, reversed ranges, bad paths) give one line on stderr naming the option and exit status 2, or, where a
value is legitimate (0 friction, a descending list of nodal diameters), a clean dry run; never a traceback, never
a run, never a file written. Kept in the fast suite: the options come from each command's own --help, and one Python
process per entry point runs all of its cases as the shell would run the script (``runpy``, as ``__main__``, with
``--check`` added so that an accepted value stops before any work), with gmsh unusable."""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ENTRY_POINTS = ["demos/contact_map.py", "demos/report.py", "demos/reduced_blade.py", "demos/blade_modes.py",
                "demos/bladed_disk.py", "demos/own_blade.py", "benchmarks/bench_disk_forced.py"]
NUMBERS = ["nan", "inf", "-inf", "1e300", "abc", ""]          # never a valid value of a numeric option
MAYBE = ["0", "-1", "-0.5"]                                  # valid for some options, refused by the others
PATHS = ("--out", "--cache", "--model", "--mesh", "--table")
NAMES = ("--clamp", "--tip")                                # free names: only an empty one is refused

# what runs each case: the script as __main__ with argv, stdout and stderr captured, gmsh unusable
DRIVER = r'''
import io, json, runpy, sys, traceback, types
class _Stub:
    def __getattr__(self, name):
        return self
    def __call__(self, *a, **k):
        raise RuntimeError("meshing started before the options were checked")
gmsh = types.ModuleType("gmsh")
gmsh.__getattr__ = lambda name: _Stub()
sys.modules["gmsh"] = gmsh
script, cases = sys.argv[1], json.loads(sys.stdin.read())
results = []
for argv in cases:
    out, err = io.StringIO(), io.StringIO()
    sys.argv = [script, *argv, "--check"]
    sys.stdout, sys.stderr = out, err
    code, trace = None, ""
    try:
        runpy.run_path(script, run_name="__main__")
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except BaseException:
        trace = traceback.format_exc()
        code = 1
    finally:
        sys.stdout, sys.stderr = sys.__stdout__, sys.__stderr__
    results.append({"argv": argv, "code": code, "out": out.getvalue(), "err": err.getvalue(), "trace": trace})
print(json.dumps(results))
'''


def options_of(script: str) -> dict[str, int]:
    """The options of a command that take values, and how many: read from its --help."""
    helps = subprocess.run([sys.executable, script, "--help"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert helps.returncode == 0, helps.stderr
    found = {}
    for line in helps.stdout.split("options:")[-1].splitlines():
        m = re.match(r"\s{2}(--[\w-]+)((?: (?:\{[^}]*\}|[A-Z_]+|\[[A-Z_]+ \.\.\.\]))*)", line)
        if m and m.group(1) not in ("--help", "--check"):
            metavars = m.group(2).split()
            found[m.group(1)] = sum(1 for v in metavars if not v.startswith("[") and v != "...]") or (
                1 if metavars else 0)
    return found


def cases_of(options: dict[str, int], tmp: Path) -> list[tuple[list[str], str, bool]]:
    """(argv, the option it concerns, may it be accepted) for every option and generated value."""
    a_file = tmp / "notes.txt"
    a_file.write_text("not what any option wants\n")
    cases = []
    for option, n in options.items():
        if n == 0:
            continue
        if option in PATHS:
            bad = ["/proc/rotor37_fuzz", str(a_file / "below")]
            bad += [str(tmp), ""] if option in ("--model", "--mesh", "--table") else [str(a_file)]
            cases += [([option, value], option, False) for value in bad]
            if option in ("--out", "--cache"):
                cases.append(([option, ""], option, True))           # the current folder
            continue
        if option in NAMES:
            cases += [([option, value], option, value != "") for value in NUMBERS]
            continue
        if option == "--name":                                  # a results file's suffix: not a path
            cases += [([option, value], option, value != "../x") for value in ["abc", "", "../x"]]
            continue
        cases += [([option, *[value] * n], option, False) for value in NUMBERS]
        cases += [([option, *[value] * n], option, True) for value in MAYBE]
        if n >= 2:
            cases.append(([option, *[str(v) for v in range(n + 1000, 1000, -1)]], option, True))   # reversed
    return cases


@pytest.mark.parametrize("script", ENTRY_POINTS)
def test_fuzz_entry_point(script, tmp_path):
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    options = options_of(script)
    assert len(options) >= 4, options
    cases = cases_of(options, tmp_path)
    env = dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    run = subprocess.run([sys.executable, "-c", DRIVER, str(ROOT / script)], input=json.dumps([c[0] for c in cases]),
                         cwd=cwd, env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    results = json.loads(run.stdout.splitlines()[-1])
    problems = []
    for (argv, option, may_pass), res in zip(cases, results):
        lines = res["err"].strip().splitlines()
        if res["trace"] or "Traceback" in res["err"]:
            problems.append(f"{argv}: traceback {(res['trace'] or res['err'])[-300:]}")
        elif res["code"] == 2:
            if len(lines) != 1 or not lines[0].startswith("error: ") or option not in lines[0]:
                problems.append(f"{argv}: not one line naming {option}: {res['err']!r}")
        elif res["code"] == 0 and may_pass:
            if "nothing was run" not in res["out"]:
                problems.append(f"{argv}: accepted without a dry run: {res['out'][-200:]!r}")
        else:
            problems.append(f"{argv}: exit {res['code']} (accepted: {may_pass}) {res['err'][-200:]!r}")
    assert not problems, f"{len(problems)} of {len(cases)} cases:\n" + "\n".join(problems)
    assert not any(cwd.iterdir()), "a refused or dry run wrote files"
    print(f"{script}: {len(cases)} cases, {sum(r['code'] == 2 for r in results)} refused")

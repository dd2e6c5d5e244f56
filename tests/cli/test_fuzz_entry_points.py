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

ROOT = Path(__file__).resolve().parents[2]
ENTRY_POINTS = ["demos/contact_map.py", "demos/report.py", "demos/reduced_blade.py", "demos/blade_modes.py",
                "demos/bladed_disk.py", "demos/own_blade.py", "benchmarks/bench_disk_forced.py",
                "demos/turning_map.py", "demos/campbell.py", "demos/disk_campbell.py",
                "benchmarks/bench_periodic_nfrc.py", "benchmarks/bench_travelling_wave.py",
                "benchmarks/bench_disk_contact.py", "benchmarks/bench_disk_cubature.py",
                "benchmarks/bench_disk_gnl_coupling.py", "benchmarks/bench_disk_map.py",
                "benchmarks/bench_disk_mistuning.py", "benchmarks/bench_gnl_vs_linear.py",
                "benchmarks/disk_backbone.py", "benchmarks/plot_disk_indicator.py", "benchmarks/speed_accuracy.py",
                "benchmarks/bench_gnl_steady.py", "benchmarks/bench_impact_numbers.py",
                "benchmarks/bench_integrator.py"]
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
                cases.append(([option, ""], option, False))          # not the current folder: refused (#85)
                cases.append(([option, "."], option, True))          # the current folder, said so
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


# ---- #85 item 9 and its rough edges: each case one line naming the option, exit status 2, no traceback, caught by
# the dry run (--check, added by DRIVER) as a real run would refuse it. '{blade}' and '{disk}' are saved reduced models
# (their small entries: what --check reads), '{text}' a text file that is no model.
GIB = 2 ** 30
REFUSED = {
    "demos/contact_map.py": [
        (["--model", "{blade}", "--r-c", "5"], "--r-c"),                 # was run on the saved model, --r-c ignored
        (["--model", "{blade}", "--preset", "coarse"], "--preset"),
        (["--model", "{disk}", "--disk", "--stress", "--mistuning", "0.02"], "--mistuning"),
        (["--seed", "3"], "--seed"),                                     # was ignored without --mistuning
        (["--disk", "--seed", "3"], "--seed"),
        (["--continuation-range", "1300", "1400"], "--continuation-range"),     # was ignored without --continuation
        (["--steady-window", "2"], "--steady-window"),
        (["--unsteady-step", "full"], "--unsteady-step"),
        (["--r-cyclic", "100"], "--r-cyclic"),
        (["--disk", "--global-md", "5"], "--global-md"),
        (["--out", ""], "--out"),                                        # was the current folder
        (["--cache", ""], "--cache"),
        (["--speeds", "1200", "1600", "1e9"], "--speeds"),               # grew to 6.6 GB in 32 s
        (["--speeds", "1200", "1600", "1e300"], "--speeds"),
        (["--speeds", "100", "1600", "10000", "--revolutions", "200"], "--speeds"),   # ~900 GiB read back for the map
        (["--r-c", "5000"], "--r-c"),                                    # was accepted at --check
        (["--r-c", "400"], "--r-c"),                                     # r = 430: 128 GiB of cubic tensors
        (["--r-md", "3000"], "--r-md"),
    ],
    "demos/report.py": [
        (["--r-c", "5000"], "--r-c"),
        (["--r-c", "400"], "--r-c"),
    ],
    "demos/turning_map.py": [
        (["--speeds", "1400", "1900", "1e9"], "--speeds"),
        (["--speeds", "1400", "1900", "1e300"], "--speeds"),
        (["--speeds", "1400", "5000", "3"], "--speeds"),                 # a turning model built beyond the blade's
        (["--continuation", "5", "--continuation-range", "1400", "5000"], "--continuation-range"),
        (["--model", "{blade}", "--r-c", "20"], "--r-c"),
        (["--out", ""], "--out"),
    ],
    "demos/campbell.py": [
        (["--speeds", "0", "2000", "inf"], "--speeds"),                  # was an OverflowError
        (["--speeds", "0", "2000", "nan"], "--speeds"),
        (["--speeds", "0", "1e6", "3"], "--speeds"),                     # was a Newton RuntimeError
        (["--speeds", "0", "2000", "1e9"], "--speeds"),
        (["--speeds", "0", "2000", "1e300"], "--speeds"),
        (["--refine", "1e300"], "--refine"),
        (["--out", ""], "--out"),
    ],
    "demos/disk_campbell.py": [
        (["--speeds", "0", "2000", "inf"], "--speeds"),
        (["--speeds", "0", "1e6", "3"], "--speeds"),
        (["--speeds", "0", "2000", "1e9"], "--speeds"),
        (["--speeds", "0", "2000", "1e300"], "--speeds"),
        (["--zzenf-speed", "1e5"], "--zzenf-speed"),
        (["--out", ""], "--out"),
    ],
    "benchmarks/bench_periodic_nfrc.py": [
        (["--out", "/proc/rotor37_fuzz"], "--out"),                      # was found after hours of work
        (["--cache", "/proc/rotor37_fuzz"], "--cache"),
        (["--out", ""], "--out"),
        (["--cache", ""], "--cache"),
        (["--model", "{text}"], "--model"),                              # was a traceback
        (["--model", "{disk}"], "--model"),
        (["--model", "{blade}", "--r-c", "5"], "--r-c"),
        (["--step", "inf"], "--step"),
        (["--max-points", "0"], "--max-points"),
        (["--range", "1300", "inf"], "--range"),
        (["--speeds", "1200", "1600", "1e9"], "--speeds"),
    ],
    "benchmarks/bench_travelling_wave.py": [
        (["--force", "inf"], "--force"),                                 # was taken
        (["--step", "inf"], "--step"),
        (["--departure", "inf"], "--departure"),
        (["--departure", "1200", "inf"], "--departure"),
        (["--max-points", "0"], "--max-points"),
        (["--max-points", "-5"], "--max-points"),
        (["--model", "{text}"], "--model"),                              # was a traceback
        (["--model", "{blade}"], "--model"),
        (["--model", "{disk}", "--k", "18"], "--k"),
        (["--model", "{disk}", "--cache", "cache"], "--cache"),
        (["--periods", "20"], "--periods"),
        (["--departure", "1200", "--every", "3"], "--every"),
        (["--range", "0.9", "inf"], "--range"),
        (["--name", "../x"], "--name"),
    ],
}
# what the dry run still accepts (no refusal of what has an effect)
ACCEPTED = {
    "demos/contact_map.py": [["--model", "{blade}"], ["--model", "{disk}", "--disk", "--stress", "--preset", "ci"],
                             ["--disk", "--mistuning", "0.02", "--seed", "3"], ["--out", "."],
                             ["--continuation", "5", "--continuation-range", "1300", "1400", "--steady-window", "2"],
                             ["--periodic", "0.05", "--continuation-range", "1300", "1400"]],
    "demos/turning_map.py": [["--speeds", "1400", "3000", "3"], ["--model", "{blade}"]],
    "demos/campbell.py": [["--speeds", "0", "3000", "11"], ["--refine", "0"]],
    "demos/disk_campbell.py": [["--zzenf-speed", "3000"]],
    "benchmarks/bench_periodic_nfrc.py": [[], ["--model", "{blade}"], ["--range", "1300", "1400"]],
    "benchmarks/bench_travelling_wave.py": [[], ["--model", "{disk}"], ["--departure", "1200", "--periods", "20"],
                                            ["--cache", "c", "--no-full"]],
}


def saved_model(path: Path, disk: bool) -> Path:
    """A stand-in saved reduced model: the small entries a dry run reads (its meta with a matching key, its forces'
    kind and its nodes), a blade's or a tuned bladed disk's with GNL forces."""
    import numpy as np

    from rotor37_rom.model.reduced import reduced_model_key

    metadata = {"source": "a test's stand-in"} | ({"kind": "disk", "n_sectors": 36, "config": {"mistuning": None}}
                                                  if disk else {})
    sizes = {"r_b": 24, "r_c": 1, "r_md": 0} | ({"n_sectors": 36} if disk else {})
    meta = {"metadata": metadata, "sizes": sizes, "key": reduced_model_key(metadata)}
    np.savez(path, meta=np.array(json.dumps(meta)),
             forces=np.array("sector_polynomial" if disk else "polynomial"), nodes_names=np.array(["LE", "TE"]))
    return path


def drive(script: str, cases: list[list[str]], tmp: Path) -> tuple[list[dict], Path]:
    """Run ``cases`` of ``script`` (each with --check) in one process through DRIVER, from an empty folder; the
    placeholders filled in."""
    cwd = tmp / "cwd"
    cwd.mkdir()
    text = tmp / "notes.txt"
    text.write_text("not a reduced model\n")
    files = {"blade": saved_model(tmp / "blade.npz", False), "disk": saved_model(tmp / "disk.npz", True),
             "text": text}
    argvs = [[a.format(**files) for a in argv] for argv in cases]
    env = dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    run = subprocess.run([sys.executable, "-c", DRIVER, str(ROOT / script)], input=json.dumps(argvs), cwd=cwd,
                         env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    return json.loads(run.stdout.splitlines()[-1]), cwd


@pytest.mark.parametrize("script", list(REFUSED))
def test_refused_in_one_line_by_the_dry_run(script, tmp_path):
    """#85 (9): each case of ``REFUSED`` exits with status 2 and one line on stderr naming its option, no traceback,
    caught by --check before any work; the Campbell studies' memory is checked too where this machine is too small
    for the case."""
    from rotor37_rom.checks import physical_memory

    cases = list(REFUSED[script])
    memory = {"demos/campbell.py": (["--speeds", "0", "2000", "1000", "--preset", "paper", "--modes", "20",
                                     "--coriolis"], 26.5 * GIB),
              "demos/disk_campbell.py": (["--speeds", "0", "2000", "1000", "--preset", "paper", "--modes", "10"],
                                         158 * GIB)}
    if script in memory and 0.8 * physical_memory() < memory[script][1]:
        cases.append((memory[script][0], "--speeds"))
    results, cwd = drive(script, [argv for argv, _ in cases], tmp_path)
    problems = []
    for (argv, option), res in zip(cases, results):
        lines = res["err"].strip().splitlines()
        if res["trace"] or "Traceback" in res["err"] or res["code"] != 2:
            problems.append(f"{argv}: exit {res['code']} {(res['trace'] or res['err'])[-300:]!r}")
        elif len(lines) != 1 or not lines[0].startswith("error: ") or option not in lines[0]:
            problems.append(f"{argv}: not one line naming {option}: {res['err']!r}")
        elif "nothing was run" in res["out"]:
            problems.append(f"{argv}: a dry run passed too: {res['out']!r}")
    assert not problems, f"{len(problems)} of {len(cases)} cases:\n" + "\n".join(problems)
    assert not any(cwd.iterdir()), "a refused run wrote files"


@pytest.mark.parametrize("script", list(ACCEPTED))
def test_what_has_an_effect_is_still_accepted(script, tmp_path):
    """The refusals above leave alone the combinations where the options act (--preset and --disk name --stress's
    mesh with --model, --seed with --mistuning, the continuation's options with --continuation, --periodic's range,
    the benchmarks' defaults): a clean dry run, nothing written."""
    results, cwd = drive(script, ACCEPTED[script], tmp_path)
    bad = [f"{res['argv']}: exit {res['code']} {(res['trace'] or res['err'])[-300:]!r}" for res in results
           if res["code"] != 0 or "nothing was run" not in res["out"]]
    assert not bad, "\n".join(bad)
    assert not any(cwd.iterdir()), "a dry run wrote files"


def test_bench_periodic_nfrc_checks_its_folders_before_any_work(tmp_path):
    """A real run (no --check) of the NFRC benchmark refuses an --out it cannot write in at once, in one line; it
    found it after the orbits and the map's probe (hours)."""
    run = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_periodic_nfrc.py"), "--out",
                          "/proc/rotor37_fuzz", "--cache", str(tmp_path / "cache")], cwd=tmp_path,
                         env=dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1"), capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 2, run.stderr[-2000:]
    assert run.stderr.strip().splitlines() == ["error: --out: cannot write in /proc/rotor37_fuzz (/proc is on a "
                                               "pseudo file system, proc)"]
    assert run.stdout == "" and not (tmp_path / "cache").exists()


@pytest.mark.parametrize("script, options", [
    ("benchmarks/bench_periodic_nfrc.py", ["--out", "{tmp}/out"]),
    ("benchmarks/bench_travelling_wave.py", ["--cache", "{tmp}/cache", "--name", "sigterm_test"]),
])
def test_sigterm_ends_a_benchmark_with_one_line(script, options, tmp_path):
    """SIGTERM while a benchmark works (its model being built) ends it with one line saying how to resume and exit
    status 128 + 15 (``rotor37_rom.cli.run_main``), not a silent kill."""
    import select
    import signal
    import time

    argv = [a.format(tmp=tmp_path) for a in options]
    proc = subprocess.Popen([sys.executable, str(ROOT / script), *argv], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1"))
    try:
        ready, _, _ = select.select([proc.stdout], [], [], 120)      # the plan, said once the options are checked
        first = proc.stdout.readline() if ready else ""
        assert first.startswith(Path(script).stem + ":"), f"no plan said in 120 s: {first!r}"
        time.sleep(1.0)                                        # working: imports, meshing, the model's build
        proc.send_signal(signal.SIGTERM)
        try:
            _, err = proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:                      # a first signal swallowed: a second always stops it
            proc.send_signal(signal.SIGTERM)
            _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 128 + signal.SIGTERM, err[-2000:]
    assert "Traceback" not in err
    assert err.strip().splitlines()[-1].startswith("stopped by SIGTERM: run the same command again"), err[-2000:]

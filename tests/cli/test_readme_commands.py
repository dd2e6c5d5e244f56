"""The README's commands run as written (#70): every `python demos/...` and `python benchmarks/...` command it quotes
(its scenes table and its text) parses, and the demos' and the forced-response benchmark's pass their own checks in a
dry run (``--check``: the options, files and folders checked, nothing meshed or written, exit status 0); a benchmark
without a dry run must at least know every option the README gives it (its --help); a `make` target must exist.

An option renamed or removed, a range tightened or a combination that a configuration refuses fails here. The dry
runs are made with gmsh unusable (a stand-in module first on the path and in the driver), so a command that meshes
before it is checked fails too. The commands of one script run in one Python process (as the fuzz test's cases)."""
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def readme_commands() -> list[str]:
    """Every command quoted in the README (a code span or a line of a shell block) that runs a demo or a benchmark,
    or a make target."""
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```bash\n(.*?)```", text, re.S)               # fenced shell blocks, line by line
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    spans = re.findall(r"`([^`\n]+)`", text) + [ln for b in blocks for ln in b.splitlines()]
    return sorted({s.strip() for s in spans if re.search(r"\bpython (demos|benchmarks)/\S+\.py", s)
                   or re.fullmatch(r"make [a-z-]+", s.strip())})


def script_and_options(command: str) -> tuple[str, list[str]]:
    """The script (demos/x.py) and its options: an environment prefix, mpirun and a trailing ellipsis dropped."""
    words = shlex.split(command.replace("…", ""))
    start = next(i for i, w in enumerate(words) if re.fullmatch(r"(demos|benchmarks)/\S+\.py", w))
    return words[start], words[start + 1:]


def test_the_readme_quotes_the_entry_points():
    commands = readme_commands()
    scripts = {script_and_options(c)[0] for c in commands if "python" in c}
    assert {"demos/contact_map.py", "demos/report.py", "demos/blade_modes.py", "demos/reduced_blade.py",
            "demos/bladed_disk.py", "demos/own_blade.py", "benchmarks/bench_disk_forced.py"} <= scripts
    assert len(commands) >= 25


@pytest.fixture(scope="module")
def no_meshing(tmp_path_factory):
    folder = tmp_path_factory.mktemp("no_gmsh")
    # any call into gmsh fails (an attribute may be looked up: dolfinx's gmshio annotates with gmsh.model)
    (folder / "gmsh.py").write_text("class _Stub:\n"
                                    "    def __getattr__(self, name):\n"
                                    "        return self\n"
                                    "    def __call__(self, *args, **kwargs):\n"
                                    "        raise RuntimeError('the command started meshing before its checks')\n"
                                    "def __getattr__(name):\n"
                                    "    return _Stub()\n")
    path = os.pathsep.join([str(folder), *filter(None, [os.environ.get("PYTHONPATH")])])
    return dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path, OPENBLAS_NUM_THREADS="1")


@pytest.fixture(scope="module")
def dry_runs(no_meshing, tmp_path_factory) -> dict:
    """command -> (its dry run's result, its script's --help result or None): the commands of one script run in one
    Python process, each as the shell would run it (``runpy`` as ``__main__``, ``--check`` added, gmsh unusable: the
    fuzz test's driver), a script without a dry run asked for its --help."""
    import json

    from test_fuzz_entry_points import DRIVER

    folder = tmp_path_factory.mktemp("readme")
    # placeholders of the user's own files: an (empty) file of the right kind; the dry run does not read it
    stand_in = folder / "my_blade.inp"
    stand_in.write_text("")
    by_script = {}
    for command in readme_commands():
        if not command.startswith("make "):
            script, options = script_and_options(command)
            options = [str(stand_in) if o in ("F", "my_blade.inp", "disk_mm.inp") else o for o in options]
            by_script.setdefault(script, []).append((command, options))

    def drive(script, cases):
        # a dry run where results would go: the output folders are checked where the README puts them
        run = subprocess.run([sys.executable, "-c", DRIVER, str(ROOT / script)], input=json.dumps(cases), cwd=ROOT,
                             env=no_meshing, capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, run.stderr[-3000:]
        return json.loads(run.stdout.splitlines()[-1])

    results = {}
    for script, commands in by_script.items():
        runs = drive(script, [options for _, options in commands])
        helps = None
        if any("unrecognized arguments: --check" in r["err"] for r in runs):
            (helps,) = drive(script, [["--help"]])
        for (command, options), run in zip(commands, runs):
            results[command] = (options, run, helps)
    return results


@pytest.mark.parametrize("command", readme_commands())
def test_readme_command(command, dry_runs):
    if command.startswith("make "):
        target = command.split()[1]
        assert re.search(rf"^{re.escape(target)}:", (ROOT / "Makefile").read_text(), re.M), command
        return
    options, run, helps = dry_runs[command]
    assert not run["trace"], (command, run["trace"][-1500:])
    earlier = [o for o in options if o.startswith("results/") and o.endswith(".npz")]
    if earlier and run["code"] == 2:     # it reads what another scene writes first: a clean clone has none, said so
        assert run["err"].count("\n") == 1 and f"{earlier[0]} does not exist" in run["err"], (command, run["err"])
        return
    if "unrecognized arguments: --check" not in run["err"]:            # a command with a dry run
        assert run["code"] == 0 and "nothing was run" in run["out"], (command, run["err"][-1500:])
    else:                                                                # without one: its --help knows the options
        assert helps["code"] == 0, helps["err"][-1500:]
        given = {o.split("=")[0] for o in options if o.startswith("--")}
        unknown = sorted(o for o in given if not re.search(rf"(^|[\s,\[]){re.escape(o)}\b", helps["out"]))
        assert not unknown, f"{command}: {script_and_options(command)[0]} has no option {unknown}"

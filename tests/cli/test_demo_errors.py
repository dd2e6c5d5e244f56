"""One kind of error (#18): every demo refuses a bad preset, a file that is not the model it asks for, and numbers out
of range with one line on stderr naming the option, exit status 2, before any meshing and before writing anything.

Each demo runs as a script, as a user types it (its ``__main__`` calls rotor37_rom.cli.run_main), with gmsh made to
fail if anything tries to mesh (a stand-in ``gmsh`` module first on the path): one line on stderr, no traceback, exit
status 2, nothing on stdout and nothing written."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

# demo -> {case: (arguments, the option the error must name)}; '{text}' is a text file that is no model at all
CASES = {
    "blade_modes": {"preset": (["--preset", "huge"], "--preset"), "model file": (["--table", "{text}"], "--table"),
                    "numbers": (["--modes", "0"], "--modes")},
    "reduced_blade": {"preset": (["--preset", "huge"], "--preset"), "model file": (["--table", "{text}"], "--table"),
                      "numbers": (["--levels", "0"], "--levels")},
    "contact_map": {"preset": (["--preset", "huge"], "--preset"), "model file": (["--model", "{text}"], "--model"),
                    "numbers": (["--revolutions", "-1"], "--revolutions"),
                    "patch": (["--contact-patch", "0.05"], "--contact-patch"),
                    "step outliers": (["--step-outliers", "drop"], "--step-outliers"),   # needs --frequency-cap
                    "perturbation": (["--perturbation", "0.02"], "--perturbation"),
                    "rotation": (["--rotation", "running", "--disk"], "--rotation"),
                    "seed without mistuning": (["--disk", "--seed", "4"], "--seed"),             # #85 (9)
                    "range without continuation": (["--continuation-range", "1300", "1400"], "--continuation-range"),
                    "count": (["--speeds", "1200", "1600", "1e300"], "--speeds")},
    "turning_map": {"cubature": (["--gnl", "on", "--cubature", "1e-4"], "--rotation"),
                    "count": (["--speeds", "1400", "1900", "1e9"], "--speeds"),                  # #85 (9)
                    "beyond the blade": (["--speeds", "1400", "5000", "3"], "--speeds")},
    "report": {"preset": (["--preset", "huge"], "--preset"), "model file": (["--table", "{text}"], "--table"),
               "numbers": (["--speeds", "1600", "1200", "5"], "--speeds")},
    "bladed_disk": {"preset": (["--preset", "huge"], "--preset"), "model file": (["--table", "{text}"], "--table"),
                    "numbers": (["--modes", "99"], "--modes")},
    "campbell": {"preset": (["--preset", "huge"], "--preset"), "numbers": (["--speeds", "0", "-5", "3"], "--speeds"),
                 "orders": (["--orders", "0", "4"], "--orders"), "refine": (["--refine", "-1"], "--refine"),
                 "infinite count": (["--speeds", "0", "2000", "inf"], "--speeds"),                # #85 (9)
                 "beyond the blade": (["--speeds", "0", "1e6", "3"], "--speeds")},
    "disk_campbell": {"preset": (["--preset", "huge"], "--preset"),
                      "numbers": (["--speeds", "0", "-5", "3"], "--speeds"),
                      "families": (["--families", "19"], "--families"), "modes": (["--modes", "0"], "--modes"),
                      "orders": (["--orders", "0", "4"], "--orders"), "refine": (["--refine", "-1"], "--refine"),
                      "zzenf": (["--zzenf-speed", "-1"], "--zzenf-speed"),
                      "infinite count": (["--speeds", "0", "2000", "inf"], "--speeds"),           # #85 (9)
                      "beyond the blade": (["--speeds", "0", "1e6", "3"], "--speeds")},
}




@pytest.fixture
def not_a_model(tmp_path):
    text = tmp_path / "notes.txt"
    text.write_text("not a blade table, not a reduced model\n")
    return text


@pytest.fixture
def no_meshing(tmp_path):
    """The environment of a demo run in which any use of gmsh fails (a stand-in ``gmsh`` module first on the path,
    whose every attribute raises: a traceback and exit status 1, not the one line of a refused input)."""
    folder = tmp_path / "no_gmsh"
    folder.mkdir()
    (folder / "gmsh.py").write_text("def __getattr__(name):\n"
                                    "    raise RuntimeError('the demo started meshing before refusing its input')\n")
    path = os.pathsep.join([str(folder), *filter(None, [os.environ.get("PYTHONPATH")])])
    return dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path)


def run_demo(demo: str, argv: list[str], env: dict | None = None) -> subprocess.CompletedProcess:
    """demos/<demo>.py run as a script from the repository's root."""
    return subprocess.run([sys.executable, str(ROOT / "demos" / f"{demo}.py"), *argv], cwd=ROOT,
                          env=env or dict(os.environ, MPLBACKEND="Agg"), capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("demo, case", [(d, c) for d, cases in CASES.items() for c in cases])
def test_bad_input_is_one_line(demo, case, not_a_model, no_meshing, tmp_path):
    args, option = CASES[demo][case]
    out = tmp_path / "out"
    argv = [a.format(text=not_a_model) for a in args] + ["--out", str(out)]
    run = run_demo(demo, argv, env=no_meshing)
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {option}"), run.stderr
    assert run.stdout == "" and not out.exists()


def test_argparse_errors_are_one_line_too():
    """What argparse refuses itself (not a number, an unknown option) is one line with exit status 2 as well."""
    for argv, words in ((["--revolutions", "abc"], "--revolutions"), (["--frobnicate"], "--frobnicate")):
        run = run_demo("report", argv)
        assert run.returncode == 2
        err = run.stderr
        assert err.count("\n") == 1 and err.startswith("error: ") and words in err, err


def test_a_stop_caught_as_another_error_is_still_said_as_a_stop(capsys):
    """SIGTERM caught on its way by a library's ``except Exception`` and raised again as a ValueError (as
    ``fem.sector.build_on_rank0`` does with gmsh's failures, while a demo or a benchmark meshes) still ends the
    command as stopped: one line on how to resume, exit status 128 + 15, not 'error: gmsh failed' and status 2."""
    import signal
    import time

    from rotor37_rom.cli import run_main

    def main(argv):
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)
        except Exception as exc:
            raise ValueError(f"gmsh failed on the disk sector ({exc})") from None
        return 0

    assert run_main(main, []) == 128 + signal.SIGTERM
    assert capsys.readouterr().err == ("stopped by SIGTERM: run the same command again to resume from the last "
                                       "checkpoint\n")

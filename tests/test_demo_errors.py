"""One kind of error (#18): every demo refuses a bad preset, a file that is not the model it asks for, and numbers out
of range with one line on stderr naming the option, exit status 2, before any meshing and before writing anything.

In-process through each demo's ``main`` (rotor37_rom.cli.run_main, as its ``__main__`` does), with gmsh made to fail
if anything tries to mesh; then once per demo as a script, as a user types it."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rotor37_rom.cli import run_main
from conftest import load_demo  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]

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
                    "perturbation": (["--perturbation", "0.02"], "--perturbation")},
    "report": {"preset": (["--preset", "huge"], "--preset"), "model file": (["--table", "{text}"], "--table"),
               "numbers": (["--speeds", "1600", "1200", "5"], "--speeds")},
    "bladed_disk": {"preset": (["--preset", "huge"], "--preset"), "model file": (["--table", "{text}"], "--table"),
                    "numbers": (["--modes", "99"], "--modes")},
}




@pytest.fixture
def not_a_model(tmp_path):
    text = tmp_path / "notes.txt"
    text.write_text("not a blade table, not a reduced model\n")
    return text


@pytest.fixture
def no_meshing(monkeypatch):
    """Any attempt to start gmsh fails the test (a RuntimeError is not the ValueError the demos turn into a line)."""
    import gmsh

    def refuse(*args, **kwargs):
        raise RuntimeError("the demo started meshing before refusing its input")

    monkeypatch.setattr(gmsh, "initialize", refuse)


@pytest.mark.parametrize("demo, case", [(d, c) for d, cases in CASES.items() for c in cases])
def test_bad_input_is_one_line(demo, case, not_a_model, no_meshing, tmp_path, capsys):
    args, option = CASES[demo][case]
    out = tmp_path / "out"
    argv = [a.format(text=not_a_model) for a in args] + ["--out", str(out)]
    assert run_main(load_demo(demo).main, argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {option}"), captured.err
    assert captured.out == "" and not out.exists()


def test_argparse_errors_are_one_line_too(capsys):
    """What argparse refuses itself (not a number, an unknown option) is one line with exit status 2 as well."""
    module = load_demo("report")
    for argv, words in ((["--revolutions", "abc"], "--revolutions"), (["--frobnicate"], "--frobnicate")):
        with pytest.raises(SystemExit) as stop:
            module.build_parser().parse_args(argv)
        assert stop.value.code == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("error: ") and words in err, err


@pytest.mark.parametrize("demo", list(CASES))
def test_script_bad_numbers(demo, tmp_path):
    """The script itself, as a user runs it: one line on stderr, no traceback, exit status 2, nothing written."""
    args, option = CASES[demo]["numbers"]
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, str(ROOT / "demos" / f"{demo}.py"), *args, "--out", str(out)],
                         env=dict(os.environ, MPLBACKEND="Agg"), capture_output=True, text=True, timeout=120)
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {option}"), run.stderr
    assert not out.exists()

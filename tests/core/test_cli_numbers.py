"""Every number option of every command, given hostile values (NaN, infinities, 1e308, 1e-308,
integers of 20 digits): refused in one line or run, never an "internal error".

The options are found in the parser itself, so an option added later is covered too."""

import argparse

import pytest

from maizeviz.cli import build_parser, main
from maizeviz.numbers import NUMBER_ARG, WHOLE_ARG

FLOATS = ("nan", "inf", "-inf", "1e308", "-1e308", "1e-308", "-5")
INTS = ("-99999999999999999999", "99999999999999999999", "0", "-1")
#: Cheap runs of each command into which one option is added (tiny.csv: one plant of 15 leaves).
BASE = {
    "leaf": ["leaf", "tiny.csv"],
    "canopy": ["canopy", "tiny.csv"],
    "light": ["light", "tiny.csv", "--sun-zenith", "10", "--sun-azimuth", "0", "--density",
              "0.05", "--heights", "0"],
    "synth": ["synth", "--plants", "1x1", "--sections", "3", "--points-across", "3", "--out",
              "o.csv"],
    "import-phenomenal": ["import-phenomenal", "PHENO", "--out", "o.csv"],
}
#: Options that only mean something in a period or a sky.
PERIOD = ["light", "tiny.csv", "--day", "--date", "2005-08-01", "--lat", "40", "--lon", "116",
          "--density", "0.05", "--heights", "0", "--sky-directions", "6", "--step", "240"]
SKY = ["light", "tiny.csv", "--sky", "soc", "--density", "0.05", "--heights", "0"]


def _cases():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name in BASE:
        for action in sub.choices[name]._actions:
            if action.type not in (NUMBER_ARG, WHOLE_ARG) or not action.option_strings:
                continue
            flag = action.option_strings[0]
            for value in FLOATS if action.type is NUMBER_ARG else INTS:
                yield pytest.param(name, flag, value, id=f"{name}{flag}={value}")


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    folder = tmp_path_factory.mktemp("numbers")
    assert main(["synth", "--plants", "1x1", "--sections", "4", "--points-across", "3",
                 "--out", str(folder / "tiny.csv")]) == 0
    return folder


@pytest.mark.parametrize("name, flag, value", list(_cases()))
def test_hostile_numbers_are_one_line_or_run(capsys, monkeypatch, tiny, name, flag, value):
    from maizeviz.resources import example_phenomenal

    monkeypatch.chdir(tiny)
    argv = list(BASE[name])
    if name == "light" and flag in ("--step", "--linke-turbidity", "--par-factor", "--altitude",
                                    "--lat", "--lon"):
        argv = list(PERIOD)
    elif name == "light" and flag == "--sky-directions":
        argv = list(SKY)
    argv = [str(example_phenomenal()) if a == "PHENO" else a for a in argv]
    if flag in argv:                                   # drop the base's value
        k = argv.index(flag)
        del argv[k:k + 2]
    argv.append(f"{flag}={value}")                     # "=": argparse reads "-inf" as a value
    code = main(argv)
    err = capsys.readouterr().err
    assert "internal error" not in err and "Traceback" not in err, err[-500:]
    errors = [ln for ln in err.splitlines() if ln.startswith("error")]
    assert code in (0, 3) or (code == 1 and len(errors) == 1), (code, err[-500:])


#: Options whose text holds numbers, dates or names, with hostile texts.
TEXTS = ("nan", "inf,-inf", "1e308,1e308,1e308,1e308", "", ",,,", "abc", "9" * 5000,
         "A" * 5000, "0x0", "-1x-1", "1e9x1e9", "\x00")
TEXT_OPTIONS = {
    "leaf": ["--levels"],
    "canopy": ["--tile", "--block", "--levels"],
    "light": ["--heights", "--rect", "--tile", "--block", "--levels", "--tz"],
    "synth": ["--plants"],
    "import-phenomenal": ["--at"],
}
DAY_TEXT_OPTIONS = ["--date", "--from", "--to", "--tz"]


def _text_cases():
    for name, flags in TEXT_OPTIONS.items():
        for flag in flags:
            for value in TEXTS:
                yield pytest.param(name, flag, value, id=f"{name}{flag}={value[:12]!r}")
    for flag in DAY_TEXT_OPTIONS:
        for value in TEXTS:
            yield pytest.param("day", flag, value, id=f"day{flag}={value[:12]!r}")


@pytest.mark.parametrize("name, flag, value", list(_text_cases()))
def test_hostile_texts_are_one_line_or_run(capsys, monkeypatch, tiny, name, flag, value):
    from maizeviz.resources import example_phenomenal

    monkeypatch.chdir(tiny)
    argv = list(PERIOD) if name == "day" else list(BASE[name])
    argv = [str(example_phenomenal()) if a == "PHENO" else a for a in argv]
    if flag in argv:
        k = argv.index(flag)
        del argv[k:k + 2]
    if name == "day" and flag in ("--from", "--to"):
        argv += ["--step", "240"]
    argv.append(f"{flag}={value}")
    code = main(argv)
    err = capsys.readouterr().err
    assert "internal error" not in err and "Traceback" not in err, err[-500:]
    errors = [ln for ln in err.splitlines() if ln.startswith("error")]
    assert code in (0, 3) or (code == 1 and len(errors) == 1), (code, err[-500:])


def test_each_command_is_found_under_its_own_name():
    """The command table names each module by the NAME it registers, and a run imports only
    its own command (the others' modules cost ~0.1 s to import)."""
    import importlib
    import subprocess
    import sys

    from maizeviz.cli import COMMANDS

    for name, module in COMMANDS.items():
        assert importlib.import_module(module).NAME == name
    code = ("import sys\nfrom maizeviz.cli import main\n"
            "try:\n    main(['fastrak-sim', '--help'])\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m.startswith('maizeviz.cli.') or "
            "m.startswith('maizeviz.sweep')))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip().splitlines()[-1]
    assert "maizeviz.cli.simulate" in out
    for other in ("maizeviz.cli.light", "maizeviz.cli.record", "maizeviz.sweep.command"):
        assert other not in out


def test_a_mistyped_command_is_a_usage_error_not_the_app(capsys, tmp_path, monkeypatch):
    """'maizeviz lihgt' names no file: it is a typo of a command, refused with exit 2 rather
    than opening the app (or, without a screen, printing the bundled report and exit 0)."""
    from maizeviz.cli import EXIT_USAGE

    monkeypatch.chdir(tmp_path)
    for typo, meant in (("lihgt", "light"), ("Light", "light"), ("canopyy", "canopy")):
        assert main([typo]) == EXIT_USAGE
        err = capsys.readouterr().err
        assert f"unknown command '{typo}'" in err and f"did you mean '{meant}'" in err
    # with its file and options after it, as typed in earnest (it was argparse's
    # "unrecognized arguments: points.csv", naming the file, not the typo)
    (tmp_path / "points.csv").write_text("plant,leaf,row,col,x,y,z\n")
    assert main(["lihgt", "points.csv", "--sun-zenith", "30"]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert "unknown command 'lihgt'" in err and "did you mean 'light'" in err
    assert err.count("\n") == 1

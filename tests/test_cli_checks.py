"""The `vlref` command as a new user meets it, run as subprocesses: memory refusal,
early output checks, --set errors, the installed golden suite, HDR-FLIP's absence, and help texts."""

import argparse
import configparser
import os
import re
import resource
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from vlref.cli import COMMANDS, build_parser
from vlref.cli.commands import command
from vlref.io.exr import write_exr

ROOT = Path(__file__).resolve().parents[1]


def vlref(*args, cwd=None, env=None, preexec_fn=None, python=("-m", "vlref")):
    """Run ``python -m vlref ARGS`` with this checkout on the path; returns the CompletedProcess."""
    full_env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
                **(env or {})}
    return subprocess.run([sys.executable, *python, *args], capture_output=True, text=True, cwd=cwd, env=full_env,
                          preexec_fn=preexec_fn, timeout=300)


# ---------------------------------------------------------------- 2: memory estimate

def _limit_address_space():
    resource.setrlimit(resource.RLIMIT_AS, (16 * 2 ** 30, resource.RLIM_INFINITY))


def test_a_render_larger_than_memory_is_refused_before_allocating(tmp_path):
    out = tmp_path / "big"
    r = vlref("render", "--set", "render.width=16384", "--set", "render.height=16384", "-o", str(out),
              preexec_fn=_limit_address_space)
    assert r.returncode == 2, r.stderr
    line = r.stderr.strip().splitlines()[-1]
    assert "<command line>: --set render.height=16384: needs about " in line and " GB available" in line
    needed = float(line.split("needs about ")[1].split(" GB")[0])
    available = float(line.split(", ")[-1].split(" GB")[0])
    assert 16384 ** 2 * 200 / 1e9 < needed < 16384 ** 2 * 400 / 1e9 and available <= 16 * 2 ** 30 / 1e9 + 0.05
    assert "--ignore-memory-check" in line and not out.exists()


# ---------------------------------------------------------------- 3: output checked before any work

@pytest.mark.parametrize("args", [
    ["render", "no_such_scene", "-o", "{file}"],
    ["reference", "no_such_scene", "-o", "{file}"],
    ["bias", "no_such_scene", "--technique", "physical", "-o", "{file}"],
    ["compare", "missing_a.exr", "missing_b.exr", "-o", "{file}"],
    ["golden", "build", "--suite", "missing.toml", "--dir", "{file}"],
    ["march", "missing_port.toml", "-o", "{file}"],
    ["march", "export", "no_such_scene", "-o", "{file}"],
    ["render", "-o", "{file}/sub"],
    ["bench", "-o", "{folder}"],
])
def test_an_unusable_output_is_refused_before_any_work(tmp_path, args):
    """Every input here is also bad (or, for bench, slow): the output error coming first shows the check
    runs before any input is read or any work is done."""
    existing = tmp_path / "existing.txt"
    existing.write_text("keep me")
    r = vlref(*[a.format(file=existing, folder=tmp_path) for a in args], cwd=tmp_path)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert "<command line>: " in r.stderr and str(existing if "{folder}" not in args else tmp_path) in r.stderr
    assert ("is not a folder" in r.stderr or "is a file, not a folder" in r.stderr or "is a folder, not a file"
            in r.stderr), r.stderr
    assert existing.read_text() == "keep me"


def test_an_uncreatable_output_folder_is_refused_before_any_work(tmp_path):
    """/proc refuses any new folder, root or not (os.access would say yes to root): exit 2 with the reason
    before the render starts (no traceback, nothing written)."""
    r = vlref("render", "-o", "/proc/vlref_out", "--set", "render.steps=4096", cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith("vlref: error: <command line>: output: cannot create /proc/vlref_out: "), r.stderr
    assert "Traceback" not in r.stderr and list(tmp_path.iterdir()) == [] and not Path("/proc/vlref_out").exists()


def test_an_unwritable_output_folder_is_refused_and_the_check_leaves_nothing(tmp_path, monkeypatch):
    """The check creates the missing folders and a probe file in each, and removes them; a file system that
    refuses the file (read-only: EROFS) is bad input, and the folders it made are gone again."""
    import errno
    import tempfile

    from vlref.errors import InputError
    from vlref.io.output_folders import check_output_dir

    assert check_output_dir(tmp_path / "a" / "b") == tmp_path and list(tmp_path.iterdir()) == []

    def refuse(*args, **kwargs):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS))

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    with pytest.raises(InputError, match=f"cannot write {tmp_path / 'a' / 'b'}: Read-only file system"):
        check_output_dir(tmp_path / "a" / "b")
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------- 4: --set errors name the command line

@pytest.mark.parametrize("setting, reason", [
    ("render.width=abc", "expected an integer"),
    ("lights.0.intensity=-1", "must be >= 0"),
])
def test_a_bad_set_value_is_reported_against_the_command_line(tmp_path, setting, reason):
    r = vlref("render", "--set", setting, "-o", str(tmp_path / "o"))
    assert r.returncode == 2
    assert r.stderr.startswith(f"vlref: error: <command line>: --set {setting}: {reason}"), r.stderr
    assert "pillars.toml" not in r.stderr and not (tmp_path / "o").exists()


# ---------------------------------------------------------------- 5: the golden suite from anywhere

def test_golden_verify_finds_the_suite_from_another_folder(tmp_path):
    r = vlref("golden", "verify", "-q", "--only", "pillars/radial", cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "1 of 1 passed" in r.stdout


def test_golden_verify_says_where_it_looked_and_how_to_point_dir(tmp_path):
    nowhere = tmp_path / "nowhere"
    r = vlref("golden", "verify", cwd=tmp_path, env={"VLREF_GOLDEN": str(nowhere)})
    assert r.returncode == 2
    assert f"looked for manifest.json in {nowhere}" in r.stderr and "--dir" in r.stderr


def test_every_golden_file_is_installed_by_setup_cfg():
    """``pip install`` puts data/golden under <prefix>/share/vlref/golden, where `golden verify` looks."""
    cfg = configparser.ConfigParser()
    cfg.read(ROOT / "setup.cfg")
    installed = set()
    for target, sources in cfg["options.data_files"].items():
        for pattern in (s.strip() for s in sources.split(",") if s.strip()):
            for f in ROOT.glob(pattern):
                installed.add((target, f.relative_to(ROOT)))
    golden = ROOT / "data" / "golden"
    missing = [f.relative_to(ROOT) for f in golden.rglob("*") if f.is_file()
               if ("share/vlref/" + str(f.parent.relative_to(ROOT / "data")), f.relative_to(ROOT)) not in installed]
    lines = sorted({f"share/vlref/{p.parent.relative_to('data')} = {p.parent}/*{p.suffix}" for p in missing})
    assert not missing, "add to [options.data_files] of setup.cfg:\n" + "\n".join(lines)


# ---------------------------------------------------------------- 6: HDR-FLIP

def test_flip_evaluator_is_a_core_dependency():
    cfg = configparser.ConfigParser()
    cfg.read(ROOT / "setup.cfg")
    assert "flip-evaluator" in cfg["options"]["install_requires"]


def test_compare_without_flip_evaluator_says_so_once_and_writes_no_flip_png(tmp_path):
    rng = np.random.default_rng(3)
    ref = rng.uniform(0.1, 1.0, (16, 16, 3))
    write_exr(tmp_path / "ref.exr", ref)
    write_exr(tmp_path / "test.exr", ref)
    blocked = ("import sys; sys.modules['flip_evaluator'] = None; from vlref.cli import main; "
               "sys.exit(main(sys.argv[1:]))")
    r = vlref("compare", str(tmp_path / "ref.exr"), str(tmp_path / "test.exr"), "-o", str(tmp_path / "rep"),
              python=("-c", blocked))
    assert r.returncode == 0, r.stderr
    assert r.stderr.count("flip-evaluator is not installed") == 1 and "pip install flip-evaluator" in r.stderr
    assert (tmp_path / "rep" / "report.html").is_file() and not (tmp_path / "rep" / "flip.png").exists()
    r = vlref("compare", "--help")
    assert "flip.png" in r.stdout and "when HDR-FLIP" in " ".join(r.stdout.split())


# ---------------------------------------------------------------- 7: help texts

def _parsers():
    top = build_parser()
    sub = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
    assert set(sub.choices) | {"march export"} == set(COMMANDS)  # every command listed in `vlref --help`
    return {name: command(name).parser() for name in COMMANDS}


def test_every_option_of_every_command_says_what_it_does_and_its_default():
    parsers = _parsers()
    assert {"render", "scenes", "reference", "bias", "compare", "golden", "march", "march export",
            "bench"} <= set(parsers)
    for name, parser in parsers.items():
        for action in parser._actions:
            if isinstance(action, (argparse._HelpAction, argparse._VersionAction)):
                continue
            label = f"vlref {name} {'/'.join(action.option_strings) or action.dest}"
            assert action.help and action.help.strip() and action.help != argparse.SUPPRESS, f"{label}: no help"
            if action.option_strings:
                text = action.help.lower()
                assert "default" in text or "required" in text, f"{label}: help does not state the default"


def test_help_of_each_command_runs():
    for args in (["render", "--help"], ["golden", "--help"], ["march", "export", "--help"]):
        r = vlref(*args)
        assert r.returncode == 0 and "default" in r.stdout, args


# ---------------------------------------------------------------- 8: what a new user tripped over

def test_golden_only_that_matches_nothing_is_bad_input(tmp_path, capsys):
    """A typo in --only must not turn the golden check into one that passes on nothing."""
    from vlref.cli import main

    for action, where in (("verify", []), ("build", ["--dir", str(tmp_path / "g")]), ("list", [])):
        assert main(["golden", action, "--only", "pillar/*", *where]) == 2, action
        err = capsys.readouterr().err
        assert "<command line>: --only: 'pillar/*' matches no entry" in err and "vlref golden list" in err, err
    assert main(["golden", "list", "--only", "pillars/*", "--only", "nope"]) == 2  # one glob of several
    assert "'nope' matches no entry" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []  # build wrote nothing


def test_the_program_freezes_its_objects_out_of_the_collectors_sight_and_a_call_does_not(capsys, monkeypatch):
    """``vlref`` as a program (argv None) freezes the objects of its imports and of its run (gc.freeze), so
    the exit does not collect them again; a call from Python (argv given) leaves the collector alone."""
    import gc

    from vlref.cli import main

    gc.unfreeze()
    try:
        assert main(["scenes"]) == 0 and gc.get_freeze_count() == 0
        monkeypatch.setattr(sys, "argv", ["vlref", "scenes"])
        assert main() == 0 and gc.get_freeze_count() > 10_000
    finally:
        gc.unfreeze()
    capsys.readouterr()


def test_the_program_imports_its_command_with_the_collector_off_and_turns_it_back_on(monkeypatch):
    import gc

    from vlref.cli import commands

    seen = []
    monkeypatch.setattr(commands, "command", lambda name: seen.append((name, gc.isenabled())) or name)
    assert gc.isenabled()
    try:
        assert commands.program_command("render") == "render"
        assert seen == [("render", False)] and gc.isenabled() and gc.get_freeze_count() > 0
    finally:
        gc.unfreeze()


def test_the_command_table_imports_nothing_heavy():
    # the program imports its command's modules (NumPy, Numba, vlref's kernels) with the collector off
    # (program_command); the module it imports before that, with the collector on, must not pull them in
    import subprocess
    import sys

    code = ("import sys, vlref.cli.commands; print(sorted(m for m in ('numpy', 'numba', 'llvmlite', 'scipy', "
            "'vlref.jit_init', 'vlref.render') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_the_render_command_imports_only_its_own_technique():
    # a fresh `vlref render` imports its command's modules at start-up: the other techniques' passes and kernels
    # (the registry imports a technique's module on first use), the quadrature reference and the warm-up's task
    # list are not among them (vlref.ahead compiles a cold render's stages)
    import subprocess
    import sys

    others = ("vlref.reference", "vlref.warmup", "vlref.froxel", "vlref.post.blur", "vlref.post.radial",
              "vlref.post.upsample", "vlref.march.urp", "vlref.march.killzone", "vlref.march.slightlymad",
              *(f"vlref.techniques.{t}" for t in ("froxel", "killzone", "radial", "slightlymad", "urp")))
    code = ("import sys; from vlref.cli.commands import program_command; program_command('render').render_to_folder; "
            f"print(sorted(m for m in sys.modules if m.startswith({others!r})), "
            "all(m in sys.modules for m in ('vlref.render', 'vlref.ahead', 'vlref.techniques.physical')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[] True"
    # the registry imports a technique's module when its render, rule or notes are asked for
    code = ("import sys; from vlref.techniques import TECHNIQUES; a = 'vlref.techniques.radial' in sys.modules; "
            "rule = TECHNIQUES['radial'].applies; print(a, rule.__module__, TECHNIQUES['froxel'].notes.__module__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "vlref.techniques.radial", "vlref.techniques.froxel"]


def test_scenes_lists_the_techniques_that_apply_to_each_scene(capsys):
    from vlref.cli import main
    from vlref.scene import bundled_scenes, load_scene

    assert main(["scenes"]) == 0
    lines = capsys.readouterr().out.splitlines()
    for name, path in bundled_scenes().items():
        scene = load_scene(path)
        row = lines[lines.index(next(l for l in lines if l.split()[0] == name)) + 1]
        listed = row.split("techniques: ")[1].split(", ")
        assert ("urp" in listed) == any(light.type == "directional" for light in scene.lights), name
        assert {"physical", "killzone", "slightlymad", "froxel"} <= set(listed), name
    assert sum("[animation: --frames]" in l for l in lines) == 3


def test_a_technique_that_needs_another_scene_names_the_bundled_scenes_that_suit_it(tmp_path, capsys):
    from vlref.cli import main

    assert main(["render", "--technique", "urp", "-o", str(tmp_path / "o"), "-q"]) == 2
    err = capsys.readouterr().err
    assert 'needs a directional light' in err and "bundled scenes with one: " in err and "urp_sun" in err
    assert not (tmp_path / "o").exists()
    assert main(["bias", "pillars", "--technique", "urp"]) == 2  # refused before the reference is computed
    assert "urp_sun" in capsys.readouterr().err
    # radial renders any scene, but behind_camera's light projects behind the camera: a note says so
    assert main(["render", "behind_camera", "--technique", "radial", "-o", str(tmp_path / "r"),
                 "--set", "render.width=32", "--set", "render.height=18"]) == 0
    err = capsys.readouterr().err
    assert "vlref: note: radial does not suit this scene (scenes whose radial light projects inside the frame); " \
           "bundled scenes that suit it: " in err and "radial_sun" in err


def test_frames_of_a_scene_without_animation_are_noted_and_counted_as_frames(tmp_path, capsys):
    from vlref.cli import main

    assert main(["render", "pillars", "--frames", "0:2", "-o", str(tmp_path / "f"), "--set", "render.width=16",
                 "--set", "render.height=9"]) == 0
    err = capsys.readouterr().err
    assert "vlref: note: pillars.toml has no [animation]: every frame shows the same scene" in err
    assert main(["render", "anim_spot", "--frames", "0:1", "-o", str(tmp_path / "a"), "--set", "render.width=16",
                 "--set", "render.height=9"]) == 0
    assert "has no [animation]" not in capsys.readouterr().err


def test_a_compiling_kernel_is_announced_once(capsys):
    """The bar stands still while Numba compiles: the first compilation says so, once; a cached or
    already compiled kernel says nothing."""
    import numba

    from vlref.cli.progress_bar import StageBar

    @numba.njit
    def fresh(x):  # not cached: compiles on its first call
        return x + 1

    with StageBar(False, 1, "test"):
        fresh(1)
        fresh(2.0)  # a second compilation (float): no second line
    with StageBar(False, 1, "test"):
        fresh(3)
    err = capsys.readouterr().err
    assert err.count("vlref: compiling kernels (first run, cached afterwards") == 1


def test_a_bar_drawn_by_the_compiling_line_is_cleared_before_the_next_line(capsys):
    """The compiling line (``tqdm.write``) draws a bar still inside its one-second delay; closing it must clear it,
    or the note printed next follows the bar's text on one line (seen in the render's note test, cold cache)."""
    import sys

    from vlref.cli.progress_bar import StageBar

    with StageBar(False, 5, "render x") as bar:
        bar.stage("one")
        bar.compiling()
    print("vlref: note: next", file=sys.stderr)
    err = capsys.readouterr().err
    assert "vlref: note: next" in err.splitlines(), repr(err)


def test_the_stage_bar_starts_no_monitor_thread():
    """tqdm's monitor thread redraws a bar without its lock, so a redraw could follow the bar's closing and put
    the bar's text in front of the next line printed (a note); the stage bars are moved by hand and start none."""
    import threading

    from tqdm import TMonitor

    from vlref.cli.progress_bar import StageBar

    def monitors():
        return sum(isinstance(t, TMonitor) and t.is_alive() for t in threading.enumerate())

    before = monitors()
    with StageBar(False, 3, "test") as bar:
        bar.stage("one")
        assert bar.bar is not None and monitors() == before


def test_a_sweep_item_that_fails_names_the_item(tmp_path, capsys):
    from vlref.cli import main

    spec = tmp_path / "sweep.toml"
    spec.write_text('scene = "pillars"\nset = ["render.width=16", "render.height=9"]\ntechniques = ["urp"]\n'
                    'rel_tol = 1e-2\npoints = [["render.steps=4"]]\n')
    assert main(["sweep", str(spec), "-o", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "1 item(s) failed:\n  urp/000: InputError: " in err and "needs a directional light" in err
    assert not (tmp_path / "out").exists()


def test_bias_prints_its_figures_to_a_few_digits():
    from vlref.reference.bias import BiasReport

    table = [{"steps": 4, "mean_abs": 1 / 3, "max_abs": 2 / 3, "mean_rel": 1 / 7, "max_rel": 1 / 9}]
    report = BiasReport("killzone", np.zeros((2, 2)), 1 / 7, 1 / 9,
                        {"depth_edges": 0.123456789012, "top_fraction": 0.01, "top_bbox": (0, 1, 2, 3)}, table,
                        -1.0123456789, 1, 1e-9)
    text = report.summary()
    assert "depth_edges 0.123," in text and "top_bbox (0, 1, 2, 3)" in text
    assert not re.search(r"\d{6}", text), text  # no float printed to more than 5 digits


def test_technique_all_renders_every_applicable_technique_at_one_exposure_with_its_level(tmp_path, capsys):
    from vlref.cli import main
    from vlref.io.exposure import luminance
    from vlref.io.images import read_image
    from vlref.io.png import png_text
    from vlref.io.tonemap import srgb8
    from vlref.sheet import LABEL_HEIGHT

    out = tmp_path / "all"
    assert main(["render", "urp_sun", "--technique", "all", "-o", str(out), "--set", "render.width=32",
                 "--set", "render.height=18"]) == 0
    err = capsys.readouterr().err
    names = ["physical", "killzone", "slightlymad", "urp", "radial", "froxel"]  # every one applies to urp_sun
    assert sorted(p.name for p in out.iterdir()) == sorted(names + ["sheet.png"])
    exposures = {float(png_text((out / n / "final.png").read_bytes())["vlref_exposure"]) for n in names}
    assert len(exposures) == 1  # one exposure for every technique
    exposure = exposures.pop()
    sheet = read_image(out / "sheet.png")
    assert sheet.shape[:2] == (2 * (18 + LABEL_HEIGHT) + 2, 3 * 32 + 2 * 2)
    physical = luminance(read_image(out / "physical" / "inscatter.exr")).mean()
    line = next(l for l in err.splitlines() if l.startswith("level against physical"))
    for i, name in enumerate(names):
        r, c = divmod(i, 3)
        panel = sheet[r * (18 + LABEL_HEIGHT + 2) + LABEL_HEIGHT:r * (18 + LABEL_HEIGHT + 2) + LABEL_HEIGHT + 18,
                      c * 34:c * 34 + 32]
        expected = srgb8(read_image(out / name / "final.exr"), exposure) / 255.0
        assert np.abs(panel - expected).max() <= 0.5 / 255, name  # the panel is the final at the shared exposure
        level = luminance(read_image(out / name / "inscatter.exr")).mean() / physical
        assert f"{name} {level:.3g}x" in line, (name, level, line)
    assert "physical 1x" in line
    assert main(["render", "--technique", "all", "--frames", "0:2", "-o", str(tmp_path / "f")]) == 2
    assert "--technique all: renders one frame of each technique: drop --frames" in capsys.readouterr().err


def test_compare_refuses_an_8bit_preview_unless_asked(tmp_path, capsys):
    from vlref.cli import main
    from vlref.io.exr import write_exr
    from vlref.io.png import write_png

    img = np.full((4, 6, 3), 0.25, np.float32)
    write_exr(tmp_path / "ref.exr", img)
    write_png(tmp_path / "test.png", img)
    assert main(["compare", str(tmp_path / "ref.exr"), str(tmp_path / "test.png")]) == 2
    err = capsys.readouterr().err
    assert "<command line>: test: " in err and "is an 8-bit image" in err and "--allow-8bit" in err
    assert main(["compare", str(tmp_path / "test.png"), str(tmp_path / "test.png"), "--allow-8bit", "-q",
                 "--no-flip"]) == 0


def test_rendering_into_a_folder_of_an_earlier_run_notes_the_files_it_kept(tmp_path, capsys):
    from vlref.cli import main

    small = ["pillars", "-o", str(tmp_path / "o"), "--set", "render.width=16", "--set", "render.height=9"]
    assert main(["render", *small, "--stages"]) == 0
    staged = {p.name for p in (tmp_path / "o").iterdir()}
    capsys.readouterr()
    assert main(["render", *small]) == 0
    err = capsys.readouterr().err
    kept = staged - {"final.exr", "final.png", "depth.exr", "inscatter.exr", "transmittance.exr"}
    assert kept and f"keeps {len(kept)} file(s) of an earlier run that this one did not write: " in err, err
    (tmp_path / "fresh").mkdir()
    assert main(["render", "pillars", "-o", str(tmp_path / "fresh"), "--set", "render.width=16",
                 "--set", "render.height=9"]) == 0
    assert "keeps" not in capsys.readouterr().err


@pytest.mark.parametrize("scene, technique, sets, says", [
    ("pillars", "slightlymad", [], "slightlymad: horizontal banding, a checker dither and stair-stepped halos"),
    ("pillars", "froxel", [], "froxel: vertical stripes in the haze are the grid's"),
    ("pillars", "froxel", ["techniques.froxel.temporal=true"], None),  # temporal: the stripes average out
    ("pillars", "radial", [], "radial: no medium, so nothing dims the far scene"),  # a spot light
    ("radial_sun", "radial", [], None),  # a directional light: no horizon note
])
def test_faithful_artifacts_are_named_in_the_render_note(tmp_path, capsys, scene, technique, sets, says):
    from vlref.cli import main

    sets = [x for s in ["render.width=16", "render.height=9", *sets] for x in ("--set", s)]
    assert main(["render", scene, "--technique", technique, "-o", str(tmp_path / "o"), *sets]) == 0
    err = capsys.readouterr().err
    notes = [l for l in err.splitlines() if l.startswith("vlref: note: ")]
    if says is None:
        assert not any("faithful" in l for l in notes), repr(err)
    else:
        assert any(says in l and "faithful" in l and "docs/TECHNIQUES.md" in l for l in notes), repr(err)


def test_sweep_summary_names_the_denominators_of_its_relative_errors(tmp_path):
    """``mean_rel`` and ``max_rel`` divide by different things (so the first can exceed the second): the
    summary holds both denominators, and each ratio times its own denominator gives back its error."""
    import csv

    from vlref.cli import main

    spec = tmp_path / "sweep.toml"
    spec.write_text('scene = "pillars"\nset = ["render.width=16", "render.height=9"]\ntechniques = ["killzone"]\n'
                    'rel_tol = 1e-2\npoints = [["render.steps=4"], ["render.steps=16"]]\n')
    assert main(["sweep", str(spec), "-o", str(tmp_path / "out"), "-q"]) == 0
    rows = list(csv.DictReader((tmp_path / "out" / "summary.csv").open()))
    assert len(rows) == 2
    for row in rows:
        v = {k: float(row[k]) for k in ("mean_abs", "max_abs", "mean_rel", "max_rel", "ref_sum", "ref_max")}
        assert v["ref_max"] <= v["ref_sum"] <= 16 * 9 * v["ref_max"]
        assert v["mean_rel"] * v["ref_sum"] == pytest.approx(v["mean_abs"] * 16 * 9, rel=1e-12)
        assert v["max_rel"] * v["ref_max"] == pytest.approx(v["max_abs"], rel=1e-12)

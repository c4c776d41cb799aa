"""The ``visviva`` command: machine-readable output that is right, and user errors that exit 2.

The promise (cli/main.py, and the issue): a user error prints one line ``error: ...`` on stderr
and exits with status 2, without a traceback; outputs are never overwritten without
``--force``. Successful commands run in-process through ``typer.testing.CliRunner``; user errors
run through :func:`visviva.cli.main.main` (where the exit status is decided) in-process, and a
few through the installed ``visviva`` executable to see the real exit status and stderr.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

import visviva as vv
from visviva.cli.main import app, main

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
DEMO_FILES = ("recording.h5", "summary.json", "energy.png", "phase.png")

runner = CliRunner()


def invoke(*args: str | Path) -> str:
    """Run a command that must succeed in-process; return its stdout."""
    result = runner.invoke(app, [str(a) for a in args])
    assert result.exception is None or isinstance(result.exception, SystemExit), (
        f"visviva {' '.join(map(str, args))} raised {result.exception!r}\n{result.output}"
    )
    assert result.exit_code == 0, result.output
    return result.stdout


def run_main(monkeypatch, capsys, *args: str | Path) -> tuple[int, str, str]:
    """Run the entry-point function ``main()`` in-process; return (status, stdout, stderr)."""
    monkeypatch.setattr(sys, "argv", ["visviva", *map(str, args)])
    try:
        main()
        status = 0
    except SystemExit as exit_:
        status = 0 if exit_.code is None else exit_.code
    captured = capsys.readouterr()
    return status, captured.out, captured.err


@pytest.fixture(scope="module")
def executable() -> str:
    """Path of the installed ``visviva`` console script."""
    path = shutil.which("visviva")
    assert path is not None, "the `visviva` entry point is not installed (pip install -e .)"
    return path


def run_executable(executable: str, cwd: Path, *args: str | Path) -> subprocess.CompletedProcess:
    """Run the real ``visviva`` command in ``cwd``."""
    return subprocess.run(
        [executable, *map(str, args)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


def assert_user_error(status: int, stderr: str, *fragments: str) -> str:
    """Exit status 2 and exactly one stderr line ``error: ...`` holding every fragment."""
    assert "Traceback" not in stderr, stderr
    assert status == 2, f"exit status {status}, stderr:\n{stderr}"
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, f"expected one line on stderr, got:\n{stderr}"
    assert lines[0].startswith("error: "), lines[0]
    missing = [fragment for fragment in fragments if fragment not in lines[0]]
    assert not missing, f"{lines[0]!r} does not mention {missing}"
    return lines[0]


def snapshot(directory: Path) -> dict[str, tuple[int, bytes]]:
    """Modification time (ns) and contents of every file in ``directory``."""
    return {
        p.name: (p.stat().st_mtime_ns, p.read_bytes())
        for p in sorted(directory.iterdir())
        if p.is_file()
    }


# --------------------------------------------------------------------------------------------
# Help and the integrator table.


def test_help_exits_zero_through_the_real_command(executable, tmp_path):
    """`visviva --help` works from the installed script and lists every command."""
    completed = run_executable(executable, tmp_path, "--help")
    assert completed.returncode == 0, completed.stderr
    for command in ("integrators", "stability", "convergence", "demo"):
        assert command in completed.stdout
    assert "Traceback" not in completed.stderr


def test_integrators_json_describes_every_registered_method():
    """`integrators --json` lists each registered method with its declared properties."""
    table = json.loads(invoke("integrators", "--json"))
    assert [row["name"] for row in table] == vv.integrators.names()
    for row in table:
        assert {"name", "order", "implicit", "symplectic"} <= set(row)
        method = vv.integrators.get(row["name"])
        assert (row["order"], row["implicit"], row["symplectic"]) == (
            method.order,
            method.implicit,
            method.symplectic,
        )
    rows = {row["name"]: row for row in table}
    assert rows["rk4"]["order"] == 4
    assert rows["rk4"]["implicit"] is False
    assert rows["implicit_midpoint"]["implicit"] is True
    assert rows["implicit_midpoint"]["symplectic"] is True


# --------------------------------------------------------------------------------------------
# Stability.


def test_stability_json_gives_the_textbook_intervals():
    """RK4 is stable on [-2.785, 0] and ±i·2√2; explicit Euler on [-2, 0] and only at 0 on iR."""
    intervals = json.loads(invoke("stability", "rk4", "explicit_euler", "--json"))
    assert set(intervals) == {"rk4", "explicit_euler"}
    rk4 = intervals["rk4"]
    assert rk4["real"] == pytest.approx([-2.7853, 0.0], abs=1e-3)
    assert rk4["imaginary"] == pytest.approx(
        [-2.0 * math.sqrt(2.0), 2.0 * math.sqrt(2.0)], abs=1e-3
    )
    euler = intervals["explicit_euler"]
    assert euler["real"] == pytest.approx([-2.0, 0.0], abs=1e-3)
    assert euler["imaginary"] == pytest.approx([0.0, 0.0], abs=1e-3)


def test_stability_json_writes_unbounded_ends_as_strings():
    """Backward Euler is A-stable: its unbounded ends are "-inf"/"inf" (valid JSON), not NaN."""
    intervals = json.loads(invoke("stability", "backward_euler", "--json"))
    backward = intervals["backward_euler"]
    assert backward["real"][0] == "-inf"
    assert backward["real"][1] == pytest.approx(0.0, abs=1e-9)
    assert backward["imaginary"] == ["-inf", "inf"]


def test_stability_plot_is_a_png_and_is_not_overwritten_without_force(
    tmp_path, monkeypatch, capsys
):
    """`-o x.png` writes a PNG; a second run refuses (exit 2) and leaves it untouched."""
    target = tmp_path / "x.png"
    invoke("stability", "rk4", "-o", target)
    assert target.read_bytes()[:8] == PNG_MAGIC
    before = snapshot(tmp_path)

    status, _, stderr = run_main(monkeypatch, capsys, "stability", "rk4", "-o", target)
    assert_user_error(status, stderr, str(target), "already exists", "--force")
    assert snapshot(tmp_path) == before

    invoke("stability", "rk4", "heun", "-o", target, "--force")
    assert target.read_bytes()[:8] == PNG_MAGIC
    assert target.read_bytes() != before["x.png"][1]


def test_stability_unknown_method_exits_2_through_the_real_command(executable, tmp_path):
    """`visviva stability rk5`: status 2, one line naming rk5, a suggestion and valid names."""
    completed = run_executable(executable, tmp_path, "stability", "rk5")
    line = assert_user_error(completed.returncode, completed.stderr, "'rk5'", "Did you mean 'rk4'?")
    assert completed.stdout == ""
    # The fresh process knows the built-in methods only (tests may register more in-process).
    listing = run_executable(executable, tmp_path, "integrators", "--json")
    assert listing.returncode == 0, listing.stderr
    known = [row["name"] for row in json.loads(listing.stdout)]
    assert {"rk4", "velocity_verlet", "dopri5", "implicit_midpoint"} <= set(known)
    assert line.endswith("Valid names: " + ", ".join(known))


def test_stability_plot_onto_a_directory_is_a_user_error(executable, tmp_path):
    """`-o DIR --force` with an existing directory is refused with one line, not a traceback."""
    directory = tmp_path / "plots"
    directory.mkdir()
    completed = run_executable(executable, tmp_path, "stability", "rk4", "-o", directory, "--force")
    assert_user_error(completed.returncode, completed.stderr, "plots")
    assert directory.is_dir()


# --------------------------------------------------------------------------------------------
# Convergence.


def test_convergence_measures_the_declared_orders():
    """On the time-dependent forced oscillator RK4 converges at order 4 and Heun at order 2."""
    report = json.loads(invoke("convergence", "rk4", "heun", "--problem", "forced", "--json"))
    assert report["problem"] == "forced"
    measured = {row["method"]: row["measured_order"] for row in report["methods"]}
    assert measured["rk4"] == pytest.approx(4.0, abs=0.1)
    assert measured["heun"] == pytest.approx(2.0, abs=0.1)
    declared = {row["method"]: row["declared_order"] for row in report["methods"]}
    assert declared == {"rk4": 4, "heun": 2}


def test_convergence_unknown_problem_lists_the_available_ones(monkeypatch, capsys):
    """`--problem nosuch` exits 2 naming the problem and listing the reference problems."""
    status, stdout, stderr = run_main(
        monkeypatch, capsys, "convergence", "rk4", "--problem", "nosuch"
    )
    assert_user_error(status, stderr, "'nosuch'", "pendulum", "forced", "damped", "first-order")
    assert stdout == ""


def test_convergence_with_no_step_sizes_is_a_user_error(monkeypatch, capsys):
    """`--levels 0` measures nothing: it must be refused (exit 2 naming levels), not print nan."""
    status, _, stderr = run_main(monkeypatch, capsys, "convergence", "rk4", "--levels", "0")
    assert_user_error(status, stderr, "levels", "0")


# --------------------------------------------------------------------------------------------
# Demos.


def test_demo_without_name_lists_the_demos():
    """`visviva demo` lists every built-in demo by name."""
    listing = invoke("demo")
    names = [line.split()[0] for line in listing.splitlines() if line.strip()]
    assert {"oscillator", "circular", "test-equation"} <= set(names)


@pytest.fixture(scope="module")
def oscillator_run(tmp_path_factory) -> Path:
    """The oscillator demo run once for 1 s into a fresh directory (outputs read-only below)."""
    directory = tmp_path_factory.mktemp("oscillator")
    invoke("demo", "oscillator", "-o", directory, "--duration", "1")
    return directory


def test_demo_writes_recording_summary_and_figures(oscillator_run):
    """The demo writes its recording, summary and two PNG figures."""
    for name in DEMO_FILES:
        assert (oscillator_run / name).is_file(), name
    for figure in ("energy.png", "phase.png"):
        assert (oscillator_run / figure).read_bytes()[:8] == PNG_MAGIC


def test_demo_summary_has_one_run_per_method(oscillator_run):
    """summary.json holds the totals and one entry per registered integrator."""
    summary = json.loads((oscillator_run / "summary.json").read_text())
    assert {"steps", "wall_time_s", "energy_drift", "warnings", "runs"} <= set(summary)
    assert set(summary["runs"]) == set(vv.integrators.names())
    assert summary["steps"] == sum(run["steps"] for run in summary["runs"].values())
    assert summary["wall_time_s"] > 0.0
    assert isinstance(summary["warnings"], list)
    drifts = [run["energy_drift"] for run in summary["runs"].values()]
    assert summary["energy_drift"] == max(drifts, key=abs)


def test_demo_explicit_euler_energy_grows_by_the_exact_factor(oscillator_run):
    """Explicit Euler multiplies the oscillator's energy by 1 + (ωh)² per step, exactly."""
    run = json.loads((oscillator_run / "summary.json").read_text())["runs"]["explicit_euler"]
    omega, dt, steps = 2.0 * math.pi, 0.02, 50
    assert (run["dt"], run["steps"]) == (dt, steps)
    expected = (1.0 + (omega * dt) ** 2) ** steps - 1.0
    assert run["energy_drift"] == pytest.approx(expected, rel=1e-9)


def test_demo_recording_holds_one_run_per_method(oscillator_run):
    """recording.h5 reads back one run per method, each from t = 0 to the 1 s requested."""
    path = oscillator_run / "recording.h5"
    runs = vv.io.read_recordings(path)
    assert list(runs) == vv.integrators.names()
    rk4 = vv.io.load_recording(path, run="rk4")
    assert rk4.attrs["method"] == "rk4"
    assert rk4.time[0] == 0.0
    assert rk4.time[-1] == pytest.approx(1.0, abs=1e-12)
    assert rk4["q"].shape == (rk4.frames, 1)
    assert rk4["energy"][0] == pytest.approx(0.5 * (2.0 * math.pi) ** 2)
    # One period of a spring with ω = 2π: RK4 at ωh ≈ 0.126 is back at q = 1 to ~1e-6.
    assert rk4["q"][-1, 0] == pytest.approx(1.0, abs=1e-5)


def test_demo_outputs_get_ordinary_file_permissions(oscillator_run):
    """Every output file is as readable as any file the user creates (no 0600 temp-file modes)."""
    reference = oscillator_run.parent / "reference.txt"
    reference.write_text("made with open()\n")
    expected = stat.S_IMODE(reference.stat().st_mode)
    modes = {name: oct(stat.S_IMODE((oscillator_run / name).stat().st_mode)) for name in DEMO_FILES}
    assert modes == dict.fromkeys(DEMO_FILES, oct(expected))


def test_stability_plot_gets_ordinary_file_permissions(tmp_path):
    """The stability PNG is as readable as any file the user creates."""
    reference = tmp_path / "reference.txt"
    reference.write_text("made with open()\n")
    invoke("stability", "rk4", "-o", tmp_path / "x.png")
    assert oct(stat.S_IMODE((tmp_path / "x.png").stat().st_mode)) == oct(
        stat.S_IMODE(reference.stat().st_mode)
    )


def test_demo_refuses_to_overwrite_without_force(tmp_path, monkeypatch, capsys):
    """A second run into the same directory exits 2 and changes nothing; --force replaces."""
    directory = tmp_path / "out"
    invoke("demo", "oscillator", "-o", directory, "--duration", "0.2")
    before = snapshot(directory)
    assert set(before) == set(DEMO_FILES)

    status, _, stderr = run_main(
        monkeypatch, capsys, "demo", "oscillator", "-o", directory, "--duration", "0.2"
    )
    assert_user_error(status, stderr, str(directory), "--force")
    assert snapshot(directory) == before

    invoke("demo", "oscillator", "-o", directory, "--duration", "0.4", "--force")
    summary = json.loads((directory / "summary.json").read_text())
    assert summary["duration_s"] == 0.4
    assert set(snapshot(directory)) == set(DEMO_FILES)


@pytest.mark.parametrize(
    ("name", "fragments"),
    [
        ("nosuch", ("'nosuch'", "oscillator", "circular", "test-equation")),
        ("oscilator", ("'oscilator'", "Did you mean 'oscillator'?")),
    ],
)
def test_demo_unknown_name_exits_2(tmp_path, monkeypatch, capsys, name, fragments):
    """An unknown demo lists the available ones; a near miss gets a suggestion; no output."""
    status, _, stderr = run_main(monkeypatch, capsys, "demo", name, "-o", tmp_path / "out")
    assert_user_error(status, stderr, *fragments)
    assert not (tmp_path / "out").exists()


def test_demo_negative_duration_exits_2_through_the_real_command(executable, tmp_path):
    """`--duration -1` is refused by the real command with one line naming `duration`."""
    completed = run_executable(
        executable, tmp_path, "demo", "circular", "--duration", "-1", "-o", tmp_path / "out"
    )
    assert_user_error(completed.returncode, completed.stderr, "`duration`", "-1")
    assert not (tmp_path / "out").exists()


def test_user_errors_leave_the_working_directory_clean(executable, tmp_path):
    """A refused command writes nothing, not even a default `out/` directory."""
    completed = run_executable(executable, tmp_path, "demo", "circular", "--duration", "nan")
    assert_user_error(completed.returncode, completed.stderr, "`duration`", "nan")
    assert os.listdir(tmp_path) == []


def test_run_reports_steps_of_dt_and_their_substeps_apart(tmp_path, monkeypatch, capsys):
    # 0.1 s at dt = 0.01 s in 4 substeps: 10 steps of dt (40 substeps), not "40 steps (dt =
    # 0.01 s)" as the report used to say.
    scene = tmp_path / "drop.toml"
    scene.write_text(
        '[scene]\nname = "drop"\n[integration]\nmethod = "symplectic_euler"\ndt = 0.01\n'
        'substeps = 4\nduration = 0.1\n[[entities]]\ntype = "particles"\n'
        "positions = [[0.0, 1.0, 0.0]]\nmass = 1.0\n"
    )
    status, out, err = run_main(monkeypatch, capsys, "run", scene, "-o", tmp_path / "out")
    assert status == 0, err
    assert "drop: 10 steps of symplectic_euler (dt = 0.01 s, 4 substeps each) in" in out


@pytest.mark.parametrize(("substeps", "verdict"), [(1, "dt is above it!"), (4, "is within it")])
def test_dry_run_advises_against_the_step_the_integrator_takes(
    tmp_path, monkeypatch, capsys, substeps, verdict
):
    # Symplectic Euler on q'' = −ω²q is stable for ω h ≤ 2: h ≤ 0.2 s at ω = 10 rad/s. At
    # dt = 0.5 s the integrator's step is h = dt / substeps: unstable alone, stable in 4.
    scene = tmp_path / "spring.toml"
    scene.write_text(
        '[scene]\nname = "spring"\n[integration]\nmethod = "symplectic_euler"\ndt = 0.5\n'
        f'substeps = {substeps}\nduration = 5.0\n[[entities]]\ntype = "system"\n'
        'system = "oscillator"\nparameters = { omega = 10.0 }\n'
    )
    status, out, err = run_main(monkeypatch, capsys, "run", scene, "--dry-run")
    assert status == 0, err
    assert "largest stable step for symplectic_euler ≈ 0.2 s" in out
    assert verdict in out


def test_energy_drift_is_reported_only_for_conservative_runs(tmp_path, monkeypatch, capsys):
    # An undamped spring conserves E = ½v² + ½ω²q²: its change is the integrator's error, a
    # drift. With air drag (force −c v) the energy falls by physics: reported as dissipated.
    spring = (
        '[integration]\nmethod = "velocity_verlet"\ndt = 0.01\nduration = 2.0\n'
        '[[entities]]\ntype = "particles"\npositions = [[0.0, 1.0, 0.0]]\n'
        "velocities = [[1.0, 0.0, 0.0]]\nmass = 1.0\n"
    )
    drag = '[[entities]]\ntype = "force"\nkind = "damping"\nrate = 0.5\n'
    for name, text in {"free": spring, "dragged": spring + drag}.items():
        (tmp_path / f"{name}.toml").write_text(f'[scene]\nname = "{name}"\n' + text)
    status, out, err = run_main(
        monkeypatch, capsys, "run", tmp_path / "free.toml", "-o", tmp_path / "free"
    )
    assert status == 0, err
    assert "energy drift:" in out and "dissipated" not in out
    status, out, err = run_main(
        monkeypatch, capsys, "run", tmp_path / "dragged.toml", "-o", tmp_path / "dragged"
    )
    assert status == 0, err
    assert "energy drift" not in out
    assert "energy dissipated:" in out and "not conservative" in out
    summary = json.loads((tmp_path / "dragged" / "summary.json").read_text())
    assert summary["conservative"] is False


def test_energy_lines_tell_the_runs_of_a_demo_apart():
    from visviva.cli.common import _energy_lines

    runs = {
        "verlet": {"conservative": True, "energy_drift": 1e-4},
        "euler": {"conservative": True, "energy_drift": 0.5},
        "damped": {"conservative": False, "energy_drift": -0.75},
        "silent": {"conservative": True, "energy_drift": None},
    }
    assert _energy_lines({"runs": runs}) == [
        "energy drift: up to +50 % of the initial energy (euler)",
        "energy dissipated: 75 % of the initial energy "
        "(not conservative: the forces do this, not the integrator)",
    ]

"""Sweeps: descriptions expanded to runs, bad input refused before anything runs, and the runner.

The promises (issue 14): a grid, zip or random design expands deterministically (a random run's
values depend only on the seed and its index); an unknown path is refused with the nearest valid
one; every run whose scene fails validation is listed before any run starts; serial and process
pool runs are bit-identical; a diverging run is recorded and the others finish; resume skips
finished runs; the CLI exits 2 with one line on bad input; hostile files never give a traceback.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tomllib
from concurrent.futures import Executor, Future
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import visviva as vv
from visviva.cli.main import main
from visviva.errors import ModelError, SweepError
from visviva.io.recording import load_recording
from visviva.sweeps import (
    SweepFailed,
    SweepInterrupted,
    expand,
    load_sweep,
    parse_sweep,
    run_values,
)

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "sweeps" / "pendulum_steps.toml"

#: A pinned particle and a free one joined by a spring of k [N/m]; m = 1 kg, dt = 0.01 s.
SPRING = """
[sweep]
name = "spring"
{sweep}

[scene.scene]
name = "spring"
[scene.integration]
method = "symplectic_euler"
dt = 0.01
duration = 0.5
[[scene.entities]]
type = "springs"
name = "pair"
points = [[0.0, 1.0, 0.0], [0.5, 1.0, 0.0]]
pairs = [[0, 1]]
stiffness = 100.0
mass = 1.0
pinned = [0]

{parameters}
"""


def spring_sweep(parameters: str, sweep: str = "", recordings: bool = False) -> str:
    text = SPRING.format(sweep=sweep, parameters=parameters)
    return text + f"\n[outputs]\nrecordings = {'true' if recordings else 'false'}\n"


def write(tmp_path: Path, text: str, name: str = "sweep.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


GRID = """
[[parameters]]
path = "entities[pair].stiffness"
values = [10.0, 100.0, 1000.0]
[[parameters]]
path = "integration.method"
values = ["explicit_euler", "rk4"]
"""


# ---------------------------------------------------------------- expansion


def test_grid_runs_every_combination_first_parameter_slowest():
    sweep = parse_sweep(spring_sweep(GRID))
    runs = expand(sweep)
    assert len(runs) == 6
    assert [tuple(r.values.values()) for r in runs] == [
        (10.0, "explicit_euler"),
        (10.0, "rk4"),
        (100.0, "explicit_euler"),
        (100.0, "rk4"),
        (1000.0, "explicit_euler"),
        (1000.0, "rk4"),
    ]
    assert [r.index for r in runs] == list(range(6))
    assert runs[3].name == "3-stiffness=100_method=rk4"
    # The values reach the run's scene (the entity named "pair" is entities[0]).
    assert runs[4].scene["entities"][0]["stiffness"] == 1000.0
    assert runs[4].scene["integration"]["method"] == "explicit_euler"
    # ... and only the run's scene: the base is untouched.
    assert sweep.base["entities"][0]["stiffness"] == 100.0


def test_ranges_are_evenly_spaced_with_exact_ends():
    sweep = parse_sweep(
        spring_sweep(
            """
[[parameters]]
path = "integration.dt"
log_range = [0.001, 0.1, 3]
[[parameters]]
path = "entities[0].stiffness"
range = [10.0, 50.0, 5]
"""
        )
    )
    values = run_values(sweep)
    assert len(values) == 15
    dts = sorted({v["integration.dt"] for v in values})
    assert dts[0] == 0.001 and dts[-1] == 0.1
    assert math.isclose(dts[1], 0.01, rel_tol=1e-14)
    assert sorted({v["entities[0].stiffness"] for v in values}) == [10.0, 20.0, 30.0, 40.0, 50.0]


def test_zip_pairs_the_lists_and_refuses_lists_of_different_lengths():
    zipped = """
[[parameters]]
path = "entities[0].stiffness"
values = [10.0, 20.0, 30.0]
[[parameters]]
path = "integration.dt"
values = [0.01, 0.005, 0.002]
"""
    runs = expand(parse_sweep(spring_sweep(zipped, 'design = "zip"')))
    assert [tuple(r.values.values()) for r in runs] == [(10.0, 0.01), (20.0, 0.005), (30.0, 0.002)]
    uneven = zipped.replace("[0.01, 0.005, 0.002]", "[0.01, 0.005]")
    with pytest.raises(SweepError, match=r"one length \(entities\[0\].stiffness: 3, integration"):
        run_values(parse_sweep(spring_sweep(uneven, 'design = "zip"')))


RANDOM = """
[[parameters]]
path = "entities[0].stiffness"
log_range = [1.0, 1000.0]
[[parameters]]
path = "integration.dt"
range = [0.001, 0.01]
[[parameters]]
path = "integration.method"
values = ["rk4", "symplectic_euler", "velocity_verlet"]
"""


def test_random_design_is_drawn_from_seed_and_index_only():
    def values(seed: int, samples: int) -> list[dict]:
        return run_values(
            parse_sweep(
                spring_sweep(RANDOM, f"design = 'random'\nseed = {seed}\nsamples = {samples}")
            )
        )

    few, many = values(7, 5), values(7, 40)
    assert few == many[:5]  # run i does not depend on how many runs there are
    assert values(7, 5) == few  # reproducible
    assert values(8, 5) != few  # the seed matters
    for run in many:
        assert 1.0 <= run["entities[0].stiffness"] <= 1000.0
        assert 0.001 <= run["integration.dt"] <= 0.01
    # Run 3 drawn directly from its own generator, parameters in the file's order.
    rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence([7, 3])))
    stiffness = float(np.exp(rng.uniform(np.log(1.0), np.log(1000.0))))
    dt = float(rng.uniform(0.001, 0.01))
    method = ["rk4", "symplectic_euler", "velocity_verlet"][int(rng.integers(3))]
    assert many[3] == {
        "entities[0].stiffness": stiffness,
        "integration.dt": dt,
        "integration.method": method,
    }
    # Log-uniform: about half of the draws below the geometric mean sqrt(1 * 1000).
    below = sum(run["entities[0].stiffness"] < math.sqrt(1000.0) for run in many)
    assert 10 <= below <= 30
    assert len({run["integration.method"] for run in many}) == 3


# ---------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("path", "suggestion"),
    [
        ("entities[0].stifness", "entities[0].stiffness"),
        ("integration.dtt", "integration.dt"),
        ("integraton.dt", "integration"),
        ("entities[piar].stiffness", "pair"),
    ],
)
def test_unknown_path_suggests_the_nearest_valid_one(path, suggestion):
    text = spring_sweep(f'[[parameters]]\npath = "{path}"\nvalues = [1.0]\n')
    with pytest.raises(SweepError) as caught:
        parse_sweep(text, source="s.toml")
    message = str(caught.value)
    assert f"Did you mean '{suggestion}'" in message
    assert "parameters[0].path" in message and "\n" not in message
    line = text.splitlines().index(f'path = "{path}"') + 1
    assert f"s.toml:{line}: " in message  # the line of the path


def test_a_renamed_field_in_a_path_names_the_new_one():
    cloth = (
        '[[scene.entities]]\ntype = "cloth"\nname = "sheet"\nresolution = [3, 3]\n'
        "stiffness = 10.0\n"
    )
    text = spring_sweep('[[parameters]]\npath = "entities[sheet].stretch"\nvalues = [1.0]\n')
    text = text.replace("[[parameters]]", cloth + "\n[[parameters]]", 1)
    with pytest.raises(SweepError) as caught:
        parse_sweep(text, source="s.toml")
    assert (
        'unknown parameter path `entities[sheet].stretch`: field "stretch" of cloth "sheet" was '
        'renamed; did you mean "stiffness"?'
    ) in str(caught.value)


def test_index_beyond_the_entities_is_refused_with_the_count():
    text = spring_sweep('[[parameters]]\npath = "entities[3].stiffness"\nvalues = [1.0]\n')
    with pytest.raises(SweepError, match=r"`entities` has 1 item, so index 3 does not exist"):
        parse_sweep(text)


@pytest.mark.parametrize(
    ("sweep", "parameters", "message"),
    [
        ("", "", "parameters: Field required"),
        ("", '[[parameters]]\npath = "integration.dt"\nvalues = []\n', "at least 1 item"),
        ("samples = 4", GRID, "`samples` sets the size of a random design"),
        ('design = "random"', GRID, "needs `samples`"),
        ("", GRID + GRID.split("[[parameters]]")[1].join(["[[parameters]]", ""]), "swept twice"),
        ("", '[[parameters]]\npath = "integration.dt"\nrange = [0.1, 0.2]\n', "add the count"),
        ("", '[[parameters]]\npath = "integration.dt"\nlog_range = [0, 1, 3]\n', "positive"),
        ("", '[[parameters]]\npath = "integration.dt"\nvalues = [nan]\n', "finite"),
        (
            "",
            '[[parameters]]\npath = "integration.dt"\nvalues = [0.1]\nrange = [1, 2, 2]\n',
            "exactly one of",
        ),
        ("sed = 3", GRID, "unknown key. Did you mean 'seed'?"),
    ],
)
def test_bad_descriptions_are_refused_naming_the_problem(sweep, parameters, message):
    with pytest.raises(SweepError, match=None) as caught:
        run_values(parse_sweep(spring_sweep(parameters, sweep)))
    assert message in str(caught.value)


def test_every_invalid_run_is_listed_before_anything_runs(tmp_path):
    text = spring_sweep(
        """
[[parameters]]
path = "entities[0].stiffness"
values = [-1.0, 10.0, 0.0]
[[parameters]]
path = "integration.dt"
values = [0.01, "fast"]
"""
    )
    out = tmp_path / "out"
    with pytest.raises(SweepError) as caught:
        vv.sweep(write(tmp_path, text), out, executor="serial")
    message = str(caught.value)
    # Runs 0, 1, 4, 5 (stiffness not positive), 1, 3, 5 (dt a text): all but run 2.
    assert "5 of 6 runs have invalid scenes" in message
    assert "run 0 (entities[0].stiffness = -1.0, integration.dt = 0.01): entities[0].stiffness" in (
        message
    )
    assert "run 3 (entities[0].stiffness = 10.0, integration.dt = 'fast'): integration.dt" in (
        message
    )
    assert "run 4 (" in message and "run 5 (" in message and "run 2 (" not in message
    assert not out.exists()  # nothing was written


# ---------------------------------------------------------------- the runner


class InlineExecutor(Executor):
    """Runs each task at submission; the task at ``interrupt_at`` raises KeyboardInterrupt
    (as Ctrl-C in the waiting process would) and the later ones never start."""

    def __init__(self, interrupt_at: int | None = None) -> None:
        self.interrupt_at = interrupt_at
        self.submitted = 0

    def submit(self, fn, /, *args, **kwargs):  # type: ignore[override]
        future: Future = Future()
        if self.interrupt_at is None or self.submitted < self.interrupt_at:
            future.set_result(fn(*args, **kwargs))
        elif self.submitted == self.interrupt_at:
            future.set_exception(KeyboardInterrupt())
        self.submitted += 1
        return future


DIVERGING = """
[[parameters]]
path = "entities[pair].stiffness"
values = [10.0, 1e6, 100.0]
[[parameters]]
path = "integration.method"
values = ["symplectic_euler", "rk4"]
"""


@pytest.fixture(scope="module")
def serial_and_pool(tmp_path_factory):
    """The diverging sweep with recordings, run serially and on a 2-process pool."""
    root = tmp_path_factory.mktemp("sweeps")
    path = write(root, spring_sweep(DIVERGING, recordings=True))
    serial = vv.sweep(path, root / "serial", executor="serial")
    pool = vv.sweep(path, root / "pool", workers=2)
    return serial, pool


def test_a_diverging_run_is_reported_and_the_others_finish(serial_and_pool):
    serial, _ = serial_and_pool
    assert serial.ran == 6 and serial.failed == 2
    by_values = {(r["entities[pair].stiffness"], r["integration.method"]): r for r in serial.rows}
    for (stiffness, _method), row in by_values.items():
        assert row["success"] is (stiffness < 1e6), row["error"]
        summary = json.loads((serial.directory / "runs" / row["run"] / "summary.json").read_text())
        assert summary["success"] is row["success"]
    # k = 1e6 N/m, m = 1 kg: ωh = 10, beyond symplectic Euler's ωh < 2 and RK4's 2.83.
    failed = by_values[(1e6, "rk4")]
    assert "diverged" in failed["error"] and failed["t_reached_s"] < 0.5
    assert by_values[(10.0, "rk4")]["t_reached_s"] == 0.5
    # RK4 at ωh = 0.0316 keeps the energy to a few parts in 1e9; the table says so.
    assert abs(by_values[(10.0, "rk4")]["energy_drift"]) < 1e-8
    table = (serial.directory / "results.csv").read_text().splitlines()
    assert table[0].startswith("index,run,entities[pair].stiffness,integration.method,success")
    assert len(table) == 7
    document = json.loads((serial.directory / "results.json").read_text())
    assert document["runs_total"] == 6 and len(document["runs"]) == 6


def test_serial_and_process_pool_runs_are_bit_identical(serial_and_pool):
    serial, pool = serial_and_pool
    physics = ("steps", "t_reached_s", "energy_drift", "max_energy_error", "success", "error")
    for one, other in zip(serial.rows, pool.rows, strict=True):
        assert one["run"] == other["run"]
        assert {k: one[k] for k in physics} == {k: other[k] for k in physics}
        first = load_recording(serial.directory / "runs" / one["run"] / "recording.h5")
        second = load_recording(pool.directory / "runs" / other["run"] / "recording.h5")
        assert first.frames == second.frames > 1
        np.testing.assert_array_equal(first.time, second.time)
        assert first.fields.keys() == second.fields.keys()
        for name, values in first.fields.items():
            np.testing.assert_array_equal(values, second.fields[name], err_msg=name)


def test_resume_skips_finished_runs_and_reruns_what_changed(tmp_path):
    path = write(tmp_path, spring_sweep(GRID))
    out = tmp_path / "out"
    first = vv.sweep(path, out, executor="serial")
    assert (first.ran, first.skipped) == (6, 0)
    summaries = sorted((out / "runs").glob("*/summary.json"))
    assert len(summaries) == 6 and not list((out / "runs").glob("*/recording.h5"))
    stamps = {p: p.stat().st_mtime_ns for p in summaries}

    again = vv.sweep(path, out, executor="serial")
    assert (again.ran, again.skipped) == (0, 6)
    assert {p: p.stat().st_mtime_ns for p in summaries} == stamps
    assert again.rows == first.rows  # the table is rebuilt from the runs' files

    # A run whose directory is gone, and a base scene changed under the runs: run again.
    removed = first.rows[2]["run"]
    for file in (out / "runs" / removed).iterdir():
        file.unlink()
    assert vv.sweep(path, out, executor="serial").ran == 1
    path.write_text(spring_sweep(GRID).replace("duration = 0.5", "duration = 0.4"))
    changed = vv.sweep(path, out, executor="serial")
    assert (changed.ran, changed.skipped) == (6, 0)
    assert {row["t_reached_s"] for row in changed.rows} == {0.4}
    assert vv.sweep(path, out, executor="serial", resume=False).ran == 6


def test_an_interrupt_keeps_the_finished_runs_and_the_next_sweep_resumes(tmp_path):
    path = write(tmp_path, spring_sweep(GRID))
    out = tmp_path / "out"
    # Runs alone, one task each (the springs would batch; an interrupt mid-batch is
    # test_sweep_batches.py's).
    with pytest.raises(SweepInterrupted, match="2 of 6 runs finished") as caught:
        vv.sweep(path, out, executor=InlineExecutor(interrupt_at=2), batch=False)
    assert [row["index"] for row in caught.value.result.rows] == [0, 1]
    assert len((out / "results.csv").read_text().splitlines()) == 3
    assert len(list((out / "runs").iterdir())) == 2
    resumed = vv.sweep(path, out, executor=InlineExecutor())
    assert (resumed.ran, resumed.skipped) == (4, 2)


def test_bad_runner_arguments_are_refused_before_anything_runs(tmp_path):
    path = write(tmp_path, spring_sweep(GRID))
    with pytest.raises(ModelError, match=r"`workers` must be at least 1 \(got 0\)"):
        vv.sweep(path, tmp_path / "a", workers=0)
    with pytest.raises(ModelError, match=r"`executor` must be a concurrent\.futures\.Executor"):
        vv.sweep(path, tmp_path / "b", executor="dask")  # type: ignore[arg-type]
    (tmp_path / "file").write_text("")
    with pytest.raises(ModelError, match="is a file, not a directory"):
        vv.sweep(path, tmp_path / "file", executor="serial")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_the_example_sweep_shows_explicit_euler_gaining_energy_with_dt(tmp_path):
    result = vv.sweep(load_sweep(EXAMPLE), tmp_path, executor="serial")
    assert (result.ran, result.failed) == (12, 0)
    drift = {(r["integration.method"], r["integration.dt"]): r["energy_drift"] for r in result.rows}
    dts = sorted({dt for _, dt in drift})
    assert dts[0] == 0.001 and dts[-1] == 0.04
    euler = [drift[("explicit_euler", dt)] for dt in dts]
    # Explicit Euler's energy grows at every step, more with a larger dt (first order: ~ dt).
    assert 0 < euler[0] < euler[1] < euler[2]
    assert euler[1] / euler[0] == pytest.approx(dts[1] / dts[0], rel=0.2)
    for dt in dts:  # the second- and fourth-order methods stay far closer to the energy
        assert abs(drift[("velocity_verlet", dt)]) < euler[0] / 10
        assert abs(drift[("rk4", dt)]) < abs(drift[("velocity_verlet", dt)])
    assert abs(drift[("rk4", 0.001)]) < 1e-12


# ---------------------------------------------------------------- the command


def run_main(monkeypatch, capsys, *args) -> tuple[int, str, str]:
    monkeypatch.setattr(sys, "argv", ["visviva", *map(str, args)])
    try:
        main()
        status = 0
    except SystemExit as exit_:
        status = 0 if exit_.code is None else exit_.code
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def test_cli_sweep_dry_run_runs_and_refuses(tmp_path, monkeypatch, capsys):
    path = write(tmp_path, spring_sweep(GRID))
    out = tmp_path / "out"
    status, stdout, _ = run_main(monkeypatch, capsys, "sweep", path, "-o", out, "--dry-run")
    assert status == 0 and "grid design, 6 runs, all scenes valid" in stdout
    assert "5\t1000.0\trk4" in stdout and not out.exists()

    status, stdout, _ = run_main(monkeypatch, capsys, "sweep", path, "-o", out, "--serial")
    assert status == 0 and "6 runs; 6 succeeded, 0 failed" in stdout
    status, stdout, _ = run_main(monkeypatch, capsys, "sweep", path, "-o", out, "--serial")
    assert "6 already finished, not run again" in stdout

    bad = write(tmp_path, spring_sweep(GRID.replace("stiffness", "stifness")), "bad.toml")
    for args in (
        ("sweep", bad, "-o", out),
        ("sweep", path, "-o", out, "--serial", "--workers", "2"),
        ("sweep", path, "-o", out, "--workers", "0"),
        ("sweep", tmp_path / "missing.toml"),
    ):
        status, _, stderr = run_main(monkeypatch, capsys, *args)
        assert status == 2, args
        assert stderr.startswith("error: ") and stderr.count("\n") == 1, stderr
        assert "Traceback" not in stderr


ALL_DIVERGE = """
[[parameters]]
path = "entities[pair].stiffness"
values = [1e6, 4e6]
"""


def test_a_sweep_whose_every_run_failed_is_an_error_after_its_table(tmp_path, monkeypatch, capsys):
    # k = 1e6 and 4e6 N/m, m = 1 kg, dt = 0.01 s: ωh = 10 and 20, far beyond symplectic
    # Euler's ωh < 2; both runs diverge, and the sweep says so instead of a quiet success.
    path = write(tmp_path, spring_sweep(ALL_DIVERGE))
    with pytest.raises(SweepFailed, match=r"all 2 runs of the sweep failed; run 0-.*diverged"):
        vv.sweep(path, tmp_path / "api", executor="serial")
    assert (tmp_path / "api" / "results.csv").exists()  # every run's error stays readable
    status, stdout, stderr = run_main(
        monkeypatch, capsys, "sweep", path, "-o", tmp_path / "cli", "--serial"
    )
    assert status == 1, stderr
    assert "2 runs; 0 succeeded, 2 failed" in stdout
    assert "all 2 runs of the sweep failed" in stderr and "Traceback" not in stderr


def test_a_script_without_a_main_guard_is_told_to_add_one(tmp_path):
    # The pool's workers import the script that started them; unguarded, that import starts
    # the sweep again inside a worker, which dies. The script must fail, saying why.
    path = write(tmp_path, spring_sweep(GRID))
    script = tmp_path / "script.py"
    script.write_text(f"import visviva as vv\nvv.sweep({str(path)!r}, 'out', workers=2)\n")
    done = subprocess.run(
        [sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert done.returncode != 0
    assert 'if __name__ == "__main__":' in done.stderr.splitlines()[-1]


# ---------------------------------------------------------------- hostile files

VALID_SCENE = tomllib.loads(SPRING.format(sweep="", parameters=""))["scene"]
_scalar = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=12),
)
_value = st.recursive(
    _scalar,
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=12,
)
_paths = st.sampled_from(
    [
        "integration.dt",
        "entities[0].stiffness",
        "entities[pair].mass",
        "world.gravity[1]",
        "entities[9]",
        "integration",
        "entities[0].points[0][1]",
        "scene.name",
        "a..b",
        "[0]",
        "",
    ]
)
_parameter = st.fixed_dictionaries(
    {"path": _paths | st.text(max_size=20)},
    optional={"values": _value, "range": _value, "log_range": _value, "extra": _value},
)
_document = st.fixed_dictionaries(
    {
        "sweep": st.fixed_dictionaries(
            {},
            optional={
                "design": st.sampled_from(["grid", "zip", "random", "latin"]) | _scalar,
                "samples": _scalar,
                "seed": _scalar,
                "scene": _scalar,
            },
        ),
        "parameters": st.lists(_parameter, max_size=3) | _value,
    },
    optional={"outputs": _value, "scene": st.just(VALID_SCENE) | _value},
)


_numbers = st.integers(min_value=-3, max_value=4) | st.floats(-1e3, 1e3)
_near_valid = st.fixed_dictionaries(
    {
        "sweep": st.fixed_dictionaries(
            {"name": st.just("hostile")},
            optional={
                "design": st.sampled_from(["grid", "zip", "random"]),
                "samples": st.integers(min_value=-1, max_value=4) | st.none(),
                "seed": st.integers(min_value=-1, max_value=2**64),
            },
        ),
        "scene": st.just(VALID_SCENE),
        "parameters": st.lists(
            st.builds(
                lambda path, source: {"path": path} | source,
                _paths,
                st.one_of(
                    st.fixed_dictionaries(
                        {"values": st.lists(_scalar | st.lists(_scalar, max_size=4), max_size=3)}
                    ),
                    st.fixed_dictionaries({"range": st.lists(_numbers, min_size=2, max_size=3)}),
                    st.fixed_dictionaries(
                        {"log_range": st.lists(_numbers, min_size=2, max_size=3)}
                    ),
                ),
            ),
            min_size=1,
            max_size=2,
        ),
    }
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(document=_document | _near_valid, text=st.text(max_size=200))
def test_hostile_sweep_files_are_refused_without_a_traceback(document, text):
    try:
        encoded = json.dumps(document)
    except ValueError:
        encoded = text
    for content, kind in ((encoded, "json"), (text, "toml"), (text, "json")):
        try:
            sweep = parse_sweep(content, kind)
            if len(run_values(sweep)) <= 4:
                expand(sweep)
        except ModelError as error:
            assert str(error).strip()


def test_one_path_inside_another_is_refused_naming_both(tmp_path):
    # Found by the hostile-file test: "integration" swept with values replacing the whole
    # table, and "integration.dt" inside it, used to end in a TypeError.
    text = spring_sweep(
        '[[parameters]]\npath = "integration"\nvalues = [false]\n'
        '[[parameters]]\npath = "integration.dt"\nvalues = [0.01]\n'
    )
    with pytest.raises(SweepError, match=r"'integration' and 'integration\.dt' overlap"):
        load_sweep(write(tmp_path, text))

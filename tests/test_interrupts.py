"""Ctrl-C and SIGTERM lose nothing: the run stops after a step, keeps what it finished, says so.

Real signals are sent to real ``visviva`` processes; each test waits until the run has streamed
frames into its staging directory, so the signal lands mid-simulation.
"""

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

import visviva as vv
from visviva.demos import run_demo
from visviva.io.job import STAGING_PREFIX
from visviva.simulation.interrupt import Interrupted

#: A run far longer than any test: 500 softened bodies for 10⁶ steps.
LONG_SCENE = """
[scene]
name = "long"
[integration]
method = "velocity_verlet"
dt = 0.001
duration = 1000.0
[[entities]]
type = "system"
system = "cluster"
parameters = { bodies = 500, softening = 0.05, seed = 1 }
"""


def _start(args, cwd):
    env = os.environ | {"PYTHONUNBUFFERED": "1"}
    return subprocess.Popen(
        [sys.executable, "-m", "visviva", *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def _wait_for_frames(out: Path, process, size=200_000, timeout=120.0):
    """Wait until the staged recording has grown past ``size`` bytes (the loop is running)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert process.poll() is None, process.communicate()
        staged = list(out.glob(f"{STAGING_PREFIX}*/recording.h5"))
        if staged and staged[0].stat().st_size > size:
            return
        time.sleep(0.1)
    process.kill()
    pytest.fail("the run never started streaming frames")


@pytest.mark.parametrize("sig, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_stops_the_run_and_keeps_the_recording(tmp_path, sig, status):
    scene = tmp_path / "long.toml"
    scene.write_text(LONG_SCENE)
    out = tmp_path / "out"
    process = _start(["run", str(scene), "-o", str(out), "-f", "mp4"], tmp_path)
    _wait_for_frames(out, process)
    process.send_signal(sig)
    stdout, stderr = process.communicate(timeout=60)
    assert process.returncode == status, stderr
    name = signal.Signals(sig).name
    assert f"interrupted by {name}" in stdout and "wrote recording.h5, summary.json" in stdout
    assert "stopped cleanly" in stderr and "Traceback" not in stderr
    # Everything moved into place; no staging directory, no video of a run that never ended.
    assert sorted(p.name for p in out.iterdir()) == ["recording.h5", "summary.json"]
    summary = json.loads((out / "summary.json").read_text())
    recording = vv.io.load_recording(out / "recording.h5")
    assert summary["interrupted"] == name and summary["complete"] is False
    assert 0.0 < summary["t_reached_s"] < 1000.0
    assert recording.attrs["complete"] is False and recording.attrs["interrupted"] == name
    # The recording ends where the run stopped; every frame is whole.
    assert recording.time[-1] == pytest.approx(summary["t_reached_s"])
    assert recording["system_points"].shape[0] == recording.time.size == recording["energy"].size
    assert summary["steps"] == round(summary["t_reached_s"] / 0.001)


def _signal_once_polling(number=signal.SIGINT):
    """A thread that sends ``number`` to this process once a simulation loop polls for it."""
    from visviva.simulation import interrupt

    def send():
        deadline = time.monotonic() + 120
        while not interrupt._polled and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.5)  # into the run
        os.kill(os.getpid(), number)

    thread = threading.Thread(target=send, daemon=True)
    thread.start()
    return thread


def test_an_interrupted_demo_writes_what_it_finished(tmp_path):
    out = tmp_path / "kepler"
    before = signal.getsignal(signal.SIGINT)  # Python's own, or SIG_IGN in a background job
    thread = _signal_once_polling()
    with pytest.raises(Interrupted) as caught:
        run_demo("kepler", out, duration=5e4)
    thread.join()
    assert caught.value.signal == "SIGINT"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] == "SIGINT" and summary["complete"] is False
    runs = vv.io.read_recordings(out / "recording.h5")
    cut = [name for name in runs if name.endswith("-interrupted")]
    assert len(cut) == 1 and runs[cut[0]].attrs["complete"] is False
    assert 0.0 < runs[cut[0]].time[-1] < 5e4
    assert not list(out.glob(f"{STAGING_PREFIX}*"))
    # Outside a job, Ctrl-C does what it did before.
    assert signal.getsignal(signal.SIGINT) is before


def _short_scene(tmp_path: Path) -> vv.Model:
    builder = vv.SceneBuilder(name="drop")
    builder.set_integration(method="symplectic_euler", dt=0.01, duration=0.5)
    builder.add_particles(positions=[[0.0, 1.0, 0.0], [1.0, 2.0, 0.0]])
    return builder.build()


def test_ctrl_c_while_writing_outputs_keeps_the_finished_ones(tmp_path, monkeypatch):
    import visviva.viz.outputs as outputs

    real = outputs.write_output
    calls = []

    def write_then_interrupt(recording, path, fps, *playback):
        calls.append(path.name)
        if len(calls) == 2:
            path.write_bytes(b"partial")
            raise KeyboardInterrupt
        real(recording, path, fps, *playback)

    monkeypatch.setattr(outputs, "write_output", write_then_interrupt)
    out = tmp_path / "out"
    with pytest.raises(Interrupted) as caught:
        vv.run_scene(_short_scene(tmp_path), out, formats=["pc2", "glb", "usd"])
    assert calls == ["points.pc2", "scene.glb"]
    assert sorted(p.name for p in out.iterdir()) == ["points.pc2", "recording.h5", "summary.json"]
    assert [p.name for p in caught.value.report.files] == [
        "recording.h5",
        "summary.json",
        "points.pc2",
    ]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] is True  # the simulation finished; an output did not
    assert summary["interrupted"] == "SIGINT" and "scene.glb" in summary["message"]


def test_staging_left_by_a_killed_process_is_removed_by_the_next_run(tmp_path):
    out = tmp_path / "out"
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    stale = out / f"{STAGING_PREFIX}{int(dead.stdout)}-abc123"
    stale.mkdir(parents=True)
    (stale / "recording.h5").write_bytes(b"\0" * 1000)
    alive = out / f"{STAGING_PREFIX}{os.getpid()}-def456"  # a job still running: kept
    alive.mkdir()
    report = vv.run_scene(_short_scene(tmp_path), out)
    assert report.removed_stale == [stale]
    assert not stale.exists() and alive.exists()


def test_a_killed_process_leaves_a_readable_recording_in_its_staging(tmp_path):
    scene = tmp_path / "long.toml"
    scene.write_text(LONG_SCENE)
    out = tmp_path / "out"
    process = _start(["run", str(scene), "-o", str(out)], tmp_path)
    _wait_for_frames(out, process, size=10_000_000)  # past the first flushes (50 frames each)
    process.kill()
    process.wait(timeout=30)
    (staged,) = out.glob(f"{STAGING_PREFIX}*/recording.h5")
    recording = vv.io.load_recording(staged)
    assert recording.frames > 0 and recording.attrs["success"] is False
    # The next run into the same directory cleans it up.
    result = subprocess.run(
        [sys.executable, "-m", "visviva", "run", str(scene), "-o", str(out), "--duration", "0.01"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert "left by a run that was killed" in result.stdout
    assert not list(out.glob(f"{STAGING_PREFIX}*"))


def _stop_at_poll(monkeypatch, polls: int) -> None:
    """The simulation loop sees Ctrl-C at its ``polls``-th look, as if the key was pressed
    there: deterministic, where a real signal lands wherever the machine's speed puts it."""
    from visviva.simulation import loop

    seen = 0

    def requested():
        nonlocal seen
        seen += 1
        return "SIGINT" if seen >= polls else None

    monkeypatch.setattr(loop, "stop_requested", requested)


DRAWN = {"particle_position", "system_points", "body_origin"}


def _exports(monkeypatch, capsys, path: Path, run: str, tmp_path: Path) -> None:
    """Run ``run`` of the recording at ``path`` exports to a video and to glTF."""
    from visviva.cli.main import main

    for kind in ("mp4", "glb"):
        target = tmp_path / f"{run}.{kind}"
        args = ["export", str(path), "--run", run, "--to", kind, "-o", str(target)]
        monkeypatch.setattr(sys, "argv", ["visviva", *args])
        try:
            main()
        except SystemExit as exit_:
            assert not exit_.code, capsys.readouterr().err
        assert target.stat().st_size > 1000


@pytest.mark.parametrize(
    "demo, polls, finished",
    [
        # A study of many runs, cut in its second: the first is kept whole.
        ("refinement-study", 150, ["corners_6"]),
        # An abstract system drawn after its run (stars as points): cut, still drawn.
        ("galaxy", 40, []),
        # Two pendulums drawn together, then more solves: cut in a later one.
        ("double-pendulum", 1000, ["rk4"]),
    ],
)
def test_a_demo_cut_short_keeps_its_finished_runs_drawable(
    tmp_path, monkeypatch, capsys, demo, polls, finished
):
    _stop_at_poll(monkeypatch, polls)
    out = tmp_path / "out"
    with pytest.raises(Interrupted):
        run_demo(demo, out)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] is False and summary["interrupted"] == "SIGINT"
    runs = vv.io.read_recordings(out / "recording.h5")
    cut = [name for name in runs if name.endswith("-interrupted")]
    assert len(cut) == 1 and runs[cut[0]].attrs["complete"] is False
    assert list(runs)[: len(finished)] == finished  # in the order they finished
    for name in finished:
        assert runs[name].attrs.get("complete", True) is not False
    drawn = [name for name, run in runs.items() if DRAWN & set(run.fields)]
    assert drawn[0] == next(iter(runs))  # the run the video shows can be drawn
    for name in drawn:  # and whatever can be drawn exports, cut short or not
        _exports(monkeypatch, capsys, out / "recording.h5", name, tmp_path)


@pytest.fixture(scope="module")
def mixed_recording():
    """Particles falling beside a tumbling box, 12 frames."""
    builder = vv.SceneBuilder(name="mixed")
    builder.set_integration(method="symplectic_euler", dt=0.01, duration=0.11)
    builder.add_particles(positions=[[0.0, 1.0, 0.0], [0.5, 1.5, 0.0]], radius=0.05)
    builder.add_body("box", size=(0.2, 0.1, 0.3), position=(1.0, 1.0, 0.0), density=500.0,
                     angular_velocity=(1.0, 2.0, 0.0))  # fmt: skip
    builder.add_collider("plane")
    return vv.Simulation(builder.build()).record(until=0.11)


@pytest.mark.parametrize("frames", [1, 2, 7])
def test_a_recording_cut_at_any_frame_exports_to_video_and_gltf(
    tmp_path, monkeypatch, capsys, mixed_recording, frames
):
    full = mixed_recording
    cut = vv.Recording(
        full.time[:frames],
        {name: value[:frames] for name, value in full.fields.items()},
        units=dict(full.units),
        attrs=dict(full.attrs) | {"complete": False, "interrupted": "SIGINT"},
        static=dict(full.static),
    )
    path = tmp_path / "cut.h5"
    vv.io.write_recordings(path, {"cut": cut})
    _exports(monkeypatch, capsys, path, "cut", tmp_path)


def test_ctrl_c_during_an_implicit_solve_stops_between_newton_iterations(monkeypatch):
    """A projected-Newton step asked to stop in its third Newton iteration is dropped: the
    run ends at the last whole step, recorded as its last frame, and can go on from there."""
    from visviva.integrators import newton

    builder = vv.SceneBuilder(name="sheet")
    builder.set_integration(method="projected_newton", dt=0.02, duration=1.0)
    builder.add_cloth((6, 6), origin=(0.0, 1.0, 0.0), along=(0.5, 0.0, 0.0),
                      across=(0.0, 0.0, 0.5), stiffness=500.0, pinned=[0, 5])  # fmt: skip
    simulation = vv.Simulation(builder.build())

    class AskedAfter:
        polls = 0

        def requested(self):
            self.polls += 1
            return "SIGINT" if self.polls > 13 else None

    asked = AskedAfter()
    monkeypatch.setattr(newton, "_stop", asked)
    with pytest.raises(Interrupted) as caught:
        simulation.record(until=1.0)
    iterations = simulation.system.counters.newton_iterations
    stopped = caught.value
    steps = round(stopped.t / 0.02)
    assert steps * 0.02 == pytest.approx(stopped.t)  # a whole step, not a part of one
    assert iterations == asked.polls - 1 and iterations > 3 * steps  # it stopped mid-solve
    assert stopped.recording.time[-1] == pytest.approx(stopped.t) == simulation.time
    monkeypatch.setattr(newton, "_stop", type("Quiet", (), {"requested": lambda self: None})())
    simulation.run(until=stopped.t + 0.1)  # and goes on from the last whole step
    assert simulation.time == pytest.approx(stopped.t + 0.1)

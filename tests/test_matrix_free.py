"""Nothing N² behind the user's back: the stability advisor and implicit methods, matrix-free.

A large problem without an analytic Jacobian never gets a dense one: the advisor's eigenvalues
come from Arnoldi on Jacobian-vector products, and implicit steps from GMRES on Newton-matrix
products (Jacobian-free Newton–Krylov). Each test holds the matrix-free answer against a closed
form or the dense computation, and counts the work.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import visviva as vv
from visviva.analysis.advisor import largest_stable_step, matrix_free_eigenvalues
from visviva.integrators import get, newton

EXAMPLES = Path(__file__).parents[1] / "examples" / "scenes"


def spring_chain(n: int, *, stiffness: float = 100.0, damping: float = 0.0):
    """``n`` unit masses on a line between two walls, joined by springs (no Jacobian given).

    Normal modes (fixed ends): ω_j = 2 √k sin(jπ / (2(n + 1))), j = 1 … n.
    """

    def force(t, q, v):
        padded = np.concatenate([[0.0], q, [0.0]])
        f = stiffness * (padded[2:] - 2.0 * padded[1:-1] + padded[:-2])
        return f - damping * v

    rng = np.random.default_rng(1)
    return vv.ode.SecondOrderProblem.from_force(
        force, np.ones(n), 0.01 * rng.standard_normal(n), np.zeros(n)
    )


def test_advisor_matches_the_closed_form_on_a_long_spring_chain():
    n, k = 1000, 100.0  # 2000 first-order unknowns: above the dense limit
    problem = spring_chain(n, stiffness=k)
    state = problem.initial_state()
    omega_max = 2.0 * np.sqrt(k) * np.sin(n * np.pi / (2 * (n + 1)))
    # Velocity Verlet is stable for h ω ≤ 2 on the imaginary axis.
    dt = largest_stable_step(problem.system(), get("velocity_verlet"), state)
    assert dt == pytest.approx(2.0 / omega_max, rel=1e-3)
    # Explicit Euler is unstable on undamped oscillations at every step.
    assert largest_stable_step(problem.system(), get("explicit_euler"), state) == 0.0


def test_advisor_matches_the_dense_spectrum_with_damping():
    """Velocity-dependent forces take the full first-order operator: the estimate agrees with
    the dense computation of the same finite-difference Jacobian to the Arnoldi tolerance."""
    problem = spring_chain(760, damping=0.5)  # 1520 unknowns: just above the dense limit
    system, state = problem.system(), problem.initial_state()
    lam = matrix_free_eigenvalues(system, state)
    dense = np.linalg.eigvals(vv.analysis.state_jacobian(system, state))
    assert np.abs(lam).max() == pytest.approx(np.abs(dense).max(), rel=1e-3)
    for method in ("rk4", "velocity_verlet", "explicit_euler"):
        expected = vv.analysis.max_stable_dt(method, eigenvalues=dense)
        got = largest_stable_step(system, get(method), state)
        assert got == pytest.approx(expected, rel=5e-3, abs=1e-12)


def test_advisor_matches_the_dense_spectrum_of_a_first_order_problem():
    """Diffusion y' = L y on 2000 points (Δx = 1): λ_j = −4 sin²(jπ / (2(n + 1))), so explicit
    Euler is stable for h ≤ 2 / |λ_max| ≈ 0.5."""
    n = 2000

    def f(t, y):
        padded = np.concatenate([[0.0], y, [0.0]])
        return padded[2:] - 2.0 * padded[1:-1] + padded[:-2]

    problem = vv.ode.FirstOrderProblem(f, np.sin(np.linspace(0, np.pi, n)))
    lam_max = 4.0 * np.sin(n * np.pi / (2 * (n + 1))) ** 2
    dt = largest_stable_step(problem.system(), get("explicit_euler"), problem.initial_state())
    assert dt == pytest.approx(2.0 / lam_max, rel=1e-3)


def test_advisor_on_a_star_cluster_agrees_with_the_dense_jacobian():
    bodies = vv.mechanics.plummer_sphere(300, total_mass=1.0, scale_radius=1.0, G=1.0, seed=2)
    problem = bodies.problem(softening=0.05)
    system, state = problem.system(), problem.initial_state()
    dense = vv.analysis.max_stable_dt(
        "velocity_verlet", jacobian=vv.analysis.state_jacobian(system, state)
    )
    assert largest_stable_step(system, get("velocity_verlet"), state) == pytest.approx(
        dense, rel=1e-2
    )


def test_free_particles_have_no_step_limit_and_cost_one_product():
    count = 3000
    builder = vv.SceneBuilder(name="free")
    builder.add_particle_cloud(count=count)
    problem = builder.build().problem()
    system = problem.system()
    limit = largest_stable_step(system, get("rk4"), problem.initial_state())
    assert limit == np.inf
    assert system.counters.f_evaluations <= 3  # the force, then one product that vanished


def _with_threshold(monkeypatch, value):
    monkeypatch.setattr(newton, "KRYLOV_THRESHOLD", value)


@pytest.mark.parametrize("method", ["backward_euler", "implicit_midpoint", "trapezoidal"])
def test_newton_krylov_agrees_with_dense_newton(monkeypatch, method):
    """Both solve the same stage equation to the same Newton tolerance (rtol 1e-10), so the
    trajectories agree to about that tolerance times the amplitude (0.01 m), not to the
    finite-difference error of the products (~1e-8 relative), which only slows Newton."""
    problem = spring_chain(300, damping=0.2)
    dense = vv.solve(problem, method, dt=0.01, until=0.2).raise_for_status().recording
    _with_threshold(monkeypatch, 100)
    krylov = vv.solve(problem, method, dt=0.01, until=0.2).raise_for_status().recording
    np.testing.assert_allclose(krylov["q"], dense["q"], rtol=0, atol=1e-10)
    np.testing.assert_allclose(krylov["v"], dense["v"], rtol=0, atol=1e-9)
    # Work: no n-column finite-difference Jacobian (300 force evaluations per Newton
    # iteration); one force per Newton iteration plus one per GMRES product.
    assert krylov.attrs["jacobian_evaluations"] == 0
    assert krylov.attrs["krylov_iterations"] > 0
    per_newton = krylov.attrs["f_evaluations"] / krylov.attrs["newton_iterations"]
    assert per_newton < 60 < dense.attrs["f_evaluations"] / dense.attrs["newton_iterations"]


def test_newton_krylov_on_a_first_order_problem(monkeypatch):
    n = 400

    def f(t, y):
        padded = np.concatenate([[0.0], y, [0.0]])
        return 100.0 * (padded[2:] - 2.0 * padded[1:-1] + padded[:-2]) - y**3

    problem = vv.ode.FirstOrderProblem(f, np.sin(np.linspace(0, 3 * np.pi, n)))
    dense = vv.solve(problem, "backward_euler", dt=0.01, until=0.1).raise_for_status().recording
    _with_threshold(monkeypatch, 100)
    krylov = vv.solve(problem, "backward_euler", dt=0.01, until=0.1).raise_for_status().recording
    np.testing.assert_allclose(krylov["y"], dense["y"], rtol=0, atol=1e-9)
    assert krylov.attrs["krylov_iterations"] > 0 and krylov.attrs["jacobian_evaluations"] == 0


#: Runs the CLI and reports its own peak resident memory (VmHWM, which, unlike ru_maxrss,
#: does not carry over the memory of the forking test process).
_MEASURED = (
    "import atexit, runpy, sys\n"
    "def peak():\n"
    "    status = open('/proc/self/status').read()\n"
    "    print('peak-kib', status.split('VmHWM:')[1].split()[0], file=sys.stderr)\n"
    "atexit.register(peak)\n"
    "sys.argv = ['visviva', *sys.argv[1:]]\n"
    "runpy.run_module('visviva', run_name='__main__')\n"
)


def _peak_memory_of(args: list[str], cwd: Path) -> tuple[subprocess.CompletedProcess, float]:
    """Run ``visviva ARGS`` and return it with its peak resident memory [GiB]."""
    result = subprocess.run(
        [sys.executable, "-c", _MEASURED, *args], cwd=cwd, capture_output=True, text=True
    )
    kib = int(result.stderr.rsplit("peak-kib", 1)[1].split()[0])
    return result, kib / 2**20


def test_star_cluster_dry_run_is_matrix_free(tmp_path):
    """20,000 stars: the dense Jacobian would be 120,000² (107 GiB)."""
    result, gigabytes = _peak_memory_of(
        ["run", str(EXAMPLES / "star_cluster.toml"), "--dry-run"], tmp_path
    )
    assert result.returncode == 0, result.stderr
    assert "largest stable step for velocity_verlet ≈" in result.stdout
    assert gigabytes < 1.5


def test_implicit_compare_of_thousands_of_particles_is_matrix_free(tmp_path):
    """6003 unknowns: a dense Newton matrix would cost 288 MB and 6003 force evaluations per
    Newton iteration."""
    # The spray of 2000 particles without its floor: compare takes smooth dynamics only.
    text = (EXAMPLES / "falling_particles.toml").read_text()
    scene = tmp_path / "spray.toml"
    scene.write_text(text.split('[[entities]]\ntype = "collider"')[0])
    args = ["compare", str(scene), "implicit_midpoint", "backward_euler", "--duration", "0.1"]
    result, gigabytes = _peak_memory_of([*args, "-o", "out"], tmp_path)
    assert result.returncode == 0, result.stderr
    assert gigabytes < 1.5
    runs = vv.io.read_recordings(tmp_path / "out" / "recording.h5")
    for run in runs.values():
        # Gravity is uniform, so ∂F/∂q = 0: one GMRES product per Newton iteration suffices.
        assert run.attrs["f_evaluations"] <= 10 * run.attrs["steps"]

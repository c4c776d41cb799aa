"""Registering your own integrator: Kutta's third-order method as a Butcher tableau.

Run it with ``python docs/examples/custom_integrator.py``. Once registered, the method works
everywhere a built-in one does — ``vv.solve``, the stability and convergence tools, the CLI in
the same process — and the test suite runs it through the same conformance tests.
"""

import numpy as np

import visviva as vv
from visviva.integrators import ButcherTableau, ExplicitRungeKutta


class Kutta3(ExplicitRungeKutta):
    """Kutta's third-order method (1901): three evaluations per step."""

    name = "kutta3"
    order = 3
    evaluations_per_step = 3
    cost = "3 f-evaluations"
    reference = "W. Kutta, Z. Math. Phys. 46 (1901) 435-453"
    summary = "Kutta's third-order Runge-Kutta method"
    tableau = ButcherTableau(
        a=[[0, 0, 0], [1 / 2, 0, 0], [-1, 2, 0]],
        b=[1 / 6, 2 / 3, 1 / 6],
        c=[0, 1 / 2, 1],
    )


def register() -> vv.integrators.Integrator:
    """Register Kutta3 once (safe to call again)."""
    if "kutta3" in vv.integrators.names():
        return vv.integrators.get("kutta3")
    return vv.integrators.register(Kutta3)


if __name__ == "__main__":
    register()
    decay = vv.ode.FirstOrderProblem(lambda t, y: -y, [1.0])
    study = vv.studies.convergence_order(decay, "kutta3", until=1.0, reference=lambda t: np.exp(-t))
    print(f"kutta3: measured order {study.order:.2f}")
    print("real stability interval:", vv.analysis.stability_interval("kutta3"))

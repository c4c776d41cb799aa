"""Simultaneous impacts by generalized reflections (Smith et al. 2012, Vouga et al. 2017).

When several contacts collide at once — a ball striking a row of touching balls, a billiards
break — solving them together as resting contacts (sequential impulses toward a target per
contact, :mod:`~visviva.collision.body_impulses`) lets the row move off as one lump: the
impulse that stops the striker is shared along the row at once. Physics says the impact
travels: in a Newton's cradle the striker stops and the last ball leaves.

*Generalized reflections* (B. Smith, D. M. Kaufman, E. Vouga, R. Tamstorf, E. Grinspun,
"Reflections on simultaneous impact", SIGGRAPH 2012) resolve an impact in rounds. Each round
takes the contacts that approach (the active set ``A``), finds the inelastic impulses
``λ_A ≥ 0`` that would just stop their approach — the projection of the velocities, in the
kinetic-energy metric, onto the set where no active contact approaches, a small complementarity
problem solved here by Gauss–Seidel sweeps to convergence — and applies ``(1 + e)`` times
them: a reflection of the velocities through that set. For ``e = 1`` a reflection keeps the
kinetic energy exactly; every round keeps linear and angular momentum. Rounds go on until no
contact approaches. A contact that only touches is not active until something drives it in, so
in a cradle the first round reflects the striker off the second ball, the next the second off
the third, and so on down the row.

E. Vouga, B. Smith, D. M. Kaufman, R. Tamstorf, E. Grinspun ("All's well that ends well:
guaranteed resolution of simultaneous rigid body impact", SIGGRAPH 2017) show that such
iterations end after finitely many rounds except in configurations that can be detected, and
that an iteration made to end there still satisfies the physical properties. Here a round that
leaves the same contacts active with no loss of approach speed is such a case, as is reaching
:data:`MAX_ROUNDS`: the remaining approach is then removed by one inelastic projection over
every contact, which always ends the impact (it dissipates only the approach that was left).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .body_impulses import contact_rows, lever_impulse, lever_speed, rates_with_world

__all__ = ["MAX_ROUNDS", "reflect_impacts"]

#: Rounds of reflections before the impact is ended by an inelastic projection.
MAX_ROUNDS = 1000
#: Gauss–Seidel sweeps of one round's projection, at most (it stops when converged).
PROJECTION_SWEEPS = 500


@njit(cache=True)
def _project(active, rows, index, mass_n, rates, impulse):
    """The inelastic impulses ``impulse`` ``(C,)`` (≥ 0, zero off ``active``) that stop the
    approach of the active contacts, by projected Gauss–Seidel to convergence, applied to the
    ``rates`` (:func:`~visviva.collision.body_impulses.rates_with_world`). Returns the largest
    approach speed left."""
    impulse[:] = 0.0
    scale = 0.0
    for c in range(active.shape[0]):
        if active[c]:
            scale = max(scale, abs(lever_speed(rows, c, 0, index, rates)))
    for _ in range(PROJECTION_SWEEPS):
        largest = 0.0
        for c in range(active.shape[0]):
            if not active[c]:
                continue
            speed = lever_speed(rows, c, 0, index, rates)
            new = max(impulse[c] - mass_n[c] * speed, 0.0)
            change = new - impulse[c]
            if change != 0.0:
                impulse[c] = new
                lever_impulse(rows, c, 0, change, index, rates)
            # Converged: a pushing contact stops approaching, an idle one does not approach.
            largest = max(largest, abs(speed) if new > 0.0 else -speed)
        if largest <= 1e-13 * scale:
            break
    left = 0.0
    for c in range(active.shape[0]):
        if active[c]:
            left = max(left, -lever_speed(rows, c, 0, index, rates))
    return left


@njit(cache=True)
def reflect_impacts(
    body_a, body_b, normal, arm_a, arm_b, mass_n, restitution, gap, reach, threshold,
    inverse_mass, inverse_inertia, v, w,
):  # fmt: skip
    """Resolve the impact of the contacts by generalized reflections (module docstring),
    changing ``v`` and ``w`` ``(B, 3)`` in place. A contact is active when it approaches
    faster than ``threshold`` [m/s] and would close its ``gap`` ``(C,)`` [m] (0 for one that
    touches) within the time ``reach`` [s] (the step) at that speed: a row of balls a
    millimetre apart passes a blow on as one that touches does.

    Returns:
        ``(impulses, rounds, ended)``: each contact's total normal impulse [N·s], the rounds
        taken and whether the impact had to be ended by the inelastic projection.
    """
    count = body_a.shape[0]
    bodies = v.shape[0]
    rows, index = contact_rows(body_a, body_b, normal, np.empty((0, 2, 3)), arm_a, arm_b,
                               inverse_mass, inverse_inertia, bodies, 1)  # fmt: skip
    rates = rates_with_world(v, w)
    total = np.zeros(count)
    impulse = np.zeros(count)
    active = np.zeros(count, dtype=np.bool_)
    previous = np.zeros(count, dtype=np.bool_)
    rounds = 0
    ended = False
    previous_speed = np.inf
    while True:
        approach = 0.0
        any_active = False
        for c in range(count):
            speed = lever_speed(rows, c, 0, index, rates)
            active[c] = speed < -threshold and -speed * reach >= gap[c]
            if active[c]:
                any_active = True
                approach = max(approach, -speed)
        if not any_active:
            break
        same = True
        for c in range(count):
            if active[c] != previous[c]:
                same = False
        if rounds >= MAX_ROUNDS or (same and approach >= previous_speed):
            # The failure case of Vouga et al.: end the impact inelastically, every contact.
            for c in range(count):
                active[c] = gap[c] <= 0.0
            _project(active, rows, index, mass_n, rates, impulse)
            for c in range(count):
                total[c] += impulse[c]
            ended = True
            break
        previous[:] = active
        previous_speed = approach
        # The inelastic projection, then as much again times e: a reflection.
        _project(active, rows, index, mass_n, rates, impulse)
        for c in range(count):
            if impulse[c] > 0.0:
                extra = restitution[c] * impulse[c]
                lever_impulse(rows, c, 0, extra, index, rates)
                total[c] += impulse[c] + extra
        rounds += 1
    v[:] = rates[:bodies, :3]
    w[:] = rates[:bodies, 3:6]
    return total, rounds, ended

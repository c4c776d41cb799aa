"""The compiled parts of the crowd stage (:mod:`visviva.particles.crowd`): the social forces of
every live agent, the exits, and the velocity update.

Symbols are those of Helbing, Farkas & Vicsek (Nature 407, 487, 2000): agent ``i`` of radius
``r_i`` [m] and mass ``m_i`` [kg] at ``x_i`` in the horizontal XZ plane; ``d_ij = |x_i − x_j|``,
``n_ij = (x_i − x_j)/d_ij``, ``t_ij = (−n_ij,z, n_ij,x)``; ``g(s) = max(s, 0)``. Per crowd:
``A`` [N], ``B`` [m], ``k`` [kg/s²], ``κ`` [kg/(m·s)], ``v⁰`` [m/s], ``τ`` [s].

The agents' own arrays are indexed by agent ``a`` (a row of the stage's ``agents``); the grid
is built over the agents' ``(x, 0, z)``, so its sorted positions name agents too.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..collision.colliders import collider_distance
from ..geometry.neighbour_cells import cell_of, neighbour_runs

__all__ = ["CHUNK", "exit_agents", "social_forces", "walk", "wall_distances"]

#: Sorted agents per parallel task of the force kernel.
CHUNK = 256


@njit(cache=True, error_model="numpy")
def _goal_direction(a, x, z, crowd, goal, has_goal, exits, exit_start):  # pragma: no cover
    """Unit vector ``e`` (XZ) from agent ``a`` at ``(x, z)`` to its goal: its crowd's goal
    point, else the centre of the nearest of its crowd's exits; ``(0, 0)`` at the goal."""
    c = crowd[a]
    if has_goal[c]:
        gx, gz = goal[c, 0], goal[c, 1]
    else:
        best = math.inf
        gx = gz = 0.0
        for e in range(exit_start[c], exit_start[c + 1]):
            cx = 0.5 * exits[e, 0] + 0.5 * exits[e, 1]
            cz = 0.5 * exits[e, 4] + 0.5 * exits[e, 5]
            dist2 = (cx - x) * (cx - x) + (cz - z) * (cz - z)
            if dist2 < best:
                best, gx, gz = dist2, cx, cz
    ex, ez = gx - x, gz - z
    norm = math.sqrt(ex * ex + ez * ez)
    if norm == 0.0:
        return 0.0, 0.0
    return ex / norm, ez / norm


@njit(cache=True)
def _sliding_share(rate, h):  # pragma: no cover - compiled
    """``φ(z) = (1 − e^(−z))/z`` at ``z = h · rate``: the sliding friction of a step, a damper
    of ``rate`` [1/s] on a pair's relative sliding, integrated exactly over the step (1 at
    ``h = 0``, the model's force; below 1 beyond, so a step never reverses the sliding)."""
    z = h * rate
    return 1.0 if z < 1e-12 else -math.expm1(-z) / z


@njit(cache=True, error_model="numpy")
def _forces_chunk(
    g, px, py, pz, vx, vz, radius, mass, crowd, params, goal, has_goal, exits, exit_start,
    wall_mask, walls, h, drive, social, wall, runs, begin, end,
):  # fmt: skip  # pragma: no cover - compiled
    """Forces [N] on the agents at sorted positions ``begin .. end − 1`` (see
    :func:`social_forces`)."""
    kinds, rows, offsets, nb, nl, tp, tn = walls
    for s in range(begin, end):
        a = g.order[s]
        c = crowd[a]
        A, B, k, kappa, v0, tau, cut = (
            params[c, 0], params[c, 1], params[c, 2], params[c, 3], params[c, 4], params[c, 5],
            params[c, 6],
        )  # fmt: skip
        xi, zi, ri = px[a], pz[a], radius[a]
        # Driving term m (v⁰ e − v)/τ.
        ex, ez = _goal_direction(a, xi, zi, crowd, goal, has_goal, exits, exit_start)
        drive[a, 0] = mass[a] * (v0 * ex - vx[a]) / tau
        drive[a, 1] = mass[a] * (v0 * ez - vz[a]) / tau
        # Agents: {A exp((r_ij − d_ij)/B) + k g(r_ij − d_ij)} n_ij + κ g(r_ij − d_ij) Δv^t_ji t_ij.
        fx = fz = 0.0
        cx, cy, cz = cell_of(g.x[s], g.y[s], g.z[s], g.inv_cell)
        for m in range(neighbour_runs(g, cx, cy, cz, runs)):
            for t in range(runs[m, 0], runs[m, 1]):
                b = g.order[t]
                if b == a:
                    continue
                dx, dz = xi - px[b], zi - pz[b]
                rij = ri + radius[b]
                d2 = dx * dx + dz * dz
                reach = rij + cut
                if d2 > reach * reach:
                    continue
                d = math.sqrt(d2)
                if d > 0.0:
                    nx, nz = dx / d, dz / d
                else:  # coincident agents: a fixed direction, opposite for the other one
                    nx, nz = (1.0, 0.0) if a < b else (-1.0, 0.0)
                overlap = rij - d
                push = A * math.exp(overlap / B)
                if overlap > 0.0:
                    kb, kappab = params[crowd[b], 2], params[crowd[b], 3]
                    push += 0.5 * (k + kb) * overlap
                    tx, tz = -nz, nx
                    damper = 0.5 * (kappa + kappab) * overlap  # [kg/s]
                    share = _sliding_share(damper * (1.0 / mass[a] + 1.0 / mass[b]), h)
                    slide = damper * share * ((vx[b] - vx[a]) * tx + (vz[b] - vz[a]) * tz)
                    fx += slide * tx
                    fz += slide * tz
                fx += push * nx
                fz += push * nz
        social[a, 0], social[a, 1] = fx, fz
        # Walls: {A exp((r_i − d_iW)/B) + k g(r_i − d_iW)} n_iW − κ g(r_i − d_iW)(v_i·t_iW) t_iW,
        # the colliders' outward normal projected on the XZ plane.
        wx = wz = 0.0
        bits = wall_mask[c]
        for w in range(kinds.shape[0]):
            if not (bits >> np.uint64(w)) & np.uint64(1):
                continue
            dist, nx, _, nz = collider_distance(
                w, xi, py[a], zi, kinds, rows, offsets, nb, nl, tp, tn
            )
            overlap = ri - dist
            if overlap < -cut:
                continue
            push = A * math.exp(overlap / B)
            if overlap > 0.0:
                push += k * overlap
                tx, tz = -nz, nx
                share = _sliding_share(kappa * overlap / mass[a], h)
                slide = -kappa * overlap * share * (vx[a] * tx + vz[a] * tz)
                wx += slide * tx
                wz += slide * tz
            wx += push * nx
            wz += push * nz
        wall[a, 0], wall[a, 1] = wx, wz


@njit(cache=True, parallel=True)
def _forces_parallel(
    g, px, py, pz, vx, vz, radius, mass, crowd, params, goal, has_goal, exits, exit_start,
    wall_mask, walls, h, drive, social, wall,
):  # fmt: skip  # pragma: no cover - compiled
    n = g.order.shape[0]
    for task in prange((n + CHUNK - 1) // CHUNK):
        runs = np.empty((27, 2), dtype=np.int64)
        _forces_chunk(
            g, px, py, pz, vx, vz, radius, mass, crowd, params, goal, has_goal, exits,
            exit_start, wall_mask, walls, h, drive, social, wall, runs, CHUNK * task,
            min(n, CHUNK * task + CHUNK),
        )  # fmt: skip


@njit(cache=True)
def _forces_serial(
    g, px, py, pz, vx, vz, radius, mass, crowd, params, goal, has_goal, exits, exit_start,
    wall_mask, walls, h, drive, social, wall,
):  # fmt: skip  # pragma: no cover - compiled
    runs = np.empty((27, 2), dtype=np.int64)
    _forces_chunk(
        g, px, py, pz, vx, vz, radius, mass, crowd, params, goal, has_goal, exits, exit_start,
        wall_mask, walls, h, drive, social, wall, runs, 0, g.order.shape[0],
    )  # fmt: skip


def social_forces(
    g, px, py, pz, vx, vz, radius, mass, crowd, params, goal, has_goal, exits, exit_start,
    wall_mask, walls, h, drive, social, wall, parallel,
) -> None:  # fmt: skip
    """The three forces [N] on every live agent, written into ``drive``, ``social`` and
    ``wall`` ``(n, 2)`` (x and z; rows of dead agents are left as they are).

    Args:
        g: The grid over the agents' ``(x, 0, z)`` (live ones only).
        px, py, pz, vx, vz: Agent positions [m] and horizontal velocities [m/s], ``(n,)``.
        radius, mass: ``r_i`` [m] and ``m_i`` [kg], ``(n,)``.
        crowd: Each agent's crowd, ``(n,)`` int64.
        params: Per crowd ``(A, B, k, κ, v⁰, τ, cut)``, ``(C, 7)``; ``cut`` [m] is how far
            beyond contact the repulsion is felt.
        goal, has_goal: Per crowd its goal point (x, z) [m] ``(C, 2)`` and whether it has one.
        exits: Exit boxes ``(E, 6)``: x, y and z bounds (low, high) [m], crowd after crowd;
            ``exit_start`` ``(C + 1,)``: each crowd's first exit.
        wall_mask: Per crowd, bit ``w`` set if collider ``w`` is one of its walls.
        walls: The colliders' kernel arrays (what :func:`collider_distance` takes).
        h: The step [s] the sliding friction is integrated over (:func:`_sliding_share`; 0:
            the model's force at an instant).
        parallel: Use every core (a parallel region costs tens of µs to start).
    """
    kernel = _forces_parallel if parallel else _forces_serial
    kernel(
        g, px, py, pz, vx, vz, radius, mass, crowd, params, goal, has_goal, exits, exit_start,
        wall_mask, walls, h, drive, social, wall,
    )  # fmt: skip


@njit(cache=True)
def exit_agents(agents, alive, x, v, crowd, exits, exit_start, exit_time, t):  # pragma: no cover
    """Remove the live agents whose centre lies in one of their crowd's exits (bounds
    inclusive): ``alive`` False, parked at rest at the origin, ``exit_time`` ``t`` [s]. Agents
    that left before are parked again (the integrator's forces, gravity say, moved them).
    Returns how many left in this step."""
    left = 0
    for a in range(agents.shape[0]):
        i = agents[a]
        if not alive[i]:
            for q in range(3):
                x[i, q] = 0.0
                v[i, q] = 0.0
            continue
        c = crowd[a]
        for e in range(exit_start[c], exit_start[c + 1]):
            if (
                exits[e, 0] <= x[i, 0] <= exits[e, 1]
                and exits[e, 2] <= x[i, 1] <= exits[e, 3]
                and exits[e, 4] <= x[i, 2] <= exits[e, 5]
            ):
                alive[i] = False
                exit_time[i] = t
                for q in range(3):
                    x[i, q] = 0.0
                    v[i, q] = 0.0
                left += 1
                break
    return left


@njit(cache=True, error_model="numpy")
def walk(agents, alive, x, v, height, mass, drive, social, wall, max_speed, crowd, h):
    """The velocity kick of a step of ``h`` [s]: ``v += h (drive + social + wall)/m`` in XZ,
    the speed capped at the crowd's ``max_speed`` [m/s]; the height kept at ``height`` [m] and
    the vertical velocity zero."""
    for a in range(agents.shape[0]):  # pragma: no cover - compiled
        i = agents[a]
        if not alive[i]:
            continue
        scale = h / mass[a]
        ux = v[i, 0] + scale * (drive[a, 0] + social[a, 0] + wall[a, 0])
        uz = v[i, 2] + scale * (drive[a, 1] + social[a, 1] + wall[a, 1])
        speed = math.sqrt(ux * ux + uz * uz)
        top = max_speed[crowd[a]]
        if speed > top:
            ux, uz = ux * (top / speed), uz * (top / speed)
        v[i, 0], v[i, 1], v[i, 2] = ux, 0.0, uz
        x[i, 1] = height[a]


@njit(cache=True, error_model="numpy")
def wall_distances(points, walls):  # pragma: no cover - compiled
    """Signed distance [m] of each point ``(P, 3)`` to each collider of ``walls`` (the kernel
    arrays :func:`collider_distance` takes): ``(P, K)``, negative inside."""
    kinds, rows, offsets, nb, nl, tp, tn = walls
    out = np.empty((points.shape[0], kinds.shape[0]))
    for p in range(points.shape[0]):
        for w in range(kinds.shape[0]):
            out[p, w] = collider_distance(
                w, points[p, 0], points[p, 1], points[p, 2], kinds, rows, offsets, nb, nl, tp, tn
            )[0]
    return out

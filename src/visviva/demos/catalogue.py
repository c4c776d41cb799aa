"""The built-in demos' names and summaries, listed without importing the demos.

A demo's module imports what it simulates with (Numba's kernels, SciPy, sympy), which
``visviva demo`` without a name, a list, does not need. This table gives each built-in demo's
name, its module in this package and its one-line summary; the module declares the rest of the
demo (default duration, playback, ``run``) and is imported when the demo is asked for. Adding a
demo is a module and a line here.
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["BUILTIN_DEMOS", "BuiltinDemo"]


class BuiltinDemo(NamedTuple):
    """Where a built-in demo lives and what it shows.

    Attributes:
        module: Its module in :mod:`visviva.demos`, which registers it.
        summary: One line describing what it shows.
    """

    module: str
    summary: str


#: Every built-in demo by name.
BUILTIN_DEMOS: dict[str, BuiltinDemo] = {
    "arch": BuiltinDemo(
        "arch",
        "a catenary arch of 17 stone blocks stands with friction 0.6 and slides apart at 0.2; "
        "the friction it needs against limit analysis",
    ),
    "ball-pit": BuiltinDemo(
        "ball_pit",
        "balls dropped into a box: sphere collisions (restitution, friction), settling; overlaps, "
        "momentum, the floor's support",
    ),
    "billiards": BuiltinDemo(
        "billiards",
        "a 15-ball break at 8 m/s: simultaneous impacts spread the rack, sequential ones bounce "
        "the cue ball off it as one lump; momentum, energy, spread",
    ),
    "boids": BuiltinDemo(
        "boids",
        "10,000 birds flock around an obstacle to a goal: Reynolds' boids; polarisation, spacing",
    ),
    "bottle-flip": BuiltinDemo(
        "bottle_flip",
        "a flick at a bottle's base gives it spin (τ = r × F); same flick, different I",
    ),
    "bunny-drop": BuiltinDemo(
        "bunny_drop",
        "non-convex bunnies cut into convex pieces (CoACD) fall onto a floor and a step and "
        "rest on their own surfaces; one as its hull, for comparison",
    ),
    "bunny-throw": BuiltinDemo(
        "bunny_throw",
        "a rabbit-shaped mesh thrown with spin: parabola for its centre, tumbling about it",
    ),
    "circular": BuiltinDemo(
        "circular",
        "seed 004's circular motion: explicit Euler spirals out, implicit in, symplectic stays",
    ),
    "cloth-drape": BuiltinDemo(
        "cloth_drape",
        "cloth falls onto a ball with friction (projected Newton): no penetration, Coulomb holds",
    ),
    "cloth-hang": BuiltinDemo(
        "cloth_hang",
        "cloth held at two corners falls and hangs: energy never rises, pins carry its weight",
    ),
    "constrained-pendulum": BuiltinDemo(
        "constrained_pendulum",
        "the pendulum as a particle held by f = λ(r − c), beside the θ description",
    ),
    "cradle": BuiltinDemo(
        "cradle",
        "Newton's cradle on anchored strings: simultaneous impacts pass the blow down the row, "
        "sequential ones share it",
    ),
    "crowd": BuiltinDemo(
        "crowd",
        "a room of 200 agents evacuating through a door: social forces, flow rate, density",
    ),
    "dominoes": BuiltinDemo(
        "dominoes",
        "20 dominoes topple in turn: the wave's speed, all fallen; v ∝ √(g h) at four times the "
        "size",
    ),
    "double-pendulum": BuiltinDemo(
        "double_pendulum",
        "chaos: two double pendulums 1e-9 rad apart, Lyapunov exponent, energy",
    ),
    "dzhanibekov": BuiltinDemo(
        "dzhanibekov",
        "T-handles spun about each principal axis: only the intermediate one flips",
    ),
    "fireworks": BuiltinDemo(
        "fireworks",
        "shells burst into spheres of sparks: burst emitters, quadratic drag, colour ramps",
    ),
    "flag": BuiltinDemo(
        "flag",
        "a flag hung from a staff in the wind: its deflection against drag and weight",
    ),
    "fountain": BuiltinDemo(
        "fountain",
        "a water jet into a basin: emitter, gravity, drag, a floor; steady state and apex",
    ),
    "galaxy": BuiltinDemo(
        "galaxy",
        "two disk galaxies collide: tidal bridges and tails, gravity from the Barnes–Hut tree",
    ),
    "hair": BuiltinDemo(
        "hair",
        "hair strands swing after the head turns and stops: roots on the head, stretch bounded, "
        "chain periods",
    ),
    "jelly": BuiltinDemo(
        "jelly",
        "a jelly cube dropped on the floor: free fall, no penetration, squashed by its weight",
    ),
    "kepler": BuiltinDemo(
        "kepler",
        "two-body orbit with e = 0.5 against Kepler's equation; energy and angular momentum",
    ),
    "oscillator": BuiltinDemo(
        "oscillator",
        "every integrator on an undamped spring: energy growth, decay or conservation side by side",
    ),
    "pendulum": BuiltinDemo(
        "pendulum",
        "seed 001's pendulum from K and U: exact period vs the small-angle solution",
    ),
    "refinement-study": BuiltinDemo(
        "refinement_study",
        "one cloth at 6, 11, 21 points per side: a curtain converges, two pins do not; shear, bend",
    ),
    "rock": BuiltinDemo(
        "rock",
        "seed 001's thrown rock: integrators against the exact parabola",
    ),
    "rotation-drift": BuiltinDemo(
        "rotation_drift",
        "rotation matrices and quaternions under explicit Euler, renormalized or not",
    ),
    "pile": BuiltinDemo(
        "pile",
        "4,096 spheres, boxes, capsules, cylinders, cones and rocks (10,000 with --full) fall "
        "into a bin and come to rest: the whole contact pipeline at scale",
    ),
    "snow": BuiltinDemo(
        "snow",
        "snowflakes in wind and a gust settle on a ball and the ground (drag, vortex, friction)",
    ),
    "spring-pendulum": BuiltinDemo(
        "spring_pendulum",
        "a bob on a spring: swing and bounce trade energy (autoparametric resonance)",
    ),
    "stack": BuiltinDemo(
        "stack",
        "ten boxes stacked on the floor stand for 10 s: every box within 1 mm, at rest "
        "(issue 27's test)",
    ),
    "stiffness-study": BuiltinDemo(
        "stiffness_study",
        "explicit vs implicit on one cloth at k = 3 to 1e4 N/m: the advisor predicts blow-ups",
    ),
    "sun-earth-moon": BuiltinDemo(
        "sun_earth_moon",
        "a year of the Sun, Earth and Moon in SI units from J2000: the year and the month",
    ),
    "test-equation": BuiltinDemo(
        "dahlquist",
        "y' = -y at steps on both sides of h = 2: who decays, who oscillates, who blows up",
    ),
    "top": BuiltinDemo(
        "top",
        "a spinning top on its tip: gravity's torque makes it precess and nod, not topple",
    ),
}

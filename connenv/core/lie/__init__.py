"""Lie groups of motions and the integrator of a mechanical connection on them.

A mechanical connection A(s) (Lawton) turns shape changes ṡ into a group velocity ξ = −A(s) ṡ, which moves the
group element g by ġ = g ξ^ (body frame: ξ in the moving body's coordinates) or ġ = ξ^ g (space frame). The groups
and their coordinates are in `connenv.core.lie.groups`.

Everything here works on *components*: tuples of Python floats for one state (the fast path: no numpy call per
operation) or of arrays over the rows of a batch, with the same arithmetic, so that row i of a batch follows the
single state's path (to the last bits of sin and cos, numpy's and libm's).

`Magnus` is the stepper (``integrator="magnus"``). On SO(3) it is the Magnus method with Gauss points (Blanes,
Casas & Ros 2000; Iserles et al. 2000), each substep of length h one exponential. Of order 4, with two Gauss points,

    Ω = h/2 (ξ₁ + ξ₂) ± (√3/12) h² [ξ₁, ξ₂],    ξ_i = ξ(t + c_i h),  c_i = 1/2 ∓ √3/6,

with + in the body frame (g ← g exp Ω) and − in the space frame (g ← exp(Ω) g); of order 6 (the default: fewer
substeps for the same error), with three Gauss points and nested brackets (`magnus_omega`). SO(2), ℝ² and SE(2) are
solvable, and there the flow is nested quadratures (`quadrature_flow`): θ = ∫ω, and on SE(2) the translation
∫R(θ(t)) v(t) dt, by 8-point Gauss–Legendre rules, of spectral accuracy on smooth connections (on the abelian
groups this is the integral of ξ itself). Exponentials are closed forms (Rodrigues for SO(3)), so g stays on its
group to rounding. Where ξ is the same at every node (A constant along the path, or ṡ = 0) the step is one
exponential, the exact flow.

By default each segment's substeps come from a Richardson estimate (two extra flows per segment), which serves any
connection; where it asks for more substeps, their result is checked against twice as many. A caller that knows
every segment it can ask for (a box of shapes and a step dt) fixes the rule once instead, with `fixed_rule`: the
fewest nodes, pieces × Gauss points, that meet the tolerance on its worst segments; on SE(2) in the body frame
`se2_body_flow` then takes one state on Python floats and a batch in blocks of rows.

The package is three modules, each on the one before: `groups` (the groups in coordinates), `connections` (the
systems a connection moves) and `magnus` (the step); ``connenv.core.lie`` gives their public names.
"""

from __future__ import annotations

from connenv.core.lie.connections import (
    Connection,
    ConstantConnection,
    ExactConnection,
    connection_system,
    constant_connection,
    group_velocity,
)
from connenv.core.lie.groups import FRAMES, GROUPS, Group
from connenv.core.lie.magnus import (
    GAUSS6,
    QUADRATURE_POINTS,
    Magnus,
    fixed_rule,
    gauss_rule,
    magnus_flow,
    magnus_omega,
    quadrature_flow,
    se2_body_flow,
)

__all__ = [
    "FRAMES",
    "GAUSS6",
    "GROUPS",
    "QUADRATURE_POINTS",
    "Connection",
    "ConstantConnection",
    "ExactConnection",
    "Group",
    "Magnus",
    "connection_system",
    "constant_connection",
    "fixed_rule",
    "gauss_rule",
    "group_velocity",
    "magnus_flow",
    "magnus_omega",
    "quadrature_flow",
    "se2_body_flow",
]

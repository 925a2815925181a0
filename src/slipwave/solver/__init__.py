"""Frictional contact of an elastic slab on a rigid flat: the paper's model.

Plane-strain linear elastic slab, quasi-static loading, unilateral contact
with Coulomb friction (static and dynamic coefficients), followed increment
by increment along the bench's load path.

>>> from slipwave.solver import Slab, Coulomb, LoadPath, simulate, describe_behaviour
>>> ds = simulate(Slab(elements=40), Coulomb(fs=1.0), LoadPath())
>>> describe_behaviour(ds).sequence[0]
'opening right'
"""

from slipwave.solver.behaviour import Behaviour, describe_behaviour
from slipwave.solver.cache import SolverCache
from slipwave.solver.contact import Body, Control
from slipwave.solver.simulate import (
    Coulomb,
    LoadPath,
    SlipWeakening,
    simulate,
    simulation_memory,
)
from slipwave.solver.slab import Condensed, Slab, condense

__all__ = [
    "Behaviour",
    "Body",
    "Condensed",
    "Control",
    "Coulomb",
    "LoadPath",
    "Slab",
    "SlipWeakening",
    "SolverCache",
    "condense",
    "describe_behaviour",
    "simulate",
    "simulation_memory",
]

"""The behaviour of the interface during a simulation, as the paper maps it.

The paper (Zeghloul, Dubourg & Villechaise, 1994) sorts its 1572 cases into
behaviours by the sequence of events at the interface. Two are named:

- **ZD**: a slip zone sweeping the interface from the right edge to the left.
  Here: ``first_slip == "right"`` and ``sweep == "right_to_left"``.
- **ZG**: a slip zone starting mid-interface and sweeping to the right.
  Here: ``first_slip == "interior"`` and ``sweep == "from_interior_to_right"``.
- The mark **L**, the first opening appearing at the right edge of the
  contact, is ``first_opening == "right"``.

Two simulations have the same :attr:`Behaviour.label` when, and only when,
their sequences of events are the same.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy import ndimage

from slipwave.solver.contact import OPEN, SLIP

_EDGE_FRACTION = 0.05  # a zone within 5 % of L of an end of the contact starts "at" it


@dataclass(frozen=True)
class Behaviour:
    """What happened at the interface.

    Attributes
    ----------
    after_normal
        ``"full_stick"`` or ``"edge_slip"`` (slip zones at the edges after the
        normal loading) or ``"slip"`` (elsewhere too).
    edge_slip_extent
        Fractions of the contact length slipping at the left and right edges
        after the normal loading.
    first_opening
        Where a node in contact after the normal loading first opens during the
        tangential loading: ``"left"``, ``"right"``, ``"interior"`` or ``None``.
    first_slip
        Where slip first appears during the tangential loading (same values).
    sweep
        How the slip zone spreads until gross sliding: ``"right_to_left"``,
        ``"left_to_right"``, ``"edges_to_interior"``, ``"from_interior_to_left"``,
        ``"from_interior_to_right"``, ``"from_interior"`` or ``None`` (no slip
        before gross sliding).
    interior_nucleation
        Whether a separate slip zone appears inside the contact, away from the
        edges and from the existing slip and open zones, before gross sliding.
    partial_before_gross
        Whether part of the contact slips before all of it does.
    ratio_at_gross
        T/N at the first gross sliding, ``None`` if it was not reached.
    label
        A compact string of the above, equal for equal event sequences.

    """

    after_normal: str
    edge_slip_extent: tuple[float, float]
    first_opening: str | None
    first_slip: str | None
    sweep: str | None
    interior_nucleation: bool
    partial_before_gross: bool
    ratio_at_gross: float | None
    label: str

    @property
    def paper_name(self) -> str | None:
        """``"ZD"`` or ``"ZG"`` when the behaviour is one the paper names.

        Returns
        -------
        str or None
            The paper's name, or ``None`` for an unnamed behaviour.

        """
        if self.first_slip == "right" and self.sweep == "right_to_left":
            return "ZD"
        if self.first_slip == "interior" and self.sweep == "from_interior_to_right":
            return "ZG"
        return None


def _where(mask: np.ndarray, x: np.ndarray, contact: np.ndarray) -> str:
    """Where a set of nodes lies in the contact: left, right or interior."""
    inside = x[contact]
    near = _EDGE_FRACTION * (x[-1] - x[0])
    lo, hi = float(x[mask].min()), float(x[mask].max())
    at_left = lo <= inside.min() + near
    at_right = hi >= inside.max() - near
    if at_left and not at_right:
        return "left"
    if at_right and not at_left:
        return "right"
    if at_left and at_right:
        return "both"
    return "interior"


def _region(mask: np.ndarray, x: np.ndarray) -> str:
    """Left, right or interior third of the contact, by the centroid of ``mask``."""
    centre = float(x[mask].mean())
    third = (x[-1] - x[0]) / 6
    return "left" if centre < -third else "right" if centre > third else "interior"


def describe_behaviour(ds: xr.Dataset) -> Behaviour:
    """Classify the interface behaviour of a :func:`~slipwave.solver.simulate` result.

    Parameters
    ----------
    ds
        From :func:`~slipwave.solver.simulate`.

    Returns
    -------
    Behaviour
        The features of the zone history and their label.

    Examples
    --------
    >>> from slipwave.solver import Slab, Coulomb, LoadPath, simulate
    >>> behaviour = describe_behaviour(simulate(Slab(elements=40), Coulomb(fs=1.0), LoadPath()))
    >>> behaviour.first_opening, behaviour.first_slip
    ('right', 'right')

    """
    x = ds["x"].values
    state = ds["state"].values
    phase = ds["phase"].values
    wave = ds["wave"].values
    normal_steps = np.flatnonzero(phase == "normal")
    tangential = np.flatnonzero(phase == "tangential")
    end_normal = state[normal_steps[-1]]
    contact0 = end_normal != OPEN

    slipping0 = end_normal == SLIP
    left_run = int(np.argmin(slipping0)) if not slipping0.all() else slipping0.size
    right_run = int(np.argmin(slipping0[::-1])) if not slipping0.all() else slipping0.size
    edge_extent = (round(left_run / (x.size - 1), 4), round(right_run / (x.size - 1), 4))
    if not slipping0.any():
        after_normal = "full_stick"
    elif slipping0.sum() == left_run + right_run:
        after_normal = "edge_slip"
    else:
        after_normal = "slip"

    gross_steps = tangential[wave[tangential] == "gross"]
    last = int(gross_steps[0]) if gross_steps.size else (int(tangential[-1]) if tangential.size
                                                          else -1)
    before = tangential[tangential < last] if gross_steps.size else tangential

    first_opening = None
    for k in before:
        opened = (state[k] == OPEN) & contact0
        if opened.any():
            first_opening = _where(opened, x, contact0)
            break

    # Onset of slip per node: the first tangential step it slips in, in another
    # direction than at the end of the normal loading (edge slip going on is not new).
    direction = ds["slip_direction"].values
    direction0 = direction[normal_steps[-1]]
    onset = np.full(x.size, np.iinfo(np.int64).max)
    nucleation = False
    previous = np.zeros(x.size, dtype=bool)
    for k in before:
        slipping = (state[k] == SLIP) & (direction[k] != direction0)
        onset[slipping & (onset == np.iinfo(np.int64).max)] = k
        zones, count = ndimage.label(slipping)
        for zone in range(1, count + 1):
            members = zones == zone
            grown = ndimage.binary_dilation(previous | (state[k] == OPEN), iterations=2)
            if not (members & grown).any() and _where(members, x, contact0) == "interior":
                nucleation = nucleation or bool(previous.any())
        previous = slipping
    slipped = onset < np.iinfo(np.int64).max

    first_slip = sweep = None
    if slipped.any():
        first = onset == onset[slipped].min()
        first_slip = _where(first, x, state[int(onset[slipped].min())] != OPEN)
        in_contact_at_end = state[last] != OPEN if last >= 0 else contact0
        late = in_contact_at_end & ~slipped
        if not late.any():
            late = slipped & (onset == onset[slipped].max())
        ending = _region(late, x)
        if first_slip == "right":
            sweep = "right_to_left" if ending != "right" else "right_only"
        elif first_slip == "left":
            sweep = "left_to_right" if ending != "left" else "left_only"
        elif first_slip == "both":
            sweep = "edges_to_interior"
        else:
            sweep = {"left": "from_interior_to_left", "right": "from_interior_to_right"}.get(
                ending, "from_interior")

    ratio = None
    if gross_steps.size:
        ratio = float(ds["T"].values[last] / ds["N"].values[last])
    partial = bool(slipped.any())
    label = "|".join([
        f"N:{after_normal}",
        f"O:{first_opening or '-'}",
        f"S:{first_slip or '-'}",
        f"W:{sweep or '-'}",
        f"I:{'y' if nucleation else 'n'}",
        f"P:{'y' if partial else 'n'}",
        f"G:{'y' if gross_steps.size else 'n'}",
    ])
    return Behaviour(
        after_normal=after_normal, edge_slip_extent=edge_extent, first_opening=first_opening,
        first_slip=first_slip, sweep=sweep, interior_nucleation=nucleation,
        partial_before_gross=partial, ratio_at_gross=ratio, label=label,
    )

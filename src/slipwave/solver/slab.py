"""The slab: plane-strain finite elements, condensed onto the contact nodes.

The slab ``[-L/2, L/2] x [0, H]`` is meshed with bilinear quadrilaterals,
uniform along the contact (``elements`` of them) and graded upwards. The
volumetric term is integrated at one point per element (selective reduced
integration), which removes the volumetric locking of bilinear elements at
Poisson ratios near 1/2; at 0.48 the condensed normal and shear stiffnesses
agree with 9-node quadratic elements on the same mesh to 0.1 %.

The stiffness is condensed onto the contact nodes (static condensation, the
Schur complement of the interior), so that each load increment is a small
dense problem; the lateral displacements of the slab's faces at the sensor
height follow from the contact displacements through a 2 x 2n matrix.
Condensed matrices are computed for E = 1 and scaled, so a sweep over E or
friction does not rebuild them; a caller keeps them in a
:class:`~slipwave.solver.cache.SolverCache`, which may hand them to a store that
keeps them on disk (:class:`slipwave.cache.DiskCache`): the solver itself reads and
writes no file.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, Protocol

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from skfem import Basis, BilinearForm, ElementQuad1, ElementVector, MeshQuad, asm
from skfem.helpers import ddot, div, sym_grad

from slipwave.defaults import (
    CONTACT_LENGTH_MM,
    POISSON_RATIO,
    SLAB_ELEMENTS,
    SLAB_HEIGHT_MM,
    SLAB_WIDTH_MM,
    YOUNGS_MODULUS_MPA,
)
from slipwave.errors import SlipwaveError

if TYPE_CHECKING:
    from slipwave.solver.cache import SolverCache

SENSOR_HEIGHT = 5.0
"""Height (mm) above the contact of the DG and DD displacement sensors."""

_CACHE_VERSION = "q1sri-5"


@dataclass(frozen=True)
class Slab:
    """A rectangular elastic slab on a rigid flat (mm, MPa).

    Attributes
    ----------
    length
        L, along the contact.
    height
        H.
    width
        w, out of plane; loads are reported for the full width.
    youngs_modulus
        E.
    poisson_ratio
        nu (plane strain).
    elements
        Number of elements along the contact; the contact has ``elements + 1``
        nodes.
    holder
        ``"clamped"``: the top face is held rigidly without rotation;
        ``"free"``: held rigidly but free to rotate (no moment).
    profile
        Initial gap g0(x) (mm) between slab and flat, a vectorised callable of
        x (mm, origin at the contact centre); ``None`` for a flat slab.

    """

    length: float = CONTACT_LENGTH_MM
    height: float = SLAB_HEIGHT_MM
    width: float = SLAB_WIDTH_MM
    youngs_modulus: float = YOUNGS_MODULUS_MPA
    poisson_ratio: float = POISSON_RATIO
    elements: int = SLAB_ELEMENTS
    holder: Literal["clamped", "free"] = "clamped"
    profile: Callable[[np.ndarray], np.ndarray] | None = field(default=None, compare=False)
    growth: float = 1.15
    max_aspect: float = 4.0

    def __post_init__(self) -> None:
        if not (self.length > 0 and self.width > 0 and self.youngs_modulus > 0):
            raise SlipwaveError("slab length, width and Young's modulus must be positive")
        if not self.height > SENSOR_HEIGHT:
            raise SlipwaveError(
                f"slab height {self.height} mm must exceed the sensor height {SENSOR_HEIGHT} mm"
            )
        if not 0.0 <= self.poisson_ratio < 0.5:
            raise SlipwaveError(f"Poisson ratio {self.poisson_ratio} is not in [0, 0.5)")
        if self.elements < 4:
            raise SlipwaveError(f"{self.elements} elements along the contact: need at least 4")
        if self.holder not in ("clamped", "free"):
            raise SlipwaveError(f"holder {self.holder!r}: 'clamped' or 'free'")

    @property
    def x(self) -> np.ndarray:
        """Contact node abscissae (mm), left to right, origin at the centre.

        Returns
        -------
        numpy.ndarray
            (elements + 1,) positions, mm.

        """
        return np.linspace(-self.length / 2, self.length / 2, self.elements + 1)

    @property
    def tributary_length(self) -> np.ndarray:
        """Length of contact (mm) each node stands for: h inside, h/2 at the ends.

        Returns
        -------
        numpy.ndarray
            (elements + 1,) lengths, mm.

        """
        weights = np.full(self.elements + 1, self.length / self.elements)
        weights[[0, -1]] /= 2
        return weights

    def initial_gap(self) -> np.ndarray:
        """g0 at the contact nodes (mm).

        Returns
        -------
        numpy.ndarray
            (elements + 1,) gaps, mm (zero for a flat slab).

        """
        if self.profile is None:
            return np.zeros(self.elements + 1)
        gap = np.asarray(self.profile(self.x), dtype=np.float64)
        if gap.shape != self.x.shape or not np.isfinite(gap).all():
            raise SlipwaveError("slab profile must return a finite gap for every contact node")
        return gap - gap.min()

    def heights(self) -> np.ndarray:
        """Node rows of the mesh (mm): fine at the contact, graded upwards.

        Returns
        -------
        numpy.ndarray
            Heights of the node rows, mm, from 0 to H.

        """
        h0 = self.length / self.elements
        rows, step = [0.0], h0
        while rows[-1] < self.height - 1e-9:
            rows.append(min(rows[-1] + step, self.height))
            step = min(step * self.growth, self.max_aspect * h0)
        if len(rows) > 2 and rows[-1] - rows[-2] < 0.3 * (rows[-2] - rows[-3]):
            del rows[-2]  # no sliver row under the holder
        return np.unique(np.concatenate([rows, [SENSOR_HEIGHT]]))


@dataclass(frozen=True)
class Condensed:
    """The slab's stiffness condensed onto its contact nodes (per unit width).

    Attributes
    ----------
    stiffness
        (2n, 2n) symmetric, N/mm per mm of width; unknowns ordered
        ``[ux_0..ux_{n-1}, uy_0..uy_{n-1}]`` (tangential, then normal).
    sensors
        (2, 2n): lateral displacements of the left and right faces at the
        sensor height, from the contact displacements.
    """

    stiffness: np.ndarray
    sensors: np.ndarray


class CondensationStore(Protocol):
    """Where condensed matrices outlive the process (e.g. :class:`slipwave.cache.DiskCache`).

    The solver hands it the key of a geometry (:func:`geometry_key`) and the
    matrices for E = 1; it does no file I/O itself.
    """

    def load(self, key: str) -> Condensed | None:
        """The matrices stored under ``key``, or ``None``.

        Parameters
        ----------
        key
            From :func:`geometry_key`.

        Returns
        -------
        Condensed or None
            The stored matrices, or ``None``.

        """

    def save(self, key: str, condensed: Condensed) -> None:
        """Keep ``condensed`` under ``key``.

        Parameters
        ----------
        key
            From :func:`geometry_key`.
        condensed
            The matrices for E = 1.

        """


def rounded_corners(radius: float, length: float = CONTACT_LENGTH_MM
                    ) -> Callable[[np.ndarray], np.ndarray]:
    """A slab's profile whose two contact corners are rounded (``Slab(profile=)``).

    Over the last ``radius`` of each end of the contact the slab's face lifts off the
    flat along a quarter circle of that radius, which bounds the stress concentration
    a sharp corner has.

    Parameters
    ----------
    radius
        The corners' radius, mm.
    length
        The contact's length L, mm.

    Returns
    -------
    callable
        x (mm, 0 at the contact's centre) -> the initial gap, mm; picklable.

    Examples
    --------
    >>> gap = rounded_corners(2.0)(np.array([0.0, 38.0, 39.0, 40.0]))
    >>> gap.round(3).tolist()
    [0.0, 0.0, 0.268, 2.0]
    """
    if not 0.0 < radius < length / 2:
        raise SlipwaveError(f"corner radius {radius} mm: need 0 < radius < L/2 = "
                            f"{length / 2:g} mm")
    return functools.partial(_rounded_gap, radius=radius, start=length / 2 - radius)


def _rounded_gap(x: np.ndarray, *, radius: float, start: float) -> np.ndarray:
    beyond = np.clip(np.abs(x) - start, 0.0, radius)
    return radius - np.sqrt(radius**2 - beyond**2)


def geometry_key(slab: Slab) -> str:
    """A key naming the slab's geometry and mesh (not E, width, profile or friction).

    Parameters
    ----------
    slab
        The slab.

    Returns
    -------
    str
        24 hexadecimal digits, changed whenever the condensation would change.

    """
    fields = (
        _CACHE_VERSION, slab.length, slab.height, slab.poisson_ratio, slab.elements,
        slab.holder, slab.growth, slab.max_aspect, SENSOR_HEIGHT,
    )
    return hashlib.sha256(repr(fields).encode()).hexdigest()[:24]


def condense(slab: Slab, *, cache: SolverCache | None = None) -> Condensed:
    """Condensed stiffness and sensor matrix of a slab.

    The matrices are computed for E = 1 and scaled, so a sweep over E or
    friction does not rebuild them when a ``cache`` keeps them.

    Parameters
    ----------
    slab
        The slab.
    cache
        Where the unit matrices are looked up and kept; ``None``: computed afresh.

    Returns
    -------
    Condensed
        The slab's condensed matrices for its Young's modulus.

    """
    geometry = dataclasses.replace(slab, youngs_modulus=1.0, width=1.0, profile=None)
    if cache is None:
        unit = assemble_condensed(geometry)
    else:
        unit = cache.condensed(geometry_key(geometry), lambda: assemble_condensed(geometry))
    return Condensed(unit.stiffness * slab.youngs_modulus, unit.sensors)


@dataclass(frozen=True)
class _Assembly:
    """The slab's stiffness with the holder applied, and where its dofs are."""

    reduced: sp.csc_matrix
    basis: sp.csr_matrix
    locations: np.ndarray
    is_x: np.ndarray
    kept: np.ndarray
    interior: np.ndarray
    side: np.ndarray  # of each interior dof: 0 or 1, either side of the first cut; -1 on it
    n_contact: int


_ELEMENTS_PER_CHUNK = 2048


def _assemble(slab: Slab) -> _Assembly:
    E = slab.youngs_modulus
    nu = slab.poisson_ratio
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))

    @BilinearForm
    def deviatoric(u, v, _):  # type: ignore[no-untyped-def]
        return 2 * mu * ddot(sym_grad(u), sym_grad(v))

    @BilinearForm
    def volumetric(u, v, _):  # type: ignore[no-untyped-def]
        return lam * div(u) * div(v)

    mesh = MeshQuad.init_tensor(slab.x, slab.heights())
    element = ElementVector(ElementQuad1())
    centre = (np.array([[0.5], [0.5]]), np.array([1.0]))  # one-point rule on [0, 1]^2
    full = Basis(mesh, element, intorder=1, elements=np.arange(1))  # its dofs are global
    stiffness = sp.csr_matrix((full.N, full.N))
    # a chunk of elements at a time: the bases' values at the quadrature points and the
    # triplets stay small (at 320 elements: 70 MB for the whole mesh at once, 24 MB this way)
    for start in range(0, mesh.t.shape[1], _ELEMENTS_PER_CHUNK):
        chunk = np.arange(start, min(start + _ELEMENTS_PER_CHUNK, mesh.t.shape[1]))
        # the whole mesh's dof numbering made once (each basis would number it again)
        shared = {"elements": chunk, "dofs": full.dofs, "disable_doflocs": True}
        stiffness += asm(deviatoric, Basis(mesh, element, intorder=2, **shared))
        stiffness += asm(volumetric, Basis(mesh, element, quadrature=centre, **shared))

    locations = full.doflocs
    is_x = np.zeros(stiffness.shape[0], dtype=bool)
    is_x[full.nodal_dofs[0]] = True
    on = functools.partial(np.isclose, atol=1e-9 * slab.length)
    bottom = on(locations[1], 0.0)
    top = on(locations[1], slab.height)
    contact_x = _sorted_by_x(np.flatnonzero(bottom & is_x), locations)
    contact_y = _sorted_by_x(np.flatnonzero(bottom & ~is_x), locations)
    at_sensors = on(locations[1], SENSOR_HEIGHT) & is_x
    sensor_left = np.flatnonzero(at_sensors & on(locations[0], -slab.length / 2))
    sensor_right = np.flatnonzero(at_sensors & on(locations[0], slab.length / 2))
    kept = np.concatenate([contact_x, contact_y, sensor_left, sensor_right])

    # Map the free unknowns to all dofs: top x fixed; top y fixed (clamped) or
    # x * theta (free: a rigid rotation of the holder about the top centre).
    free = np.flatnonzero(~top)
    columns = [sp.csr_matrix((np.ones(free.size), (free, np.arange(free.size))),
                             shape=(stiffness.shape[0], free.size))]
    if slab.holder == "free":
        top_y = np.flatnonzero(top & ~is_x)
        columns.append(sp.csr_matrix((locations[0, top_y], (top_y, np.zeros(top_y.size))),
                                     shape=(stiffness.shape[0], 1)))
    basis = sp.hstack(columns).tocsr()
    reduced = (basis.T @ stiffness @ basis).tocsc()
    position = np.full(stiffness.shape[0], -1)
    position[free] = np.arange(free.size)
    kept_r = position[kept]
    interior = np.setdiff1d(np.arange(reduced.shape[0]), kept_r)
    # the interior in nested-dissection order (the holder's rotation, coupled to the
    # whole top row, last)
    x, y = slab.x, slab.heights()
    column = np.searchsorted(x, locations[0, free] - 1e-9 * slab.length)
    row = np.searchsorted(y, locations[1, free] - 1e-9 * slab.length)
    rank = np.empty(x.size * y.size, dtype=np.int64)
    rank[nested_dissection(x.size, y.size)] = np.arange(x.size * y.size)
    key = np.append(2 * rank[row * x.size + column] + ~is_x[free], 2 * rank.size)
    interior = interior[np.argsort(key[interior], kind="stable")]
    # the side of the dissection's first cut (0, 1) or on it (-1, with the rotation)
    across_columns, middle = _first_cut(x.size, y.size)
    place = np.append(column if across_columns else row, middle)
    side = np.where(place < middle, 0, np.where(place > middle, 1, -1))
    return _Assembly(reduced, basis, locations, is_x, kept_r, interior, side[interior],
                     contact_x.size + contact_y.size)


_DISSECTION_LEAF = 16  # nodes below which a part of the grid is not cut further


def nested_dissection(columns: int, rows: int) -> np.ndarray:
    """A nested-dissection order of a structured grid's nodes (George 1973).

    The grid is cut across its longer side by a line of nodes, each half is
    ordered the same way, recursively, and the separating line comes after both:
    eliminating in this order, the factor of a grid's stiffness fills in
    O(N log N) entries (a band ordering fills N^1.5, minimum degree in between).
    A grid's separators are its lines, so no graph partitioner is needed.

    Parameters
    ----------
    columns, rows
        Nodes along x and along y; node ``(i, j)`` is numbered ``j * columns + i``.

    Returns
    -------
    numpy.ndarray
        The node numbers in elimination order.

    Examples
    --------
    >>> nested_dissection(7, 3)[-3:]  # the first cut, the middle column, comes last
    array([ 3, 10, 17])
    """
    order: list[np.ndarray] = []
    parts = [(0, columns, 0, rows, False)]  # (i0, i1, j0, j1, is a separator)
    while parts:  # depth first, the separator after its halves (a stack, reversed)
        i0, i1, j0, j1, separator = parts.pop()
        across_columns, middle = _first_cut(i1 - i0, j1 - j0)
        if separator or middle < 0:
            j, i = np.mgrid[j0:j1, i0:i1]
            order.append((j * columns + i).ravel())
        elif across_columns:
            middle += i0
            parts += [(middle, middle + 1, j0, j1, True), (middle + 1, i1, j0, j1, False),
                      (i0, middle, j0, j1, False)]
        else:
            middle += j0
            parts += [(i0, i1, middle, middle + 1, True), (i0, i1, middle + 1, j1, False),
                      (i0, i1, j0, middle, False)]
    return np.concatenate(order)


def _first_cut(columns: int, rows: int) -> tuple[bool, int]:
    """Where nested dissection cuts a grid: (across its columns?, the line's index).

    The index is -1 when the grid is small enough to be left whole.
    """
    if columns * rows <= _DISSECTION_LEAF:
        return True, -1
    if columns >= rows:
        return True, columns // 2
    return False, rows // 2


def _factorise(matrix: sp.csc_matrix) -> spla.SuperLU:
    """LU of a stiffness in its given (nested-dissection) order, pivots on its diagonal.

    The stiffness is symmetric positive definite, so no pivoting is needed and the
    order chosen for its fill is kept (SuperLU's default threshold pivoting would
    move rows off it).
    """
    return spla.splu(matrix, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                     options={"SymmetricMode": True})


def _schur_complement(assembly: _Assembly) -> np.ndarray:
    """K_kk - K_ki K_ii^-1 K_ik: the slab condensed onto its kept dofs.

    By substructuring at the nested dissection's first cut: each side's interior is
    condensed onto the dofs it touches (its kept dofs, the cut's line, the holder's
    rotation), the sides' contributions are summed, densely, and the cut is then
    condensed out. Each side is one sparse factorisation, half the size of the whole
    slab's, which halves the peak memory (the factor's export is as large as the
    factor itself).
    """
    reduced, kept = assembly.reduced, assembly.kept
    boundary = np.concatenate([kept, assembly.interior[assembly.side < 0]])
    schur = reduced[boundary][:, boundary].toarray()
    for side in np.unique(assembly.side[assembly.side >= 0]):
        inner = assembly.interior[assembly.side == side]
        touched = np.flatnonzero(abs(reduced[inner][:, boundary]).sum(axis=0))
        outer = boundary[touched]
        # K_bi K_ii^-1 K_ib of this side: K_bb minus the trailing block of the factor
        # of [[K_ii, K_ib], [K_bi, K_bb]]
        correction = reduced[outer][:, outer].toarray() - _trailing_schur(
            reduced, inner, outer)
        schur[np.ix_(touched, touched)] -= correction
    n_kept = kept.size
    if boundary.size == n_kept:
        return schur
    cut = sla.cho_factor(schur[n_kept:, n_kept:])
    coupling = schur[:n_kept, n_kept:]
    return schur[:n_kept, :n_kept] - coupling @ sla.cho_solve(cut, coupling.T)


def _trailing_schur(reduced: sp.csc_matrix, inner: np.ndarray, outer: np.ndarray
                    ) -> np.ndarray:
    """K_oo - K_oi K_ii^-1 K_io, from one factorisation with the outer dofs last.

    Without pivoting, the trailing blocks of the factors multiply to the Schur
    complement (L_oo U_oo), so no solve per outer dof is needed (those solves, one
    sweep of the whole factor each, took several times the factorisation).
    """
    order = np.concatenate([inner, outer])
    factor = _factorise(reduced[order][:, order].tocsc())
    if not (np.array_equal(factor.perm_c, np.arange(order.size))
            and np.array_equal(factor.perm_r, np.arange(order.size))):
        raise SlipwaveError("the slab's condensation: its factorisation left the order "
                            "it was given")
    # symmetric, unpivoted: U = D L^T, so L_oo U_oo = U_oo^T D_oo^-1 U_oo and only U is
    # exported (each export is as large as SuperLU's own storage)
    upper = factor.U[inner.size:, inner.size:].toarray()
    return upper.T @ (upper / np.diag(upper)[:, None])


def _interior_response(assembly: _Assembly) -> tuple[np.ndarray, np.ndarray]:
    """(K_ik, K_ii^-1 K_ik), dense: the interior's response to the kept dofs, whole."""
    reduced, interior, kept = assembly.reduced, assembly.interior, assembly.kept
    k_ii = reduced[interior][:, interior].tocsc()
    k_ik = reduced[interior][:, kept].toarray()
    return k_ik, _factorise(k_ii).solve(k_ik)


def _condense_sensors(schur: np.ndarray, n_contact: int) -> tuple[np.ndarray, np.ndarray]:
    """The sensor dofs carry no load: condense them too, keeping their response."""
    k_cc, k_co = schur[:n_contact, :n_contact], schur[:n_contact, n_contact:]
    sensors = -np.linalg.solve(schur[n_contact:, n_contact:], k_co.T)
    contact = k_cc + k_co @ sensors
    return 0.5 * (contact + contact.T), sensors


def condensation_memory(slab: Slab, *, recovery: bool = False) -> int:
    """Bytes that condensing the slab takes at its peak, estimated from its mesh.

    The sparse factors of the slab's two halves in nested-dissection order, about
    N log2 N entries for N dofs, and their exports dominate (170 bytes per N log2 N;
    see ``benchmarks/RESULTS.md`` for the measured figures); ``recovery`` adds the dense
    maps of :func:`displacement_recovery` (the virtual bench's camera).

    Parameters
    ----------
    slab
        The slab.
    recovery
        Whether the displacement recovery is built too.

    Returns
    -------
    int
        The estimate, bytes (within a factor of about 2 of what is measured).

    Examples
    --------
    >>> condensation_memory(Slab(elements=160)) < 100e6 < condensation_memory(Slab(elements=2000))
    True
    """
    columns = slab.elements + 1
    rows = slab.heights().size
    kept = 2 * columns + 2
    dofs = 2 * columns * rows
    total = 170 * dofs * np.log2(dofs) + 4 * kept * kept * 8
    if recovery:
        total += 4 * dofs * kept * 8 + 2 * rows * columns * kept * 8
    return int(total)


def assemble_condensed(slab: Slab) -> Condensed:
    """Assemble the slab with scikit-fem and condense it (no cache).

    Parameters
    ----------
    slab
        The slab.

    Returns
    -------
    Condensed
        Its condensed matrices for its own E.

    """
    assembly = _assemble(slab)
    schur = _schur_complement(assembly)
    contact, sensors = _condense_sensors(0.5 * (schur + schur.T), assembly.n_contact)
    return Condensed(contact, sensors)


@dataclass(frozen=True)
class DisplacementRecovery:
    """The slab's nodal displacements from its contact displacements.

    Attributes
    ----------
    x, y
        The mesh's node columns and rows (mm).
    ux, uy
        (rows, columns, 2n): ``ux @ u_contact`` is the tangential displacement
        of every node, ``u_contact`` ordered as the solver's ``[ux, uy]``.
    """

    x: np.ndarray
    y: np.ndarray
    ux: np.ndarray
    uy: np.ndarray


def displacement_recovery(slab: Slab) -> DisplacementRecovery:
    """Linear map from contact displacements to every node's displacement.

    The interior follows from the contact (no other load acts on the slab), so
    the whole field of a solver step is ``recovery.ux @ [ux; uy]``.

    Parameters
    ----------
    slab
        The slab.

    Returns
    -------
    DisplacementRecovery
        The map and the mesh it gives displacements on.

    """
    assembly = _assemble(slab)
    k_ik, response = _interior_response(assembly)
    kept = assembly.kept
    schur = assembly.reduced[kept][:, kept].toarray() - k_ik.T @ response
    _, sensors = _condense_sensors(0.5 * (schur + schur.T), assembly.n_contact)
    n2 = assembly.n_contact
    of_contact = np.vstack([np.eye(n2), sensors])  # kept dofs from contact dofs
    reduced_u = np.zeros((assembly.reduced.shape[0], n2))
    reduced_u[kept] = of_contact
    reduced_u[assembly.interior] = -response @ of_contact
    full = np.asarray(assembly.basis @ reduced_u)
    x, y = slab.x, slab.heights()
    locations = assembly.locations
    column = np.searchsorted(x, locations[0] - 1e-9 * slab.length)
    row = np.searchsorted(y, locations[1] - 1e-9 * slab.length)
    ux = np.zeros((y.size, x.size, n2))
    uy = np.zeros((y.size, x.size, n2))
    ux[row[assembly.is_x], column[assembly.is_x]] = full[assembly.is_x]
    uy[row[~assembly.is_x], column[~assembly.is_x]] = full[~assembly.is_x]
    return DisplacementRecovery(x=x, y=y, ux=ux, uy=uy)


def _sorted_by_x(dofs: np.ndarray, locations: np.ndarray) -> np.ndarray:
    return dofs[np.argsort(locations[0, dofs], kind="stable")]

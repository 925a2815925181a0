"""The paper's behaviour map: the interface's succession of events over f x H/L.

The paper (its figure 2) runs 1572 cases, f = 0.10..1.40 step 0.01 times H/L in
0.1..1.0 step 0.1, 1.2 and 1.5, about 76 N normal load then 2 N tangential
increments until gross sliding, and sorts them by the succession of events at the
interface. :func:`map_row` runs one H/L (one geometry: the slab is condensed once)
over every f; :func:`assemble_map` joins the rows and numbers the behaviours;
:func:`plot_map` draws the figure and :func:`behaviour_legend` says in words what
each behaviour is. :func:`mesh_band` marks where the map still moves with the mesh
(the same cases at a coarser mesh, :func:`map_meshes`).
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pandas as pd
import xarray as xr

from slipwave import __version__
from slipwave.defaults import (
    CONTACT_LENGTH_MM,
    CONVENTIONS,
    MAP_ELEMENTS,
    MAP_FRICTIONS,
    MAP_HEIGHT_RATIOS,
    MAP_NORMAL_CONTROL,
    MAP_NORMAL_FRICTION,
    MIN_ZONE_MM,
)
from slipwave.errors import SlipwaveError

if TYPE_CHECKING:
    from slipwave.solver import LoadPath, SolverCache

# The solver (numba, scipy: 0.4 s to import) is imported where cases are simulated: the
# Snakefile and `slipwave map assemble` import this module only to plan and join the map.

MAP_CASE_VARIABLES = ("phase", "wave", "T", "N", "state", "slip_direction", "residual")
"""What a map case keeps of its simulation (``simulate``'s ``variables``): the
variables :func:`~slipwave.solver.behaviour.describe_behaviour` reads, and the
residual."""

PAPER_HEIGHT_RATIOS = MAP_HEIGHT_RATIOS
"""The paper's slab slendernesses H/L (the map's default)."""


def map_row(
    height_ratio: float,
    frictions: Sequence[float] | np.ndarray,
    *,
    elements: int = MAP_ELEMENTS,
    length: float = CONTACT_LENGTH_MM,
    path: LoadPath | None = None,
    min_size: float = MIN_ZONE_MM,
    cache: SolverCache | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> xr.Dataset:
    """One row of the map: every friction coefficient at one H/L.

    Parameters
    ----------
    height_ratio
        H/L of the slab.
    frictions
        Friction coefficients (fs = fd).
    elements
        Elements along the contact.
    length
        L, mm.
    path
        The load path; by default the map's: 76 N held constant (the paper's
        setting), a frictionless approach, 2 N steps.
    min_size
        Shortest zone that decides anything, mm.
    cache
        Where the slab's condensation and normal approach are kept (computed once for
        the row); ``None``: a cache of the row's own.
    progress
        Called with (cases done, cases) after each case.

    Returns
    -------
    xarray.Dataset
        Dimensions ``height_ratio`` (1) and ``friction``; see :func:`assemble_map`
        for the variables.

    Raises
    ------
    SlipwaveError
        If a case fails: it names the case.

    Examples
    --------
    >>> row = map_row(0.5, [0.3, 1.0], elements=80)
    >>> [str(s) for s in row["sequence"].values[0]][1]
    'opening right -> slip zone from right edge sweeps right-to-left -> gross sliding'

    """
    from slipwave.solver import Coulomb, LoadPath, Slab, SolverCache, condense, simulate
    from slipwave.solver.behaviour import describe_behaviour

    path = path or LoadPath(normal_control=MAP_NORMAL_CONTROL,  # type: ignore[arg-type]
                            normal_friction=MAP_NORMAL_FRICTION)
    slab = Slab(length=length, height=height_ratio * length, elements=elements)
    started = time.perf_counter()
    cache = cache or SolverCache()
    condense(slab, cache=cache)
    condensation = time.perf_counter() - started
    rows = []
    for k, friction in enumerate(frictions):
        started = time.perf_counter()
        try:
            ds = simulate(slab, Coulomb(fs=float(friction)), path, cache=cache,
                          variables=MAP_CASE_VARIABLES)
        except SlipwaveError as err:
            raise SlipwaveError(f"map case H/L {height_ratio:g}, f {friction:g}: {err}") from err
        behaviour = describe_behaviour(ds, min_size=min_size)
        rows.append(_case(ds, behaviour, time.perf_counter() - started))
        if progress:
            progress(k + 1, len(frictions))
    table = pd.DataFrame(rows)
    data: dict[str, Any] = {}
    for name, (variable_attrs, kind) in _VARIABLES.items():
        values = table[name].to_numpy()
        data[name] = (("height_ratio", "friction"), values.astype(kind)[None, :],
                      variable_attrs)
    coords = {
        "height_ratio": ("height_ratio", [float(height_ratio)],
                         {"units": "1", "long_name": "slab height over contact length H/L"}),
        "friction": ("friction", np.asarray(frictions, dtype=float),
                     {"units": "1", "long_name": "friction coefficient (fs = fd)"}),
    }
    attrs: dict[str, str | int | float] = {
        "title": "slipwave behaviour map",
        "product": "map row",
        "Conventions": CONVENTIONS,
        "source": f"slipwave {__version__} slipwave.map.map_row",
        "contact_elements": elements,
        "contact_length_mm": length,
        "min_zone_mm": min_size,
        "normal_load_N": path.normal_load,
        "tangential_step_N": path.tangential_step,
        "normal_control": path.normal_control,
        "normal_friction": int(path.normal_friction),
        "condensation_s": round(condensation, 4),
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


_VARIABLES: dict[str, tuple[dict[str, str], Any]] = {
    "sequence": ({"long_name": "succession of events at the interface"}, object),
    "paper_name": ({"long_name": "the paper's name of the behaviour (ZD, ZG) or empty"}, object),
    "L": ({"long_name": "first opening at the right edge (the paper's mark L)",
           "units": "1"}, np.int8),
    "first_opening": ({"long_name": "where the first opening appeared (right, left, inside; "
                                    "empty: none)"}, object),
    "first_opening_x": ({"long_name": "centre of the first open zone when it appeared",
                         "units": "mm"}, float),
    "first_slip": ({"long_name": "origin of the first slip zone driven by T"}, object),
    "first_slip_x": ({"long_name": "centre of the first slip zone when it appeared",
                      "units": "mm"}, float),
    "end": ({"long_name": "how the run ended: gross sliding or jammed"}, object),
    "ratio_at_gross": ({"long_name": "T/N at gross sliding", "units": "1"}, float),
    "steps": ({"long_name": "load steps of the run", "units": "1"}, np.int32),
    "max_residual": ({"long_name": "largest relative complementarity residual of the run",
                      "units": "1"}, float),
    "seconds": ({"long_name": "wall time of the case", "units": "s"}, float),
}


def _case(ds: xr.Dataset, behaviour: Any, seconds: float) -> dict[str, Any]:
    return {
        "sequence": behaviour.text,
        "paper_name": behaviour.paper_name or "",
        "L": int(behaviour.opens_right_first),
        "first_opening": behaviour.first_opening or "",
        "first_opening_x": behaviour.first_opening_x,
        "first_slip": behaviour.first_slip or "",
        "first_slip_x": behaviour.first_slip_x,
        "end": behaviour.end,
        "ratio_at_gross": np.nan if behaviour.ratio_at_gross is None
        else behaviour.ratio_at_gross,
        "steps": int(ds.sizes["step"]),
        # (from the variable: a DataArray's max() cost 0.2 ms, 3 % of a case)
        "max_residual": float(ds.variables["residual"].values.max()),
        "seconds": seconds,
    }


def assemble_map(rows: Sequence[xr.Dataset]) -> xr.Dataset:
    """Join map rows and number their behaviours.

    Behaviours are numbered by how many cases show them, most first (1, 2, ...);
    ``behaviours`` holds each number's succession of events.

    Parameters
    ----------
    rows
        From :func:`map_row` (or several rows joined along ``height_ratio``), any H/L
        order; a row may come in shards (parts of its f range, :func:`shard`), joined
        along f first.

    Returns
    -------
    xarray.Dataset
        ``height_ratio`` x ``friction``: ``behaviour`` (number), ``sequence``,
        ``paper_name``, ``L``, ``first_opening``, ``first_opening_x``,
        ``first_slip``, ``first_slip_x``, ``end``, ``ratio_at_gross``, ``steps``,
        ``max_residual`` (``seconds`` too, when the rows kept it); and along
        ``behaviour_id``: ``behaviours``
        (the succession), ``behaviour_name``, ``cases``. A behaviour whose slip
        zone leading to gross sliding is the paper's ZD (or ZG) is named ``ZD``
        for the most frequent such succession and ``ZD-b``, ``ZD-c``... for the
        others; the rest are ``C<number>``.

    """
    if not rows:
        raise SlipwaveError("no map rows to assemble")
    # shards of one H/L first (along f), then the H/L: the same map whatever the sharding
    # (a job's file may hold several H/L)
    by_ratio: dict[float, list[xr.Dataset]] = {}
    for piece in rows:
        for k in range(piece.sizes["height_ratio"]):
            by_ratio.setdefault(float(piece["height_ratio"][k]), []).append(
                piece.isel(height_ratio=[k]))
    joined = []
    for ratio in sorted(by_ratio):
        pieces = sorted(by_ratio[ratio], key=lambda p: float(p["friction"][0]))
        frictions = np.concatenate([p["friction"].values for p in pieces])
        if np.unique(frictions).size != frictions.size:
            raise SlipwaveError(f"map rows of H/L {ratio:g} overlap in f")
        joined.append(xr.concat(pieces, dim="friction", combine_attrs="drop_conflicts")
                      if len(pieces) > 1 else pieces[0])
    whole = xr.concat(joined, dim="height_ratio", combine_attrs="drop_conflicts")
    counts = Counter(str(s) for s in whole["sequence"].values.ravel())
    order = sorted(counts, key=lambda s: (-counts[s], s))
    number = {s: k + 1 for k, s in enumerate(order)}
    names = []
    family_count: Counter[str] = Counter()
    for sequence in order:
        where = whole["sequence"].values == sequence
        paper = Counter(str(p) for p in whole["paper_name"].values[where]).most_common(1)[0][0]
        if paper:
            family_count[paper] += 1
            rank = family_count[paper]
            names.append(paper if rank == 1 else f"{paper}-{chr(ord('a') + rank - 1)}")
        else:
            names.append(f"C{number[sequence]}")
    whole["behaviour"] = (("height_ratio", "friction"),
                          np.vectorize(lambda s: number[str(s)])(whole["sequence"].values)
                          .astype(np.int16),
                          {"long_name": "behaviour number (see behaviours)", "units": "1"})
    whole = whole.assign_coords(behaviour_id=("behaviour_id", np.arange(1, len(order) + 1),
                                              {"long_name": "behaviour number"}))
    whole["behaviours"] = ("behaviour_id", np.array(order, dtype=object),
                           {"long_name": "succession of events of each behaviour"})
    whole["behaviour_name"] = ("behaviour_id", np.array(names, dtype=object),
                               {"long_name": "the paper's name (ZD, ZG) or C<number>"})
    whole["cases"] = ("behaviour_id", np.array([counts[s] for s in order], dtype=np.int32),
                      {"long_name": "cases showing the behaviour", "units": "1"})
    whole.attrs["source"] = f"slipwave {__version__} slipwave.map.assemble_map"
    whole.attrs["product"] = "behaviour map"
    whole.attrs.pop("condensation_s", None)
    return whole


def map_meshes(elements: int, band_elements: int) -> list[int]:
    """The meshes the map is computed at: its own, then the coarser one its band comes from.

    Parameters
    ----------
    elements
        Elements along the contact of the map (config ``map.elements``).
    band_elements
        Elements of the coarser map the band is drawn from (``map.band_elements``);
        0: no band.

    Returns
    -------
    list of int
        ``[elements]`` or ``[elements, band_elements]``.

    Raises
    ------
    SlipwaveError
        If the band's mesh is not coarser than the map's.

    Examples
    --------
    >>> map_meshes(320, 160)
    [320, 160]
    """
    if not band_elements:
        return [elements]
    if band_elements >= elements:
        raise SlipwaveError(f"map.band_elements {band_elements}: the band is drawn from a "
                            f"coarser map than the map's own {elements} elements (or 0: "
                            "no band)")
    return [elements, band_elements]


def mesh_band(whole: xr.Dataset, coarser: xr.Dataset, steps: int) -> xr.DataArray:
    """Where the map's successions still move with the mesh.

    A case is in the band when its succession of events differs from the same case's
    in the map at a coarser mesh, or lies within ``steps`` f steps (at its H/L) of
    such a case: a boundary that moved between the two meshes may move on by about
    as much at a finer one (the documentation's "Mesh convergence" measures how
    many of the changes at twice the map's mesh the band holds).

    Parameters
    ----------
    whole
        The map (:func:`assemble_map` or :func:`map_row`).
    coarser
        The same cases at a coarser mesh.
    steps
        f steps the band is widened by on each side.

    Returns
    -------
    xarray.DataArray
        ``height_ratio`` x ``friction``, 1 in the band, 0 elsewhere.

    Raises
    ------
    SlipwaveError
        If the two maps do not hold the same cases, or ``steps`` is negative.

    Examples
    --------
    >>> import xarray as xr
    >>> def grid(sequences):
    ...     return xr.Dataset({"sequence": (("height_ratio", "friction"), [sequences])},
    ...                       coords={"height_ratio": [0.5], "friction": [0.1, 0.2, 0.3, 0.4]})
    >>> mesh_band(grid(["a", "a", "b", "b"]), grid(["a", "b", "b", "b"]), 1).values.tolist()
    [[1, 1, 1, 0]]
    """
    if steps < 0:
        raise SlipwaveError(f"map band of {steps} f steps: need 0 or more")
    for name in ("height_ratio", "friction"):
        if not np.array_equal(whole[name].values, coarser[name].values):
            raise SlipwaveError(f"the band's map and the map hold different {name} values")
    moved = whole["sequence"].values != coarser["sequence"].values
    band = moved.copy()
    for shift in range(1, steps + 1):
        band[:, shift:] |= moved[:, :-shift]
        band[:, :-shift] |= moved[:, shift:]
    elements = whole.attrs.get("contact_elements", "the map's")
    band_elements = coarser.attrs.get("contact_elements", "a coarser")
    return xr.DataArray(
        band.astype(np.int8), dims=("height_ratio", "friction"),
        coords={"height_ratio": whole["height_ratio"], "friction": whole["friction"]},
        attrs={"long_name": f"1 where the succession still moves with the mesh: it differs "
                            f"between {band_elements} and {elements} elements within "
                            f"{steps} f steps",
               "units": "1"})


def map_table(whole: xr.Dataset) -> pd.DataFrame:
    """One row per case: the map as a table (``map.csv``).

    Parameters
    ----------
    whole
        From :func:`assemble_map`.

    Returns
    -------
    pandas.DataFrame
        ``height_ratio``, ``friction`` and every per-case variable.

    """
    names = [v for v, var in whole.data_vars.items()
             if var.dims == ("height_ratio", "friction")]
    return whole[names].to_dataframe().reset_index()


def map_agreement(first: xr.Dataset, second: xr.Dataset, *,
                  by: Literal["sequence", "behaviour"] = "sequence") -> float:
    """Fraction of the cases both maps hold that have the same behaviour in both.

    Parameters
    ----------
    first, second
        Maps (:func:`assemble_map` or :func:`map_row`).
    by
        Compare the successions (behaviour numbers differ between maps).

    Returns
    -------
    float
        Between 0 and 1.

    """
    a, b = xr.align(first[by], second[by], join="inner")
    if a.size == 0:
        raise SlipwaveError("the two maps share no case")
    return float((a.values == b.values).mean())


def contiguity(whole: xr.Dataset) -> float:
    """Fraction of cases sharing their behaviour with at least one of their four neighbours.

    Parameters
    ----------
    whole
        From :func:`assemble_map`.

    Returns
    -------
    float
        Between 0 and 1.

    """
    grid = whole["sequence"].values
    same = np.zeros(grid.shape, dtype=bool)
    same[1:, :] |= grid[1:, :] == grid[:-1, :]
    same[:-1, :] |= grid[:-1, :] == grid[1:, :]
    same[:, 1:] |= grid[:, 1:] == grid[:, :-1]
    same[:, :-1] |= grid[:, :-1] == grid[:, 1:]
    return float(same.mean())




def deal_rows(height_ratios: Sequence[float], jobs: int) -> list[list[float]]:
    """The map's rows dealt to ``jobs`` jobs of about equal cost, each run in one process.

    A job pays its process's start-up once (imports, the compiled solver loaded), so
    a few jobs of several rows each beat one job per row on a few cores. A row's cost
    grows with its slab's height, as 2 + H/L (which fits the rows' wall times at 160
    elements). Rows are dealt costliest first, each to the job with the least so far.

    Parameters
    ----------
    height_ratios
        The rows' H/L.
    jobs
        How many jobs; more than the rows gives one row per job.

    Returns
    -------
    list of list of float
        Each job's H/L, in the order given; no job is empty.

    Examples
    --------
    >>> deal_rows([0.1, 0.5, 1.0, 1.5], 2)
    [[0.1, 1.5], [0.5, 1.0]]
    """
    if jobs < 1:
        raise SlipwaveError(f"{jobs} map jobs: need at least 1")
    loads = [0.0] * min(jobs, len(height_ratios))
    dealt: list[list[float]] = [[] for _ in loads]
    for ratio in sorted(height_ratios, key=lambda r: -r):
        job = loads.index(min(loads))
        loads[job] += 2.0 + ratio
        dealt[job].append(ratio)
    return [[r for r in height_ratios if r in job] for job in dealt]


def shard(frictions: np.ndarray, index: int, size: int) -> np.ndarray:
    """The ``index``-th run of ``size`` coefficients of a row (0: the whole row).

    Parameters
    ----------
    frictions
        The row's coefficients (:func:`friction_grid`).
    index
        Which shard, from 0.
    size
        Coefficients per shard; 0: one shard, the whole row.

    Returns
    -------
    numpy.ndarray
        The shard's coefficients.

    Raises
    ------
    SlipwaveError
        If the shard lies beyond the row.

    Examples
    --------
    >>> shard(friction_grid(0.1, 1.4, 0.01), 2, 50)[[0, -1]].tolist()
    [1.1, 1.4]
    """
    if size <= 0:
        return frictions
    part = frictions[index * size:(index + 1) * size]
    if index < 0 or not part.size:
        raise SlipwaveError(f"shard {index} of {size} coefficients lies beyond the row's "
                            f"{frictions.size}")
    return part


def shard_count(frictions: np.ndarray, size: int) -> int:
    """How many shards of ``size`` coefficients a row makes (1 for ``size`` 0).

    Parameters
    ----------
    frictions
        The row's coefficients.
    size
        Coefficients per shard; 0: the whole row.

    Returns
    -------
    int
        The number of shards.

    Examples
    --------
    >>> shard_count(friction_grid(0.1, 1.4, 0.01), 50)
    3
    """
    return 1 if size <= 0 else -(-frictions.size // size)


def friction_grid(start: float, stop: float, step: float) -> np.ndarray:
    """Friction coefficients from ``start`` to ``stop`` inclusive, rounded to the step.

    Parameters
    ----------
    start, stop, step
        The range (``stop`` included when it falls on the grid).

    Returns
    -------
    numpy.ndarray
        The coefficients.

    Examples
    --------
    >>> friction_grid(0.10, 1.40, 0.01).size
    131
    """
    if not (step > 0 and stop >= start > 0):
        raise SlipwaveError(f"friction grid {start:g}..{stop:g} step {step:g}: need "
                            "0 < start <= stop and step > 0")
    count = int(np.floor((stop - start) / step + 1e-9)) + 1
    decimals = max(0, int(np.ceil(-np.log10(step) + 1e-9)) + 1)
    return np.round(start + step * np.arange(count), decimals)


def representative_cases(whole: xr.Dataset) -> pd.DataFrame:
    """One case per behaviour, the one deepest inside its region of the map.

    Depth is the number of the case's eight neighbours on the grid that share its
    behaviour; ties go to the case nearest the region's centre.

    Parameters
    ----------
    whole
        From :func:`assemble_map`.

    Returns
    -------
    pandas.DataFrame
        ``behaviour``, ``name``, ``height_ratio``, ``friction``, ``sequence``, in
        behaviour order.

    """
    grid = whole["behaviour"].values
    padded = np.pad(grid, 1, constant_values=-1)
    depth = np.zeros(grid.shape, dtype=int)
    rows, cols = grid.shape
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di or dj:
                depth += padded[1 + di : 1 + di + rows, 1 + dj : 1 + dj + cols] == grid
    out = []
    for k, number in enumerate(whole["behaviour_id"].values):
        i, j = np.nonzero(grid == number)
        centre = np.array([i.mean(), j.mean()])
        score = depth[i, j] * 1e6 - np.hypot(i - centre[0], j - centre[1])
        best = int(np.argmax(score))
        out.append({"behaviour": int(number),
                    "name": str(whole["behaviour_name"].values[k]),
                    "height_ratio": float(whole["height_ratio"].values[i[best]]),
                    "friction": float(whole["friction"].values[j[best]]),
                    "sequence": str(whole["behaviours"].values[k])})
    return pd.DataFrame(out)


def simulate_case(whole: xr.Dataset, height_ratio: float, friction: float, *,
                  cache: SolverCache | None = None) -> xr.Dataset:
    """Run one case of a map again, with the map's settings (for its zone history).

    Parameters
    ----------
    whole
        From :func:`assemble_map` (its attributes give the settings).
    height_ratio, friction
        The case.
    cache
        Where the slab's condensation is looked up and kept; ``None``: computed afresh.

    Returns
    -------
    xarray.Dataset
        From :func:`~slipwave.solver.simulate`.

    """
    from slipwave.solver import Coulomb, LoadPath, Slab, simulate

    attrs = whole.attrs
    length = float(attrs["contact_length_mm"])
    slab = Slab(length=length, height=height_ratio * length,
                elements=int(attrs["contact_elements"]))
    path = LoadPath(normal_load=float(attrs["normal_load_N"]),
                    tangential_step=float(attrs["tangential_step_N"]),
                    normal_control=str(attrs["normal_control"]),  # type: ignore[arg-type]
                    normal_friction=bool(int(attrs["normal_friction"])))
    return simulate(slab, Coulomb(fs=friction), path, cache=cache)


def place_tests(summary: pd.DataFrame, height_ratios: dict[str, float | str]) -> pd.DataFrame:
    """The campaign's tests on the map: their H/L and measured T/N at gross slips.

    Parameters
    ----------
    summary
        The campaign summary (``results/summary.csv``): ``test_id``,
        ``static_ratio_mean``, ``static_ratio_ci_low``, ``static_ratio_ci_high``.
    height_ratios
        H/L of each test's slab (the campaign table's ``height_ratio``).

    Returns
    -------
    pandas.DataFrame
        ``test_id``, ``height_ratio``, ``ratio``, ``ci_low``, ``ci_high`` for the
        tests with an H/L and at least one gross slip.

    """
    rows = []
    for _, test in summary.iterrows():
        test_id = str(test["test_id"])
        if test_id not in height_ratios or not np.isfinite(test["static_ratio_mean"]):
            continue
        rows.append({"test_id": test_id, "height_ratio": float(height_ratios[test_id]),
                     "ratio": float(test["static_ratio_mean"]),
                     "ci_low": float(test["static_ratio_ci_low"]),
                     "ci_high": float(test["static_ratio_ci_high"])})
    return pd.DataFrame(rows, columns=["test_id", "height_ratio", "ratio", "ci_low", "ci_high"])


def behaviour_legend(whole: xr.Dataset) -> str:
    """The behaviours in words, one Markdown list item each.

    Parameters
    ----------
    whole
        From :func:`assemble_map`.

    Returns
    -------
    str
        ``- **B1** (ZD, L in 480 of 486 cases, 486 cases): slip zone from ...``.

    """
    lines = []
    for k, number in enumerate(whole["behaviour_id"].values):
        where = whole["behaviour"].values == number
        name = str(whole["behaviour_name"].values[k])
        L = int(whole["L"].values[where].sum())
        cases = int(where.sum())
        hl = whole["height_ratio"].values[np.nonzero(where)[0]]
        f = whole["friction"].values[np.nonzero(where)[1]]
        paper = f"{name.split('-')[0]}, " if name.startswith(("ZD", "ZG")) else ""
        lines.append(f"- **{name}** ({paper}{cases} cases, L in {L}; H/L {hl.min():g}-"
                     f"{hl.max():g}, f {f.min():.2f}-{f.max():.2f}): "
                     f"{whole['behaviours'].values[k]}")
    return "\n".join(lines)


PAPER_FRICTIONS = tuple(friction_grid(*MAP_FRICTIONS).tolist())
"""The paper's friction coefficients (the map's default grid), 0.10..1.40 step 0.01."""

__all__ = [
    "PAPER_FRICTIONS",
    "PAPER_HEIGHT_RATIOS",
    "assemble_map",
    "behaviour_legend",
    "contiguity",
    "friction_grid",
    "map_agreement",
    "map_row",
    "map_table",
    "place_tests",
    "representative_cases",
    "simulate_case",
]
